// SPDX-License-Identifier: MIT
// Each term of the multi-feature metric against values worked out by hand (spec/algorithm.md).
#include <gtest/gtest.h>

#include <cmath>

#include "../../encoder/src/metric.hpp"
#include "pmz/simplify.hpp"
#include "simplify_test_meshes.hpp"

using pmz::detail::Features;
using pmz::detail::HalfEdgeMesh;

namespace {

HalfEdgeMesh build(const pmz::IndexedMesh& mesh) {
  HalfEdgeMesh m;
  std::string error;
  EXPECT_TRUE(pmz::detail::build_halfedge(mesh, m, error)) << error;
  return m;
}

Features features(const HalfEdgeMesh& m, float epsilon) {
  Features f;
  f.epsilon = epsilon;
  f.compute_all(m);
  return f;
}

// Three faces of the unit cube meeting at the origin (vertex 0), outward normals -x, -y, -z.
pmz::IndexedMesh cube_corner() {
  pmz::IndexedMesh m;
  pmz_test::add_vertex(m, 0, 0, 0);
  pmz_test::add_vertex(m, 1, 0, 0);
  pmz_test::add_vertex(m, 0, 1, 0);
  pmz_test::add_vertex(m, 0, 0, 1);
  m.indices = {0, 2, 1, 0, 1, 3, 0, 3, 2};
  return m;
}

uint32_t half_edge(const HalfEdgeMesh& m, uint32_t a, uint32_t b) {
  for (uint32_t h = 0; h < m.vert.size(); ++h)
    if (m.vert[h] == a && m.dest(h) == b) return h;
  return pmz::detail::kNone;
}

}  // namespace

TEST(Metric, FlatPatchHasNoNormalVariationNorTorsion) {
  const auto mesh = pmz_test::grid(5);
  const auto m = build(mesh);
  const auto f = features(m, 0.5f);
  for (uint32_t v = 0; v < m.vertex_count(); ++v) {
    EXPECT_NEAR(f.c_norm(v), 0.f, 1e-6f) << v;
    EXPECT_NEAR(f.torsion(v), 0.f, 1e-6f) << v;
    EXPECT_NEAR(f.normal(v)[2], 1.f, 1e-6f) << v;
    // B = mean of (1 - eps)^2 n_i = 0.25 * (0, 0, 1) everywhere, whatever the valence.
    EXPECT_NEAR(f.b(v)[2], 0.25f, 1e-6f) << v;
  }
}

TEST(Metric, CubeCorner) {
  const auto m = build(cube_corner());
  const float eps = 0.5f;
  const auto f = features(m, eps);
  const double s3 = 1 / std::sqrt(3.0), s2 = 1 / std::sqrt(2.0);
  // Corner: n = -(1,1,1)/sqrt3, every face at n.n_i = 1/sqrt3.
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(f.normal(0)[k], -s3, 1e-6);
  EXPECT_NEAR(f.c_norm(0), 1 - s3, 1e-6);
  const double h0 = (s3 - eps) * (s3 - eps);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(f.b(0)[k], -h0 / 3, 1e-6);
  // Vertex 1 lies on the faces -z and -y: n = -(0,1,1)/sqrt2, n.n_i = 1/sqrt2.
  EXPECT_NEAR(f.c_norm(1), 1 - s2, 1e-6);
  const double h1 = (s2 - eps) * (s2 - eps);
  EXPECT_NEAR(f.b(1)[0], 0, 1e-6);
  EXPECT_NEAR(f.b(1)[1], -h1 / 2, 1e-6);
  EXPECT_NEAR(f.b(1)[2], -h1 / 2, 1e-6);
  // T(0) = sum |B_i - B_0| / sum |v_i - v_0| = |B_1 - B_0| by symmetry (unit edges).
  const double dx = h0 / 3, dyz = -h1 / 2 + h0 / 3;
  EXPECT_NEAR(f.torsion(0), std::sqrt(dx * dx + 2 * dyz * dyz), 1e-6);
  // With epsilon above 1/sqrt3 the corner's faces drop out of B.
  const auto g = features(m, 0.6f);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(g.b(0)[k], 0.f);

  // Area-weighted quadric of the corner: planes x=0, y=0, z=0 with area 1/2 each.
  std::vector<pmz::detail::Quadric> q;
  pmz::detail::initial_quadrics(m, 0.0, q);
  const float p[3] = {1, 2, 3};
  EXPECT_NEAR(q[0].error(p), 0.5 * (1 + 4 + 9), 1e-9);
  EXPECT_NEAR(q[1].error(p), 0.5 * (4 + 9), 1e-9);  // planes y=0 and z=0
  const float on_plane[3] = {0, 0, 0.25f};
  EXPECT_NEAR(q[0].error(on_plane), 0.5 * 0.0625, 1e-9);
}

