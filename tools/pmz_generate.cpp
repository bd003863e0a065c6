// SPDX-License-Identifier: MIT
// pmz-generate: a procedural terrain of any size as a binary PLY (samples/include/pmz/terrain.hpp),
// written while it is made: tests and benchmarks of large meshes need no download.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#include "pmz/app_support.hpp"
#include "pmz/terrain.hpp"

namespace app_support = pmz::app_support;

int main(int argc, char** argv) {
  app_support::init("pmz-generate");
  CLI::App app{
      "pmz-generate: write a procedural terrain (fractal relief, ridges, terraces, a valley) "
      "as a binary PLY; the same size and seed give the same bytes",
      "pmz-generate"};
  std::string output;
  pmz::TerrainOptions options;
  bool quiet = false, force_progress = false;
  app.add_option("-o,--output", output, "output .ply (- for stdout)")->required();
  app.add_option("--faces", options.faces,
                 "about this many faces (exactly 2 (n - 1)^2 for the grid side n)")
      ->capture_default_str();
  app.add_option("--seed", options.seed, "seed of the relief")->capture_default_str();
  app_support::add_progress_options(app, quiet, force_progress);
  app_support::set_footer(app);
  if (int rc = app_support::parse(app, argc, argv); rc >= 0) return rc;
  if (options.faces < 2) return app_support::usage_error("--faces must be at least 2");
  if (output != "-" && app_support::extension(output) != "ply")
    return app_support::usage_error("the output is a PLY file: give a name ending in .ply");

  app_support::Progress progress(quiet, force_progress);
  options.progress = [&](double f) { progress.update("writing", f); };
  app_support::OutputFile out;
  std::string error;
  if (!out.open(output, true, error)) {
    app_support::print_error(error);
    return app_support::kExitFailure;
  }
  const bool written =
      pmz::write_terrain_ply(options, [&](const void* p, size_t n) { return out.write(p, n); });
  progress.clear();
  if (!written || !out.commit(error)) {
    if (error.empty()) error = output + ": cannot write";
    app_support::print_error(error);
    return app_support::kExitFailure;
  }
  const uint32_t side = pmz::terrain_grid_side(options.faces);
  std::fprintf(output == "-" ? stderr : stdout, "pmz-generate: %s: %llu faces, %llu vertices\n",
               output.c_str(), 2ull * (side - 1) * (side - 1), 1ull * side * side);
  return app_support::kExitOk;
}
