// SPDX-License-Identifier: MIT
// The attribute stream's once-per-file parts (HEAD's fields, the base ATTR chunk), apart from
// the per-split ones in attribute_stream.cpp so that they can be built for size.
#include "attribute_stream.hpp"
#include "pmz/wasm_hints.hpp"

namespace pmz {

bool AttributeStream::head(const uint8_t* p, size_t n, uint64_t full_faces, std::string& error) {
  ByteReader r(p, n);
  AttributeHeader a;
  if (!read_attribute_header(r, a, error)) return false;
  // Every wedge is named by a corner of the full mesh.
  if (a.full_wedges > 3 * full_faces) return error = "more wedges than corners", false;
  state.init(a);
  quant.init(a);
  models = std::make_unique<AttributeModels>();
  return true;
}

bool AttributeStream::base(const uint8_t* p, size_t n, const ProgressiveMesh& pm,
                           const int32_t* coords, const float* positions, std::string& error) {
  const AttributeHeader& h = state.head;
  const uint32_t fn = pm.face_count();
  if (h.base_wedges > 3ull * fn) return error = "ATTR: more base wedges than corners", false;
  if (h.has_wedges()) state.corner_wedge.assign(size_t(fn) * 3, kPendingWedge);
  if (!h.materials.empty())
    state.face_material.assign(fn, h.materials.size() > 1 ? kPendingWedge : 0);
  RangeDecoder dec(p, n);
  RangeState rc = dec.state();
  models->cost.resume(rc);  // where counting symbol costs resumes (when it is on)
  state.wedge_vertex.reserve(h.base_wedges);
  state.values.reserve(size_t(h.base_wedges) * state.stride);
  for (uint32_t f = 0; f < fn; ++f) {
    if (h.materials.size() > 1 && !decode_face_material(rc, *models, pm, state, f))
      return error = "ATTR: base face " + PMZ_DECIMAL(f) + " material malformed", false;
    if (!h.has_wedges()) continue;
    for (uint32_t k = 0; k < 3; ++k)
      if (state.wedge_count > h.base_wedges ||
          !decode_corner_wedge(rc, *models, pm, coords, state, f * 3 + k))
        return error = "ATTR: base corner " + PMZ_DECIMAL(f * 3 + k) + " wedge malformed", false;
    models->cost.charge(rc, AttributeCost::kWedges);  // the face's reference symbols
  }
  if (!rc.ok || state.wedge_count != h.base_wedges)
    return error = "ATTR: base wedges do not match HEAD", false;
  new_wedges(positions);
  return true;
}

}  // namespace pmz
