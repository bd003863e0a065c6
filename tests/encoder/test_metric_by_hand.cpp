// SPDX-License-Identifier: MIT
// The multi-feature cost of a collapse, recomputed in this file from the formulas of
// spec/algorithm.md section 2 (the paper's eq. 1-3 with pmz's normalisations), in double and with
// none of the encoder's functions: every directed edge of a cube corner, a bent sheet and a saddle
// against the engine's own cost, and the terms (C_norm, B, T, sigma) against metric.cpp. The
// tolerances are float rounding: dropping a factor, flipping a sign or changing a
// normalisation moves some of the values by far more.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "../../encoder/src/metric.hpp"
#include "pmz/simplify.hpp"
#include "simplify_test_meshes.hpp"

namespace {

using Vec = std::array<double, 3>;
Vec sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec& a) { return std::sqrt(dot(a, a)); }
Vec scaled(const Vec& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }

// A plane n.p + d = 0 with its weight: the quadric's contribution is w (n.p + d)^2.
struct Plane {
  Vec n;
  double d, w;
};

// Every term of the metric, by the book (spec/algorithm.md section 2).
struct HandMetric {
  std::vector<Vec> p;
  std::vector<std::array<uint32_t, 3>> faces;
  std::vector<Vec> face_normal;
  std::vector<double> face_area;
  std::vector<std::vector<uint32_t>> faces_of;  // faces around each vertex
  std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>> edge_faces;  // (min, max)
  std::vector<Vec> normal, b;
  std::vector<double> c_norm, torsion;
  std::vector<std::vector<Plane>> planes;  // the input quadric of each vertex
  double mean_edge = 0;

