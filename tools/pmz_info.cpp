// pmz-info: a .pmz file's header, counts, bytes per section and per stream, and bits per
// vertex split divided into connectivity (groups, vertex choice, wedges) and geometry (residuals):
// the two streams of every SPLT chunk.
// Reads the container directly (chunk framing + stream sizes); validates by a full decode.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <string>
#include <vector>

#include "pmz/decoder.hpp"
#include "pmz/format.hpp"
#include "pmz/split_codec.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "pmz-info: print a .pmz file's header, counts, bytes per section and bits per vertex split"};
  std::string input;
  bool json = false;
  app.add_option("input", input, "input .pmz")->required();
  app.add_flag("--json", json, "machine-readable output");
  CLI11_PARSE(app, argc, argv);

  std::vector<uint8_t> data;
  if (FILE* f = std::fopen(input.c_str(), "rb")) {
    uint8_t buf[1 << 16];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) data.insert(data.end(), buf, buf + n);
    std::fclose(f);
  } else {
    std::fprintf(stderr, "pmz-info: cannot read %s\n", input.c_str());
    return 1;
  }
  pmz::Decoder d;
  pmz::Status s = d.feed(data.data(), data.size());
  if (s == pmz::Status::ok) s = d.finish();
  if (s != pmz::Status::ok) {
    std::fprintf(stderr, "pmz-info: %s\n", d.error_message().c_str());
    return 1;
  }
  // Wall time, and the process's CPU time (std::clock), which other processes on a busy
  // machine do not inflate.
  auto t0 = std::chrono::steady_clock::now();
  std::clock_t c0 = std::clock();
  d.refine();
  double refine_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double refine_cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
  // Wedge and residual symbols are decoded as splits are first applied: damage there shows now.
  if (d.status() != pmz::Status::ok) {
    std::fprintf(stderr, "pmz-info: %s\n", d.error_message().c_str());
    return 1;
  }
  // Again with memory already touched and positions computed: the per-frame refinement cost.
  d.coarsen();
  t0 = std::chrono::steady_clock::now();
  c0 = std::clock();
  d.refine();
  double warm_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double warm_cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;

  // Section sizes from the framing (the decode above validated it).
  uint64_t head = 8, base = 0, splits = 0, other = 0, chunks = 0;
  uint64_t stream_bytes[pmz::kSplitStreamCount] = {};
  for (size_t at = 8; at < data.size();) {
    pmz::ChunkFrame f;
    if (pmz::parse_chunk_frame(data.data() + at, data.size() - at, f) != pmz::FrameStatus::ok ||
        f.payload_size > data.size() - at - f.header_size)
      break;  // cannot happen before END: the decode above validated it
    const uint64_t total = f.header_size + f.payload_size;
    if (f.type == pmz::kChunkEnd) {
      other += total;
      break;  // the decoder ignores what follows END, even bytes that frame as chunks
    }
    if (f.type == pmz::kChunkHead)
      head += total;
    else if (f.type == pmz::kChunkBase)
      base += total;
    else if (f.type == pmz::kChunkSplits) {
      splits += total;
      ++chunks;
      uint64_t count = 0, sizes[pmz::kSplitStreamCount] = {};
      pmz::split_chunk_stream_sizes(data.data() + at + f.header_size, size_t(f.payload_size), count,
                                    sizes);
      for (int k = 0; k < pmz::kSplitStreamCount; ++k) stream_bytes[k] += sizes[k];
    } else
      other += total;
    at += total;
  }
  const pmz::StreamInfo& i = d.info();
  const double ns = double(std::max<uint64_t>(1, i.total_splits));
  // The two streams of every SPLT chunk are exactly this split (per symbol kind: pmz-encode's
  // ideal code lengths).
  const double conn = double(stream_bytes[pmz::kStreamConnectivity]) * 8 / ns;
  const double geom = double(stream_bytes[pmz::kStreamGeometry]) * 8 / ns;
  const char* names[pmz::kSplitStreamCount] = {"connectivity", "geometry"};
  const double splits_per_s = refine_s > 0 ? double(i.total_splits) / refine_s : 0;
  const double warm_per_s = warm_s > 0 ? double(i.total_splits) / warm_s : 0;
  if (json) {
    std::printf(
        "{\"file\":\"%s\",\"bytes\":%zu,\"version\":\"%u.%u\",\"position_bits\":%u,\"curvature\":%"
        "u,\"fine_curvature\":%u,"
        "\"base_vertices\":%llu,\"base_faces\":%llu,\"full_vertices\":%llu,\"full_faces\":%llu,"
        "\"splits\":%llu,\"split_chunks\":%llu,\"header_bytes\":%llu,\"base_bytes\":%llu,"
        "\"split_bytes\":%llu,\"other_bytes\":%llu,\"bits_per_vertex\":%.4f,"
        "\"connectivity_bits_per_split\":%.4f,\"geometry_bits_per_split\":%.4f,"
        "\"refine_splits_per_second\":%.0f,\"rerefine_splits_per_second\":%.0f,"
        "\"refine_cpu_ms\":%.3f,\"rerefine_cpu_ms\":%.3f,\"stream_bytes\":{",
        input.c_str(), data.size(), i.version_major, i.version_minor, i.position_bits, i.curvature,
        i.fine_curvature, (unsigned long long)i.base_vertices, (unsigned long long)i.base_faces,
        (unsigned long long)i.full_vertices, (unsigned long long)i.full_faces,
        (unsigned long long)i.total_splits, (unsigned long long)chunks, (unsigned long long)head,
        (unsigned long long)base, (unsigned long long)splits, (unsigned long long)other,
        data.size() * 8.0 / double(std::max<uint64_t>(1, i.full_vertices)), conn, geom,
        splits_per_s, warm_per_s, refine_cpu * 1e3, warm_cpu * 1e3);
    for (int k = 0; k < pmz::kSplitStreamCount; ++k)
      std::printf("%s\"%s\":%llu", k ? "," : "", names[k], (unsigned long long)stream_bytes[k]);
    std::printf("}}\n");
    return 0;
  }
  std::printf("%s: %zu bytes, format %u.%u, %s, curvature %u/8 + %u/8\n", input.c_str(),
              data.size(), i.version_major, i.version_minor,
              i.position_bits ? (std::to_string(i.position_bits) + "-bit positions").c_str()
                              : "lossless float32 positions",
              i.curvature, i.fine_curvature);
  std::printf("  bbox      (%g %g %g) - (%g %g %g)\n", i.bbox_min[0], i.bbox_min[1], i.bbox_min[2],
              i.bbox_max[0], i.bbox_max[1], i.bbox_max[2]);
  std::printf("  base      %llu vertices, %llu faces\n", (unsigned long long)i.base_vertices,
              (unsigned long long)i.base_faces);
  std::printf("  full      %llu vertices, %llu faces, %llu splits in %llu chunks\n",
              (unsigned long long)i.full_vertices, (unsigned long long)i.full_faces,
              (unsigned long long)i.total_splits, (unsigned long long)chunks);
  std::printf("  sections  header %llu, base %llu, splits %llu, other %llu bytes\n",
              (unsigned long long)head, (unsigned long long)base, (unsigned long long)splits,
              (unsigned long long)other);
  std::printf("  per split connectivity %.2f bits, geometry %.2f bits; %.2f bits/vertex overall\n",
              conn, geom, data.size() * 8.0 / double(std::max<uint64_t>(1, i.full_vertices)));
  std::printf(
      "  streams   connectivity %llu bytes, geometry %llu bytes (SPLT framing and counts %llu)\n",
      (unsigned long long)stream_bytes[pmz::kStreamConnectivity],
      (unsigned long long)stream_bytes[pmz::kStreamGeometry],
      (unsigned long long)(splits - stream_bytes[pmz::kStreamConnectivity] -
                           stream_bytes[pmz::kStreamGeometry]));
  std::printf(
      "  full refinement %.3f ms (%.1f M splits/s); after coarsening, again %.3f ms (%.1f M "
      "splits/s)\n",
      refine_s * 1e3, splits_per_s / 1e6, warm_s * 1e3, warm_per_s / 1e6);
  std::printf("  cpu time  full refinement %.3f ms, again %.3f ms\n", refine_cpu * 1e3,
              warm_cpu * 1e3);
  return 0;
}
