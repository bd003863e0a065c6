// SPDX-License-Identifier: MIT
#include "pmz/node_table.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <optional>
#include <tuple>

#include "pmz/coding.hpp"
#include "pmz/format.hpp"

namespace pmz {

namespace {

uint64_t zigzag64(int64_t v) { return (uint64_t(v) << 1) ^ uint64_t(v >> 63); }
int64_t unzigzag64(uint64_t v) { return int64_t(v >> 1) ^ -int64_t(v & 1); }

// Sides and origins beyond what 32-bit coordinates need are refused (no overflow below).
constexpr int64_t kMaxSide = int64_t(1) << 32, kMaxOrigin = int64_t(1) << 32;

// The cells of `coarse` that the cell `cell` of `fine` overlaps, per axis [lo, hi].
void overlap(const NodeGrid& fine, const int64_t cell[3], const NodeGrid& coarse, int64_t lo[3],
             int64_t hi[3]) {
  for (int a = 0; a < 3; ++a) {
    if (coarse.side == 0) {
      lo[a] = hi[a] = 0;
      continue;
    }
    // The fine cell's coordinates, clamped to 32 bits (no vertex lies outside them).
    const int64_t start = fine.origin[a] + cell[a] * fine.side;
    const int64_t c0 = std::max<int64_t>(start, INT32_MIN);
    const int64_t c1 = std::min<int64_t>(start + fine.side - 1, INT32_MAX);
    lo[a] = coarse.index(int32_t(c0), a);
    hi[a] = coarse.index(int32_t(std::max(c0, c1)), a);
  }
}

}  // namespace

void write_node_table(std::vector<uint8_t>& out, const NodeTable& t) {
  put_varint(out, t.levels.size());
  for (const NodeGrid& g : t.levels) {
    put_varint(out, uint64_t(g.side));
    for (int a = 0; a < 3; ++a) put_varint(out, zigzag64(g.origin[a]));
  }
  put_varint(out, t.nodes.size());
  for (const NodeEntry& n : t.nodes) {
    put_varint(out, n.level);
    if (t.levels[n.level].side > 0)
      for (int a = 0; a < 3; ++a) put_varint(out, zigzag64(n.cell[a]));
    put_varint(out, n.splits);
    put_varint(out, n.faces);
    if (t.attributes) put_varint(out, n.wedges);
    put_varint(out, n.bytes);
    for (int a = 0; a < 3; ++a) put_f32le(out, n.center[a]);
    put_f32le(out, n.radius);
    put_f32le(out, n.error);
  }
  if (t.cones)
    for (const NodeEntry& n : t.nodes) {
      for (int a = 0; a < 3; ++a) out.push_back(uint8_t(n.cone_axis[a]));
      out.push_back(n.cone_cutoff);
    }
}

bool read_node_table(const uint8_t* p, size_t size, uint64_t total_splits, uint64_t max_nodes,
                     bool attributes, bool cones, NodeTable& t, std::string& error) {
  ByteReader r(p, size);
  t = {};
  t.attributes = attributes;
  t.cones = cones;
  const uint64_t level_count = r.varint();
  if (!r.ok || level_count == 0 || level_count > kMaxNodeLevels)
    return error = "NODE: level count not in 1..32", false;
  for (uint64_t l = 0; l < level_count; ++l) {
    NodeGrid g;
    const uint64_t side = r.varint();
    for (int a = 0; a < 3; ++a) g.origin[a] = unzigzag64(r.varint());
    if (!r.ok) return error = "NODE: table ends early", false;
    if (side > uint64_t(kMaxSide)) return error = "NODE: cell side beyond 2^32", false;
    g.side = int64_t(side);
    for (int a = 0; a < 3; ++a)
      if (g.origin[a] > kMaxOrigin || g.origin[a] < -kMaxOrigin)
        return error = "NODE: grid origin beyond 2^32", false;
    if (g.side == 0 && l + 1 != level_count)
      return error = "NODE: a level other than the last without cells", false;
    if (l > 0 && g.side != 0 && g.side < t.levels.back().side)
      return error = "NODE: a level's cells smaller than the level before", false;
    t.levels.push_back(g);
  }
  const uint64_t node_count = r.varint();
  if (!r.ok || node_count == 0) return error = "NODE: no nodes", false;
  if (node_count > max_nodes || node_count > total_splits)
    return error = "NODE: more nodes than splits or than the limit allows", false;
  uint64_t splits = 0;
  t.nodes.reserve(size_t(std::min<uint64_t>(node_count, r.remaining() / 16 + 1)));
  for (uint64_t k = 0; k < node_count; ++k) {
    NodeEntry n;
    const uint64_t level = r.varint();
    if (!r.ok || level >= level_count) return error = "NODE: node level out of range", false;
    n.level = uint32_t(level);
    const NodeGrid& g = t.levels[n.level];
    if (g.side > 0)
      for (int a = 0; a < 3; ++a) {
        n.cell[a] = unzigzag64(r.varint());
        if (n.cell[a] < g.index(INT32_MIN, a) || n.cell[a] > g.index(INT32_MAX, a))
          return error = "NODE: a cell outside the coordinate range", false;
      }
    n.splits = r.varint();
    n.faces = r.varint();
    if (attributes) n.wedges = r.varint();
    n.bytes = r.varint();
    for (int a = 0; a < 3; ++a) n.center[a] = r.f32le();
    n.radius = r.f32le();
    n.error = r.f32le();
    if (!r.ok) return error = "NODE: table ends early", false;
    if (n.splits == 0 || n.splits > total_splits - splits)
      return error = "NODE: node split counts exceed HEAD's total", false;
    splits += n.splits;
    if (n.faces > 2 * n.splits) return error = "NODE: more faces than two per split", false;
    if (n.bytes == 0) return error = "NODE: a node without bytes", false;
    bool finite = std::isfinite(n.radius) && std::isfinite(n.error);
    for (int a = 0; a < 3; ++a) finite = finite && std::isfinite(n.center[a]);
    if (!finite || !(n.radius >= 0) || !(n.error >= 0))
      return error = "NODE: a bounding sphere or error bound not finite and non-negative", false;
    t.nodes.push_back(n);
  }
  if (splits != total_splits) return error = "NODE: node split counts short of HEAD's total", false;
  if (cones) {
    if (r.remaining() < t.nodes.size() * 4) return error = "NODE: the cones end early", false;
    for (NodeEntry& n : t.nodes) {
      for (int a = 0; a < 3; ++a) n.cone_axis[a] = int8_t(r.u8());
      n.cone_cutoff = r.u8();
    }
  }
  // Every node once per cell, after every node of a coarser level that overlaps it.
  const NodeIndex index(t);
  for (uint32_t k = 0; k < t.nodes.size(); ++k) {
    if (index.find(t.nodes[k].level, t.nodes[k].cell) != k)
      return error = "NODE: a cell holds two nodes", false;
    const std::vector<uint32_t> parents = index.parents(k);
    if (!parents.empty() && parents.back() > k)
      return error = "NODE: a node before one of its parents", false;
  }
  return true;
}

bool NodeIndex::less(const Key& a, const Key& b) {
  return std::tie(a.level, a.cell[0], a.cell[1], a.cell[2], a.node) <
         std::tie(b.level, b.cell[0], b.cell[1], b.cell[2], b.node);
}

NodeIndex::NodeIndex(const NodeTable& t) : t_(t) {
  sorted_.reserve(t.nodes.size());
  for (uint32_t k = 0; k < t.nodes.size(); ++k) {
    const NodeEntry& n = t.nodes[k];
    sorted_.push_back({n.level, {n.cell[0], n.cell[1], n.cell[2]}, k});
  }
  std::sort(sorted_.begin(), sorted_.end(), less);
}

int64_t NodeIndex::find(uint32_t level, const int64_t cell[3]) const {
  const Key want{level, {cell[0], cell[1], cell[2]}, 0};
  auto it = std::lower_bound(sorted_.begin(), sorted_.end(), want, less);
  if (it == sorted_.end() || it->level != level || it->cell[0] != cell[0] ||
      it->cell[1] != cell[1] || it->cell[2] != cell[2])
    return -1;
  return it->node;
}

std::vector<uint32_t> NodeIndex::parents(uint32_t k) const {
  std::vector<uint32_t> out;
  const NodeEntry& n = t_.nodes[k];
  for (uint32_t m = n.level + 1; m < t_.levels.size(); ++m) {
    int64_t lo[3], hi[3];
    overlap(t_.levels[n.level], n.cell, t_.levels[m], lo, hi);
    for (int64_t x = lo[0]; x <= hi[0]; ++x)
      for (int64_t y = lo[1]; y <= hi[1]; ++y)
        for (int64_t z = lo[2]; z <= hi[2]; ++z) {
          const int64_t c[3] = {x, y, z};
          if (const int64_t p = find(m, c); p >= 0) out.push_back(uint32_t(p));
        }
  }
  std::sort(out.begin(), out.end());
  return out;
}

void CellBins::build(const NodeTable& t, uint32_t level, const int32_t* coords, uint32_t count) {
  const NodeGrid& g = t.levels[level];
  bins_.assign(t.nodes.size(), {});
  // The level's nodes by cell in a dense array over the box of their cells: every vertex is looked
  // up once per level, and a search of the whole table per vertex was most of what decoding in
  // nodes cost beyond one node. A box too large for its nodes (cells far apart: a table a writer
  // would not make) is searched instead.
  int64_t lo[3] = {INT64_MAX, INT64_MAX, INT64_MAX}, hi[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
  uint64_t level_nodes = 0;
  for (const NodeEntry& n : t.nodes)
    if (n.level == level) {
      ++level_nodes;
      for (int a = 0; a < 3; ++a)
        lo[a] = std::min(lo[a], n.cell[a]), hi[a] = std::max(hi[a], n.cell[a]);
    }
  if (level_nodes == 0) return;
  const uint64_t limit = std::max<uint64_t>(uint64_t(1) << 20, 64 * level_nodes);
  uint64_t dim[3], cells = 1;
  for (int a = 0; a < 3; ++a) {
    dim[a] = uint64_t(hi[a] - lo[a]) + 1;  // (cells lie within +-2^32: read_node_table)
    cells = dim[a] > limit || cells > limit / dim[a] ? limit + 1 : cells * dim[a];  // (no wrap)
  }
  const bool dense = cells <= limit;
  constexpr uint32_t kNone = UINT32_MAX;
  std::vector<uint32_t> node_of(dense ? cells : 0, kNone);
  auto at = [&](const int64_t cell[3]) {
    return (uint64_t(cell[2] - lo[2]) * dim[1] + uint64_t(cell[1] - lo[1])) * dim[0] +
           uint64_t(cell[0] - lo[0]);
  };
  for (uint32_t k = 0; dense && k < t.nodes.size(); ++k)
    if (t.nodes[k].level == level) node_of[at(t.nodes[k].cell)] = k;
  std::optional<NodeIndex> index;
  if (!dense) index.emplace(t);
  for (uint32_t v = 0; v < count; ++v) {
    int64_t cell[3] = {0, 0, 0};
    bool inside = true;
    if (g.side)
      for (int a = 0; a < 3; ++a) {
        cell[a] = g.index(coords[size_t(v) * 3 + a], a);
        inside = inside && cell[a] >= lo[a] && cell[a] <= hi[a];
      }
    const int64_t k = !dense ? index->find(level, cell) : inside ? int64_t(node_of[at(cell)]) : -1;
    if (k >= 0 && k != kNone) bins_[size_t(k)].push_back(v);
  }
}

std::vector<uint32_t> CellBins::take(uint32_t node) { return std::move(bins_[node]); }

}  // namespace pmz
