// SPDX-License-Identifier: MIT
// Repair of raw input into a manifold-with-boundary triangle mesh, one test per input case.
#include <cmath>
#include <random>

#include "test_mesh_input_util.hpp"

using pmz_test::expect_same_triangles;
using pmz_test::manifold_problem;
using pmz_test::soup;
using pmz_test::TempDir;

namespace {

pmz::IndexedMesh repaired(const pmz::PolygonSoup& s, pmz::MeshRepairStats& stats) {
  pmz::IndexedMesh m;
  pmz::repair_mesh(s, m, stats);
  return m;
}

// Signed area of triangle t projected on z (for planar test polygons in the xy plane).
double area_z(const pmz::IndexedMesh& m, uint32_t t) {
  const float* a = &m.positions[m.indices[t * 3] * 3];
  const float* b = &m.positions[m.indices[t * 3 + 1] * 3];
  const float* c = &m.positions[m.indices[t * 3 + 2] * 3];
  return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
}

}  // namespace

TEST(MeshInputRepair, CleanMeshIsUnchanged) {
  // Two components, each an open square of two triangles (open boundary), plus a closed
  // tetrahedron.
  auto s = soup({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 5, 0, 0, 6, 0, 0, 5, 1, 0, 5, 0, 1},
                {{0, 1, 2}, {0, 2, 3}, {4, 6, 5}, {4, 5, 7}, {5, 6, 7}, {4, 7, 6}});
  pmz::MeshRepairStats st;
  auto m = repaired(s, st);
  EXPECT_EQ(m.indices, s.corners);
  EXPECT_EQ(m.positions, s.positions);
  EXPECT_EQ(st.summary(), "");
  EXPECT_EQ(manifold_problem(m), "");
}

TEST(MeshInputRepair, DegenerateFacesDroppedAndReported) {
  // Face 1 repeats a vertex (dropped); face 2 is zero-area with three distinct vertices (kept).
  auto s = soup({0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0}, {{0, 1, 2}, {0, 0, 1}, {1, 0, 3}, {2, 2, 2}});
  pmz::MeshRepairStats st;
  auto m = repaired(s, st);
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 1, 0, 3}));
  EXPECT_EQ(m.positions, s.positions);
  EXPECT_EQ(st.degenerate_faces_dropped, 2u);
  EXPECT_NE(st.summary().find("dropped 2 degenerate faces (repeated vertex)"), std::string::npos)
      << st.summary();
}

