// SPDX-License-Identifier: MIT
// The collapse rule for attribute wedges (encoder/src/attr_collapse.hpp) on a grid with a
// texture seam, and mesh_after() carrying attributes through a whole simplification.
#include <gtest/gtest.h>

#include "../../encoder/src/attr_collapse.hpp"
#include "pmz/simplify.hpp"
#include "seamed_grid.hpp"

namespace {

using pmz_test::grid_vertex;

TEST(AttrCollapse, LeftArcRule) {
  const std::vector<uint32_t> sector = {4, 4, 7, 7, 4};
  EXPECT_EQ(pmz::collapse_left_arc(sector, 4, true, true), 2u);  // up to the first other wedge
  EXPECT_EQ(pmz::collapse_left_arc(sector, 7, true, true), 0u);
  EXPECT_EQ(pmz::collapse_left_arc(sector, 7, true, false), 5u);  // only L: all
  EXPECT_EQ(pmz::collapse_left_arc(sector, 4, false, true), 0u);  // only R: none
}

// The third vertex of the face holding the directed edge a -> b (kNoVertex if none).
uint32_t third(const pmz::IndexedMesh& m, uint32_t a, uint32_t b) {
  for (size_t f = 0; f < m.indices.size(); f += 3)
    for (int k = 0; k < 3; ++k)
      if (m.indices[f + k] == a && m.indices[f + (k + 1) % 3] == b)
        return m.indices[f + (k + 2) % 3];
  return pmz::kNoVertex;
}

pmz::HalfEdgeCollapse collapse_of(const pmz::IndexedMesh& m, uint32_t u, uint32_t v) {
  return {u, v, third(m, u, v), third(m, v, u), 0.f};
}

// Every live corner names a wedge of its own vertex, and every face left (right) of the seam
// names left-chart (right-chart) wedges: what the rule promises for collapses along the seam
// and off it.
void expect_charts_kept(const pmz::IndexedMesh& m, const pmz::CollapseReplay& r,
                        uint32_t seam_x100) {
  const pmz::MeshAttributes& a = m.attributes;
  for (uint32_t f = 0; f < r.face_alive.size(); ++f) {
    if (!r.face_alive[f]) continue;
    float cx = 0;
    for (int k = 0; k < 3; ++k) cx += m.positions[r.corner_vertex[f * 3 + k] * 3] / 3;
    const bool right = cx * 100 > float(seam_x100);
    for (int k = 0; k < 3; ++k) {
      const uint32_t w = r.corner_wedge[f * 3 + k];
      EXPECT_EQ(a.wedge_vertices[w], r.corner_vertex[f * 3 + k]) << "face " << f;
      EXPECT_EQ(a.normals[w * 3] > 0.3f, right) << "face " << f << " corner " << k;
    }
  }
}

TEST(AttrCollapse, AlongTheSeamEachSideKeepsItsChart) {
  const uint32_t n = 6, seam = 3;
  const pmz::IndexedMesh m = pmz_test::seamed_grid(n, seam);
  pmz::CollapseReplay r(m);
  // u and v on the seam, u interior: u's two wedges end as v's two wedges, side by side.
  pmz::CollapseFan fan;
  ASSERT_TRUE(r.collapse(collapse_of(m, grid_vertex(n, seam, 2), grid_vertex(n, seam, 3)), &fan));
  EXPECT_EQ(fan.corners.size(), 6u * 3);
  EXPECT_EQ(fan.wedges.size(), fan.corners.size());
  expect_charts_kept(m, r, 50);
  // Off the seam, an interior vertex into a seam vertex: v's wedge on u's side.
  ASSERT_TRUE(r.collapse(collapse_of(m, grid_vertex(n, seam - 1, 4), grid_vertex(n, seam, 4))));
  expect_charts_kept(m, r, 50);
  // A one-wedge vertex into another.
  ASSERT_TRUE(r.collapse(collapse_of(m, grid_vertex(n, 5, 2), grid_vertex(n, 5, 3))));
  expect_charts_kept(m, r, 50);
  // Not a collapse of this mesh (u and v are not adjacent): refused, nothing changed.
  const auto before = r.corner_vertex;
  EXPECT_FALSE(r.collapse({grid_vertex(n, 0, 0), grid_vertex(n, 6, 6), 1, 2, 0.f}));
  EXPECT_EQ(r.corner_vertex, before);
}

TEST(AttrCollapse, BoundaryCollapseTakesTheExistingSide) {
  const uint32_t n = 4, seam = 2;
  const pmz::IndexedMesh m = pmz_test::seamed_grid(n, seam);
  pmz::CollapseReplay r(m);
  // Along the bottom boundary into the seam vertex: only one of L and R exists.
  const auto c = collapse_of(m, grid_vertex(n, 1, 0), grid_vertex(n, seam, 0));
  EXPECT_TRUE(c.vl == pmz::kNoVertex || c.vr == pmz::kNoVertex);
  ASSERT_TRUE(r.collapse(c));
  expect_charts_kept(m, r, 50);
}

// mesh_after() of a whole simplification: the geometry of the geometry-only replay, and at
// every level a consistent attribute mesh whose wedge values are input wedge values.
TEST(AttrCollapse, MeshAfterCarriesAttributes) {
  const pmz::IndexedMesh m = pmz_test::seamed_grid(8, 4);
  pmz::CollapseSequence seq;
  std::string error;
  ASSERT_TRUE(pmz::simplify(m, {}, seq, error)) << error;
  ASSERT_GT(seq.collapses.size(), 10u);
  pmz::CollapseSequence plain = seq;
  plain.mesh.attributes = {};
  for (size_t k = 0; k <= seq.collapses.size(); ++k) {
    const pmz::IndexedMesh after = pmz::mesh_after(seq, k);
    const pmz::IndexedMesh geometry = pmz::mesh_after(plain, k);
    ASSERT_EQ(after.positions, geometry.positions) << k;
    ASSERT_EQ(after.indices, geometry.indices) << k;
    const pmz::MeshAttributes& a = after.attributes;
    ASSERT_EQ(a.corner_wedges.size(), after.indices.size());
    ASSERT_EQ(a.face_materials.size(), after.face_count());
    ASSERT_EQ(a.texcoords.size(), 1u);
    ASSERT_EQ(a.texcoords[0].size(), a.wedge_count() * 2u);
    ASSERT_EQ(a.normals.size(), a.wedge_count() * 3u);
    ASSERT_EQ(a.colors.size(), a.wedge_count() * 3u);
    ASSERT_EQ(a.materials, m.attributes.materials);
    std::vector<char> used(a.wedge_count(), 0);
    for (size_t c = 0; c < after.indices.size(); ++c) {
      const uint32_t w = a.corner_wedges[c];
      ASSERT_LT(w, a.wedge_count());
      EXPECT_EQ(a.wedge_vertices[w], after.indices[c]) << "level " << k << " corner " << c;
      used[w] = 1;
    }
    EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0) << "unused wedges at level " << k;
    // Each wedge is an input wedge of the same position (values coded once).
    for (uint32_t w = 0; w < a.wedge_count(); ++w) {
      bool found = false;
      for (uint32_t iw = 0; iw < m.attributes.wedge_count() && !found; ++iw)
        found = m.attributes.texcoords[0][iw * 2] == a.texcoords[0][w * 2] &&
                m.attributes.texcoords[0][iw * 2 + 1] == a.texcoords[0][w * 2 + 1] &&
                m.attributes.normals[iw * 3] == a.normals[w * 3];
      EXPECT_TRUE(found) << "level " << k << " wedge " << w;
    }
  }
  // Level 0 is the input itself.
  const pmz::IndexedMesh full = pmz::mesh_after(seq, 0);
  EXPECT_EQ(full.attributes.corner_wedges, m.attributes.corner_wedges);
  EXPECT_EQ(full.attributes.texcoords, m.attributes.texcoords);
}

}  // namespace
