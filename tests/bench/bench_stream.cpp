// SPDX-License-Identifier: MIT
// bench-stream: feeds a .pmz file to the decoder library the way a streaming client does and
// times it. Two uses:
//  - a streaming client's interleaving: slices of --slice bytes, refine(--refine) after
//    each feed (--refine 0: once, after the last slice); prints the decoder's CPU and wall time.
//  - a link of --mbit Mbit/s on a virtual clock: slice i has arrived at (i + 1) * slice * 8 /
//    rate; the clock is max(arrival, clock) before each feed and advances by the measured time
//    of feed + refine (process CPU time, which the other processes of a shared machine do not
//    inflate; --clock wall for elapsed time). Reports the clock when the mesh first reaches each
//    --faces target and when it is complete (every split applied). --refine all refines
//    everything that has arrived after each feed, as a client that only wants the best mesh.
// Output: one JSON line. Uses the public decoder API only (pmz/decoder.hpp).
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "pmz/decoder.hpp"

namespace {
double cpu_now() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}
double wall_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
[[noreturn]] void usage() {
  std::fprintf(stderr,
               "usage: bench-stream FILE.pmz [--slice BYTES] [--refine N|all] [--mbit RATE] "
               "[--faces F1,F2,...] [--clock cpu|wall]\n");
  std::exit(2);
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) usage();
  const char* path = argv[1];
  size_t slice = 997;
  uint64_t per_feed = 5000;  // 0: refine once at the end
  double mbit = 0;           // 0: no link, as fast as the decoder goes
  bool wall_clock = false;
  std::vector<uint64_t> targets;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) usage();
    const char* v = argv[++i];
    if (a == "--slice")
      slice = std::max<size_t>(1, std::strtoull(v, nullptr, 10));
    else if (a == "--refine")
      per_feed = std::string(v) == "all" ? UINT64_MAX : std::strtoull(v, nullptr, 10);
    else if (a == "--clock") {
      if (std::string(v) != "cpu" && std::string(v) != "wall") usage();
      wall_clock = std::string(v) == "wall";
    } else if (a == "--mbit")
      mbit = std::strtod(v, nullptr);
    else if (a == "--faces") {
      for (const char* p = v; *p;) {
        char* end;
        targets.push_back(std::strtoull(p, &end, 10));
        p = *end == ',' ? end + 1 : end;
        if (end == p && *p) usage();
      }
    } else
      usage();
  }
  std::vector<uint8_t> data;
  if (FILE* f = std::fopen(path, "rb")) {
    uint8_t buf[1 << 16];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) data.insert(data.end(), buf, buf + n);
    std::fclose(f);
  } else {
    std::fprintf(stderr, "bench-stream: cannot read %s\n", path);
    return 1;
  }
  std::sort(targets.begin(), targets.end());
  std::vector<double> reached(targets.size(), -1);
  size_t next_target = 0;
  const double bytes_per_s = mbit > 0 ? mbit * 1e6 / 8 : 0;

  auto now = [&] { return wall_clock ? wall_now() : cpu_now(); };
  pmz::Decoder d;
  double clock = 0;  // virtual clock (link mode), seconds
  const double cpu0 = cpu_now(), wall0 = wall_now();
  auto note = [&] {
    while (next_target < targets.size() && d.face_count() >= targets[next_target])
      reached[next_target++] = clock;
  };
  for (size_t at = 0; at < data.size(); at += slice) {
    const size_t n = std::min(slice, data.size() - at);
    if (bytes_per_s > 0) clock = std::max(clock, double(at + n) / bytes_per_s);
    const double t0 = now();
    if (d.feed(data.data() + at, n) != pmz::Status::ok) {
      std::fprintf(stderr, "bench-stream: %s: %s\n", path, d.error_message().c_str());
      return 1;
    }
    if (per_feed > 0 && d.info().base_done) {
      d.refine(per_feed);
      d.clear_changes();
    }
    clock += now() - t0;
    note();
  }
  if (d.finish() != pmz::Status::ok) {
    std::fprintf(stderr, "bench-stream: %s: %s\n", path, d.error_message().c_str());
    return 1;
  }
  // What has arrived but is not applied yet (everything with --refine 0).
  while (d.splits_applied() < d.splits_available()) {
    const double t0 = now();
    d.refine(per_feed > 0 ? per_feed : UINT64_MAX);
    d.clear_changes();
    clock += now() - t0;
    note();
  }
  const double cpu = cpu_now() - cpu0, wall = wall_now() - wall0;
  if (d.status() != pmz::Status::ok) {
    std::fprintf(stderr, "bench-stream: %s: %s\n", path, d.error_message().c_str());
    return 1;
  }
  std::printf(
      "{\"file\": \"%s\", \"bytes\": %zu, \"slice\": %zu, \"refine\": %llu, \"mbit\": %g, "
      "\"splits\": %llu, \"faces\": %u, \"cpu_s\": %.6f, \"wall_s\": %.6f, "
      "\"splits_per_cpu_s\": %.0f, \"complete_s\": %.6f, \"reached\": [",
      path, data.size(), slice, (unsigned long long)per_feed, mbit,
      (unsigned long long)d.splits_applied(), d.face_count(), cpu, wall,
      double(d.splits_applied()) / cpu, clock);
  for (size_t i = 0; i < targets.size(); ++i)
    std::printf("%s[%llu, %.6f]", i ? ", " : "", (unsigned long long)targets[i], reached[i]);
  std::printf("]}\n");
  return 0;
}
