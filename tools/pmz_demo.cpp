// SPDX-License-Identifier: MIT
// pmz-demo: the whole job on an embedded default. Makes the procedural sample mesh, encodes it
// to .pmz with the multi-feature metric, then streams the file into the decoder and reports,
// for several levels of detail, how many bytes had to arrive and how far the mesh is from the
// original (Metro-style symmetric Hausdorff, relative to the bounding-box diagonal).
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "pmz/app_support.hpp"
#include "pmz/compare.hpp"
#include "pmz/decoder.hpp"
#include "pmz/sample_mesh.hpp"
#include "pmz/simplify.hpp"
#include "pmz/writer.hpp"

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

pmz::IndexedMesh current_mesh(const pmz::Decoder& d) {
  pmz::IndexedMesh m;
  m.positions.assign(d.positions(), d.positions() + size_t(d.vertex_count()) * 3);
  m.indices.assign(d.indices(), d.indices() + size_t(d.face_count()) * 3);
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  pmz::app_support::init("pmz-demo");
  if (argc > 1 && !std::strcmp(argv[1], "--version")) {
    std::printf("pmz-demo %s\n", pmz::app_support::version());
    return 0;
  }
  if (argc > 1 && (!std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h"))) {
    std::printf(
        "usage: pmz-demo [OUT_DIR] [--faces N] | --version\n"
        "Makes a procedural sample mesh (sharp creases + smooth ripples, ~50k triangles),\n"
        "encodes it to OUT_DIR/sample.pmz, streams it back through the decoder and prints,\n"
        "per level of detail: faces, bytes that had to arrive, and the symmetric Hausdorff\n"
        "error (mean / max, relative to the bounding-box diagonal). OUT_DIR defaults to\n"
        "./pmz-demo; it also receives sample.obj and the decoded levels as lod_*.obj.\n\n%s\n",
        pmz::app_support::kExitStatusHelp);
    return 0;
  }
  std::filesystem::path out_dir = "pmz-demo";
  uint32_t faces = 50000;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--faces") && i + 1 < argc)
      faces = uint32_t(std::strtoul(argv[++i], nullptr, 10));
    else if (argv[i][0] == '-') {
      std::fprintf(stderr, "pmz-demo: unknown option %s (see --help)\n", argv[i]);
      return 2;
    } else
      out_dir = argv[i];
  }
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) {
    std::fprintf(stderr, "pmz-demo: cannot create %s: %s\n", out_dir.c_str(), ec.message().c_str());
    return 1;
  }

  std::string error;
  const pmz::IndexedMesh mesh = pmz::make_sample_mesh(faces);
  if (!pmz::write_mesh((out_dir / "sample.obj").string(), mesh, error)) {
    std::fprintf(stderr, "pmz-demo: %s\n", error.c_str());
    return 1;
  }
  std::printf("sample mesh: %u vertices, %u faces -> %s\n", mesh.vertex_count(), mesh.face_count(),
              (out_dir / "sample.obj").c_str());

  auto t0 = std::chrono::steady_clock::now();
  pmz::CollapseSequence seq;
  if (!pmz::simplify(mesh, pmz::SimplifyOptions{}, seq, error)) {
    std::fprintf(stderr, "pmz-demo: simplify: %s\n", error.c_str());
    return 1;
  }
  const double t_simplify = seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  std::vector<uint8_t> bytes;
  pmz::WriteOptions wopt;
  if (!pmz::write_pmz(seq, wopt, bytes, error)) {
    std::fprintf(stderr, "pmz-demo: write: %s\n", error.c_str());
    return 1;
  }
  const double t_write = seconds_since(t0);
  const auto pmz_path = out_dir / "sample.pmz";
  if (!pmz::app_support::write_output(pmz_path.string(), bytes.data(), bytes.size(), error)) {
    pmz::app_support::print_error(error);
    return 1;
  }
  std::printf(
      "encoded: %zu collapses in %.2f s, written in %.2f s: %zu bytes (%.2f bits/vertex, "
      "%d-bit positions) -> %s\n",
      seq.collapses.size(), t_simplify, t_write, bytes.size(),
      8.0 * double(bytes.size()) / mesh.vertex_count(), int(wopt.position_bits), pmz_path.c_str());

  // Stream the file in 4 KiB slices as a download would deliver it, noting after each slice
  // how many splits had become available.
  pmz::Decoder dec;
  std::vector<std::pair<uint64_t, uint64_t>> arrival;  // (bytes fed, splits available)
  const size_t slice = 4096;
  t0 = std::chrono::steady_clock::now();
  for (size_t pos = 0; pos < bytes.size(); pos += slice) {
    size_t n = std::min(slice, bytes.size() - pos);
    if (dec.feed(bytes.data() + pos, n) != pmz::Status::ok) {
      std::fprintf(stderr, "pmz-demo: decode: %s\n", dec.error_message().c_str());
      return 1;
    }
    if (dec.info().base_done) arrival.emplace_back(pos + n, dec.splits_available());
  }
  if (dec.finish() != pmz::Status::ok) {
    std::fprintf(stderr, "pmz-demo: decode: %s\n", dec.error_message().c_str());
    return 1;
  }
  dec.refine();
  const double t_decode = seconds_since(t0);
  std::printf("decoded: %u faces, %u vertices in %.3f s (streamed in %zu-byte slices)\n\n",
              dec.face_count(), dec.vertex_count(), t_decode, slice);

  std::printf("%9s %9s %12s %8s %12s %12s\n", "level", "faces", "bytes read", "% file",
              "mean error", "max error");
  const double ratios[] = {0, 0.01, 0.02, 0.05, 0.10, 0.25, 0.50, 1.0};
  for (double r : ratios) {
    uint64_t target = r == 0 ? 0 : uint64_t(r * mesh.face_count() + 0.5);
    dec.set_face_target(target);
    uint64_t need = dec.splits_applied();
    uint64_t bytes_read = bytes.size();
    for (const auto& [fed, avail] : arrival)
      if (avail >= need) {
        bytes_read = fed;
        break;
      }
    pmz::IndexedMesh lod = current_mesh(dec);
    pmz::CompareResult cr;
    if (!pmz::compare(mesh, lod, pmz::CompareOptions{}, cr, error)) {
      std::fprintf(stderr, "pmz-demo: compare: %s\n", error.c_str());
      return 1;
    }
    char name[32];
    if (r == 0)
      std::snprintf(name, sizeof name, "base");
    else
      std::snprintf(name, sizeof name, "%g%%", r * 100);
    std::string file =
        "lod_" + std::string(r == 0 ? "base" : std::to_string(int(r * 1000 + 0.5))) + ".obj";
    if (!pmz::write_mesh((out_dir / file).string(), lod, error)) {
      std::fprintf(stderr, "pmz-demo: %s\n", error.c_str());
      return 1;
    }
    std::printf("%9s %9u %12llu %7.1f%% %12.3e %12.3e\n", name, dec.face_count(),
                (unsigned long long)bytes_read, 100.0 * double(bytes_read) / double(bytes.size()),
                cr.symmetric.mean / cr.diag, cr.symmetric.max / cr.diag);
  }
  std::printf(
      "\nerrors: Metro-style symmetric Hausdorff distance relative to the bounding-box "
      "diagonal\n(the last row differs from 0 by the %d-bit position quantization).\n",
      int(wopt.position_bits));
  return 0;
}
