// SPDX-License-Identifier: MIT
// Reading a mesh file as a stream (pmz/mesh_stream.hpp): through a window of any size, down to
// one byte, the readers give the soup (or the error) that the same bytes give from memory, for
// files whose lines, tokens and records cross the window's boundaries; a file cut at any byte
// gives the same one line; a file larger than the default window reads as from memory.
#include <gtest/gtest.h>

#include <bit>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "pmz/mesh.hpp"
#include "pmz/mesh_stream.hpp"
#include "test_mesh_input_util.hpp"

namespace {

using pmz_test::TempDir;
namespace fs = std::filesystem;

void expect_same_soup(const pmz::PolygonSoup& a, const pmz::PolygonSoup& b) {
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.corners, b.corners);
  EXPECT_EQ(a.face_offsets, b.face_offsets);
  EXPECT_EQ(a.welded_vertices, b.welded_vertices);
  const pmz::SoupAttributes &x = a.attributes, &y = b.attributes;
  EXPECT_EQ(x.texcoords, y.texcoords);
  EXPECT_EQ(x.corner_texcoords, y.corner_texcoords);
  EXPECT_EQ(x.normals, y.normals);
  EXPECT_EQ(x.corner_normals, y.corner_normals);
  EXPECT_EQ(x.colors, y.colors);
  EXPECT_EQ(x.color_components, y.color_components);
  EXPECT_EQ(x.corner_colors, y.corner_colors);
  EXPECT_EQ(x.face_materials, y.face_materials);
  EXPECT_EQ(x.materials, y.materials);
  EXPECT_EQ(x.material_library, y.material_library);
}

// `bytes` as the file `name` read through a window of `window` bytes, against the same bytes
// parsed from memory: the same result, soup or error. Returns whether it read. `on_disk`: a
// file written to the temporary directory, else the bytes through fmemopen (a seekable FILE).
bool expect_stream_as_memory(const TempDir& tmp, const std::string& name, std::string bytes,
                             size_t window, bool on_disk = true) {
  const std::string path = on_disk || bytes.empty() ? tmp.write(name, bytes) : tmp.path(name);
  pmz::PolygonSoup memory, streamed;
  std::string memory_error, stream_error;
  const bool memory_ok = pmz::parse_polygon_soup(path, bytes, memory, memory_error);
  std::FILE* f = on_disk || bytes.empty() ? std::fopen(path.c_str(), "rb")
                                          : ::fmemopen(bytes.data(), bytes.size(), "rb");
  EXPECT_NE(f, nullptr);
  if (!f) return false;
  const bool stream_ok = pmz::read_polygon_soup(path, f, streamed, stream_error, {}, window);
  std::fclose(f);
  EXPECT_EQ(stream_ok, memory_ok) << name << " window " << window << ": " << stream_error;
  EXPECT_EQ(stream_error, memory_error) << name << " window " << window;
  if (memory_ok && stream_ok) expect_same_soup(streamed, memory);
  return stream_ok;
}

std::string le32(uint32_t v) { return {char(v), char(v >> 8), char(v >> 16), char(v >> 24)}; }
std::string be32(uint32_t v) { return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)}; }
std::string lef(float f) { return le32(std::bit_cast<uint32_t>(f)); }
std::string bef(float f) { return be32(std::bit_cast<uint32_t>(f)); }

// A small grid of n x n vertices (two triangles per cell), its coordinates with many digits so
// that tokens cross small windows.
struct Grid {
  int n;
  float x(int i) const { return float(i % n) * 0.1234567f - 0.5f; }
  float y(int i) const { return float(i / n) * 0.7654321f + 1e-3f; }
  float z(int i) const { return float((i * 7919) % 13) * -0.0625f; }
  int vertices() const { return n * n; }
  int faces() const { return (n - 1) * (n - 1) * 2; }
  template <typename F>
  void each_face(F f) const {
    for (int r = 0; r + 1 < n; ++r)
      for (int c = 0; c + 1 < n; ++c) {
        const int a = r * n + c;
        f(a, a + 1, a + n + 1);
        f(a, a + n + 1, a + n);
      }
  }
};

std::string text(float v) {
  std::ostringstream s;
  s.precision(9);
  s << v;
  return s.str();
}