TEST(Metric, BoundaryQuadricPenalisesLeavingTheBorder) {
  const auto m = build(pmz_test::grid(2));
  std::vector<pmz::detail::Quadric> with, without;
  pmz::detail::initial_quadrics(m, 1.0, with);
  pmz::detail::initial_quadrics(m, 0.0, without);
  // Corner vertex 0 at (0,0): moving it in-plane costs nothing without boundary planes, and
  // w * l^2 * d^2 per boundary edge with them (edges along x and y, both of length 1).
  const float inward[3] = {0.5f, 0.5f, 0};
  EXPECT_NEAR(without[0].error(inward), 0, 1e-12);
  EXPECT_NEAR(with[0].error(inward), 0.25 + 0.25, 1e-9);
}

TEST(Metric, CurrentQuadricEqualsTheInitialOneOnTheInput) {
  // Before any collapse, Q of the current mesh is QSlim's initial quadric (faces and boundary
  // planes), up to the float face normals it reads.
  for (const auto& mesh : {pmz_test::grid(3), pmz_test::icosphere(2), cube_corner()}) {
    const auto m = build(mesh);
    const auto f = features(m, 0.3f);
    std::vector<pmz::detail::Quadric> initial;
    pmz::detail::initial_quadrics(m, 1.0, initial);
    for (uint32_t v = 0; v < m.vertex_count(); ++v) {
      pmz::detail::Quadric q;
      pmz::detail::current_quadric(m, f, v, 1.0, q);
      const float* p = m.p(v);
      for (const float d : {0.f, 0.1f, -0.3f}) {
        const float probe[3] = {p[0] + d, p[1] - 0.5f * d, p[2] + 2 * d};
        EXPECT_NEAR(q.error(probe), initial[v].error(probe), 1e-5 * (1 + initial[v].error(probe)))
            << "vertex " << v;
      }
    }
  }
}

TEST(Metric, EdgeLengthRatio) {
  const auto mesh = pmz_test::grid(2);
  const auto m = build(mesh);
  const auto f = features(m, 0.5f);
  // Interior diagonal (0,0)-(1,1): sqrt2 over the four unit legs of its two triangles.
  const uint32_t diagonal = half_edge(m, 0, 4);
  ASSERT_NE(diagonal, pmz::detail::kNone);
  EXPECT_NEAR(pmz::detail::edge_length_ratio(m, f, diagonal), std::sqrt(2.0) / 4, 1e-6);
  // Boundary edge (0,0)-(1,0): 1 over the other two edges of its one triangle, 1 and sqrt2.
  const uint32_t border = half_edge(m, 0, 1);
  ASSERT_NE(border, pmz::detail::kNone);
  EXPECT_NEAR(pmz::detail::edge_length_ratio(m, f, border), 1 / (1 + std::sqrt(2.0)), 1e-6);
  // Equilateral pair: 1/4 inside.
  pmz::IndexedMesh rhombus;
  pmz_test::add_vertex(rhombus, 0, 0, 0);
  pmz_test::add_vertex(rhombus, 1, 0, 0);
  pmz_test::add_vertex(rhombus, 0.5, std::sqrt(0.75), 0);
  pmz_test::add_vertex(rhombus, 0.5, -std::sqrt(0.75), 0);
  rhombus.indices = {0, 1, 2, 1, 0, 3};
  const auto r = build(rhombus);
  const auto fr = features(r, 0.5f);
  EXPECT_NEAR(pmz::detail::edge_length_ratio(r, fr, half_edge(r, 0, 1)), 0.25, 1e-6);
  EXPECT_NEAR(pmz::detail::edge_length_ratio(r, fr, half_edge(r, 1, 2)), 0.5, 1e-6);
}

