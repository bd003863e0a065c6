// SPDX-License-Identifier: MIT
#include "attribute_stream.hpp"

#include <algorithm>

namespace pmz {

namespace {

// Room for n elements, growing geometrically (a split's reservation must not make every later
// split reallocate).
template <class Vector>
[[gnu::noinline, gnu::cold]] void grow(Vector& v, size_t n) {
  v.reserve(std::max(v.capacity() * 2, n));
}
template <class Vector>
inline void reserve_total(Vector& v, size_t n) {
  if (n > v.capacity()) [[unlikely]]
    grow(v, n);  // out of line: the decoder library has a size budget
}
template <class Vector>
inline void reserve_more(Vector& v, size_t extra) {
  reserve_total(v, v.size() + extra);
}

// `assigned` entries per split, a little above the usual: its new faces' materials and two per
// corner of split_corners() (2 per new face, u's two in L and R, u's in the sector faces); 18.3
// on a UV sphere.
constexpr size_t kAssignedPerSplit = 24;

}  // namespace

void AttributeStream::reserve_wedges(size_t wedges) {
  reserve_total(state.wedge_vertex, wedges);
  reserve_total(state.values, wedges * state.stride);
  reserve_total(wedge_positions, wedges * 3);
  for (uint32_t t = 0; t < state.head.texcoord_sets; ++t) reserve_total(texcoords[t], wedges * 2);
  if (state.head.normals) reserve_total(normals, wedges * 3);
  reserve_total(colors, wedges * state.head.color_components);
}

void AttributeStream::reserve(size_t faces, uint64_t splits, uint64_t total) {
  const AttributeHeader& h = state.head;
  reserve_total(wedge_end, splits);
  reserve_total(assign_begin, splits + 1);
  reserve_total(assigned, splits * kAssignedPerSplit);
  if (!h.materials.empty()) reserve_total(state.face_material, faces);
  if (!h.has_wedges()) return;
  reserve_total(state.corner_wedge, faces * 3);
  // The new wedges in proportion to the splits (all of them for the whole stream).
  const uint64_t fresh = h.full_wedges - h.base_wedges;
  reserve_wedges(
      h.base_wedges +
      (splits >= total ? fresh : size_t(double(fresh) * double(splits) / double(total)) + 1));
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

void AttributeStream::reserve_split(uint32_t faces, uint32_t ring) {
  const AttributeHeader& h = state.head;
  // split_corners(): 2 per new face, u's in L and R, and u's in the sector (at most the ring);
  // at most one new wedge per corner.
  const size_t n = size_t(ring) + 6, faces_after = size_t(faces) + 2;
  reserve_more(assigned, 2 + 2 * n);
  reserve_more(assign_begin, 1);
  reserve_more(wedge_end, 1);
  reserve_more(corners, n);
  reserve_more(saved, n);
  reserve_more(sector_wedges, n);
  if (!h.materials.empty())
    reserve_more(state.face_material, faces_after - state.face_material.size());
  if (!h.has_wedges()) return;
  reserve_more(state.corner_wedge, faces_after * 3 - state.corner_wedge.size());
  // No more wedges than HEAD announced (decode_new_wedge refuses them): near the end, room
  // for a whole ring of new ones would double every buffer for nothing.
  // Every per-wedge buffer holds the wedges ever decoded (wedge_vertex.size()).
  reserve_wedges(state.wedge_vertex.size() +
                 std::min<size_t>(n, h.full_wedges - state.wedge_count));
}

bool AttributeStream::first_apply(const ProgressiveMesh& pm, const int32_t* coords,
                                  const float* positions, bool has_l, bool has_r) {
  const AttributeHeader& h = state.head;
  const uint32_t fn = pm.face_count(), f0 = fn - (has_l ? 1u : 0u) - (has_r ? 1u : 0u);
  const uint32_t wedges_before = state.wedge_count, last_simple = models->last_simple;
  const size_t assigned_before = assigned.size();
  RangeDecoder& dec = *lazy.front();
  RangeState rc = dec.state();
  models->cost.resume(rc);  // where counting symbol costs resumes (when it is on)
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
    saved.resize(corners.size());  // reserved: no allocation
    for (size_t i = 0; i < corners.size(); ++i) {
      saved[i] = state.corner_wedge[corners[i]];
      state.corner_wedge[corners[i]] = kPendingWedge;
    }
    ok = decode_split_wedges(rc, *models, pm, coords, state, corners, pm.vertex_count() - 1);
    if (ok) {
      // Undoing by the collapse rule must give every sector corner back its a-wedge from
      // before the split (so every level stays valid however the stream was damaged).
      sector_wedges.clear();
      for (uint32_t c : corners)
        if (c < size_t(f0) * 3) sector_wedges.push_back(state.corner_wedge[c]);
      const uint32_t fr = f0 + (has_l ? 1u : 0u);
      const uint32_t arc =
          collapse_left_arc(sector_wedges, has_l ? state.corner_wedge[f0 * 3] : 0, has_l, has_r);
      for (size_t i = 0, j = 0; i < corners.size() && ok; ++i) {
        if (corners[i] >= size_t(f0) * 3) continue;
        const uint32_t back =
            j++ < arc ? state.corner_wedge[f0 * 3 + 1] : state.corner_wedge[fr * 3];
        ok = back == saved[i];
      }
    }
    if (!ok)  // the sector corners back to v's wedges (the new faces' entries are dropped)
      for (size_t i = 0; i < corners.size(); ++i)
        if (corners[i] < size_t(f0) * 3) state.corner_wedge[corners[i]] = saved[i];
    const size_t at = assigned.size();
    assigned.resize(at + 2 * corners.size());  // reserved: no allocation
    for (size_t i = 0; i < corners.size(); ++i) {
      assigned[at + 2 * i] = corners[i];
      assigned[at + 2 * i + 1] = state.corner_wedge[corners[i]];
    }
  }
  if (!ok || !rc.ok) {
    assigned.resize(assigned_before);
    if (!state.corner_wedge.empty()) state.corner_wedge.resize(size_t(f0) * 3);
    if (!state.face_material.empty()) state.face_material.resize(f0);
    state.wedge_count = wedges_before;
    state.wedge_vertex.resize(wedges_before);
    state.values.resize(size_t(wedges_before) * state.stride);
    models->last_simple = last_simple;
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
  const uint32_t* end = assigned.data() + assign_begin[i + 1];
  if (!h.materials.empty()) {
    state.face_material.resize(fn);
    for (uint32_t f = f0; f < fn; ++f) state.face_material[f] = *a++;
  }
  if (h.has_wedges()) {
    state.corner_wedge.resize(size_t(fn) * 3);
    for (; a != end; a += 2) state.corner_wedge[a[0]] = a[1];
  }
  state.wedge_count = wedge_end[i];
}

void AttributeStream::undo(const ProgressiveMesh& pm, uint64_t i, bool has_l, bool has_r) {
  const AttributeHeader& h = state.head;
  const uint32_t f0 = pm.face_count();  // the new faces were f0 (L, if any) and the next
  if (h.has_wedges()) {
    const uint32_t fr = f0 + (has_l ? 1u : 0u);
    const uint32_t u_l = has_l ? state.corner_wedge[f0 * 3] : 0;
    const uint32_t v_l = has_l ? state.corner_wedge[f0 * 3 + 1] : 0;
    const uint32_t v_r = has_r ? state.corner_wedge[fr * 3] : 0;
    // The sector corners (now v's) still name u's wedges: the collapse rule gives them v's.
    const uint32_t new_faces = (has_l ? 1u : 0u) + (has_r ? 1u : 0u);
    const uint32_t* a = assigned.data() + assign_begin[i] + (h.materials.empty() ? 0 : new_faces);
    const uint32_t* end = assigned.data() + assign_begin[i + 1];
    sector_wedges.clear();
    for (const uint32_t* p = a; p != end; p += 2)
      if (p[0] < size_t(f0) * 3) sector_wedges.push_back(state.corner_wedge[p[0]]);
    const uint32_t arc = collapse_left_arc(sector_wedges, u_l, has_l, has_r);
    uint32_t j = 0;
    for (const uint32_t* p = a; p != end; p += 2)
      if (p[0] < size_t(f0) * 3) state.corner_wedge[p[0]] = j++ < arc ? v_l : v_r;
    state.corner_wedge.resize(size_t(f0) * 3);
  }
  if (!h.materials.empty()) state.face_material.resize(f0);
  state.wedge_count = i ? wedge_end[i - 1] : h.base_wedges;
}

}  // namespace pmz
