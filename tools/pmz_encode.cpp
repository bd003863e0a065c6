// pmz-encode: simplify a mesh and write it as a progressive .pmz stream (atomically).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <string>

#include "pmz/format.hpp"
#include "pmz/mesh.hpp"
#include "pmz/simplify.hpp"
#include "pmz/writer.hpp"

namespace {
bool write_file_atomic(const std::string& path, const std::vector<uint8_t>& bytes,
                       std::string& error) {
  std::string tmp = path + ".tmp";
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) return error = "cannot write " + tmp, false;
  bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  ok = std::fclose(f) == 0 && ok;
  if (!ok || std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    return error = "cannot write " + path, false;
  }
  return true;
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "pmz-encode: simplify a mesh with the multi-feature metric and write a progressive .pmz "
      "stream"};
  std::string input, output, metric = "guarded";
  pmz::WriteOptions wopt;
  app.add_option("input", input, "input mesh (OBJ/OFF/PLY/STL)")->required();
  app.add_option("-o,--output", output, "output .pmz")->required();
  app.add_option("--metric", metric,
                 "guarded (default): the paper's multi-feature metric plus the Hausdorff guard "
                 "(spec/algorithm.md section 6); multifeature: the paper's metric alone; qem: "
                 "plain QEM (QSlim)")
      ->check(CLI::IsMember({"guarded", "multifeature", "qem"}));
  app.add_option("--position-bits", wopt.position_bits, "quantization bits (0 = lossless float32)")
      ->check(CLI::Range(0, 30));
  app.add_option("--base-faces", wopt.base_faces,
                 "stop simplifying at this many faces (0: as far as possible)");
  app.add_flag("--symbol-stats", wopt.symbol_stats,
               "also print the code length per kind of split symbol (groups, choice, wedges, "
               "residual slots)");
  CLI11_PARSE(app, argc, argv);

  auto t0 = std::chrono::steady_clock::now();
  pmz::IndexedMesh mesh;
  std::string error;
  if (!pmz::read_mesh(input, mesh, error)) {
    std::fprintf(stderr, "pmz-encode: %s\n", error.c_str());
    return 1;
  }
  if (!mesh.attributes.empty())  // never a silent loss: the format codes geometry only so far
    std::fprintf(stderr,
                 "pmz-encode: %s: attributes not encoded yet (%s): the .pmz holds positions "
                 "and triangles only\n",
                 input.c_str(), mesh.attributes.describe().c_str());
  pmz::SimplifyOptions sopt;
  sopt.metric = metric == "qem"            ? pmz::Metric::qem
                : metric == "multifeature" ? pmz::Metric::multifeature
                                           : pmz::Metric::guarded;
  // A progress line only on a terminal: redirected stderr (logs, CI) gets no carriage returns.
  const bool tty = isatty(2);
  int last_pct = -1;
  if (tty)
    sopt.progress = [&](double f) {
      int pct = int(f * 100);
      if (pct != last_pct) {
        last_pct = pct;
        std::fprintf(stderr, "\rpmz-encode: simplifying %3d%%", pct);
      }
    };
  pmz::CollapseSequence seq;
  if (!pmz::simplify(mesh, sopt, seq, error)) {
    if (tty) std::fputs("\r\033[K", stderr);
    std::fprintf(stderr, "pmz-encode: %s\n", error.c_str());
    return 1;
  }
  if (tty) std::fputs("\rpmz-encode: simplified, writing\033[K", stderr);
  std::vector<uint8_t> bytes;
  pmz::WriteStats st;
  const bool written =
      pmz::write_pmz(seq, wopt, bytes, error, &st) && write_file_atomic(output, bytes, error);
  if (tty) std::fputs("\r\033[K", stderr);
  if (!written) {
    std::fprintf(stderr, "pmz-encode: %s\n", error.c_str());
    return 1;
  }
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double nv = seq.mesh.vertex_count();
  std::printf(
      "%s: %u faces, %u vertices -> %zu bytes, %.2f bits/vertex (connectivity %.2f, geometry %.2f "
      "bits/split), %.2fs\n",
      output.c_str(), seq.mesh.face_count(), seq.mesh.vertex_count(), bytes.size(),
      bytes.size() * 8.0 / nv, st.connectivity_bits / std::max(1.0, double(seq.collapses.size())),
      st.geometry_bits / std::max(1.0, double(seq.collapses.size())), secs);
  if (!wopt.symbol_stats) return 0;
  // Per kind of symbol, the bits its symbols take of their stream (the streams interleave kinds,
  // so their sizes cannot split them further).
  const char* kinds[pmz::kSymbolKinds] = {"groups",      "choice",      "wedge_count", "wedge_rank",
                                          "residual_t0", "residual_t1", "residual_n"};
  std::printf("  code bits/split:");
  for (int k = 0; k < pmz::kSymbolKinds; ++k)
    std::printf(" %s %.2f", kinds[k],
                st.symbol_bits[k] / std::max(1.0, double(seq.collapses.size())));
  std::printf("\n");
  return 0;
}