TEST(Metric, SphereTermsAreNearlyConstant) {
  const auto m = build(pmz_test::icosphere(4));
  const auto f = features(m, 0.5f);
  const double edge = pmz::detail::mean_edge_length(m);
  double c_min = 1e9, c_max = 0, t_min = 1e9, t_max = 0;
  for (uint32_t v = 0; v < m.vertex_count(); ++v) {
    c_min = std::min<double>(c_min, f.c_norm(v)), c_max = std::max<double>(c_max, f.c_norm(v));
    t_min = std::min<double>(t_min, f.torsion(v)), t_max = std::max<double>(t_max, f.torsion(v));
  }
  // C_norm ~ (angle between face and vertex normals)^2 / 2 ~ (edge / 2)^2 / 2 on the unit sphere.
  EXPECT_GT(c_min, 0);
  EXPECT_LT(c_max / c_min, 2.0);
  EXPECT_NEAR(c_max, edge * edge / 8, edge * edge / 8);
  // B = (1-eps)^2-weighted normal: its change per unit length is ~ (1-eps)^2 on the unit sphere.
  EXPECT_GT(t_min, 0);
  EXPECT_LT(t_max / t_min, 1.5);
  EXPECT_NEAR(t_max, 0.25, 0.1);
}

TEST(Metric, CostIsScaleInvariant) {
  // Scaling by a power of two scales every length exactly: the collapse order must not change.
  const auto mesh = pmz_test::torus(20, 10);
  auto scaled = mesh;
  for (float& c : scaled.positions) c *= 8;
  pmz::CollapseSequence a, b;
  std::string error;
  ASSERT_TRUE(pmz::simplify(mesh, {}, a, error)) << error;
  ASSERT_TRUE(pmz::simplify(scaled, {}, b, error)) << error;
  ASSERT_EQ(a.collapses.size(), b.collapses.size());
  for (size_t i = 0; i < a.collapses.size(); ++i) {
    EXPECT_EQ(a.collapses[i].u, b.collapses[i].u);
    EXPECT_EQ(a.collapses[i].v, b.collapses[i].v);
    EXPECT_FLOAT_EQ(a.collapses[i].cost, b.collapses[i].cost);
  }
}

TEST(Metric, QemAndMultifeatureBothRunAndDiffer) {
  const auto mesh = pmz_test::torus(32, 16);
  pmz::SimplifyOptions options;
  options.target_faces = 200;
  pmz::CollapseSequence mf, qem;
  std::string error;
  ASSERT_TRUE(pmz::simplify(mesh, options, mf, error)) << error;
  options.metric = pmz::Metric::qem;
  ASSERT_TRUE(pmz::simplify(mesh, options, qem, error)) << error;
  EXPECT_EQ(mf.base_indices.size(), 600u);
  EXPECT_EQ(qem.base_indices.size(), 600u);
  bool differ = false;
  for (size_t i = 0; i < mf.collapses.size() && !differ; ++i)
    differ = mf.collapses[i].u != qem.collapses[i].u || mf.collapses[i].v != qem.collapses[i].v;
  EXPECT_TRUE(differ);
}
