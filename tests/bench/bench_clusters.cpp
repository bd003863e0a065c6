// SPDX-License-Identifier: MIT
// bench-clusters: the node graph of a hierarchical simplification and what it would give a
// decoder: per level the nodes and splits; the critical path (the longest chain of splits that
// depend on each other) and a greedy schedule's time on 1, 2, 4 and 8 workers, in splits;
// and, written with the current writer, the size of the stream in the engine's collapse order
// and node by node (NAME.levels.pmz, NAME.nodes.pmz beside --out).
// Usage: bench-clusters MESH --cluster-vertices N [--position-bits B] [--out PREFIX]
// Output: one JSON object.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "pmz/cluster_plan.hpp"
#include "pmz/mesh.hpp"
#include "pmz/simplify.hpp"
#include "pmz/writer.hpp"

namespace {

bool write_file(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  return bool(f);
}

}  // namespace

int main(int argc, char** argv) {
  std::string input, out;
  uint32_t cell_vertices = 0, bits = 14;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--cluster-vertices" && i + 1 < argc)
      cell_vertices = uint32_t(std::strtoul(argv[++i], nullptr, 10));
    else if (a == "--position-bits" && i + 1 < argc)
      bits = uint32_t(std::strtoul(argv[++i], nullptr, 10));
    else if (a == "--out" && i + 1 < argc)
      out = argv[++i];
    else
      input = a;
  }
  if (input.empty() || cell_vertices == 0) {
    std::fprintf(stderr,
                 "usage: bench-clusters MESH --cluster-vertices N [--position-bits B] "
                 "[--out PREFIX]\n");
    return 2;
  }
  pmz::IndexedMesh mesh;
  std::string error;
  if (!pmz::read_mesh(input, mesh, error)) {
    std::fprintf(stderr, "bench-clusters: %s: %s\n", input.c_str(), error.c_str());
    return 1;
  }
  pmz::SimplifyOptions options;
  options.clusters.vertices = cell_vertices;
  options.clusters.position_bits = bits;
  pmz::CollapseSequence seq;
  if (!pmz::simplify(mesh, options, seq, error)) {
    std::fprintf(stderr, "bench-clusters: %s: %s\n", input.c_str(), error.c_str());
    return 1;
  }
  const pmz::ClusterPlan plan = pmz::plan_clusters(seq, bits);
  std::map<uint32_t, std::pair<uint64_t, uint64_t>> per_level;  // nodes, splits
  uint64_t parents = 0;
  for (const pmz::ClusterNode& n : plan.nodes) {
    ++per_level[n.level].first;
    per_level[n.level].second += n.count;
    parents += n.parents.size();
  }
  std::printf(
      "{\"mesh\": \"%s\", \"faces\": %u, \"cluster_vertices\": %u, \"levels\": %zu, "
      "\"nodes\": %zu, \"parents_per_node\": %.2f, \"per_level\": [",
      input.c_str(), mesh.face_count(), cell_vertices, seq.levels.size(), plan.nodes.size(),
      plan.nodes.empty() ? 0.0 : double(parents) / plan.nodes.size());
  bool first = true;
  for (auto it = per_level.rbegin(); it != per_level.rend(); ++it) {
    std::printf("%s[%u, %llu, %llu]", first ? "" : ", ", it->first,
                (unsigned long long)it->second.first, (unsigned long long)it->second.second);
    first = false;
  }
  std::printf("], \"schedule\": {");
  for (uint32_t w : {1u, 2u, 4u, 8u}) {
    const pmz::ClusterSchedule s = pmz::schedule_clusters(plan, w);
    if (w == 1)
      std::printf("\"splits\": %llu, \"critical_path\": %llu", (unsigned long long)s.total,
                  (unsigned long long)s.critical_path);
    std::printf(", \"speedup_%u\": %.3f", w, s.makespan ? double(s.total) / s.makespan : 0.0);
  }
  std::printf("}");
  if (!out.empty()) {
    pmz::WriteOptions w;
    w.position_bits = bits;
    std::vector<uint8_t> bytes;
    if (!pmz::write_pmz(seq, w, bytes, error)) {
      std::fprintf(stderr, "bench-clusters: %s\n", error.c_str());
      return 1;
    }
    write_file(out + ".levels.pmz", bytes);
    std::printf(", \"bytes_levels\": %zu", bytes.size());
    const pmz::CollapseSequence ordered = pmz::node_ordered(seq, plan);
    if (!pmz::write_pmz(ordered, w, bytes, error)) {
      std::fprintf(stderr, "bench-clusters: node order: %s\n", error.c_str());
      return 1;
    }
    write_file(out + ".nodes.pmz", bytes);
    std::printf(", \"bytes_nodes\": %zu", bytes.size());
  }
  std::printf("}\n");
  return 0;
}
