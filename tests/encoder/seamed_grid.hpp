// SPDX-License-Identifier: MIT
// A flat (n x n)-quad grid with a texture seam down column `seam`: the vertices on that column
// have two wedges (left chart, right chart), the others one. Normals per wedge, RGB colours,
// and two materials (left and right of the seam), so every attribute kind is present.
#pragma once
#include <cstdint>

#include "pmz/mesh.hpp"

namespace pmz_test {

inline uint32_t grid_vertex(uint32_t n, uint32_t i, uint32_t j) { return j * (n + 1) + i; }

inline pmz::IndexedMesh seamed_grid(uint32_t n, uint32_t seam) {
  pmz::IndexedMesh m;
  pmz::MeshAttributes& a = m.attributes;
  a.texcoords.resize(1);
  a.color_components = 3;
  a.materials.resize(2);
  a.materials[0].name = "left";
  a.materials[1].name = "right";
  // wedge_of[vertex * 2 + side]: side 0 left chart, 1 right chart (the same off the seam).
  std::vector<uint32_t> wedge_of((n + 1) * (n + 1) * 2);
  for (uint32_t j = 0; j <= n; ++j)
    for (uint32_t i = 0; i <= n; ++i) {
      const uint32_t v = grid_vertex(n, i, j);
      const float x = float(i) / float(n), y = float(j) / float(n);
      m.positions.insert(m.positions.end(), {x, y, 0.05f * float((i * 7 + j * 3) % 5)});
      for (uint32_t side = 0; side < 2; ++side) {
        if (side == 1 && i != seam) {
          wedge_of[v * 2 + 1] = wedge_of[v * 2];
          continue;
        }
        const bool right = side == 1 || i > seam;
        wedge_of[v * 2 + side] = a.wedge_count();
        a.wedge_vertices.push_back(v);
        a.texcoords[0].insert(a.texcoords[0].end(), {right ? 0.55f + 0.4f * x : 0.5f * x, y});
        a.normals.insert(a.normals.end(), {right ? 0.6f : 0.f, 0.f, right ? 0.8f : 1.f});
        a.colors.insert(a.colors.end(), {x, y, right ? 1.f : 0.f});
      }
    }
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t q[4] = {grid_vertex(n, i, j), grid_vertex(n, i + 1, j),
                             grid_vertex(n, i + 1, j + 1), grid_vertex(n, i, j + 1)};
      const uint32_t side = i < seam ? 0 : 1;
      const uint32_t tris[2][3] = {{q[0], q[1], q[2]}, {q[0], q[2], q[3]}};
      for (const auto& t : tris) {
        for (uint32_t x : t) {
          m.indices.push_back(x);
          a.corner_wedges.push_back(wedge_of[x * 2 + side]);
        }
        a.face_materials.push_back(side);
      }
    }
  return m;
}

}  // namespace pmz_test
