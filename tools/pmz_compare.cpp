// SPDX-License-Identifier: MIT
// pmz-compare ORIGINAL OTHER [--format F] [--samples N] [--json] (either mesh may be - for
// stdin): Metro-style symmetric Hausdorff distance,
// where the maximum is, and the attribute error at corresponding surface points when both meshes
// have attributes.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#include "pmz/app_support.hpp"
#include "pmz/compare.hpp"
#include "pmz/mesh.hpp"
#include "tool_mesh.hpp"

namespace app_support = pmz::app_support;
namespace tool = pmz::tool;

namespace {

const char* site_name(pmz::DistanceStats::Site site) {
  switch (site) {
    case pmz::DistanceStats::Site::vertex:
      return "vertex";
    case pmz::DistanceStats::Site::edge:
      return "edge";
    case pmz::DistanceStats::Site::face:
      return "face";
  }
  return "?";
}

}  // namespace

int main(int argc, char** argv) {
  app_support::init("pmz-compare");
  CLI::App app{
      "pmz-compare: Metro-style surface distance between two meshes (both directions).\n"
      "Relative values are divided by the bounding-box diagonal of ORIGINAL.\n"
      "When both meshes carry texture coordinates, normals or colours, also their error at\n"
      "corresponding points: for samples on ORIGINAL, the closest point of OTHER, the values\n"
      "interpolated at both compared (texture coordinates: |delta uv| of set 0 in texture\n"
      "units; normals: angle in degrees; colours: |delta rgb(a)|, channels 0..1).\n"
      "Texture coordinates are compared on the sample's own chart: the smallest |delta uv|\n"
      "over the closest face of OTHER, the closest face of OTHER's part of the sample's chart\n"
      "(the OTHER chart lying mostly over it), and at both the faces across a texture seam at\n"
      "their corners; so a seam moved by quantization, or a sheet of another chart passing\n"
      "close by, is not read as the jump between charts.",
      "pmz-compare"};
  std::string original_path, other_path, format;
  pmz::CompareOptions options;
  bool json = false, one_sided = false;
  bool no_attributes = false;
  app.add_option("ORIGINAL", original_path,
                 tool::mesh_files_help("reference mesh", false, "- for stdin with --format"))
      ->required();
  app.add_option("OTHER", other_path, "mesh to measure against it (- for stdin with --format)")
      ->required();
  tool::add_format_option(app, format, true, false, "format of a mesh read from stdin");
  app.add_option(
      "--samples", options.samples,
      "face samples per direction (default: 10x the larger face count, within [200k, 2M])");
  app.add_option("--seed", options.seed, "sampling seed (fixed by default)");
  app.add_option("--threads", options.threads, "worker threads (result does not depend on it)")
      ->check(CLI::Range(1u, 256u));
  app.add_flag("--one-sided", one_sided, "only ORIGINAL -> OTHER");
  app.add_flag("--no-attributes", no_attributes, "skip the attribute error");
  app.add_flag("--json", json, "print one JSON object");
  app_support::set_footer(app);
  if (int rc = app_support::parse(app, argc, argv); rc >= 0) return rc;
  if (const std::string problem = tool::stdin_input_problem({original_path, other_path}, format);
      !problem.empty())
    return app_support::usage_error(problem);
  options.both_directions = !one_sided;
  options.attributes = !no_attributes;

  pmz::IndexedMesh original, other;
  std::string error;
  if (!tool::read_mesh_input(original_path, format, original, error) ||
      !tool::read_mesh_input(other_path, format, other, error)) {
    app_support::print_error(error);
    return app_support::kExitFailure;
  }
  pmz::CompareResult r;
  if (!pmz::compare(original, other, options, r, error)) {
    app_support::print_error(error);
    return app_support::kExitFailure;
  }
  const double inv = r.diag > 0 ? 1.0 / r.diag : 0.0;
  if (json) {
    auto stats = [&](const pmz::DistanceStats& s) {
      std::printf(
          "{\"max\": %.9g, \"mean\": %.9g, \"rms\": %.9g, \"max_abs\": %.9g, \"mean_abs\": %.9g, "
          "\"rms_abs\": %.9g, \"samples\": %llu, \"max_at\": [%.9g, %.9g, %.9g], "
          "\"max_on\": \"%s\"}",
          s.max * inv, s.mean * inv, s.rms * inv, s.max, s.mean, s.rms,
          (unsigned long long)s.samples, s.max_at[0], s.max_at[1], s.max_at[2],
          site_name(s.max_on));
    };
    const pmz::DistanceStats& s = r.symmetric;
    std::printf(
        "{\"max\": %.9g, \"mean\": %.9g, \"rms\": %.9g, \"diag\": %.9g, \"max_abs\": %.9g, "
        "\"mean_abs\": %.9g, \"rms_abs\": %.9g, \"faces_original\": %u, \"faces_other\": %u, "
        "\"seconds\": %.4f, \"forward\": ",
        s.max * inv, s.mean * inv, s.rms * inv, r.diag, s.max, s.mean, s.rms, original.face_count(),
        other.face_count(), r.seconds);
    stats(r.forward);
    std::printf(", \"backward\": ");
    stats(r.backward);
    const pmz::AttributeErrorStats* kinds[3] = {&r.attributes.texcoord, &r.attributes.normal,
                                                &r.attributes.color};
    const char* names[3] = {"texcoord", "normal_degrees", "color"};
    std::printf(", \"attributes\": {");
    const char* sep = "";
    for (int k = 0; k < 3; ++k) {
      if (kinds[k]->samples == 0) continue;
      std::printf("%s\"%s\": {\"max\": %.9g, \"mean\": %.9g, \"rms\": %.9g, \"samples\": %llu}",
                  sep, names[k], kinds[k]->max, kinds[k]->mean, kinds[k]->rms,
                  (unsigned long long)kinds[k]->samples);
      sep = ", ";
    }
    std::printf("}}\n");
    return 0;
  }
  std::printf("original: %s (%u faces)\nother:    %s (%u faces)\nbbox diagonal of original: %.9g\n",
              original_path == "-" ? "stdin" : original_path.c_str(), original.face_count(),
              other_path == "-" ? "stdin" : other_path.c_str(), other.face_count(), r.diag);
  std::printf("%-22s %14s %14s %14s %14s %14s %14s %10s\n", "direction", "max", "mean", "rms",
              "max_abs", "mean_abs", "rms_abs", "samples");
  auto row = [&](const char* name, const pmz::DistanceStats& s) {
    std::printf("%-22s %14.6e %14.6e %14.6e %14.6e %14.6e %14.6e %10llu\n", name, s.max * inv,
                s.mean * inv, s.rms * inv, s.max, s.mean, s.rms, (unsigned long long)s.samples);
  };
  row("original -> other", r.forward);
  if (options.both_directions) {
    row("other -> original", r.backward);
    row("symmetric", r.symmetric);
  }
  // Where the worst case is: the sample that found the max, on the mesh it was taken from.
  const pmz::DistanceStats& worst = r.symmetric;
  std::printf("max at: (%.9g, %.9g, %.9g), a %s sample of %s\n", worst.max_at[0], worst.max_at[1],
              worst.max_at[2], site_name(worst.max_on),
              options.both_directions && r.backward.max > r.forward.max ? "OTHER" : "ORIGINAL");
  const pmz::AttributeErrorStats* kinds[3] = {&r.attributes.texcoord, &r.attributes.normal,
                                              &r.attributes.color};
  const char* names[3] = {"texcoord (uv)", "normal (degrees)", "colour"};
  bool header = false;
  for (int k = 0; k < 3; ++k) {
    const pmz::AttributeErrorStats& s = *kinds[k];
    if (s.samples == 0) continue;
    if (!header)
      std::printf(
          "attribute error at corresponding points (original -> other):\n%-22s %14s %14s %14s "
          "%10s\n",
          "attribute", "max", "mean", "rms", "samples"),
          header = true;
    std::printf("%-22s %14.6e %14.6e %14.6e %10llu\n", names[k], s.max, s.mean, s.rms,
                (unsigned long long)s.samples);
  }
  std::printf("time: %.3f s\n", r.seconds);
  return 0;
}
