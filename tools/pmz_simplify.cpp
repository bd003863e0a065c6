// SPDX-License-Identifier: MIT
// pmz-simplify: simplify a mesh to a face count or ratio with the multi-feature metric (or
// plain QEM) and write it in any format meshio writes (pmz/mesh_file_formats.hpp).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "pmz/app_support.hpp"
#include "pmz/mesh.hpp"
#include "pmz/simplify.hpp"
#include "tool_mesh.hpp"
#include "tool_simplify.hpp"

namespace app_support = pmz::app_support;
namespace tool = pmz::tool;

int main(int argc, char** argv) {
  app_support::init("pmz-simplify");
  CLI::App app{
      "pmz-simplify: simplify a triangle mesh by half-edge collapses (multi-feature metric or "
      "QEM)",
      "pmz-simplify"};
  std::string input, output, format;
  double ratio = -1;
  uint64_t faces = 0;
  bool verbose = false, quiet = false, force_progress = false;
  tool::SimplifierCli simplifier;
  app.add_option("input", input, tool::mesh_files_help("input mesh", false, "- for stdin"))
      ->required();
  app.add_option("-o,--output", output,
                 tool::mesh_files_help("output mesh", true,
                                       "- for stdout; .off and .stl hold no attributes"))
      ->required();
  tool::add_format_option(app, format, true, true,
                          "format of stdin, and of an output without a mesh extension (stdout, "
                          "devices)");
  auto* ratio_opt =
      app.add_option("--ratio", ratio, "target face count as a fraction of the input's (0..1]");
  auto* faces_opt = app.add_option("--faces", faces, "target face count");
  ratio_opt->excludes(faces_opt);
  simplifier.add_to(app);
  app.add_flag("-v,--verbose", verbose, "print where the time went");
  app_support::add_progress_options(app, quiet, force_progress);
  app_support::set_footer(app);
  if (int rc = app_support::parse(app, argc, argv); rc >= 0) return rc;
  auto usage = app_support::usage_error;
  if (ratio_opt->count() == 0 && faces_opt->count() == 0)
    return usage("give --ratio R or --faces N");
  if (ratio_opt->count() && !(ratio > 0 && ratio <= 1)) return usage("--ratio must be in (0, 1]");
  if (faces_opt->count() && faces == 0) return usage("--faces must be at least 1");
  if (const std::string problem = tool::stdin_input_problem({input}, format); !problem.empty())
    return usage(problem);
  std::string problem;
  const std::string output_format = app_support::mesh_output_format(output, format, problem);
  if (output_format.empty()) return usage(problem);
  if (app_support::same_file(input, output)) {
    app_support::print_error(output, "is the input file; not overwriting it");
    return app_support::kExitFailure;
  }
  pmz::SimplifyOptions options;
  simplifier.apply(options);

  std::string error;
  pmz::IndexedMesh mesh;
  app_support::Progress progress(quiet, force_progress);
  if (!tool::read_mesh_input(input, format, mesh, error,
                             progress.enabled() ? &progress : nullptr)) {
    app_support::print_error(error);
    return app_support::kExitFailure;
  }
  tool::warn_if_attributes_lost(output, output_format, mesh);
  simplifier.apply_clusters(options, mesh.vertex_count());
  const uint64_t in_faces = mesh.face_count();
  options.target_faces =
      faces_opt->count() ? faces
                         : std::max<uint64_t>(1, uint64_t(std::llround(ratio * double(in_faces))));
  pmz::SimplifyStats stats;
  options.stats = &stats;
  if (progress.enabled()) options.progress = [&](double f) { progress.update("simplifying", f); };
  const auto t0 = std::chrono::steady_clock::now();
  pmz::CollapseSequence seq;
  const bool ok = pmz::simplify(mesh, options, seq, error);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.clear();
  if (!ok) {
    app_support::print_error(input == "-" ? "stdin" : input, error);
    return app_support::kExitFailure;
  }
  pmz::IndexedMesh result = pmz::mesh_after(seq, seq.collapses.size());
  if (!tool::write_mesh_output(output, output_format, result, error)) {
    app_support::print_error(error);
    return app_support::kExitFailure;
  }
  // With -o -, stdout carries the mesh: the summary goes to stderr.
  FILE* report = output == "-" ? stderr : stdout;
  std::fprintf(report, "%s: %llu -> %llu faces (target %llu%s), %s metric, %.3f s\n",
               input == "-" ? "stdin" : input.c_str(), (unsigned long long)in_faces,
               (unsigned long long)result.face_count(), (unsigned long long)options.target_faces,
               result.face_count() == options.target_faces ? "" : "; no legal collapse gets closer",
               simplifier.metric.c_str(), seconds);
  if (verbose)
    std::fprintf(
        report,
        "time: setup %.3f, initial costs %.3f, collapse+checks %.3f, update terms %.3f, update "
        "costs %.3f; %llu cost evaluations, %llu legality checks, %llu guard bounds, %llu held "
        "back\n",
        stats.setup, stats.initial_costs, stats.collapse, stats.update_terms, stats.update_costs,
        (unsigned long long)stats.cost_evaluations, (unsigned long long)stats.legality_checks,
        (unsigned long long)stats.guard_checks, (unsigned long long)stats.guard_deferrals);
  return app_support::kExitOk;
}