std::string ascii_ply(const Grid& g) {
  std::string s = "ply\r\nformat ascii 1.0\ncomment crossing windows\nelement vertex " +
                  std::to_string(g.vertices()) +
                  "\nproperty float x\nproperty float y\nproperty float z\n"
                  "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face " +
                  std::to_string(g.faces()) +
                  "\nproperty list uchar int vertex_indices\nend_header\n";
  for (int i = 0; i < g.vertices(); ++i)
    s += text(g.x(i)) + "  " + text(g.y(i)) + "\t" + text(g.z(i)) + " " + std::to_string(i % 256) +
         " 7 " + std::to_string((i * 3) % 256) + "\n";
  g.each_face([&](int a, int b, int c) {
    s += "3 " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(c) + "\n";
  });
  return s;
}

std::string binary_ply(const Grid& g, bool big_endian) {
  auto u32 = big_endian ? be32 : le32;
  auto f32 = big_endian ? bef : lef;
  std::string s =
      std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
      " 1.0\nelement vertex " + std::to_string(g.vertices()) +
      "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\n"
      "property float ny\nproperty float nz\nelement face " +
      std::to_string(g.faces()) + "\nproperty list uchar uint vertex_indices\nend_header\n";
  for (int i = 0; i < g.vertices(); ++i)
    s += f32(g.x(i)) + f32(g.y(i)) + f32(g.z(i)) + f32(0) + f32(0.6f) + f32(0.8f);
  g.each_face([&](int a, int b, int c) {
    s += '\3' + u32(uint32_t(a)) + u32(uint32_t(b)) + u32(uint32_t(c));
  });
  return s;
}

std::string obj(const Grid& g) {
  std::string s = "# grid\nmtllib none.mtl\n";
  for (int i = 0; i < g.vertices(); ++i)
    s += "v " + text(g.x(i)) + " " + text(g.y(i)) + " " + text(g.z(i)) + "\nvt " +
         text(g.x(i) + 0.5f) + " " + text(g.y(i)) + "\n";
  s += "vn 0 0 1\nusemtl first\n";
  int f = 0;
  g.each_face([&](int a, int b, int c) {
    if (f++ == g.faces() / 2) s += "usemtl second # half way\n";
    s += "f " + std::to_string(a + 1) + "/" + std::to_string(a + 1) + "/1 " +
         std::to_string(b + 1) + "/" + std::to_string(b + 1) + "/1 " + std::to_string(c + 1) + "/" +
         std::to_string(c + 1) + "/1\n";
  });
  return s;
}

std::string off(const Grid& g) {
  std::string s = "OFF\n# counts next\n\n" + std::to_string(g.vertices()) + " " +
                  std::to_string(g.faces()) + " 0\n";
  for (int i = 0; i < g.vertices(); ++i)
    s += text(g.x(i)) + " " + text(g.y(i)) + " " + text(g.z(i)) + "\n";
  g.each_face([&](int a, int b, int c) {
    s += "3 " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(c) + "\n";
  });
  return s;
}

// OpenMesh's layout: little endian, no colour count after a face.
std::string binary_off(const Grid& g) {
  std::string s =
      "OFF BINARY\n" + le32(uint32_t(g.vertices())) + le32(uint32_t(g.faces())) + le32(0);
  for (int i = 0; i < g.vertices(); ++i) s += lef(g.x(i)) + lef(g.y(i)) + lef(g.z(i));
  g.each_face([&](int a, int b, int c) {
    s += le32(3) + le32(uint32_t(a)) + le32(uint32_t(b)) + le32(uint32_t(c));
  });
  return s;
}

std::string ascii_stl(const Grid& g) {
  std::string s = "solid grid\n";
  g.each_face([&](int a, int b, int c) {
    s += "  facet normal 0 0 1\n    outer loop\n";
    for (int v : {a, b, c})
      s += "      vertex " + text(g.x(v)) + " " + text(g.y(v)) + " " + text(g.z(v)) + "\n";
    s += "    endloop\n  endfacet\n";
  });
  return s + "endsolid grid\n";
}