  HandMetric(const pmz::IndexedMesh& mesh, double epsilon, double boundary_weight) {
    const uint32_t n = mesh.vertex_count();
    for (uint32_t v = 0; v < n; ++v)
      p.push_back({mesh.positions[v * 3], mesh.positions[v * 3 + 1], mesh.positions[v * 3 + 2]});
    faces_of.resize(n);
    for (uint32_t f = 0; f < mesh.face_count(); ++f) {
      const std::array<uint32_t, 3> t = {mesh.indices[f * 3], mesh.indices[f * 3 + 1],
                                         mesh.indices[f * 3 + 2]};
      faces.push_back(t);
      const Vec c = cross(sub(p[t[1]], p[t[0]]), sub(p[t[2]], p[t[0]]));
      face_normal.push_back(scaled(c, 1 / norm(c)));
      face_area.push_back(norm(c) / 2);
      for (int k = 0; k < 3; ++k) {
        faces_of[t[k]].push_back(f);
        const uint32_t a = t[k], b2 = t[(k + 1) % 3];
        edge_faces[{std::min(a, b2), std::max(a, b2)}].push_back(f);
      }
    }
    for (const auto& [e, fs] : edge_faces) mean_edge += norm(sub(p[e.first], p[e.second]));
    mean_edge /= double(edge_faces.size());

    // Eq. 1 and the vector of eq. 2 (a mean over the faces), from the area-weighted normal.
    for (uint32_t v = 0; v < n; ++v) {
      Vec s = {0, 0, 0};
      for (uint32_t f : faces_of[v])
        for (int i = 0; i < 3; ++i) s[i] += face_area[f] * face_normal[f][i];
      const Vec nv = scaled(s, 1 / norm(s));
      double c = 0;
      Vec bv = {0, 0, 0};
      for (uint32_t f : faces_of[v]) {
        const double cosine = dot(nv, face_normal[f]);
        c += 1 - cosine;
        if (cosine > epsilon)
          for (int i = 0; i < 3; ++i)
            bv[i] += (cosine - epsilon) * (cosine - epsilon) * face_normal[f][i];
      }
      const double k = double(faces_of[v].size());
      normal.push_back(nv);
      c_norm.push_back(c / k);
      b.push_back(scaled(bv, 1 / k));
    }
    // Eq. 2: T(v) = sum |B(w) - B(v)| / sum |w - v| over the neighbours w.
    for (uint32_t v = 0; v < n; ++v) {
      double num = 0, den = 0;
      for (uint32_t w : neighbours(v)) {
        num += norm(sub(b[w], b[v]));
        den += norm(sub(p[w], p[v]));
      }
      torsion.push_back(num / den);
    }
    // Quadrics: area-weighted face planes; on each boundary edge the plane through it
    // perpendicular to its face, weighted boundary_weight * length^2, for both its ends.
    planes.resize(n);
    for (uint32_t f = 0; f < faces.size(); ++f) {
      const Vec& nf = face_normal[f];
      for (uint32_t v : faces[f]) planes[v].push_back({nf, -dot(nf, p[faces[f][0]]), face_area[f]});
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = faces[f][k], c = faces[f][(k + 1) % 3];
        if (edge_faces[{std::min(a, c), std::max(a, c)}].size() != 1) continue;
        const Vec e = sub(p[c], p[a]);
        const Vec bn = scaled(cross(e, nf), 1 / norm(cross(e, nf)));
        const Plane plane = {bn, -dot(bn, p[a]), boundary_weight * dot(e, e)};
        planes[a].push_back(plane);
        planes[c].push_back(plane);
      }
    }
  }

  std::set<uint32_t> neighbours(uint32_t v) const {
    std::set<uint32_t> out;
    for (uint32_t f : faces_of[v])
      for (uint32_t w : faces[f])
        if (w != v) out.insert(w);
    return out;
  }
  // Eq. 3: |uv| over the other edges of the one or two triangles on uv.
  double sigma(uint32_t u, uint32_t v) const {
    double others = 0;
    for (uint32_t f : edge_faces.at({std::min(u, v), std::max(u, v)}))
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = faces[f][k], c = faces[f][(k + 1) % 3];
        if (std::min(a, c) != std::min(u, v) || std::max(a, c) != std::max(u, v))
          others += norm(sub(p[a], p[c]));
      }
    return norm(sub(p[u], p[v])) / others;
  }
  double quadric(uint32_t v, const Vec& at) const {
    double e = 0;
    for (const Plane& pl : planes[v]) e += pl.w * (dot(pl.n, at) + pl.d) * (dot(pl.n, at) + pl.d);
    return e;
  }
  // The torsion part of the factor, w_T sigma(uv) T(u) L, and the whole directed cost:
  // (c0 + C_norm(u) + w_T sigma T(u) L) (1 + mu) (Q_u + Q_v)(p_v) / L^4.
  double torsion_part(uint32_t u, uint32_t v, const pmz::MetricParams& mp) const {
    return mp.torsion_weight * sigma(u, v) * torsion[u] * mean_edge;
  }
  double cost(uint32_t u, uint32_t v, const pmz::MetricParams& mp) const {
    const double l4 = std::pow(mean_edge, 4);
    const double e = (1 + double(mp.quadric_memory)) * (quadric(u, p[v]) + quadric(v, p[v])) / l4;
    return (mp.quadric_floor + c_norm[u] + torsion_part(u, v, mp)) * e;
  }
};

// A square [0, s]^2 of n x n quads spanned by axes a and b from origin o (normal a x b).
void add_square(pmz::IndexedMesh& m, std::map<std::array<float, 3>, uint32_t>& ids, const Vec& o,
                const Vec& a, const Vec& b, int n, double s) {
  auto id = [&](int i, int j) {
    std::array<float, 3> q;
    for (int k = 0; k < 3; ++k) q[k] = float(o[k] + s * (i * a[k] + j * b[k]) / n);
    auto [it, fresh] = ids.try_emplace(q, m.vertex_count());
    if (fresh) pmz_test::add_vertex(m, q[0], q[1], q[2]);
    return it->second;
  };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t p00 = id(i, j), p10 = id(i + 1, j), p11 = id(i + 1, j + 1), p01 = id(i, j + 1);
      pmz_test::add_face(m, p00, p10, p11);
      pmz_test::add_face(m, p00, p11, p01);
    }
}

