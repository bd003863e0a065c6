// SPDX-License-Identifier: MIT
// What repair_mesh promises (meshio/include/pmz/mesh.hpp), checked on its output by the mesh
// fuzz targets: indices in range, no face repeating a vertex, every directed edge used once
// (so every undirected edge has at most two faces, opposite), one fan of faces per vertex, the
// input vertices first and unchanged, no face lost but those with fewer than three distinct
// corners, and attribute wedges consistent with their corners.
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "fuzz_common.hpp"
#include "pmz/mesh.hpp"

namespace pmz_fuzz {

inline void check_repaired(const pmz::PolygonSoup& soup, const pmz::IndexedMesh& mesh,
                           const pmz::MeshRepairStats& stats) {
  const uint32_t nv = mesh.vertex_count(), nf = mesh.face_count();
  PMZ_FUZZ_CHECK(mesh.indices.size() == size_t(nf) * 3);
  PMZ_FUZZ_CHECK(stats.input_faces == soup.face_count());
  // Input vertices keep their ids and positions; copies come after them.
  PMZ_FUZZ_CHECK(nv >= soup.vertex_count());
  PMZ_FUZZ_CHECK(std::equal(soup.positions.begin(), soup.positions.end(), mesh.positions.begin(),
                            [](float a, float b) { return std::memcmp(&a, &b, 4) == 0; }));
  // Each face that is kept gives at least one triangle.
  PMZ_FUZZ_CHECK(stats.degenerate_faces_dropped <= stats.input_faces);
  PMZ_FUZZ_CHECK(nf >= stats.input_faces - stats.degenerate_faces_dropped);
  std::vector<uint64_t> edges;
  edges.reserve(size_t(nf) * 3);
  for (uint32_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = mesh.indices[f * 3 + k], b = mesh.indices[f * 3 + (k + 1) % 3];
      PMZ_FUZZ_CHECK(a < nv);
      PMZ_FUZZ_CHECK(a != b);
      edges.push_back(uint64_t(a) << 32 | b);
    }
  std::sort(edges.begin(), edges.end());
  PMZ_FUZZ_CHECK(std::adjacent_find(edges.begin(), edges.end()) == edges.end());
  // One fan per vertex: v's corners, joined when their faces share an edge at v, are connected.
  // The face across corner c's edge (v, n) holds n -> v: its corner at v comes after n.
  std::vector<uint32_t> first(size_t(nv) + 1, 0), around(size_t(nf) * 3), root;
  for (uint32_t i : mesh.indices) ++first[i + 1];
  for (uint32_t v = 0; v < nv; ++v) first[v + 1] += first[v];
  std::vector<uint32_t> fill(first.begin(), first.end() - 1);
  for (uint32_t c = 0; c < nf * 3; ++c) around[fill[mesh.indices[c]]++] = c;
  auto vertex_at = [&](uint32_t c, int step) {
    return mesh.indices[c - c % 3 + (c % 3 + step) % 3];
  };
  for (uint32_t v = 0; v < nv; ++v) {
    const uint32_t b = first[v], n = first[v + 1] - b;
    if (n < 2) continue;
    root.resize(n);
    for (uint32_t i = 0; i < n; ++i) root[i] = i;
    auto find = [&](uint32_t x) {
      while (root[x] != x) x = root[x] = root[root[x]];
      return x;
    };
    uint32_t components = n;
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t after = vertex_at(around[b + i], 1);
      for (uint32_t j = 0; j < n; ++j)
        if (vertex_at(around[b + j], 2) == after) {
          const uint32_t x = find(i), y = find(j);
          if (x != y) root[x] = y, --components;
          break;
        }
    }
    PMZ_FUZZ_CHECK(components == 1);
  }
  const pmz::MeshAttributes& a = mesh.attributes;
  if (a.has_wedges()) {
    PMZ_FUZZ_CHECK(a.corner_wedges.size() == mesh.indices.size());
    for (size_t c = 0; c < a.corner_wedges.size(); ++c) {
      PMZ_FUZZ_CHECK(a.corner_wedges[c] < a.wedge_count());
      PMZ_FUZZ_CHECK(a.wedge_vertices[a.corner_wedges[c]] == mesh.indices[c]);
    }
    for (const auto& t : a.texcoords) PMZ_FUZZ_CHECK(t.size() == a.wedge_count() * 2u);
    PMZ_FUZZ_CHECK(a.normals.empty() || a.normals.size() == a.wedge_count() * 3u);
    PMZ_FUZZ_CHECK(a.colors.size() == size_t(a.wedge_count()) * a.color_components);
  }
  if (!a.face_materials.empty()) {
    PMZ_FUZZ_CHECK(a.face_materials.size() == nf);
    for (uint32_t m : a.face_materials) PMZ_FUZZ_CHECK(m < a.materials.size());
  }
}

}  // namespace pmz_fuzz
