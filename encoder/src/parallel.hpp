// SPDX-License-Identifier: MIT
// Internal: the engine's set-up on two threads. Each loop run this way computes every index
// independently of the others (no shared sums), so the results are the same bits as one thread's.
#pragma once
#include <cstdint>
#include <thread>

namespace pmz::detail {

// f(begin, end) over [0, n) in two halves, one on a second thread. Small ranges run inline.
template <class F>
void parallel_halves(uint32_t n, F&& f) {
  if (n < 65536) {
    f(uint32_t(0), n);
    return;
  }
  const uint32_t half = n / 2;
  std::thread other([&] { f(half, n); });
  f(uint32_t(0), half);
  other.join();
}

}  // namespace pmz::detail
