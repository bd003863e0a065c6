// SPDX-License-Identifier: MIT
// The decoder's current level as an IndexedMesh for meshio's write_mesh: positions and faces,
// and with attributes (format 8.0) the wedges (the decoder's a-wedges: texture coordinates,
// normals, colours), the faces' materials and the material table.
#pragma once
#include <algorithm>

#include "pmz/decoder.hpp"
#include "pmz/mesh.hpp"

namespace pmz::tool {

// A mesh decoded for a view (Decoder::update_view) holds every id of the stream: the faces of
// nodes not applied are degenerate and their vertices unused. Drops both (a mesh without such
// faces is left as it is).
inline void drop_unused_ids(IndexedMesh& m) {
  std::vector<uint32_t>& ix = m.indices;
  size_t kept = 0;
  for (size_t f = 0; f + 2 < ix.size(); f += 3)
    if (ix[f] != ix[f + 1]) {
      std::copy_n(&ix[f], 3, &ix[kept]);
      kept += 3;
    }
  if (kept == ix.size()) return;
  ix.resize(kept);
  std::vector<uint32_t> remap(m.vertex_count(), UINT32_MAX);
  std::vector<float> positions;
  for (uint32_t& v : ix) {
    if (remap[v] == UINT32_MAX) {
      remap[v] = uint32_t(positions.size() / 3);
      positions.insert(positions.end(), &m.positions[size_t(v) * 3],
                       &m.positions[size_t(v) * 3 + 3]);
    }
    v = remap[v];
  }
  m.positions = std::move(positions);
}

inline IndexedMesh decoded_mesh(const Decoder& d) {
  IndexedMesh m;
  const uint32_t nv = d.vertex_count(), nf = d.face_count(), nw = d.wedge_count();
  if (nv) m.positions.assign(d.positions(), d.positions() + size_t(nv) * 3);
  if (nf) m.indices.assign(d.indices(), d.indices() + size_t(nf) * 3);
  MeshAttributes& a = m.attributes;
  if (nw) {
    a.corner_wedges.assign(d.wedge_indices(), d.wedge_indices() + size_t(nf) * 3);
    a.wedge_vertices.assign(d.wedge_vertices(), d.wedge_vertices() + nw);
    for (uint32_t s = 0; s < d.texcoord_set_count(); ++s)
      a.texcoords.emplace_back(d.texcoords(s), d.texcoords(s) + size_t(nw) * 2);
    if (d.normals()) a.normals.assign(d.normals(), d.normals() + size_t(nw) * 3);
    if (d.colors()) {
      a.color_components = d.color_components();
      a.colors.assign(d.colors(), d.colors() + size_t(nw) * a.color_components);
    }
  }
  if (d.face_materials()) a.face_materials.assign(d.face_materials(), d.face_materials() + nf);
  for (uint32_t i = 0; i < d.material_count(); ++i) {
    const MaterialInfo& in = *d.material(i);
    Material& out = a.materials.emplace_back();
    out.name = in.name;
    out.base_color_texture = in.base_color_texture;
    out.normal_texture = in.normal_texture;
    std::copy(in.base_color, in.base_color + 4, out.base_color);
  }
  a.material_library = d.material_library();
  if (!nw) drop_unused_ids(m);
  return m;
}

}  // namespace pmz::tool