TEST(MeshInputRepair, RepeatedCornersOfPolygonAreRemovedNotTheFace) {
  // A quad with a doubled corner is the triangle it draws; a pinched hexagon is two triangles.
  auto s = soup({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, -1, 0, 0, -1, -1, 0},
                {{0, 1, 1, 2}, {0, 2, 3, 0, 4, 5}});
  pmz::MeshRepairStats st;
  auto m = repaired(s, st);
  EXPECT_EQ(m.face_count(), 3u);
  EXPECT_EQ(st.degenerate_faces_dropped, 0u);
  EXPECT_EQ(st.repeated_corners_removed, 2u);
  EXPECT_EQ(std::vector<uint32_t>(m.indices.begin(), m.indices.begin() + 3),
            (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_EQ(manifold_problem(m), "");
}

TEST(MeshInputRepair, DuplicateFacesAreKeptAndSeparated) {
  // A square (two triangles) where the first triangle appears again in the same orientation
  // and once more reversed: all four faces survive and the result is manifold.
  auto s = soup({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, {{0, 1, 2}, {0, 2, 3}, {0, 1, 2}, {2, 1, 0}});
  pmz::MeshRepairStats st;
  auto m = repaired(s, st);
  expect_same_triangles(s, m);
  EXPECT_EQ(st.duplicate_faces, 2u);
  EXPECT_EQ(manifold_problem(m), "");
  EXPECT_NE(st.summary().find("kept 2 duplicate faces"), std::string::npos) << st.summary();
}

TEST(MeshInputRepair, IsolatedVerticesAreKept) {
  auto s = soup({0, 0, 0, 1, 0, 0, 0, 1, 0, 7, 7, 7, 8, 8, 8}, {{0, 1, 2}});
  pmz::MeshRepairStats st;
  auto m = repaired(s, st);
  EXPECT_EQ(m.positions, s.positions);
  EXPECT_EQ(m.indices, s.corners);
  EXPECT_EQ(st.isolated_vertices, 2u);
}

TEST(MeshInputRepair, ThreeFacesOnAnEdgeAllKept) {
  auto s = soup({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1}, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
  pmz::MeshRepairStats st;
  auto m = repaired(s, st);
  expect_same_triangles(s, m);
  EXPECT_EQ(manifold_problem(m), "");
  EXPECT_EQ(st.nonmanifold_edges, 1u);
  // Faces 0 and 1 (first pair in input order) stay glued; face 2 gets its own edge copy.
  EXPECT_EQ(m.indices[0], 0u);
  EXPECT_EQ(m.indices[1], 1u);
  EXPECT_EQ(m.indices[3], 1u);
  EXPECT_EQ(m.indices[4], 0u);
  EXPECT_GE(m.vertex_count(), 6u);
  EXPECT_NE(st.summary().find("cut 1 non-manifold edge"), std::string::npos) << st.summary();
}

TEST(MeshInputRepair, FourFacesOnAnEdgeBecomeTwoManifoldPairs) {
  auto s = soup({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1},
                {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {1, 0, 5}});
  pmz::MeshRepairStats st;
  auto m = repaired(s, st);
  expect_same_triangles(s, m);
  EXPECT_EQ(manifold_problem(m), "");
  EXPECT_EQ(m.vertex_count(), 8u);  // one copy of each edge end
}

TEST(MeshInputRepair, InconsistentOrientationIsCutNotFlipped) {
  // Two triangles using the same directed edge 0->1: winding is kept, the edge is cut.
  auto s = soup({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0}, {{0, 1, 2}, {0, 1, 3}});
  pmz::MeshRepairStats st;
  auto m = repaired(s, st);
  expect_same_triangles(s, m);
  EXPECT_EQ(manifold_problem(m), "");
  EXPECT_EQ(st.nonmanifold_edges, 1u);
  EXPECT_EQ(m.vertex_count(), 6u);
}

TEST(MeshInputRepair, BowtieVertexIsSplitIntoOneVertexPerFan) {
  auto s = soup({0, 0, 0, 1, 0, 0, 1, 1, 0, -1, 0, 0, -1, -1, 0}, {{0, 1, 2}, {0, 3, 4}});
  pmz::MeshRepairStats st;
  auto m = repaired(s, st);
  expect_same_triangles(s, m);
  EXPECT_EQ(manifold_problem(m), "");
  EXPECT_EQ(st.nonmanifold_vertices, 1u);
  EXPECT_EQ(st.vertices_added, 1u);
  EXPECT_EQ(m.indices[0], 0u);  // the first fan keeps the input id
  EXPECT_EQ(m.indices[3], 5u);  // the second gets a copy appended after the input vertices
  EXPECT_NE(st.summary().find("split 1 non-manifold vertex"), std::string::npos) << st.summary();
}

TEST(MeshInputRepair, TwoConesTouchingAtTheirApex) {
  // Two closed fans around vertex 0 (two pyramids sharing the apex, bases open).
  std::vector<float> p = {0, 0, 0};
  std::vector<std::vector<uint32_t>> f;
  for (int cone = 0; cone < 2; ++cone) {
    uint32_t base = uint32_t(p.size() / 3);
    for (int k = 0; k < 4; ++k)
      p.insert(p.end(),
               {float(std::cos(k * M_PI / 2)), float(std::sin(k * M_PI / 2)), cone ? 1.f : -1.f});
    for (uint32_t k = 0; k < 4; ++k) f.push_back({0, base + k, base + (k + 1) % 4});
  }
  auto s = soup(p, f);
  pmz::MeshRepairStats st;
  auto m = repaired(s, st);
  expect_same_triangles(s, m);
  EXPECT_EQ(manifold_problem(m), "");
  EXPECT_EQ(st.vertices_added, 1u);
}

TEST(MeshInputRepair, QuadAndPentagonAreTriangulatedInOrder) {
  auto s = soup({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0.5f, 0, 3, 0, 0},
                {{0, 1, 2, 3}, {1, 5, 4, 2, 0}});
  pmz::MeshRepairStats st;
  auto m = repaired(s, st);
  EXPECT_EQ(m.face_count(), 2u + 3u);
  EXPECT_EQ(st.polygons_triangulated, 2u);
  // A convex polygon becomes the fan from its first corner, in input order, same winding.
  EXPECT_EQ(std::vector<uint32_t>(m.indices.begin(), m.indices.begin() + 6),
            (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  double pentagon = 0;
  for (uint32_t t = 0; t < 5; ++t) EXPECT_GE(area_z(m, t), 0);
  for (uint32_t t = 2; t < 5; ++t) pentagon += area_z(m, t);
  EXPECT_DOUBLE_EQ(pentagon, 1.5);  // (1,0) (3,0) (2,.5) (1,1) (0,0): 1 + 0.5
  EXPECT_EQ(manifold_problem(m), "");
}

TEST(MeshInputRepair, NonConvexPolygonIsEarClipped) {
  // An L-shaped hexagon (reflex corner at vertex 3): a fan from corner 0 would overlap itself.
  auto s = soup({0, 0, 0, 2, 0, 0, 2, 1, 0, 1, 1, 0, 1, 2, 0, 0, 2, 0}, {{0, 1, 2, 3, 4, 5}});
  pmz::MeshRepairStats st;
  auto m = repaired(s, st);
  ASSERT_EQ(m.face_count(), 4u);
  double total = 0;
  for (uint32_t t = 0; t < 4; ++t) {
    EXPECT_GT(area_z(m, t), 0) << "triangle " << t << " flipped";
    total += area_z(m, t);
  }
  EXPECT_DOUBLE_EQ(total, 3.0);
  EXPECT_EQ(manifold_problem(m), "");
}

TEST(MeshInputRepair, RandomSoupsBecomeManifoldWithoutLosingFaces) {
  // Few vertices, many random triangles: heavy non-manifold edges, bowties, duplicates.
  std::mt19937 rng(7);
  for (int round = 0; round < 300; ++round) {
    uint32_t nv = 4 + rng() % 12, nf = 1 + rng() % 60;
    std::vector<float> p(nv * 3);
    for (float& x : p) x = float(rng() % 1000) / 100.f;
    std::vector<std::vector<uint32_t>> faces;
    while (faces.size() < nf) {
      uint32_t a = rng() % nv, b = rng() % nv, c = rng() % nv;
      if (a != b && b != c && a != c) faces.push_back({a, b, c});
    }
    auto s = soup(p, faces);
    pmz::MeshRepairStats st;
    auto m = repaired(s, st);
    expect_same_triangles(s, m);
    ASSERT_EQ(manifold_problem(m), "") << "round " << round;
    EXPECT_EQ(m.vertex_count(), nv + st.vertices_added);
  }
}

TEST(MeshInputRepair, ReadMeshPrintsTheSummaryOnStderr) {
  TempDir dir;
  auto path = dir.write(
      "bowtie.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv -1 0 0\nv -1 -1 0\nf 1 2 3\nf 1 4 5\nf 1 1 2\n");
  pmz::IndexedMesh m;
  std::string err;
  testing::internal::CaptureStderr();
  ASSERT_TRUE(pmz::read_mesh(path, m, err)) << err;
  std::string printed = testing::internal::GetCapturedStderr();
  EXPECT_NE(printed.find("dropped 1 degenerate face (repeated vertex)"), std::string::npos)
      << printed;
  EXPECT_NE(printed.find("split 1 non-manifold vertex"), std::string::npos) << printed;
  EXPECT_EQ(m.face_count(), 2u);
}

// A quad meeting a non-manifold edge: OpenMesh's own mesh building (what mesh_io used before;
// OpenMesh 9.0's read_mesh gives 3 faces) loses one of its triangles; pmz keeps all four.
TEST(MeshInputRepair, KeepsEveryFaceAtANonManifoldEdge) {
  TempDir dir;
  auto path = dir.write(
      "fin.off",
      "OFF\n6 3 0\n0 0 0\n1 0 0\n0 1 0\n0 -1 0\n0 0 1\n1 1 1\n3 0 1 2\n3 1 0 3\n4 0 1 5 4\n");
  pmz::IndexedMesh m;
  pmz::MeshRepairStats st;
  std::string err;
  ASSERT_TRUE(pmz::read_mesh(path, m, st, err)) << err;
  EXPECT_EQ(m.face_count(), 4u);
  EXPECT_EQ(manifold_problem(m), "");
  EXPECT_EQ(st.nonmanifold_edges, 1u);
}

// The repair that consumes its soup (freeing the soup's arrays as it goes, taking its positions)
// gives the mesh and the statistics of the one that reads it, attributes included, on random
// polygon soups over few vertices (non-manifold edges, repeated corners, polygons), and leaves
// the soup empty.
TEST(MeshInputRepair, ConsumingTheSoupGivesTheSameMesh) {
  std::mt19937 rng(11);
  auto pick = [&](uint32_t n) { return uint32_t(rng() % n); };
  for (int round = 0; round < 200; ++round) {
    const uint32_t nv = 3 + pick(10);
    std::vector<float> positions;
    for (uint32_t v = 0; v < nv * 3; ++v) positions.push_back(float(pick(4)));
    std::vector<std::vector<uint32_t>> faces(1 + pick(40));
    for (auto& f : faces) {
      f.resize(3 + (pick(3) == 0 ? pick(4) : 0));
      for (uint32_t& c : f) c = pick(nv);
    }
    pmz::PolygonSoup input = soup(positions, faces);
    if (round % 2) {  // per-corner normals from a pool of two, a material per face
      pmz::SoupAttributes& a = input.attributes;
      a.normals = {0, 0, 1, 0, 0, -1};
      for (size_t c = 0; c < input.corners.size(); ++c) a.corner_normals.push_back(pick(2));
      a.materials.resize(2);
      for (size_t f = 0; f < faces.size(); ++f) a.face_materials.push_back(pick(2));
    }
    pmz::IndexedMesh read, consumed;
    pmz::MeshRepairStats read_stats, consumed_stats;
    pmz::repair_mesh(input, read, read_stats);
    pmz::repair_mesh(std::move(input), consumed, consumed_stats);
    EXPECT_EQ(consumed.positions, read.positions) << "round " << round;
    EXPECT_EQ(consumed.indices, read.indices) << "round " << round;
    EXPECT_EQ(consumed.attributes.corner_wedges, read.attributes.corner_wedges);
    EXPECT_EQ(consumed.attributes.wedge_vertices, read.attributes.wedge_vertices);
    EXPECT_EQ(consumed.attributes.normals, read.attributes.normals);
    EXPECT_EQ(consumed.attributes.face_materials, read.attributes.face_materials);
    EXPECT_EQ(consumed_stats.summary(), read_stats.summary());
    EXPECT_EQ(input.vertex_count() + input.face_count(), 0u);  // NOLINT(bugprone-use-after-move)
    EXPECT_EQ(manifold_problem(consumed), "") << "round " << round;
  }
}
