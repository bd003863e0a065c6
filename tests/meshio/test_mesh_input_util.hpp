// SPDX-License-Identifier: MIT
// What the mesh input tests share: temporary files and the manifold/face-kept checks.
#pragma once
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <string>
#include <vector>

#include "pmz/mesh.hpp"

namespace pmz_test {

namespace fs = std::filesystem;

// A fresh directory per test, removed at the end.
struct TempDir {
  fs::path dir;
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir = fs::temp_directory_path() / ("pmz_io_" + std::to_string(::getpid()) + "_" +
                                       info->test_suite_name() + "_" + info->name());
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~TempDir() { fs::remove_all(dir); }
  std::string write(const std::string& name, const std::string& bytes) const {
    fs::path p = dir / name;
    std::ofstream(p, std::ios::binary) << bytes;
    return p.string();
  }
  std::string path(const std::string& name) const { return (dir / name).string(); }
};

// read_mesh refuses the file with one line naming it and saying `what`, and returns no faces.
inline void expect_refused(const std::string& path, const std::string& what) {
  pmz::IndexedMesh m;
  pmz::MeshRepairStats st;
  std::string err;
  EXPECT_FALSE(pmz::read_mesh(path, m, st, err)) << path;
  EXPECT_NE(err.find(what), std::string::npos) << "message: " << err;
  EXPECT_EQ(err.rfind(path, 0), 0u) << "message: " << err;
  EXPECT_EQ(err.find('\n'), std::string::npos) << "message: " << err;
  EXPECT_EQ(m.face_count(), 0u);
}

// Every undirected edge has at most two faces, of opposite orientation, and the faces around
// every used vertex form one fan (connected through shared edges). Empty string when manifold.
inline std::string manifold_problem(const pmz::IndexedMesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>>
      edge_faces;  // directed edge -> faces
  const uint32_t nf = m.face_count();
  for (uint32_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = m.indices[f * 3 + k], b = m.indices[f * 3 + (k + 1) % 3];
      if (a == b) return "face " + std::to_string(f) + " repeats a vertex";
      edge_faces[{a, b}].push_back(f);
    }
  for (const auto& [e, faces] : edge_faces) {
    if (faces.size() > 1) return "directed edge used by two faces";
    if (e.first < e.second) continue;
    auto it = edge_faces.find({e.second, e.first});
    if (it != edge_faces.end() && it->second.size() > 1) return "edge with 3+ faces";
  }
  std::vector<std::vector<uint32_t>> vertex_faces(m.vertex_count());
  for (uint32_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) vertex_faces[m.indices[f * 3 + k]].push_back(f);
  for (uint32_t v = 0; v < m.vertex_count(); ++v) {
    const auto& faces = vertex_faces[v];
    if (faces.size() < 2) continue;
    // Flood through faces sharing an edge (v, x).
    std::vector<char> reached(faces.size(), 0);
    std::vector<size_t> stack = {0};
    reached[0] = 1;
    size_t count = 1;
    while (!stack.empty()) {
      uint32_t f = faces[stack.back()];
      stack.pop_back();
      for (size_t j = 0; j < faces.size(); ++j) {
        if (reached[j]) continue;
        int shared = 0;
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) shared += m.indices[f * 3 + a] == m.indices[faces[j] * 3 + b];
        if (shared >= 2) reached[j] = 1, ++count, stack.push_back(j);
      }
    }
    if (count != faces.size()) return "vertex " + std::to_string(v) + " has several fans";
  }
  return "";
}

// Flat soup from a list of faces (any corner count).
inline pmz::PolygonSoup soup(std::vector<float> positions,
                             const std::vector<std::vector<uint32_t>>& faces) {
  pmz::PolygonSoup s;
  s.positions = std::move(positions);
  s.face_offsets.push_back(0);
  for (const auto& f : faces) {
    s.corners.insert(s.corners.end(), f.begin(), f.end());
    s.face_offsets.push_back(uint32_t(s.corners.size()));
  }
  return s;
}

// For an all-triangle soup without degenerate faces: the repaired mesh has the same faces in the
// same order, each corner at the same position as in the input, and the input vertices first.
inline void expect_same_triangles(const pmz::PolygonSoup& in, const pmz::IndexedMesh& out) {
  ASSERT_EQ(out.face_count(), in.face_count());
  ASSERT_GE(out.vertex_count(), in.vertex_count());
  EXPECT_TRUE(std::equal(in.positions.begin(), in.positions.end(), out.positions.begin()));
  for (size_t c = 0; c < in.corners.size(); ++c)
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(out.positions[size_t(out.indices[c]) * 3 + k],
                in.positions[size_t(in.corners[c]) * 3 + k])
          << "corner " << c;
}

}  // namespace pmz_test
