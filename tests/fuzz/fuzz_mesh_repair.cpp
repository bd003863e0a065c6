// SPDX-License-Identifier: MIT
// The repair pass on its own: polygon soups built from the bytes, as any reader may hand them
// over (the PolygonSoup contract in meshio/include/pmz/mesh.hpp: corner indices in range,
// finite coordinates and values; per-corner attribute lists empty or one entry per corner, each
// in its pool or kNoAttribute; face materials empty or one per face, each in the table), but
// with what the readers rarely produce: few vertices and many faces on them (repeated corners,
// pinched polygons, non-manifold edges and vertices, duplicate and opposite faces), coincident
// and collinear positions, polygons of up to 70 corners, attribute lists of every shape.
// repair_mesh must hold its promises on every one (fuzz_mesh_check.hpp).
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_mesh_check.hpp"
#include "pmz/mesh.hpp"

namespace {

constexpr uint32_t kNo = pmz::kNoAttribute;

float coordinate(FuzzedDataProvider& in) {
  // Mostly a small grid (coincident, collinear and coplanar points), sometimes any finite float.
  if (in.ConsumeIntegralInRange<int>(0, 7) != 0) return float(in.ConsumeIntegralInRange(-2, 2));
  const float x = in.ConsumeFloatingPoint<float>();
  return std::isfinite(x) ? x : 0.0f;
}

// A pool of `entries` values of `width` floats and, unless `none`, an index per corner.
void attribute(FuzzedDataProvider& in, size_t corners, uint32_t width, std::vector<float>& pool,
               std::vector<uint32_t>& per_corner) {
  const uint32_t entries = in.ConsumeIntegralInRange<uint32_t>(0, 6);
  for (uint32_t i = 0; i < entries * width; ++i) pool.push_back(coordinate(in));
  if (in.ConsumeBool()) return;  // a declared pool that no corner names
  per_corner.resize(corners);
  for (uint32_t& c : per_corner)
    c = entries == 0 || in.ConsumeIntegralInRange<int>(0, 5) == 0
            ? kNo
            : in.ConsumeIntegralInRange<uint32_t>(0, entries - 1);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider in(data, size);
  pmz::PolygonSoup soup;
  const uint32_t nv = in.ConsumeIntegralInRange<uint32_t>(1, 40);
  for (uint32_t i = 0; i < nv * 3; ++i) soup.positions.push_back(coordinate(in));
  const uint32_t nf = in.ConsumeIntegralInRange<uint32_t>(1, 200);
  soup.face_offsets.push_back(0);
  for (uint32_t f = 0; f < nf && in.remaining_bytes() > 0; ++f) {
    const uint32_t k = in.ConsumeBool() ? 3 : in.ConsumeIntegralInRange<uint32_t>(1, 70);
    for (uint32_t c = 0; c < k; ++c)
      soup.corners.push_back(in.ConsumeIntegralInRange<uint32_t>(0, nv - 1));
    soup.face_offsets.push_back(uint32_t(soup.corners.size()));
  }
  if (soup.face_count() == 0) return 0;  // readers refuse a file without faces
  const size_t corners = soup.corners.size();
  pmz::SoupAttributes& a = soup.attributes;
  const uint32_t sets = in.ConsumeIntegralInRange<uint32_t>(0, 2);
  a.texcoords.resize(sets);
  a.corner_texcoords.resize(sets);
  for (uint32_t s = 0; s < sets; ++s)
    attribute(in, corners, 2, a.texcoords[s], a.corner_texcoords[s]);
  if (in.ConsumeBool()) attribute(in, corners, 3, a.normals, a.corner_normals);
  if (in.ConsumeBool()) {
    a.color_components = in.ConsumeBool() ? 3 : 4;
    attribute(in, corners, a.color_components, a.colors, a.corner_colors);
  }
  if (in.ConsumeBool()) {
    a.materials.resize(in.ConsumeIntegralInRange<size_t>(1, 3));
    for (size_t m = 0; m < a.materials.size(); ++m) a.materials[m].name = "m" + std::to_string(m);
    a.face_materials.resize(soup.face_count());
    for (uint32_t& m : a.face_materials)
      m = in.ConsumeIntegralInRange<uint32_t>(0, uint32_t(a.materials.size()) - 1);
  }
  pmz::IndexedMesh mesh;
  pmz::MeshRepairStats stats;
  pmz::repair_mesh(soup, mesh, stats);
  pmz_fuzz::check_repaired(soup, mesh, stats);
  return 0;
}
