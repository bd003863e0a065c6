// SPDX-License-Identifier: MIT
// Internal: what the comparisons share: the seeded sample generator, triangle area, and the
// fixed-block thread pool (blocks are reduced in block order by the caller, so results do not
// depend on the thread count).
#pragma once
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <thread>
#include <vector>

namespace pmz::sampling {

inline uint64_t splitmix64(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
inline double uniform01(uint64_t& state) { return double(splitmix64(state) >> 11) * 0x1.0p-53; }

// Barycentric weights of a uniform point in a triangle (square-root warp of two uniforms).
inline void uniform_barycentric(uint64_t& state, double w[3]) {
  const double s = std::sqrt(uniform01(state)), r = uniform01(state);
  w[0] = 1 - s, w[1] = s * (1 - r), w[2] = s * r;
}

inline double triangle_area(const float* a, const float* b, const float* c) {
  double u[3], v[3];
  for (int k = 0; k < 3; ++k) u[k] = double(b[k]) - a[k], v[k] = double(c[k]) - a[k];
  const double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2],
               z = u[0] * v[1] - u[1] * v[0];
  return 0.5 * std::sqrt(x * x + y * y + z * z);
}

// Runs block(b, hint) for b in [0, blocks) on up to `threads` threads; hint is each thread's
// BVH search hint (TriangleBvh::closest_distance2), carried from one block to its next.
template <class Block>
void for_each_block(uint64_t blocks, unsigned threads, Block&& block) {
  std::atomic<uint64_t> next{0};
  auto worker = [&] {
    uint32_t hint = 0xFFFFFFFFu;
    for (uint64_t b; (b = next.fetch_add(1)) < blocks;) block(b, hint);
  };
  threads = std::max(1u, std::min<unsigned>(threads, unsigned(std::min<uint64_t>(blocks, 64))));
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
}

}  // namespace pmz::sampling
