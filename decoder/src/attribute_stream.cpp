#include "attribute_stream.hpp"

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

void AttributeStream::new_wedges(const float* positions) {
  const AttributeHeader& h = state.head;
  for (size_t w = wedge_positions.size() / 3; w < state.wedge_count; ++w) {
    const int32_t* v = &state.values[w * state.stride];
    const float* p = positions + size_t(state.wedge_vertex[w]) * 3;
    wedge_positions.insert(wedge_positions.end(), p, p + 3);
    for (uint32_t t = 0; t < h.texcoord_sets; ++t, v += 2)
      for (int k = 0; k < 2; ++k) texcoords[t].push_back(quant.texcoord[t].dequantize(v[k], k));
    if (h.normals) {
      float nrm[3];
      quant.dequantize_normal(v, nrm);
      normals.insert(normals.end(), nrm, nrm + 3);
      v += h.normal_components();
    }
    for (uint32_t k = 0; k < h.color_components; ++k)
      colors.push_back(quant.dequantize_color(v[k]));
  }
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
  state.wedge_vertex.reserve(h.base_wedges);
  state.values.reserve(size_t(h.base_wedges) * state.stride);
  for (uint32_t f = 0; f < fn; ++f) {
    if (h.materials.size() > 1 && !decode_face_material(rc, *models, pm, state, f))
      return error = "ATTR: base face " + std::to_string(f) + " material malformed", false;
    if (!h.has_wedges()) continue;
    for (uint32_t k = 0; k < 3; ++k)
      if (state.wedge_count > h.base_wedges ||
          !decode_corner_wedge(rc, *models, pm, coords, state, f * 3 + k, false))
        return error = "ATTR: base corner " + std::to_string(f * 3 + k) + " wedge malformed", false;
  }
  if (!rc.ok || state.wedge_count != h.base_wedges)
    return error = "ATTR: base wedges do not match HEAD", false;
  new_wedges(positions);
  return true;
}

bool AttributeStream::first_apply(const ProgressiveMesh& pm, const int32_t* coords,
                                  const float* positions, bool has_l, bool has_r) {
  const AttributeHeader& h = state.head;
  const uint32_t fn = pm.face_count(), f0 = fn - (has_l ? 1u : 0u) - (has_r ? 1u : 0u);
  const uint32_t wedges_before = state.wedge_count;
  const size_t assigned_before = assigned.size();
  RangeDecoder& dec = *lazy.front();
  RangeState rc = dec.state();
  bool ok = true;
  if (!h.materials.empty()) {
    state.face_material.resize(fn, h.materials.size() > 1 ? kPendingWedge : 0);
    for (uint32_t f = f0; f < fn && ok; ++f) {
      ok = h.materials.size() < 2 || decode_face_material(rc, *models, pm, state, f);
      assigned.push_back(state.face_material[f]);
    }
  }
  if (ok && h.has_wedges()) {
    split_corners(pm, has_l, has_r, corners);
    state.corner_wedge.resize(size_t(fn) * 3, kPendingWedge);
    saved.clear();
    for (uint32_t c : corners) {
      saved.push_back(state.corner_wedge[c]);
      state.corner_wedge[c] = kPendingWedge;
    }
    const uint32_t u = pm.vertex_count() - 1;
    for (uint32_t c : corners) {
      ok = decode_corner_wedge(rc, *models, pm, coords, state, c, pm.corner_vertex[c] == u);
      if (!ok) break;
      assigned.push_back(state.corner_wedge[c]);
    }
    if (ok && rc.ok) {
      // Undoing by the collapse rule must give every sector corner back its a-wedge from
      // before the split (so every level stays valid however the stream was damaged).
      std::vector<uint32_t>& wedges = state.scratch_wedges;
      wedges.clear();
      for (uint32_t c : corners)
        if (c < size_t(f0) * 3) wedges.push_back(state.corner_wedge[c]);
      const uint32_t fr = f0 + (has_l ? 1u : 0u);
      const uint32_t arc =
          collapse_left_arc(wedges, has_l ? state.corner_wedge[f0 * 3] : 0, has_l, has_r);
      for (size_t i = 0, j = 0; i < corners.size() && ok; ++i) {
        if (corners[i] >= size_t(f0) * 3) continue;
        const uint32_t back =
            j++ < arc ? state.corner_wedge[f0 * 3 + 1] : state.corner_wedge[fr * 3];
        ok = back == saved[i];
      }
    } else {
      ok = false;
    }
    if (!ok)  // the sector corners back to v's wedges (the new faces' entries are dropped)
      for (size_t i = 0; i < corners.size(); ++i)
        if (corners[i] < size_t(f0) * 3) state.corner_wedge[corners[i]] = saved[i];
  }
  if (!ok || !rc.ok) {
    assigned.resize(assigned_before);
    if (!state.corner_wedge.empty()) state.corner_wedge.resize(size_t(f0) * 3);
    if (!state.face_material.empty()) state.face_material.resize(f0);
    state.wedge_count = wedges_before;
    state.wedge_vertex.resize(wedges_before);
    state.values.resize(size_t(wedges_before) * state.stride);
    return false;
  }
  dec.set_state(rc);
  new_wedges(positions);
  wedge_end.push_back(state.wedge_count);
  assign_begin.push_back(assigned.size());
  return true;
}

void AttributeStream::reapply(const ProgressiveMesh& pm, uint64_t i, bool has_l, bool has_r) {
  const AttributeHeader& h = state.head;
  const uint32_t fn = pm.face_count(), f0 = fn - (has_l ? 1u : 0u) - (has_r ? 1u : 0u);
  const uint32_t* a = assigned.data() + assign_begin[i];
  if (!h.materials.empty()) {
    state.face_material.resize(fn);
    for (uint32_t f = f0; f < fn; ++f) state.face_material[f] = *a++;
  }
  if (h.has_wedges()) {
    split_corners(pm, has_l, has_r, corners);
    state.corner_wedge.resize(size_t(fn) * 3);
    for (uint32_t c : corners) state.corner_wedge[c] = *a++;
  }
  state.wedge_count = wedge_end[i];
}

}  // namespace pmz
