// SPDX-License-Identifier: MIT
// The list of mesh file formats (pmz/mesh_file_formats.hpp) against what meshio's readers and
// writers do: a format listed as written is written, one listed as read is parsed, and nothing
// else is; the glTF buffer files a reader would look up are found.
#include <gtest/gtest.h>

#include <string>

#include "pmz/mesh.hpp"
#include "pmz/mesh_file_formats.hpp"

namespace {

pmz::IndexedMesh triangle() {
  pmz::IndexedMesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  mesh.indices = {0, 1, 2};
  return mesh;
}

// The bytes meshio writes as `format`, or "" when it refuses.
std::string written(const std::string& format) {
  std::string bytes, error;
  const pmz::MeshSink sink = [&](const void* data, size_t size) {
    bytes.append(static_cast<const char*>(data), size);
    return true;
  };
  return pmz::write_mesh_to("out", format, triangle(), sink, error) ? bytes : "";
}

TEST(MeshFileFormats, ListMatchesTheWriters) {
  for (const char* format : {"obj", "off", "ply", "stl", "gltf", "glb", "dae", "3ds", ""}) {
    SCOPED_TRACE(format);
    EXPECT_EQ(pmz::mesh_format_writable(format), !written(format).empty());
  }
}

TEST(MeshFileFormats, ListMatchesTheReaders) {
  for (const pmz::MeshFileFormat& f : pmz::mesh_file_formats()) {
    SCOPED_TRACE(f.name);
    EXPECT_TRUE(f.read || f.write);
    if (!f.read) continue;
    // What a written format reads back; glTF's JSON as the .glb's first chunk holds it.
    std::string data = written(f.write ? f.name : "glb");
    if (!f.write) {
      uint32_t length = 0;
      for (int i = 3; i >= 0; --i) length = length << 8 | uint8_t(data[12 + i]);
      data = data.substr(20, length);
    }
    pmz::PolygonSoup soup;
    std::string error;
    const bool ok = pmz::parse_polygon_soup(std::string("m.") + f.name, data, soup, error);
    // The JSON alone names a buffer it does not hold: refused, but as glTF, not as unknown.
    EXPECT_EQ(error.find("unknown mesh format"), std::string::npos) << error;
    if (f.write) {
      EXPECT_TRUE(ok) << error;
    }
  }
  pmz::PolygonSoup soup;
  std::string error;
  EXPECT_FALSE(pmz::parse_polygon_soup("m.dae", "x", soup, error));
  EXPECT_NE(error.find("unknown mesh format"), std::string::npos) << error;
  EXPECT_FALSE(pmz::mesh_format_readable("dae"));
}

TEST(MeshFileFormats, Lists) {
  EXPECT_EQ(pmz::mesh_format_list(true, "|"), "obj|off|ply|stl|glb");
  EXPECT_EQ(pmz::mesh_format_list(false, ", ", " or ", "."),
            ".obj, .off, .ply, .stl, .gltf or .glb");
}

TEST(MeshFileFormats, GltfExternalBuffers) {
  using pmz::gltf_external_buffers;
  const std::string json =
      R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":4,"uri":"data:;base64,AAAAAA=="},)"
      R"({"byteLength":4,"uri":"a b.bin"},{"byteLength":4}]})";
  EXPECT_EQ(gltf_external_buffers(json), std::vector<std::string>{"a b.bin"});
  // The same JSON as a .glb's first chunk.
  std::string glb = "glTF";
  glb += std::string("\2\0\0\0", 4) + std::string(4, '\0');
  const uint32_t n = uint32_t(json.size());
  glb += std::string{char(n), char(n >> 8), char(n >> 16), char(n >> 24)} + "JSON" + json;
  EXPECT_EQ(gltf_external_buffers(glb), std::vector<std::string>{"a b.bin"});
  // A .glb meshio writes holds its buffer.
  EXPECT_TRUE(gltf_external_buffers(written("glb")).empty());
  EXPECT_TRUE(gltf_external_buffers("not json").empty());
  EXPECT_TRUE(gltf_external_buffers("glTF").empty());
}

}  // namespace
