// SPDX-License-Identifier: MIT
// A mesh reader on arbitrary bytes, then the repair pass behind it. Built once per format
// (PMZ_FUZZ_MESH_EXT names it: fuzz_mesh_obj, _off, _ply, _stl, _gltf). Either the reader refuses
// with a message, or the repaired mesh holds repair_mesh's promises (fuzz_mesh_check.hpp).
#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_mesh_check.hpp"
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
  pmz_fuzz::check_repaired(soup, mesh, stats);
  return 0;
}
