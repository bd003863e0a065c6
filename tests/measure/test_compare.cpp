// SPDX-License-Identifier: MIT
// pmz::compare on cases with known answers.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <utility>

#include "pmz/compare.hpp"

namespace {

// Unit square [0,1]^2 at height z, split into n x n quads (two triangles each).
pmz::IndexedMesh square(float z, int n = 1, float size = 1.0f) {
  pmz::IndexedMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      m.positions.insert(m.positions.end(), {size * i / n, size * j / n, z});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
    }
  return m;
}

// Icosphere: icosahedron inscribed in the unit sphere, `levels` midpoint subdivisions with the
// new vertices pushed onto the sphere.
pmz::IndexedMesh icosphere(int levels) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  pmz::IndexedMesh m;
  m.positions = {-1, t,  0,  1, t, 0,  -1, -t, 0,  1, -t, 0, 0,  -1, t,  0,  1, t,
                 0,  -1, -t, 0, 1, -t, t,  0,  -1, t, 0,  1, -t, 0,  -1, -t, 0, 1};
  m.indices = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
               4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
               6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
  auto normalize = [&](uint32_t v) {
    float* p = &m.positions[v * 3];
    float l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (int k = 0; k < 3; ++k) p[k] /= l;
  };
  for (uint32_t v = 0; v < 12; ++v) normalize(v);
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
    auto mid = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      uint32_t v = m.vertex_count();
      for (int k = 0; k < 3; ++k)
        m.positions.push_back(0.5f * (m.positions[a * 3 + k] + m.positions[b * 3 + k]));
      normalize(v);
      midpoints.emplace(key, v);
      return v;
    };
    std::vector<uint32_t> next;
    for (size_t f = 0; f < m.indices.size(); f += 3) {
      uint32_t a = m.indices[f], b = m.indices[f + 1], c = m.indices[f + 2];
      uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    m.indices = std::move(next);
  }
  return m;
}

// Face f (index of its first corner): corner a, edges u = b - a, v = c - a, u x v, area.
struct Face {
  const float* a;
  double u[3], v[3], normal[3], area;
};
Face face(const pmz::IndexedMesh& m, size_t f) {
  Face t;
  t.a = &m.positions[m.indices[f] * 3];
  const float* b = &m.positions[m.indices[f + 1] * 3];
  const float* c = &m.positions[m.indices[f + 2] * 3];
  for (int k = 0; k < 3; ++k) t.u[k] = double(b[k]) - t.a[k], t.v[k] = double(c[k]) - t.a[k];
  const double *u = t.u, *v = t.v;
  t.normal[0] = u[1] * v[2] - u[2] * v[1];
  t.normal[1] = u[2] * v[0] - u[0] * v[2];
  t.normal[2] = u[0] * v[1] - u[1] * v[0];
  t.area = 0.5 * std::sqrt(t.normal[0] * t.normal[0] + t.normal[1] * t.normal[1] +
                           t.normal[2] * t.normal[2]);
  return t;
}

// Smallest distance from the origin to a face plane (the polyhedron's inradius).
double min_face_plane_distance(const pmz::IndexedMesh& m) {
  double best = 1e30;
  for (size_t f = 0; f < m.indices.size(); f += 3) {
    const Face t = face(m, f);
    const double* n = t.normal;
    best = std::min(best, std::abs(n[0] * t.a[0] + n[1] * t.a[1] + n[2] * t.a[2]) / (2 * t.area));
  }
  return best;
}

// Area-weighted mean of (1 - |x|) over the polyhedron's surface, by a dense regular
// barycentric grid on each face (independent of compare's random sampling).
double mean_depth_below_sphere(const pmz::IndexedMesh& m) {
  const int n = 200;
  double sum = 0, area_sum = 0;
  for (size_t f = 0; f < m.indices.size(); f += 3) {
    const Face t = face(m, f);
    const float* a = t.a;
    const double *u = t.u, *v = t.v, area = t.area;
    double face_sum = 0;
    int count = 0;
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        // Centroids of the n^2 equal sub-triangles: upright (i + j <= n-1) and flipped (<= n-2).
        for (int flip = 0; flip < 2; ++flip) {
          if (flip && i + j + 2 > n) continue;
          double s = flip ? (i + 2.0 / 3) / n : (i + 1.0 / 3) / n;
          double r = flip ? (j + 2.0 / 3) / n : (j + 1.0 / 3) / n;
          double p[3];
          for (int k = 0; k < 3; ++k) p[k] = a[k] + s * u[k] + r * v[k];
          face_sum += 1.0 - std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
          ++count;
        }
      }
    sum += area * face_sum / count;
    area_sum += area;
  }
  return sum / area_sum;
}

pmz::CompareResult run(const pmz::IndexedMesh& a, const pmz::IndexedMesh& b,
                       pmz::CompareOptions opt = {}) {
  pmz::CompareResult r;
  std::string err;
  EXPECT_TRUE(pmz::compare(a, b, opt, r, err)) << err;
  return r;
}

}  // namespace

TEST(Compare, ParallelSquaresAreDistanceDApart) {
  const float d = 0.25f;
  pmz::CompareResult r = run(square(0), square(d, 3));
  EXPECT_NEAR(r.diag, std::sqrt(2.0), 1e-6);
  for (const pmz::DistanceStats* s : {&r.forward, &r.backward, &r.symmetric}) {
    EXPECT_NEAR(s->max, d, 1e-6);
    EXPECT_NEAR(s->mean, d, 1e-6);
    EXPECT_NEAR(s->rms, d, 1e-6);
    EXPECT_GT(s->samples, 100000u);
  }
}

