// SPDX-License-Identifier: MIT
// pmz::compare's attribute error at corresponding surface points, on cases with known answers.
#include <gtest/gtest.h>

#include <cmath>

#include "../encoder/seamed_grid.hpp"
#include "pmz/compare.hpp"

namespace {

// The unit square split into n x n quads, one wedge per vertex: texture coordinates
// (x, y) + uv_offset, normal (0, sin a, cos a), colour (x, y, 0) + red.
pmz::IndexedMesh square(int n, float uv_offset = 0, float normal_angle = 0, float red = 0) {
  pmz::IndexedMesh m;
  pmz::MeshAttributes& a = m.attributes;
  a.texcoords.resize(1);
  a.color_components = 3;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const float x = float(i) / n, y = float(j) / n;
      m.positions.insert(m.positions.end(), {x, y, 0.f});
      a.wedge_vertices.push_back(uint32_t(a.wedge_vertices.size()));
      a.texcoords[0].insert(a.texcoords[0].end(), {x + uv_offset, y + uv_offset});
      a.normals.insert(a.normals.end(), {0.f, std::sin(normal_angle), std::cos(normal_angle)});
      a.colors.insert(a.colors.end(), {x + red, y, 0.f});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t p = uint32_t(j * (n + 1) + i), q = p + 1, r = p + uint32_t(n) + 1, s = r + 1;
      m.indices.insert(m.indices.end(), {p, q, s, p, s, r});
    }
  m.attributes.corner_wedges = m.indices;
  return m;
}

pmz::AttributeErrors measure(const pmz::IndexedMesh& a, const pmz::IndexedMesh& b) {
  pmz::CompareResult r;
  std::string error;
  pmz::CompareOptions options;
  options.samples = 20000;
  EXPECT_TRUE(pmz::compare(a, b, options, r, error)) << error;
  return r.attributes;
}

// A linear field is reproduced exactly by a coarser mesh of the same plane: no error.
TEST(CompareAttributes, LinearFieldOnACoarserMeshHasNoError) {
  const pmz::AttributeErrors e = measure(square(16), square(1));
  EXPECT_GT(e.texcoord.samples, 10000u);
  EXPECT_LT(e.texcoord.max, 1e-6);
  EXPECT_LT(e.normal.max, 1e-3);  // degrees
  EXPECT_LT(e.color.max, 1e-6);
}

// Known offsets: |(0.03, 0.03)| in texture space, 10 degrees, 0.1 in red.
TEST(CompareAttributes, KnownOffsetsAreMeasured) {
  const float angle = 10.f * float(M_PI) / 180.f;
  const pmz::AttributeErrors e = measure(square(16), square(3, 0.03f, angle, 0.1f));
  const double uv = 0.03 * std::sqrt(2.0);
  EXPECT_NEAR(e.texcoord.mean, uv, 1e-6);
  EXPECT_NEAR(e.texcoord.rms, uv, 1e-6);
  EXPECT_NEAR(e.texcoord.max, uv, 1e-6);
  EXPECT_NEAR(e.normal.mean, 10.0, 1e-3);
  EXPECT_NEAR(e.color.mean, 0.1, 1e-6);
}

// A field that is not linear (u = x^2 at the fine mesh's vertices) against its linear
// interpolation on one quad: the error is the interpolation's, x(1 - x) on average 1/6 minus
// the fine mesh's own interpolation error (1/6 - 1/(6 n^2)); the sampled mean agrees closely.
TEST(CompareAttributes, InterpolationErrorOfAQuadraticField) {
  const int n = 16;
  pmz::IndexedMesh fine = square(n), coarse = square(1);
  for (uint32_t w = 0; w < fine.attributes.wedge_count(); ++w) {
    const float x = fine.positions[size_t(w) * 3];
    fine.attributes.texcoords[0][size_t(w) * 2] = x * x;
  }
  const pmz::AttributeErrors e = measure(fine, coarse);
  EXPECT_NEAR(e.texcoord.mean, 1.0 / 6.0 - 1.0 / (6.0 * n * n), 2e-3);
  EXPECT_NEAR(e.texcoord.max, 0.25, 2e-3);
}

// The seamed grid (16 x 16, seam at column 7: u jumps by about 0.5 there) with the seam's
// vertices moved by 0.002 in x, as quantizing positions moves them: samples of the right chart
// within 0.002 of the seam now find the left chart's faces nearest. The faces across the seam
// count too, so the error stays that of the moved geometry (below 0.4 * 0.002 in u), not the
// jump.
pmz::IndexedMesh moved_seam() {
  pmz::IndexedMesh m = pmz_test::seamed_grid(16, 7);
  for (uint32_t j = 0; j <= 16; ++j)
    m.positions[size_t(pmz_test::grid_vertex(16, 7, j)) * 3] += 0.002f;
  return m;
}

