// SPDX-License-Identifier: MIT
// Builds the engine's half-edge arrays from an indexed mesh, rejecting non-manifold input.
#include "halfedge.hpp"

#include "parallel.hpp"

namespace pmz::detail {

bool build_halfedge(const IndexedMesh& in, HalfEdgeMesh& m, std::string& error) {
  const uint32_t vertex_count = in.vertex_count(), face_count = in.face_count();
  if (in.indices.size() % 3 != 0 || in.positions.size() % 3 != 0) {
    error = "mesh arrays are not a multiple of three";
    return false;
  }
  for (uint32_t f = 0; f < face_count; ++f) {
    const uint32_t* t = &in.indices[size_t(f) * 3];
    if (t[0] >= vertex_count || t[1] >= vertex_count || t[2] >= vertex_count) {
      error = "face " + std::to_string(f) + " references a vertex out of range";
      return false;
    }
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) {
      error = "face " + std::to_string(f) + " is degenerate (repeated vertex)";
      return false;
    }
  }
  m.pos = in.positions;
  m.vert.assign(size_t(face_count) * 4, kNone);
  for (uint32_t f = 0; f < face_count; ++f)
    for (uint32_t k = 0; k < 3; ++k)
      m.vert[HalfEdgeMesh::half_edge(f, k)] = in.indices[size_t(f) * 3 + k];
  const uint32_t slots = m.slot_count();

  // Outgoing half-edges grouped by origin (counting sort): twins are found in O(valence).
  std::vector<uint32_t> first(size_t(vertex_count) + 1, 0), by_origin(size_t(face_count) * 3);
  for (uint32_t h = 0; h < slots; ++h)
    if (m.vert[h] != kNone) ++first[m.vert[h] + 1];
  for (uint32_t v = 0; v < vertex_count; ++v) first[v + 1] += first[v];
  {
    std::vector<uint32_t> fill(first.begin(), first.end() - 1);
    for (uint32_t h = 0; h < slots; ++h)
      if (m.vert[h] != kNone) by_origin[fill[m.vert[h]]++] = h;
  }
  m.twin.assign(slots, kNone);
  // Each half's first failure (smallest index), so the message is the one-thread one.
  uint32_t bad_edge[2] = {kNone, kNone}, bad_vertex[2] = {kNone, kNone};
  parallel_halves(slots, [&](uint32_t begin, uint32_t end) {
    for (uint32_t h = begin; h < end; ++h) {
      if (m.vert[h] == kNone) continue;  // padding slot
      const uint32_t a = m.vert[h], b = m.dest(h);
      uint32_t same = 0, opposite = 0, found = kNone;
      for (uint32_t i = first[a]; i < first[a + 1]; ++i) same += m.dest(by_origin[i]) == b;
      for (uint32_t i = first[b]; i < first[b + 1]; ++i)
        if (m.dest(by_origin[i]) == a) ++opposite, found = by_origin[i];
      if (same > 1 || opposite > 1) {
        bad_edge[begin != 0] = h;
        return;
      }
      m.twin[h] = found;
    }
  });
  for (const uint32_t h : bad_edge)
    if (h != kNone) {
      error = "non-manifold or inconsistently oriented edge between vertices " +
              std::to_string(m.vert[h]) + " and " + std::to_string(m.dest(h));
      return false;
    }
  m.out.assign(vertex_count, kNone);
  parallel_halves(vertex_count, [&](uint32_t begin, uint32_t end) {
    for (uint32_t v = begin; v < end; ++v) {
      const uint32_t degree = first[v + 1] - first[v];
      if (degree == 0) continue;
      uint32_t start = by_origin[first[v]], boundary_outs = 0;
      for (uint32_t i = first[v]; i < first[v + 1]; ++i)
        if (m.twin[by_origin[i]] == kNone) ++boundary_outs, start = by_origin[i];
      m.out[v] = start;
      uint32_t visited = 0;
      for_each_outgoing(m, v, [&](uint32_t) { ++visited; });
      // More than one boundary fan, or a fan that misses faces: two surface sheets meet at v.
      if (boundary_outs > 1 || visited != degree) {
        bad_vertex[begin != 0] = v;
        return;
      }
    }
  });
  for (const uint32_t v : bad_vertex)
    if (v != kNone) {
      error = "non-manifold vertex " + std::to_string(v);
      return false;
    }
  return true;
}

}  // namespace pmz::detail
