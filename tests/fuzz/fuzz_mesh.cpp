// SPDX-License-Identifier: MIT
// A mesh reader on arbitrary bytes, then the repair pass behind it. Built once per format
// (PMZ_FUZZ_MESH_EXT names it: fuzz_mesh_obj, _off, _ply, _stl, _gltf). Either the reader refuses
// with a message, or the repaired mesh holds repair_mesh's promises (fuzz_mesh_check.hpp). The
// same bytes are read again as a stream of unknown size (a FILE that cannot seek, served in
// reads of 1 to 64 bytes, through a window of 1 to 64 bytes), which must give the same soup or
// the same error.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_mesh_check.hpp"
#include "pmz/mesh.hpp"
#include "pmz/mesh_stream.hpp"

namespace {

// The bytes behind a FILE without a seek function: ftell fails, as on a pipe.
struct Trickle {
  std::string_view left;
  uint32_t state;
};

ssize_t trickle_read(void* cookie, char* buf, size_t size) {
  Trickle& t = *static_cast<Trickle*>(cookie);
  t.state = t.state * 1664525u + 1013904223u;
  const size_t n = std::min({size, t.left.size(), size_t(1 + (t.state >> 24) % 64)});
  std::memcpy(buf, t.left.data(), n);
  t.left.remove_prefix(n);
  return ssize_t(n);
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * 4) == 0);
}

void check_same_soup(const pmz::PolygonSoup& a, const pmz::PolygonSoup& b) {
  PMZ_FUZZ_CHECK(same_bits(a.positions, b.positions));
  PMZ_FUZZ_CHECK(a.corners == b.corners && a.face_offsets == b.face_offsets);
  PMZ_FUZZ_CHECK(a.welded_vertices == b.welded_vertices);
  const pmz::SoupAttributes &x = a.attributes, &y = b.attributes;
  PMZ_FUZZ_CHECK(x.texcoords.size() == y.texcoords.size());
  for (size_t s = 0; s < x.texcoords.size(); ++s)
    PMZ_FUZZ_CHECK(same_bits(x.texcoords[s], y.texcoords[s]));
  PMZ_FUZZ_CHECK(x.corner_texcoords == y.corner_texcoords);
  PMZ_FUZZ_CHECK(same_bits(x.normals, y.normals) && x.corner_normals == y.corner_normals);
  PMZ_FUZZ_CHECK(same_bits(x.colors, y.colors) && x.corner_colors == y.corner_colors);
  PMZ_FUZZ_CHECK(x.color_components == y.color_components);
  PMZ_FUZZ_CHECK(x.face_materials == y.face_materials && x.materials == y.materials);
  PMZ_FUZZ_CHECK(x.material_library == y.material_library);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view bytes(reinterpret_cast<const char*>(data), size);
  // A name in a directory that does not exist: files the input refers to (MTL, glTF buffers)
  // are never found, so the result depends on the bytes alone.
  const std::string path = std::string("/nonexistent-pmz-fuzz/input") + PMZ_FUZZ_MESH_EXT;
  pmz::PolygonSoup soup;
  std::string error;
  const bool ok = pmz::parse_polygon_soup(path, bytes, soup, error);

  uint32_t seed = 2166136261u;
  for (size_t i = 0; i < std::min<size_t>(size, 64); ++i) seed = (seed ^ data[i]) * 16777619u;
  Trickle trickle{bytes, seed};
  std::FILE* file = ::fopencookie(&trickle, "rb", {trickle_read, nullptr, nullptr, nullptr});
  PMZ_FUZZ_CHECK(file != nullptr);
  pmz::PolygonSoup streamed;
  std::string stream_error;
  const bool stream_ok =
      pmz::read_polygon_soup(path, file, streamed, stream_error, {}, 1 + (seed >> 8) % 64);
  std::fclose(file);
  PMZ_FUZZ_CHECK(stream_ok == ok && stream_error == error);

  if (!ok) {
    PMZ_FUZZ_CHECK(!error.empty() && error.find('\n') == std::string::npos);
    return 0;
  }
  check_same_soup(soup, streamed);
  PMZ_FUZZ_CHECK(soup.face_count() > 0);
  for (uint32_t c : soup.corners) PMZ_FUZZ_CHECK(c < soup.vertex_count());
  pmz::IndexedMesh mesh;
  pmz::MeshRepairStats stats;
  pmz::repair_mesh(soup, mesh, stats);
  pmz_fuzz::check_repaired(soup, mesh, stats);
  return 0;
}