TEST(Compare, IdenticalMeshesAreZero) {
  pmz::IndexedMesh m = icosphere(3);
  pmz::CompareResult r = run(m, m);
  EXPECT_LT(r.symmetric.max, 1e-6);
  EXPECT_LT(r.symmetric.mean, 1e-7);
}

TEST(Compare, OneSidedDistanceOfASubsetIsZero) {
  // A 1x1 square against the 2x2 square containing it: every point of the small one lies on
  // the big one (forward 0), but the far corner of the big one is sqrt(2) from the small one.
  pmz::IndexedMesh small = square(0, 2), big = square(0, 4, 2.0f);
  pmz::CompareResult r = run(small, big);
  EXPECT_LT(r.forward.max, 1e-6);
  EXPECT_NEAR(r.backward.max, std::sqrt(2.0), 2e-3);
  EXPECT_NEAR(r.symmetric.max, r.backward.max, 0);
  // The max is found at that corner, a vertex of the big square.
  EXPECT_EQ(r.symmetric.max_on, pmz::DistanceStats::Site::vertex);
  EXPECT_EQ(r.symmetric.max_at[0], 2.0);
  EXPECT_EQ(r.symmetric.max_at[1], 2.0);
  EXPECT_EQ(r.symmetric.max_at[2], 0.0);
  // Mean of the distance to the unit square over [0,2]^2: 3/4 of the area is outside it.
  EXPECT_GT(r.backward.mean, 0.3);
  EXPECT_NEAR(r.symmetric.mean, 0.5 * r.backward.mean, 1e-12);

  pmz::CompareOptions one_sided;
  one_sided.both_directions = false;
  pmz::CompareResult f = run(small, big, one_sided);
  EXPECT_EQ(f.backward.samples, 0u);
  EXPECT_EQ(f.symmetric.max, f.forward.max);
}

TEST(Compare, SphereAgainstInscribedIcosphereMeetsTheBounds) {
  // "Sphere": a level-5 icosphere (20480 faces), within eps of the unit sphere.
  // Coarse: the icosahedron (level 0) and level 1, inscribed in the unit sphere.
  const pmz::IndexedMesh sphere = icosphere(5);
  const double eps = 1.0 - min_face_plane_distance(sphere);
  ASSERT_LT(eps, 5e-4);
  // The icosahedron's inradius for circumradius 1: sqrt((5 + 2 sqrt 5) / 15) = 0.794654...
  EXPECT_NEAR(min_face_plane_distance(icosphere(0)), std::sqrt((5 + 2 * std::sqrt(5.0)) / 15),
              1e-6);
  for (int level : {0, 1}) {
    const pmz::IndexedMesh coarse = icosphere(level);
    const double h = min_face_plane_distance(coarse);
    // Both meshes are convex and star-shaped around 0; a point at direction n of the face with
    // the smallest plane distance h is 1 - h from the coarse mesh (its foot is the face's
    // circumcenter, inside the acute face), and no point of either surface is farther than 1 - h
    // from the other (radial segment). Hence max = 1 - h, up to eps and sampling density.
    pmz::CompareResult r = run(sphere, coarse);
    SCOPED_TRACE(level);
    EXPECT_LE(r.forward.max, 1 - h + 1e-6);
    EXPECT_GE(r.forward.max, 1 - h - eps - 0.02 * (1 - h));
    EXPECT_LE(r.backward.max, 1 - h + 1e-6);
    EXPECT_GE(r.backward.max, 1 - h - eps - 0.02 * (1 - h));
    // Backward (coarse -> sphere): distance is 1 - |x| up to eps; its mean is an integral.
    const double expected_mean = mean_depth_below_sphere(coarse);
    EXPECT_NEAR(r.backward.mean, expected_mean, 0.01 * expected_mean + eps);
    // Forward mean: each sphere point is no farther than radially, so it is below the
    // radial mean, and positive.
    EXPECT_GT(r.forward.mean, 0.2 * expected_mean);
    EXPECT_LT(r.forward.mean, r.forward.max);
  }
}

TEST(Compare, DeterministicAndThreadIndependent) {
  pmz::IndexedMesh a = icosphere(4), b = icosphere(2);
  pmz::CompareOptions one, two;
  one.threads = 1;
  two.threads = 2;
  pmz::CompareResult r1 = run(a, b, one), r2 = run(a, b, two), r3 = run(a, b, two);
  EXPECT_EQ(r1.symmetric.mean, r2.symmetric.mean);
  EXPECT_EQ(r1.symmetric.max, r2.symmetric.max);
  EXPECT_EQ(r2.symmetric.rms, r3.symmetric.rms);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(r1.symmetric.max_at[k], r2.symmetric.max_at[k]);
}

TEST(Compare, RejectsBadInput) {
  pmz::IndexedMesh empty, bad = square(0);
  bad.indices[4] = 99;
  pmz::CompareResult r;
  std::string err;
  EXPECT_FALSE(pmz::compare(empty, square(0), {}, r, err));
  EXPECT_NE(err.find("no faces"), std::string::npos);
  EXPECT_FALSE(pmz::compare(square(0), bad, {}, r, err));
  EXPECT_NE(err.find("out of range"), std::string::npos);
}