std::string binary_stl(const Grid& g) {
  std::string s(80, ' ');
  s += le32(uint32_t(g.faces()));
  g.each_face([&](int a, int b, int c) {
    s += lef(0) + lef(0) + lef(1);
    for (int v : {a, b, c}) s += lef(g.x(v)) + lef(g.y(v)) + lef(g.z(v));
    s += std::string(2, '\0');
  });
  return s;
}

struct Sample {
  std::string name, bytes;
  bool truncation_refused;  // every proper prefix is refused (the format states its counts)
};

std::vector<Sample> samples(const Grid& g) {
  return {{"grid.ply", ascii_ply(g), false},
          {"grid-le.ply", binary_ply(g, false), true},
          {"grid-be.ply", binary_ply(g, true), true},
          {"grid.obj", obj(g), false},
          {"grid.off", off(g), false},
          {"grid-binary.off", binary_off(g), true},
          {"grid-ascii.stl", ascii_stl(g), false},
          {"grid.stl", binary_stl(g), true}};
}

TEST(MeshStream, AnyWindowReadsTheSoupOfMemory) {
  TempDir tmp;
  for (const Sample& s : samples(Grid{6}))
    for (size_t window : {1, 2, 3, 5, 7, 16, 61, 256, 4096})
      EXPECT_TRUE(expect_stream_as_memory(tmp, s.name, s.bytes, window)) << s.name;
}

TEST(MeshStream, AFileCutAtAnyByteGivesTheErrorOfMemory) {
  TempDir tmp;
  for (const Sample& s : samples(Grid{3}))
    for (size_t cut = 0; cut < s.bytes.size(); ++cut)
      for (size_t window : {1, 7, 64}) {
        const bool ok = expect_stream_as_memory(tmp, s.name, s.bytes.substr(0, cut), window, false);
        if (s.truncation_refused) {
          EXPECT_FALSE(ok) << s.name << " cut at " << cut;
        }
      }
}

TEST(MeshStream, TheFuzzRegressionsReadAsFromMemory) {
  TempDir tmp;
  const fs::path dir = fs::path(PMZ_SOURCE_DIR) / "tests" / "data" / "fuzz-regressions";
  int read = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".ply" && ext != ".obj" && ext != ".off" && ext != ".stl") continue;
    std::ifstream in(entry.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    for (size_t window : {1, 3, 64})
      expect_stream_as_memory(tmp, entry.path().filename().string(), bytes, window);
    ++read;
  }
  EXPECT_GT(read, 0);
}

// Larger than the default window (kReadWindow): read_polygon_soup by path streams it.
TEST(MeshStream, AFileLargerThanTheWindowReadsAsFromMemory) {
  TempDir tmp;
  const Grid g{300};
  for (const std::string& bytes : {ascii_ply(g), binary_ply(g, false)}) {
    ASSERT_GT(bytes.size(), pmz::kReadWindow);
    const std::string path = tmp.write("large.ply", bytes);
    pmz::PolygonSoup memory, streamed;
    std::string error;
    ASSERT_TRUE(pmz::parse_polygon_soup(path, bytes, memory, error)) << error;
    ASSERT_TRUE(pmz::read_polygon_soup(path, streamed, error)) << error;
    EXPECT_EQ(streamed.face_count(), uint32_t(g.faces()));
    expect_same_soup(streamed, memory);
    // Cut inside the last face (a corner short): one line naming the file.
    const std::string cut = tmp.write("cut.ply", bytes.substr(0, bytes.size() - 10));
    EXPECT_FALSE(pmz::read_polygon_soup(cut, streamed, error));
    EXPECT_EQ(error.rfind(cut + ": ", 0), 0u) << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  }
}

// A file that cannot seek (a pipe) is read whole, with the same result.
TEST(MeshStream, APipeReadsAsAFile) {
  TempDir tmp;
  const std::string bytes = ascii_ply(Grid{5});
  const std::string path = tmp.write("piped.ply", bytes);
  std::FILE* pipe = ::popen(("cat '" + path + "'").c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  pmz::PolygonSoup piped, memory;
  std::string error;
  ASSERT_TRUE(pmz::read_polygon_soup(path, pipe, piped, error, {}, 3)) << error;
  ::pclose(pipe);
  ASSERT_TRUE(pmz::parse_polygon_soup(path, bytes, memory, error)) << error;
  expect_same_soup(piped, memory);
}

}  // namespace
