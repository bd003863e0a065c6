// pmz-simplify: simplify a mesh to a face count or ratio with the multi-feature metric (or
// plain QEM) and write it as OBJ/OFF/PLY.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "pmz/mesh.hpp"
#include "pmz/simplify.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "pmz-simplify: simplify a triangle mesh by half-edge collapses (multi-feature metric or "
      "QEM)"};
  std::string input, output, metric_name = "guarded";
  double ratio = -1;
  uint64_t faces = 0;
  bool verbose = false;
  pmz::SimplifyOptions options;
  app.add_option("input", input, "input mesh (OBJ, OFF, PLY, STL)")->required();
  app.add_option("-o,--output", output, "output mesh (.obj, .off, .ply, .stl)")->required();
  auto* ratio_opt =
      app.add_option("--ratio", ratio, "target face count as a fraction of the input's (0..1]");
  auto* faces_opt = app.add_option("--faces", faces, "target face count");
  ratio_opt->excludes(faces_opt);
  app.add_option("--metric", metric_name,
                 "guarded (default): the paper's multi-feature metric plus the Hausdorff guard "
                 "(spec/algorithm.md section 6); multifeature: the paper's metric alone; qem: "
                 "plain QEM (QSlim)")
      ->check(CLI::IsMember({"guarded", "multifeature", "qem"}));
  app.add_option("--epsilon", options.params.epsilon, "torsion threshold epsilon (eq. 2)");
  app.add_option("--quadric-floor", options.params.quadric_floor,
                 "c0 in (c0 + C_norm + w_T * sigma * T) * Q");
  app.add_option("--torsion-weight", options.params.torsion_weight,
                 "weight w_T of sigma * T in the quadric's factor");
  app.add_option("--boundary-weight", options.params.boundary_weight,
                 "weight of boundary quadrics");
  app.add_option(
      "--quadric-memory", options.params.quadric_memory,
      "multifeature: weight of the accumulated (QSlim) quadric added to the current mesh's");
  app.add_option("--guard-slack", options.params.guard_slack,
                 "guarded: collapses whose bound exceeds this times the worst bound so far are "
                 "penalised");
  app.add_flag("-v,--verbose", verbose, "print where the time went");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (ratio_opt->count() == 0 && faces_opt->count() == 0) {
    std::fprintf(stderr, "pmz-simplify: give --ratio R or --faces N\n");
    return 2;
  }
  if (ratio_opt->count() && !(ratio > 0 && ratio <= 1)) {
    std::fprintf(stderr, "pmz-simplify: --ratio must be in (0, 1]\n");
    return 2;
  }
  if (faces_opt->count() && faces == 0) {
    std::fprintf(stderr, "pmz-simplify: --faces must be at least 1\n");
    return 2;
  }
  options.metric = metric_name == "qem"            ? pmz::Metric::qem
                   : metric_name == "multifeature" ? pmz::Metric::multifeature
                                                   : pmz::Metric::guarded;

  std::string error;
  pmz::IndexedMesh mesh;
  if (!pmz::read_mesh(input, mesh, error)) {
    std::fprintf(stderr, "pmz-simplify: %s\n", error.c_str());
    return 1;
  }
  if (!mesh.attributes.empty())  // never a silent loss: the simplifier keeps geometry only so far
    std::fprintf(stderr,
                 "pmz-simplify: %s: attributes not kept yet (%s): the output holds positions "
                 "and triangles only\n",
                 input.c_str(), mesh.attributes.describe().c_str());
  const uint64_t in_faces = mesh.face_count();
  options.target_faces =
      faces_opt->count() ? faces
                         : std::max<uint64_t>(1, uint64_t(std::llround(ratio * double(in_faces))));
  pmz::SimplifyStats stats;
  options.stats = &stats;
  const bool tty = isatty(2);
  if (tty)
    options.progress = [](double f) {
      const int width = 40, filled = int(f * width);
      std::fprintf(stderr, "\r[%.*s%*s] %3d%%", filled,
                   "========================================", width - filled, "", int(f * 100));
    };
  const auto t0 = std::chrono::steady_clock::now();
  pmz::CollapseSequence seq;
  const bool ok = pmz::simplify(mesh, options, seq, error);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (tty) std::fputs("\r\033[K", stderr);
  if (!ok) {
    std::fprintf(stderr, "pmz-simplify: %s: %s\n", input.c_str(), error.c_str());
    return 1;
  }
  pmz::IndexedMesh result = pmz::mesh_after(seq, seq.collapses.size());
  if (!pmz::write_mesh(output, result, error)) {
    std::fprintf(stderr, "pmz-simplify: %s\n", error.c_str());
    return 1;
  }
  std::printf("%s: %llu -> %llu faces (target %llu%s), %s metric, %.3f s\n", input.c_str(),
              (unsigned long long)in_faces, (unsigned long long)result.face_count(),
              (unsigned long long)options.target_faces,
              result.face_count() == options.target_faces ? "" : "; no legal collapse gets closer",
              metric_name.c_str(), seconds);
  if (verbose)
    std::printf(
        "time: setup %.3f, initial costs %.3f, collapse+checks %.3f, update terms %.3f, update "
        "costs %.3f; "
        "%llu cost evaluations, %llu legality checks, %llu guard bounds, %llu held back\n",
        stats.setup, stats.initial_costs, stats.collapse, stats.update_terms, stats.update_costs,
        (unsigned long long)stats.cost_evaluations, (unsigned long long)stats.legality_checks,
        (unsigned long long)stats.guard_checks, (unsigned long long)stats.guard_deferrals);
  return 0;
}
