// SPDX-License-Identifier: MIT
// bench-metric-sweep [--eps E] [--c0 C] [--wt W] [--mem M] [--bw B] [--ratio R]... MESH...
// The parameter search of docs/design.md section 2, in process: for each mesh and face ratio
// (default 0.1 and 0.02), simplify to round(R * F) faces with multifeature (the given
// parameters, defaults otherwise) and with qem, then pmz::compare each result with the input
// (default samples). Prints one line per mesh and ratio (mean and max symmetric error / bbox
// diagonal, x1e-4) and the median multifeature / qem ratio of the means per ratio; a mesh that
// both metrics simplify exactly (mean below 1e-10 of the diagonal) counts 1. For the first
// metric also: the two one-sided maxima, where the max is, the max over the input vertices
// alone and the guard's final bound (docs/design.md section 2).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "pmz/compare.hpp"
#include "pmz/mesh.hpp"
#include "pmz/simplify.hpp"

namespace {

const char* kTool = "bench-metric-sweep";

double parse_number(const char* text) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (!end || *end || text[0] == 0) {
    std::fprintf(stderr, "%s: not a number: '%s'\n", kTool, text);
    std::exit(2);
  }
  return v;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n == 0 ? 0 : n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  pmz::MetricParams params;
  pmz::Metric first = pmz::Metric::guarded;
  bool with_qem = true;
  std::vector<double> ratios;
  std::vector<std::string> meshes;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--eps" && has_value)
      params.epsilon = float(parse_number(argv[++i]));
    else if (a == "--c0" && has_value)
      params.quadric_floor = float(parse_number(argv[++i]));
    else if (a == "--wt" && has_value)
      params.torsion_weight = float(parse_number(argv[++i]));
    else if (a == "--mem" && has_value)
      params.quadric_memory = float(parse_number(argv[++i]));
    else if (a == "--bw" && has_value)
      params.boundary_weight = float(parse_number(argv[++i]));
    else if (a == "--no-qem")
      with_qem = false;
    else if (a == "--slack" && has_value)
      params.guard_slack = float(parse_number(argv[++i]));
    else if (a == "--metric" && has_value) {
      const std::string name = argv[++i];
      if (name != "guarded" && name != "multifeature")
        return std::fprintf(stderr, "%s: --metric guarded|multifeature\n", kTool), 2;
      first = name == "guarded" ? pmz::Metric::guarded : pmz::Metric::multifeature;
    } else if (a == "--ratio" && has_value)
      ratios.push_back(parse_number(argv[++i]));
    else if (!a.empty() && a[0] == '-') {
      std::fprintf(stderr,
                   "usage: %s [--metric guarded|multifeature] [--eps E] [--c0 C] [--wt W] [--mem "
                   "M] [--bw B] "
                   "[--slack S] [--no-qem] [--ratio R]... MESH...\n",
                   kTool);
      return 2;
    } else
      meshes.push_back(a);
  }
  if (ratios.empty()) ratios = {0.1, 0.02};
  std::vector<std::vector<double>> ratio_of(ratios.size());
  for (const std::string& path : meshes) {
    pmz::IndexedMesh mesh;
    pmz::MeshRepairStats repairs;
    std::string error;
    if (!pmz::read_mesh(path, mesh, repairs, error))
      return std::fprintf(stderr, "%s: %s\n", kTool, error.c_str()), 1;
    std::string name = path.substr(path.find_last_of('/') + 1);
    name = name.substr(0, name.find_last_of('.'));
    for (size_t r = 0; r < ratios.size(); ++r) {
      double mean[2], max[2], forward_max = 0, backward_max = 0;
      pmz::DistanceStats worst;
      double vertex_max = 0, bound = 0;  // guarded / multifeature: the direction holding the max
      uint64_t faces[2];
      mean[1] = max[1] = 0, faces[1] = 0;
      for (int k = 0; k < (with_qem ? 2 : 1); ++k) {
        pmz::SimplifyOptions options;
        options.metric = k == 0 ? first : pmz::Metric::qem;
        options.params = params;
        options.target_faces =
            std::max<uint64_t>(4, uint64_t(std::llround(ratios[r] * mesh.face_count())));
        pmz::SimplifyStats stats;
        options.stats = &stats;
        pmz::CollapseSequence seq;
        if (!pmz::simplify(mesh, options, seq, error))
          return std::fprintf(stderr, "%s: %s: %s\n", kTool, path.c_str(), error.c_str()), 1;
        const pmz::IndexedMesh out = pmz::mesh_after(seq, seq.collapses.size());
        pmz::CompareResult cmp;
        if (!pmz::compare(mesh, out, {}, cmp, error))
          return std::fprintf(stderr, "%s: %s\n", kTool, error.c_str()), 1;
        mean[k] = cmp.symmetric.mean / cmp.diag;
        max[k] = cmp.symmetric.max / cmp.diag;
        faces[k] = out.face_count();
        if (k == 0) {
          forward_max = cmp.forward.max / cmp.diag, backward_max = cmp.backward.max / cmp.diag,
          worst = cmp.symmetric;
          pmz::CompareOptions vertices_only;  // one face sample, no edge samples
          vertices_only.samples = 1, vertices_only.both_directions = false;
          pmz::CompareResult at_vertices;
          pmz::compare(mesh, out, vertices_only, at_vertices, error);
          vertex_max = at_vertices.forward.max / cmp.diag;
          bound = stats.guard_worst_bound / cmp.diag;
        }
      }
      const bool both_exact = mean[0] < 1e-10 && mean[1] < 1e-10;
      const double q = both_exact ? 1.0 : mean[1] > 0 ? mean[0] / mean[1] : INFINITY;
      ratio_of[r].push_back(q);
      std::printf(
          "%-20s %5.3f  mf %10.5f max %9.4f (%llu faces)  qem %10.5f max %9.4f (%llu faces)  "
          "mf/qem %.3f  (mf max: input to output %.4f, output to input %.4f, at %.6g %.6g %.6g "
          "%s; input vertices %.4f, guard bound %.4f)\n",
          name.c_str(), ratios[r], mean[0] * 1e4, max[0] * 1e4, (unsigned long long)faces[0],
          mean[1] * 1e4, max[1] * 1e4, (unsigned long long)faces[1], q, forward_max * 1e4,
          backward_max * 1e4, worst.max_at[0], worst.max_at[1], worst.max_at[2],
          worst.max_on == pmz::DistanceStats::Site::vertex ? "vertex"
          : worst.max_on == pmz::DistanceStats::Site::edge ? "edge"
                                                           : "face",
          vertex_max * 1e4, bound * 1e4);
      std::fflush(stdout);
    }
  }
  for (size_t r = 0; r < ratios.size(); ++r)
    std::printf("ratio %.3f: median mf/qem %.3f over %zu meshes\n", ratios[r], median(ratio_of[r]),
                ratio_of[r].size());
  return 0;
}
