// SPDX-License-Identifier: MIT
// ProgressiveMesh::build: once per file (the base mesh), apart from the refinement code so the
// WebAssembly build compiles it and its sort for size (scripts/web.sh lists the -O3 files).
#include <algorithm>
#include <string>
#include <vector>

#include "pmz/progressive_mesh.hpp"
#include "pmz/wasm_hints.hpp"

namespace pmz {

[[gnu::cold]] bool ProgressiveMesh::build(uint32_t n, const uint32_t* indices, size_t faces,
                                          std::string& error) {
  corner_vertex.assign(indices, indices + faces * 3);
  opposite.assign(faces * 3, kNoCorner);
  vertex_corner.assign(n, kNoCorner);
  // Directed edge (from, to) of corner c is the edge opposite c: next(c) -> prev(c).
  std::vector<uint64_t> edges(faces * 3);
  for (uint32_t c = 0; c < faces * 3; ++c) {
    uint32_t a = corner_vertex[c];
    if (a >= n) return error = "face index out of range", false;
    uint32_t f = c - c % 3;
    if (corner_vertex[f] == corner_vertex[f + 1] || corner_vertex[f] == corner_vertex[f + 2] ||
        corner_vertex[f + 1] == corner_vertex[f + 2])
      return error = "degenerate face", false;
    vertex_corner[a] = c;
  }
  // The corners in the order of their edges (start, end): two stable counting sorts, by end
  // then by start (vertices are below n; smaller code than a comparison sort in the WASM build).
  std::vector<uint32_t> order(faces * 3), by_end(faces * 3), count(size_t(n) + 1);
  for (uint32_t c = 0; c < faces * 3; ++c)
    edges[c] = uint64_t(corner_vertex[next_corner(c)]) << 32 | corner_vertex[prev_corner(c)];
  for (int pass = 0; pass < 2; ++pass) {
    const int shift = pass ? 32 : 0;
    std::fill(count.begin(), count.end(), 0u);
    for (uint32_t c = 0; c < faces * 3; ++c) ++count[uint32_t(edges[c] >> shift) + 1];
    for (size_t v = 1; v <= n; ++v) count[v] += count[v - 1];
    for (uint32_t i = 0; i < faces * 3; ++i) {
      const uint32_t c = pass ? by_end[i] : i;
      (pass ? order : by_end)[count[uint32_t(edges[c] >> shift)]++] = c;
    }
  }
  for (size_t i = 1; i < order.size(); ++i)
    if (edges[order[i]] == edges[order[i - 1]]) return error = "non-manifold edge", false;
  for (uint32_t c = 0; c < faces * 3; ++c) {
    uint64_t twin = edges[c] << 32 | edges[c] >> 32;
    auto it = std::lower_bound(order.begin(), order.end(), twin,
                               [&](uint32_t x, uint64_t key) { return edges[x] < key; });
    if (it != order.end() && edges[*it] == twin) opposite[c] = *it;
  }
  // Each vertex's faces must form one fan (spec/format.md sections 6 and 7: a vertex in several
  // fans is refused): the fan walked from its stored corner holds all of its corners.
  std::vector<uint32_t> corners_at(n, 0);
  for (uint32_t c = 0; c < faces * 3; ++c) ++corners_at[corner_vertex[c]];
  for (uint32_t v = 0; v < n; ++v) {
    uint32_t fan_faces = 0;
    for_each_fan_face(v, [&](uint32_t, uint32_t) { ++fan_faces; });
    if (fan_faces != corners_at[v])
      return error = "vertex " + PMZ_DECIMAL(v) + " in several fans", false;
  }
  return true;
}

}  // namespace pmz
