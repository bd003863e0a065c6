// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <map>
#include <utility>

#include "pmz/sample_mesh.hpp"

// The sample is a closed, consistently oriented, genus-0 manifold of about the asked size.
TEST(SampleMesh, IsClosedOrientedManifoldSphere) {
  pmz::IndexedMesh m = pmz::make_sample_mesh(50000);
  EXPECT_GT(m.face_count(), 40000u);
  EXPECT_LT(m.face_count(), 60000u);
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (uint32_t f = 0; f < m.face_count(); ++f)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = m.indices[f * 3 + k], b = m.indices[f * 3 + (k + 1) % 3];
      ASSERT_NE(a, b);
      ++directed[{a, b}];
    }
  for (const auto& [e, n] : directed) {
    EXPECT_EQ(n, 1) << "directed edge used twice";
    EXPECT_EQ(directed.count({e.second, e.first}), 1u) << "open or flipped edge";
  }
  long long V = m.vertex_count(), E = long(directed.size()) / 2, F = m.face_count();
  EXPECT_EQ(V - E + F, 2);
  // Outward orientation: the signed volume is positive.
  double vol = 0;
  for (uint32_t f = 0; f < m.face_count(); ++f) {
    const float* a = &m.positions[m.indices[f * 3] * 3];
    const float* b = &m.positions[m.indices[f * 3 + 1] * 3];
    const float* c = &m.positions[m.indices[f * 3 + 2] * 3];
    vol += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
            a[2] * (b[0] * c[1] - b[1] * c[0])) /
           6.0;
  }
  EXPECT_GT(vol, 4.0);  // about pi * r^2 * h = 2 pi, less the groove
}
