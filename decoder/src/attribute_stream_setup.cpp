// The attribute stream's once-per-file parts (HEAD's fields, the base ATTR chunk), apart from
// the per-split ones in attribute_stream.cpp so that they can be built for size.
#include "attribute_stream.hpp"
#include "huge_pages.hpp"
#include "pmz/wasm_hints.hpp"

namespace pmz {

namespace {

// Grown to n at once, the new capacity hinted for huge pages (no-op when it has room).
template <class T>
void reserve_advised(std::vector<T>& v, size_t n) {
  if (n <= v.capacity()) return;
  v.reserve(n);
  advise_huge_pages(v);
}

// `assigned` entries per split, a little above the usual: its new faces' materials and two per
// corner of split_corners() (2 per new face, u's two in L and R, u's in the sector faces); 18.3
// on a UV sphere.
constexpr size_t kAssignedPerSplit = 24;

}  // namespace

void AttributeStream::reserve(size_t faces, uint64_t splits, uint64_t total) {
  const AttributeHeader& h = state.head;
  reserve_advised(wedge_end, splits);
  reserve_advised(assign_begin, splits + 1);
  reserve_advised(assigned, splits * kAssignedPerSplit);
  if (!h.materials.empty()) reserve_advised(state.face_material, faces);
  if (!h.has_wedges()) return;
  reserve_advised(state.corner_wedge, faces * 3);
  // The new wedges in proportion to the splits (all of them for the whole stream).
  const uint64_t fresh = h.full_wedges - h.base_wedges;
  const size_t wedges =
      h.base_wedges +
      (splits >= total ? fresh : size_t(double(fresh) * double(splits) / double(total)) + 1);
  each_wedge_buffer(
      [wedges](auto& v, size_t per_wedge) { reserve_advised(v, wedges * per_wedge); });
}

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
  }
  if (!rc.ok || state.wedge_count != h.base_wedges)
    return error = "ATTR: base wedges do not match HEAD", false;
  new_wedges(positions);
  return true;
}

}  // namespace pmz