TEST(CompareAttributes, AMovedSeamIsNotAChartJump) {
  const pmz::AttributeErrors e = measure(pmz_test::seamed_grid(16, 7), moved_seam());
  EXPECT_GT(e.texcoord.samples, 10000u);
  EXPECT_LT(e.texcoord.max, 0.002);
  EXPECT_LT(e.texcoord.mean, 1e-3);
}

// A real error at the same moved seam is still measured: u + 0.05 on every corner of the right
// chart gives 0.05 on that chart (the left chart's values across the seam, 0.5 away, do not
// hide it) and none on the left, so the mean is 0.05 times the right chart's share of the area.
TEST(CompareAttributes, AShiftedChartAtAMovedSeamIsMeasured) {
  const pmz::IndexedMesh original = pmz_test::seamed_grid(16, 7);
  pmz::IndexedMesh shifted = moved_seam();
  std::vector<float>& uv = shifted.attributes.texcoords[0];
  for (size_t w = 0; w < uv.size(); w += 2)
    if (uv[w] > 0.5f) uv[w] += 0.05f;  // the right chart: u >= 0.55
  double area[2] = {0, 0};
  for (uint32_t f = 0; f < original.face_count(); ++f) {
    const float* p[3];
    for (int k = 0; k < 3; ++k) p[k] = &original.positions[size_t(original.indices[f * 3 + k]) * 3];
    double a[3], b[3];
    for (int k = 0; k < 3; ++k) a[k] = p[1][k] - p[0][k], b[k] = p[2][k] - p[0][k];
    const double x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2],
                 z = a[0] * b[1] - a[1] * b[0];
    area[original.attributes.face_materials[f]] += 0.5 * std::sqrt(x * x + y * y + z * z);
  }
  const pmz::AttributeErrors e = measure(original, shifted);
  EXPECT_NEAR(e.texcoord.max, 0.05, 0.002);
  EXPECT_NEAR(e.texcoord.mean, 0.05 * area[1] / (area[0] + area[1]), 0.002);
}

// Two sheets that cross (a surface that passes through itself), each its own chart: the unit
// square at z = lift (u, v = x, y) and a 5 x 5 square tilted through it along x = 0.5 (u, v =
// x + 0.5, y + 0.5). Lifting the flat one by 1e-3 puts the tilted sheet nearest to its samples
// within about 2e-3 of the crossing; its own chart, 1e-3 away, is the one compared: no error,
// not the 0.7 between the charts.
TEST(CompareAttributes, ACrossingSheetOfAnotherChartIsNotTheCorrespondent) {
  auto sheets = [](float lift) {
    pmz::IndexedMesh m = square(4);
    const pmz::IndexedMesh tilted = square(5, 0.5f);
    const uint32_t nv = m.vertex_count(), nw = m.attributes.wedge_count();
    for (size_t i = 0; i < m.positions.size(); i += 3) m.positions[i + 2] = lift;
    for (size_t i = 0; i < tilted.positions.size(); i += 3) {
      const float x = tilted.positions[i];
      m.positions.insert(m.positions.end(), {x, tilted.positions[i + 1], 0.5f * (x - 0.5f)});
    }
    pmz::MeshAttributes& a = m.attributes;
    const pmz::MeshAttributes& b = tilted.attributes;
    for (uint32_t i = 0; i < tilted.indices.size(); ++i)
      m.indices.push_back(nv + tilted.indices[i]),
          a.corner_wedges.push_back(nw + b.corner_wedges[i]);
    for (uint32_t v : b.wedge_vertices) a.wedge_vertices.push_back(nv + v);
    a.texcoords[0].insert(a.texcoords[0].end(), b.texcoords[0].begin(), b.texcoords[0].end());
    a.normals.insert(a.normals.end(), b.normals.begin(), b.normals.end());
    a.colors.insert(a.colors.end(), b.colors.begin(), b.colors.end());
    return m;
  };
  const pmz::AttributeErrors e = measure(sheets(0), sheets(1e-3f));
  EXPECT_GT(e.texcoord.samples, 10000u);
  EXPECT_LT(e.texcoord.max, 1e-6);
}

// Attributes only one mesh has are not measured.
TEST(CompareAttributes, MissingAttributesAreNotMeasured) {
  pmz::IndexedMesh bare = square(2);
  bare.attributes = {};
  EXPECT_EQ(measure(square(4), bare).texcoord.samples, 0u);
  pmz::IndexedMesh no_normals = square(2);
  no_normals.attributes.normals.clear();
  const pmz::AttributeErrors e = measure(square(4), no_normals);
  EXPECT_EQ(e.normal.samples, 0u);
  EXPECT_GT(e.texcoord.samples, 0u);
}

}  // namespace
