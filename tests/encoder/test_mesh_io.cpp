#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "pmz/mesh.hpp"

namespace fs = std::filesystem;

static std::string write_temp(const std::string& name, const std::string& text) {
  fs::path p = fs::temp_directory_path() / ("pmz_test_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(p) << text;
  return p.string();
}

TEST(MeshIO, ReadsOffAndTriangulatesQuads) {
  auto path = write_temp("quad.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
  pmz::IndexedMesh m;
  std::string err;
  ASSERT_TRUE(pmz::read_mesh(path, m, err)) << err;
  EXPECT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.face_count(), 2u);
  fs::remove(path);
}

TEST(MeshIO, RefusesMissingFile) {
  pmz::IndexedMesh m;
  std::string err;
  EXPECT_FALSE(pmz::read_mesh("/nonexistent/x.off", m, err));
  EXPECT_NE(err.find("no such file"), std::string::npos);
}

TEST(MeshIO, WriteThenReadRoundTrips) {
  pmz::IndexedMesh m;
  m.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  m.indices = {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2};
  fs::path p = fs::temp_directory_path() / ("pmz_test_" + std::to_string(::getpid()) + "_tet.off");
  std::string err;
  ASSERT_TRUE(pmz::write_mesh(p.string(), m, err)) << err;
  pmz::IndexedMesh r;
  ASSERT_TRUE(pmz::read_mesh(p.string(), r, err)) << err;
  EXPECT_EQ(r.positions, m.positions);
  EXPECT_EQ(r.indices, m.indices);
  fs::remove(p);
}
