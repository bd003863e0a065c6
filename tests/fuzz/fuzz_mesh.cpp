// A mesh reader on arbitrary bytes, then the repair pass behind it. Built once per format
// (PMZ_FUZZ_MESH_EXT names it: fuzz_mesh_obj, _off, _ply, _stl, _gltf). Either the reader refuses
// with a message, or the repaired mesh holds its invariants: indices and wedges in range, each
// corner's wedge on the corner's vertex, no directed edge used twice (manifold with boundary).
#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_common.hpp"
#include "pmz/mesh.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view bytes(reinterpret_cast<const char*>(data), size);
  // A name in a directory that does not exist: files the input refers to (MTL, glTF buffers)
  // are never found, so the result depends on the bytes alone.
  const std::string path = std::string("/nonexistent-pmz-fuzz/input") + PMZ_FUZZ_MESH_EXT;
  pmz::PolygonSoup soup;
  std::string error;
  if (!pmz::parse_polygon_soup(path, bytes, soup, error)) {
    PMZ_FUZZ_CHECK(!error.empty() && error.find('\n') == std::string::npos);
    return 0;
  }
  PMZ_FUZZ_CHECK(soup.face_count() > 0);
  for (uint32_t c : soup.corners) PMZ_FUZZ_CHECK(c < soup.vertex_count());
  pmz::IndexedMesh mesh;
  pmz::MeshRepairStats stats;
  pmz::repair_mesh(soup, mesh, stats);
  const uint32_t nv = mesh.vertex_count();
  for (uint32_t i : mesh.indices) PMZ_FUZZ_CHECK(i < nv);
  std::vector<uint64_t> edges;
  for (uint32_t f = 0; f < mesh.face_count(); ++f)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = mesh.indices[f * 3 + k], b = mesh.indices[f * 3 + (k + 1) % 3];
      PMZ_FUZZ_CHECK(a != b);
      edges.push_back(uint64_t(a) << 32 | b);
    }
  std::sort(edges.begin(), edges.end());
  PMZ_FUZZ_CHECK(std::adjacent_find(edges.begin(), edges.end()) == edges.end());
  const pmz::MeshAttributes& a = mesh.attributes;
  if (a.has_wedges()) {
    PMZ_FUZZ_CHECK(a.corner_wedges.size() == mesh.indices.size());
    for (size_t c = 0; c < a.corner_wedges.size(); ++c) {
      PMZ_FUZZ_CHECK(a.corner_wedges[c] < a.wedge_count());
      PMZ_FUZZ_CHECK(a.wedge_vertices[a.corner_wedges[c]] == mesh.indices[c]);
    }
    for (const auto& t : a.texcoords) PMZ_FUZZ_CHECK(t.size() == a.wedge_count() * 2u);
    PMZ_FUZZ_CHECK(a.normals.empty() || a.normals.size() == a.wedge_count() * 3u);
    PMZ_FUZZ_CHECK(a.colors.size() == size_t(a.wedge_count()) * a.color_components);
  }
  if (!a.face_materials.empty()) {
    PMZ_FUZZ_CHECK(a.face_materials.size() == mesh.face_count());
    for (uint32_t m : a.face_materials) PMZ_FUZZ_CHECK(m < a.materials.size());
  }
  PMZ_FUZZ_CHECK(stats.input_faces == soup.face_count());
  return 0;
}