// Three faces of the cube [0, 2]^3 meeting at the origin, n x n quads each, normals outward.
pmz::IndexedMesh cube_corner(int n) {
  pmz::IndexedMesh m;
  std::map<std::array<float, 3>, uint32_t> ids;
  add_square(m, ids, {0, 0, 0}, {0, 1, 0}, {1, 0, 0}, n, 2);  // z = 0, normal -z
  add_square(m, ids, {0, 0, 0}, {1, 0, 0}, {0, 0, 1}, n, 2);  // y = 0, normal -y
  add_square(m, ids, {0, 0, 0}, {0, 0, 1}, {0, 1, 0}, n, 2);  // x = 0, normal -x
  return m;
}

// A 4 x 3 sheet bent along x = 0 (z = 0.7 |x|), unevenly spaced across the bend.
pmz::IndexedMesh bent_sheet() {
  pmz::IndexedMesh m;
  const double xs[] = {-1.6, -0.7, 0, 0.5, 1.4};
  for (int j = 0; j <= 3; ++j)
    for (double x : xs) pmz_test::add_vertex(m, x, 0.8 * j, 0.7 * std::abs(x));
  for (uint32_t j = 0; j < 3; ++j)
    for (uint32_t i = 0; i < 4; ++i) {
      const uint32_t a = j * 5 + i, b = a + 1, c = a + 5, d = c + 1;
      pmz_test::add_face(m, a, b, d);
      pmz_test::add_face(m, a, d, c);
    }
  return m;
}

// z = 0.3 (x^2 - y^2) over [-1.5, 1.5]^2, 4 x 4 quads with alternating diagonals.
pmz::IndexedMesh saddle() {
  pmz::IndexedMesh m;
  for (int j = 0; j <= 4; ++j)
    for (int i = 0; i <= 4; ++i) {
      const double x = -1.5 + 0.75 * i, y = -1.5 + 0.75 * j + 0.05 * i;
      pmz_test::add_vertex(m, x, y, 0.3 * (x * x - y * y));
    }
  for (uint32_t j = 0; j < 4; ++j)
    for (uint32_t i = 0; i < 4; ++i) {
      const uint32_t a = j * 5 + i, b = a + 1, c = a + 5, d = c + 1;
      if ((i + j) % 2) {
        pmz_test::add_face(m, a, b, d);
        pmz_test::add_face(m, a, d, c);
      } else {
        pmz_test::add_face(m, a, b, c);
        pmz_test::add_face(m, b, d, c);
      }
    }
  return m;
}

pmz::detail::HalfEdgeMesh build(const pmz::IndexedMesh& mesh) {
  pmz::detail::HalfEdgeMesh m;
  std::string error;
  EXPECT_TRUE(pmz::detail::build_halfedge(mesh, m, error)) << error;
  return m;
}

// Agreement to float rounding (the engine keeps the terms in float): relative, and absolute
// for values that are zero up to the rounding of terms of order one.
::testing::AssertionResult close(double got, double want, double rel = 2e-5, double abs = 1e-12) {
  if (std::abs(got - want) <= rel * std::abs(want) + abs) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << got << " vs " << want << " by hand";
}

// The terms of metric.cpp against the hand values: C_norm, B and T per vertex, sigma per
// directed edge, the mean edge length.
void expect_terms(const pmz::IndexedMesh& mesh, double epsilon) {
  const HandMetric hand(mesh, epsilon, 1.0);
  const auto m = build(mesh);
  pmz::detail::Features f;
  f.epsilon = float(epsilon);
  f.compute_all(m);
  EXPECT_TRUE(close(pmz::detail::mean_edge_length(m), hand.mean_edge, 1e-6));
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    EXPECT_TRUE(close(f.c_norm(v), hand.c_norm[v], 1e-5, 5e-7)) << "C_norm, vertex " << v;
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(f.b(v)[i], hand.b[v][i], 1e-6) << "B, vertex " << v;
    EXPECT_TRUE(close(f.torsion(v), hand.torsion[v], 1e-5, 5e-7)) << "T, vertex " << v;
  }
  for (uint32_t h = 0; h < m.vert.size(); ++h) {
    if (m.vert[h] == pmz::detail::kNone) continue;
    EXPECT_TRUE(
        close(pmz::detail::edge_length_ratio(m, f, h), hand.sigma(m.vert[h], m.dest(h)), 1e-6))
        << "sigma of " << m.vert[h] << " -> " << m.dest(h);
  }
}

