// SPDX-License-Identifier: MIT
// The procedural terrain (samples/include/pmz/terrain.hpp): the PLY it streams is what its
// header says, reads back as a manifold grid, and the same size and seed give the same bytes.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "pmz/mesh.hpp"
#include "pmz/terrain.hpp"

namespace {

std::vector<uint8_t> terrain(uint64_t faces, uint64_t seed) {
  std::vector<uint8_t> bytes;
  pmz::TerrainOptions options;
  options.faces = faces;
  options.seed = seed;
  EXPECT_TRUE(pmz::write_terrain_ply(options, [&](const void* p, size_t n) {
    bytes.insert(bytes.end(), static_cast<const uint8_t*>(p), static_cast<const uint8_t*>(p) + n);
    return true;
  }));
  return bytes;
}

TEST(Terrain, ReadsBackAsTheGridItsHeaderStates) {
  const std::vector<uint8_t> bytes = terrain(20000, 7);
  const uint32_t n = pmz::terrain_grid_side(20000);
  EXPECT_EQ(n, 101u);
  const std::string path = testing::TempDir() + "terrain_test.ply";
  {
    std::ofstream f(path, std::ios::binary);
    f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  }
  pmz::IndexedMesh mesh;
  std::string error;
  ASSERT_TRUE(pmz::read_mesh(path, mesh, error)) << error;
  std::remove(path.c_str());
  ASSERT_EQ(mesh.vertex_count(), n * n);
  ASSERT_EQ(mesh.face_count(), 2 * (n - 1) * (n - 1));
  // Vertices on the unit square, heights from terrain_height.
  for (uint32_t j = 0; j < n; j += 17)
    for (uint32_t i = 0; i < n; i += 13) {
      const float* p = &mesh.positions[size_t(j * n + i) * 3];
      EXPECT_FLOAT_EQ(p[0], float(i / double(n - 1)));
      EXPECT_FLOAT_EQ(p[1], float(j / double(n - 1)));
      EXPECT_EQ(p[2], pmz::terrain_height(i / double(n - 1), j / double(n - 1), 7));
    }
  // Every directed edge once, faces facing +z (counter-clockwise seen from above).
  std::set<std::pair<uint32_t, uint32_t>> edges;
  for (uint32_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* t = &mesh.indices[size_t(f) * 3];
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(edges.insert({t[k], t[(k + 1) % 3]}).second);
    const float* a = &mesh.positions[size_t(t[0]) * 3];
    const float* b = &mesh.positions[size_t(t[1]) * 3];
    const float* c = &mesh.positions[size_t(t[2]) * 3];
    EXPECT_GT((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]), 0) << "face " << f;
  }
  // Relief: not flat, and not noise without scale (heights within a sane band).
  float lo = 1, hi = -1;
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v)
    lo = std::min(lo, mesh.positions[v * 3 + 2]), hi = std::max(hi, mesh.positions[v * 3 + 2]);
  EXPECT_GT(hi - lo, 0.05f);
  EXPECT_LT(hi - lo, 1.0f);
}

TEST(Terrain, SameSizeAndSeedSameBytesOtherSeedOtherRelief) {
  const std::vector<uint8_t> a = terrain(5000, 3), b = terrain(5000, 3), c = terrain(5000, 4);
  EXPECT_EQ(a, b);
  ASSERT_EQ(a.size(), c.size());
  EXPECT_NE(a, c);
}

TEST(Terrain, AStoppedWriterStopsTheTerrain) {
  pmz::TerrainOptions options;
  options.faces = 5000;
  size_t calls = 0;
  EXPECT_FALSE(pmz::write_terrain_ply(options, [&](const void*, size_t) { return ++calls < 3; }));
  EXPECT_EQ(calls, 3u);
}

}  // namespace
