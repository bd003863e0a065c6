// SPDX-License-Identifier: MIT
#include "pmz/cluster_plan.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <queue>
#include <tuple>
#include <unordered_map>

#include "pmz/format.hpp"

namespace pmz {
namespace {

// Cell index of coordinate c on one axis of a grid (floor division).
int64_t cell_index(int64_t c, int64_t origin, int64_t side) {
  const int64_t d = c - origin;
  return d >= 0 ? d / side : -((-d + side - 1) / side);
}

struct CellKey {
  uint32_t level;
  int64_t i[3];
  bool operator<(const CellKey& o) const {
    return std::tie(level, i[0], i[1], i[2]) < std::tie(o.level, o.i[0], o.i[1], o.i[2]);
  }
};

}  // namespace

ClusterPlan plan_clusters(const CollapseSequence& seq, uint32_t position_bits) {
  ClusterPlan plan;
  const IndexedMesh& mesh = seq.mesh;
  const uint32_t n = mesh.vertex_count();
  float lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = INFINITY, hi[a] = -INFINITY;
  for (uint32_t v = 0; v < n; ++v)
    for (int a = 0; a < 3; ++a)
      lo[a] = std::min(lo[a], mesh.positions[size_t(v) * 3 + a]),
      hi[a] = std::max(hi[a], mesh.positions[size_t(v) * 3 + a]);
  Quantizer quant;
  quant.init(position_bits, lo, hi);
  auto coord = [&](uint32_t v, int a) {
    return quant.quantize(mesh.positions[size_t(v) * 3 + a], a);
  };

  // Group the collapses by (level, cell); a sequence without levels is one node.
  std::vector<CollapseSequence::Level> levels = seq.levels;
  if (levels.empty()) levels.push_back({CellGrid{}, 0});
  std::map<CellKey, std::vector<uint64_t>> groups;
  for (uint32_t l = 0; l < levels.size(); ++l) {
    const uint64_t end =
        l + 1 < levels.size() ? levels[l + 1].first_collapse : seq.collapses.size();
    const CellGrid& g = levels[l].grid;
    for (uint64_t i = levels[l].first_collapse; i < end; ++i) {
      CellKey key{l, {0, 0, 0}};
      if (g.side > 0)
        for (int a = 0; a < 3; ++a)
          key.i[a] = cell_index(coord(seq.collapses[i].u, a), g.origin[a], g.side);
      groups[key].push_back(i);
    }
  }
  // Nodes: levels from the last (coarsest) down, within a level the larger max_cost first.
  std::vector<std::pair<CellKey, const std::vector<uint64_t>*>> order;
  for (const auto& [key, list] : groups) order.push_back({key, &list});
  auto max_cost = [&](const std::vector<uint64_t>& list) {
    float m = 0;
    for (uint64_t i : list) m = std::max(m, seq.collapses[i].cost);
    return m;
  };
  std::stable_sort(order.begin(), order.end(), [&](const auto& a, const auto& b) {
    if (a.first.level != b.first.level) return a.first.level > b.first.level;
    return max_cost(*a.second) > max_cost(*b.second);
  });
  std::map<CellKey, uint32_t> node_of;
  for (const auto& [key, list] : order) {
    ClusterNode node;
    node.level = key.level;
    for (int a = 0; a < 3; ++a) node.cell[a] = key.i[a];
    node.first = plan.collapses.size();
    node.count = list->size();
    node.max_cost = max_cost(*list);
    plan.collapses.insert(plan.collapses.end(), list->begin(), list->end());
    // The sphere: centre of the box of u and v of its collapses, radius to its farthest corner.
    float blo[3] = {INFINITY, INFINITY, INFINITY}, bhi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t i : *list)
      for (uint32_t x : {seq.collapses[i].u, seq.collapses[i].v})
        for (int a = 0; a < 3; ++a)
          blo[a] = std::min(blo[a], mesh.positions[size_t(x) * 3 + a]),
          bhi[a] = std::max(bhi[a], mesh.positions[size_t(x) * 3 + a]);
    double r2 = 0;
    for (int a = 0; a < 3; ++a) {
      node.center[a] = 0.5f * (blo[a] + bhi[a]);
      r2 += 0.25 * double(bhi[a] - blo[a]) * double(bhi[a] - blo[a]);
    }
    node.radius = float(std::sqrt(r2));
    // Parents: at each coarser level, the at most two cells per axis that overlap this cell.
    const CellGrid& g = levels[key.level].grid;
    for (uint32_t m = key.level + 1; m < levels.size(); ++m) {
      const CellGrid& h = levels[m].grid;
      int64_t j0[3] = {0, 0, 0}, j1[3] = {0, 0, 0};
      if (h.side > 0)
        for (int a = 0; a < 3; ++a) {
          const int64_t c0 = g.origin[a] + key.i[a] * g.side, c1 = c0 + g.side - 1;
          j0[a] = cell_index(c0, h.origin[a], h.side);
          j1[a] = cell_index(c1, h.origin[a], h.side);
        }
      for (int64_t x = j0[0]; x <= j1[0]; ++x)
        for (int64_t y = j0[1]; y <= j1[1]; ++y)
          for (int64_t z = j0[2]; z <= j1[2]; ++z)
            if (auto it = node_of.find(CellKey{m, {x, y, z}}); it != node_of.end())
              node.parents.push_back(it->second);
    }
    node_of[key] = uint32_t(plan.nodes.size());
    plan.nodes.push_back(std::move(node));
  }
  return plan;
}

CollapseSequence node_ordered(const CollapseSequence& seq, const ClusterPlan& plan) {
  CollapseSequence out;
  out.mesh = seq.mesh;
  out.base_indices = seq.base_indices;
  out.collapses.reserve(seq.collapses.size());
  for (size_t k = plan.nodes.size(); k-- > 0;) {
    const ClusterNode& node = plan.nodes[k];
    for (uint64_t i = 0; i < node.count; ++i)
      out.collapses.push_back(seq.collapses[plan.collapses[node.first + i]]);
  }
  return out;
}

ClusterSchedule schedule_clusters(const ClusterPlan& plan, uint32_t workers) {
  ClusterSchedule s;
  const size_t n = plan.nodes.size();
  std::vector<uint64_t> path(n, 0), done(n, 0);
  for (size_t k = 0; k < n; ++k) {
    const ClusterNode& node = plan.nodes[k];
    uint64_t before = 0;
    for (uint32_t p : node.parents) before = std::max(before, path[p]);
    path[k] = before + node.count;
    s.total += node.count;
    s.critical_path = std::max(s.critical_path, path[k]);
  }
  // Greedy list scheduling: each worker takes the first node (plan order) whose parents are
  // done by the time the worker is free.
  std::priority_queue<uint64_t, std::vector<uint64_t>, std::greater<>> free_at;
  for (uint32_t w = 0; w < std::max(1u, workers); ++w) free_at.push(0);
  for (size_t k = 0; k < n; ++k) {  // plan order is a valid topological order
    const uint64_t t = free_at.top();
    free_at.pop();
    uint64_t ready = 0;
    for (uint32_t p : plan.nodes[k].parents) ready = std::max(ready, done[p]);
    done[k] = std::max(t, ready) + plan.nodes[k].count;
    free_at.push(done[k]);
    s.makespan = std::max(s.makespan, done[k]);
  }
  return s;
}

}  // namespace pmz