// Every directed edge's cost, engine against hand; returns how many of them carry a torsion
// part of at least 10% of the factor on a quadric error that is not zero (what makes a
// dropped or flipped torsion factor visible).
int expect_costs(const pmz::IndexedMesh& mesh, const pmz::MetricParams& params) {
  const HandMetric hand(mesh, params.epsilon, params.boundary_weight);
  pmz::SimplifyOptions options;
  options.params = params;
  int telling = 0;
  for (const auto& [e, fs] : hand.edge_faces)
    for (auto [u, v] : {e, std::make_pair(e.second, e.first)}) {
      const double want = hand.cost(u, v, params);
      // The engine's T and C_norm are floats (~1e-7 off), times w_T sigma L in the factor: 1e-4.
      EXPECT_TRUE(close(pmz::detail::initial_collapse_cost(mesh, options, u, v), want, 1e-4))
          << "cost of " << u << " -> " << v;
      const double factor = params.quadric_floor + hand.c_norm[u] + hand.torsion_part(u, v, params);
      telling += want > 1e-9 && hand.torsion_part(u, v, params) > 0.1 * factor;
    }
  return telling;
}

}  // namespace

// The reference itself against values worked out on paper (the cube corner with one quad per
// face: 7 vertices, the corner at the origin, edges 2 and diagonals 2 sqrt 2).
TEST(MetricByHand, ReferenceMatchesTheCubeCornerOnPaper) {
  const double eps = 0.3;
  const HandMetric hand(cube_corner(1), eps, 1.0);
  ASSERT_EQ(hand.p.size(), 7u);
  // The corner: six faces, two per plane, n = -(1,1,1)/sqrt3; each face at n.n_f = 1/sqrt3.
  const double s3 = 1 / std::sqrt(3.0);
  EXPECT_NEAR(hand.c_norm[0], 1 - s3, 1e-12);
  const double h0 = (s3 - eps) * (s3 - eps);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(hand.b[0][i], -h0 / 3, 1e-12);
  // Mean edge: 3 axis edges and 6 rim edges of length 2, 3 face diagonals of 2 sqrt2.
  EXPECT_NEAR(hand.mean_edge, (9 * 2 + 3 * 2 * std::sqrt(2.0)) / 12, 1e-12);
  // sigma of a face diagonal (interior): 2 sqrt2 over four sides of 2; of an axis edge
  // (interior, two triangles in two planes): 2 over 2 + 2 sqrt2 twice; of a rim edge (boundary):
  // 2 over 2 + 2 sqrt2.
  auto vertex = [&](double a, double b2, double c) {
    for (uint32_t v = 0; v < hand.p.size(); ++v)
      if (hand.p[v] == Vec{a, b2, c}) return v;
    ADD_FAILURE() << "no vertex at " << a << " " << b2 << " " << c;
    return 0u;
  };
  const uint32_t o = vertex(0, 0, 0), ax = vertex(2, 0, 0), dxy = vertex(2, 2, 0);
  EXPECT_NEAR(hand.sigma(o, dxy), 2 * std::sqrt(2.0) / 8, 1e-12);
  EXPECT_NEAR(hand.sigma(o, ax), 2 / (4 + 4 * std::sqrt(2.0)), 1e-12);
  EXPECT_NEAR(hand.sigma(ax, dxy), 2 / (2 + 2 * std::sqrt(2.0)), 1e-12);
  EXPECT_NEAR(hand.sigma(dxy, ax), hand.sigma(ax, dxy), 0);
  // The rim vertex (2, 2, 0): faces (0, ay, dxy) and (0, dxy, ax), both normal -z: C_norm 0,
  // B = (1 - eps)^2 (0, 0, -1).
  EXPECT_NEAR(hand.c_norm[dxy], 0, 1e-12);
  EXPECT_NEAR(hand.b[dxy][2], -(1 - eps) * (1 - eps), 1e-12);
  // The axis vertex (2, 0, 0): one face -z, one -y (area 2 each): n = -(0,1,1)/sqrt2,
  // n.n_f = 1/sqrt2, B = (1/sqrt2 - eps)^2 (0, -1/2, -1/2).
  const double s2 = 1 / std::sqrt(2.0), h1 = (s2 - eps) * (s2 - eps);
  EXPECT_NEAR(hand.c_norm[ax], 1 - s2, 1e-12);
  EXPECT_NEAR(hand.b[ax][1], -h1 / 2, 1e-12);
  EXPECT_NEAR(hand.b[ax][2], -h1 / 2, 1e-12);
  // T(corner): its neighbours are the three axis vertices (|B_a - B_0| each, at distance 2) and
  // the three rim diagonals (B = (1-eps)^2 along one axis, at distance 2 sqrt2).
  const double da = std::sqrt(h0 * h0 / 9 + 2 * (h1 / 2 - h0 / 3) * (h1 / 2 - h0 / 3));
  const double r = (1 - eps) * (1 - eps);
  const double dd = std::sqrt((r - h0 / 3) * (r - h0 / 3) + 2 * (h0 / 3) * (h0 / 3));
  EXPECT_NEAR(hand.torsion[o], (3 * da + 3 * dd) / (3 * 2 + 3 * 2 * std::sqrt(2.0)), 1e-12);
  // Its quadric: planes x = 0, y = 0, z = 0, two faces of area 2 each.
  EXPECT_NEAR(hand.quadric(o, {1, 2, 3}), 4 * (1 + 4 + 9), 1e-12);
}

