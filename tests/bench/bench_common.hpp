// SPDX-License-Identifier: MIT
// Shared bits of the benchmark harness programs: a wall clock and the one-line JSON report
// the driver (bench.py) parses from stdout.
#pragma once
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace pmz_bench {

class Stopwatch {
 public:
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

// "seconds" is the time of the algorithm alone (no file input/output).
inline void report(double seconds, unsigned long long faces_in, unsigned long long faces_out) {
  std::printf("{\"seconds\": %.6f, \"faces_in\": %llu, \"faces_out\": %llu}\n", seconds, faces_in,
              faces_out);
}

inline int fail(const char* tool, const std::string& message) {
  std::fprintf(stderr, "%s: %s\n", tool, message.c_str());
  return 1;
}

// Parses "--faces N" style unsigned arguments; exits with a one-line error when malformed.
inline unsigned long long parse_count(const char* tool, const char* text) {
  char* end = nullptr;
  unsigned long long v = std::strtoull(text, &end, 10);
  if (!end || *end || text[0] == '-' || text[0] == 0) {
    std::fprintf(stderr, "%s: not a count: '%s'\n", tool, text);
    std::exit(2);
  }
  return v;
}

}  // namespace pmz_bench