TEST(MetricByHand, TermsOfTheCubeCorner) {
  expect_terms(cube_corner(1), 0.3);
  expect_terms(cube_corner(2), 0.3);
  expect_terms(cube_corner(2), 0.65);  // eps above 1/sqrt2: faces drop out of B at the creases
}
TEST(MetricByHand, TermsOfTheBentSheet) { expect_terms(bent_sheet(), 0.3); }
TEST(MetricByHand, TermsOfTheSaddle) { expect_terms(saddle(), 0.3); }

// The combined cost of every directed collapse: the defaults, then each factor made to count
// more (a low floor, a large torsion weight, no memory, another boundary weight and epsilon).
TEST(MetricByHand, CollapseCostsOfTheCubeCornerBentSheetAndSaddle) {
  pmz::MetricParams defaults;
  pmz::MetricParams torsion_heavy;
  // A small floor, not none: where C_norm and T are zero by hand the engine's float terms are
  // ~1e-7, which a zero floor would compare relatively.
  torsion_heavy.quadric_floor = 0.05f;
  torsion_heavy.torsion_weight = 40.f;
  torsion_heavy.quadric_memory = 0.f;
  torsion_heavy.boundary_weight = 2.5f;
  torsion_heavy.epsilon = 0.5f;
  for (const auto& params : {defaults, torsion_heavy}) {
    SCOPED_TRACE(params.quadric_floor);
    EXPECT_GE(expect_costs(cube_corner(1), params), 4) << "cube corner";
    EXPECT_GE(expect_costs(cube_corner(2), params), 4) << "cube corner, 2 x 2";
    EXPECT_GE(expect_costs(bent_sheet(), params), 4) << "bent sheet";
    EXPECT_GE(expect_costs(saddle(), params), 4) << "saddle";
  }
}
