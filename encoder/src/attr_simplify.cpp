// SPDX-License-Identifier: MIT
// Attribute wedges in the collapse engine: seams as discontinuity curves and the attribute
// deviation term (spec/algorithm.md section 7).
#include "attr_simplify.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

namespace pmz::detail {

// One unit of a normal or colour weighs like a deviation of this many edge lengths (chosen on
// fandisk and camel with the textured benchmark's attributes, spec/algorithm.md section 7).
constexpr double kValueUnit = 10.0;
// A moved corner's squared deviation counts at most this many times its face's own largest
// squared attribute change along an edge: a corner that takes the far side of a seam is wrong
// whatever the jump's size, and the face's extent grows as the mesh gets coarser, so a seam
// gives way late in simplification instead of pinning the face budget (spec/algorithm.md
// section 7; 16 and not less: on the assimp spider's uv, a smaller cap let ordinary collapses
// distort as much as seam jumps).
constexpr double kJumpCap = 16.0;
// The seam planes' weight relative to attribute_weight: Garland & Heckbert's discontinuity
// planes, so that sliding along a seam keeps the seam's course (the fields on both sides are
// unchanged by such a collapse; only where the seam runs moves). 0.12 (was 0.04) since the field
// term decays (below): the texture error at gltfpack's face counts then stays at or below
// gltfpack's on every textured benchmark mesh (spec/algorithm.md section 7).
constexpr double kSeamPlaneWeight = 0.12;
// The field term is scaled by (faces / input faces)^kFieldDecay, so that it decides between
// collapses of similar geometric cost at every level instead of outgrowing geometry late: left
// absolute, a seam crossing or a seam corner's move cost far more than any geometric error the
// heap offered at the coarse levels, and seam vertices took their budget (man at 2%: 91% of the
// remaining vertices on seams, 34% in the geometry run). A capped seam price (area times 16
// extents squared) starts hundreds of times above a typical collapse's geometric error and
// closes that gap only as fast as the faces grow; the exponent 3 was chosen on the textured
// benchmark (1, 2 and 3 tried, with plane weights 0.04 to 0.12). The seam planes stay
// absolute: a seam's course is measured in the input's texture space whatever the level.
constexpr double kFieldDecay = 3.0;

void AttributeField::init(const HalfEdgeMesh& m, const std::vector<uint32_t>& corner_wedges,
                          const std::vector<uint32_t>& face_materials,
                          const MeshAttributes& attributes, AttributeMode mode, float weight,
                          double unit) {
  const uint32_t faces = m.face_count();
  // Wedges out of range (a caller's inconsistent arrays) are ignored rather than read past.
  const bool wedges = corner_wedges.size() == size_t(faces) * 3 && attributes.has_wedges() &&
                      std::all_of(corner_wedges.begin(), corner_wedges.end(),
                                  [&](uint32_t w) { return w < attributes.wedge_count(); });
  const bool materials = face_materials.size() == faces;
  active = mode != AttributeMode::geometry_only && (wedges || materials);
  if (!active) return;
  wedge.assign(m.slot_count(), 0);
  if (wedges)
    for (uint32_t f = 0; f < faces; ++f)
      for (uint32_t k = 0; k < 3; ++k)
        wedge[HalfEdgeMesh::half_edge(f, k)] = corner_wedges[size_t(f) * 3 + k];
  // One material everywhere has no boundary: left out, so the priced rule skips the walk.
  if (materials && std::adjacent_find(face_materials.begin(), face_materials.end(),
                                      std::not_equal_to<>()) != face_materials.end())
    material = face_materials;
  cost_term = weight > 0 && wedges;
  // Without the term nothing would price a seam: it stays locked.
  priced = mode == AttributeMode::full && cost_term;
  if (!cost_term) return;

  // Each attribute kind: source array, components, and whether it is divided by its mean
  // change along an edge. Texture coordinates are a parametrisation: so divided, a deviation
  // reads in edge lengths. Normals (about radians) and colours (0..1) are divided by
  // kValueUnit instead: divided by their own mean change, a nearly constant attribute (the
  // normals of a CAD part's flat faces) outweighed everything (fandisk at 10%: geometric mean
  // error 4x the geometry run's, texture error 1.9x).
  struct Kind {
    const std::vector<float>* data;
    uint32_t components;
    bool per_edge;
  };
  std::vector<Kind> kinds;
  for (const auto& set : attributes.texcoords) kinds.push_back({&set, 2, true});
  if (!attributes.normals.empty()) kinds.push_back({&attributes.normals, 3, false});
  if (!attributes.colors.empty())
    kinds.push_back({&attributes.colors, attributes.color_components, false});
  dims = 0;
  for (const Kind& k : kinds) dims += k.components;
  const uint32_t wedge_count = attributes.wedge_count();
  values.assign(size_t(wedge_count) * dims, 0.f);
  uint32_t offset = 0;
  for (const Kind& kind : kinds) {
    const uint32_t c = kind.components;
    if (kind.data->size() < size_t(wedge_count) * c) {  // not one value per wedge: left out
      offset += c;
      continue;
    }
    auto at = [&](uint32_t wd) { return kind.data->data() + size_t(wd) * c; };
    // The typical change along an edge: the mean over interior non-seam edges, each once.
    double sum = 0;
    uint64_t count = 0;
    for (uint32_t h = 0; h < m.slot_count(); ++h) {
      const uint32_t t = m.twin[h];
      if (m.vert[h] == kNone || t == kNone || t < h || is_seam(m, h)) continue;
      const float *a = at(wedge[h]), *b = at(wedge[HalfEdgeMesh::next(h)]);
      double d2 = 0;
      for (uint32_t i = 0; i < c; ++i) d2 += double(a[i] - b[i]) * (a[i] - b[i]);
      sum += std::sqrt(d2), ++count;
    }
    const double typical = !kind.per_edge ? kValueUnit : count ? sum / double(count) : 0;
    if (typical > 0 && std::isfinite(typical))
      for (uint32_t wd = 0; wd < wedge_count; ++wd)
        for (uint32_t i = 0; i < c; ++i)
          values[size_t(wd) * dims + offset + i] = float(at(wd)[i] / typical);
    offset += c;
  }
  scale = input_scale_ = double(weight) / (unit * unit);
  input_faces_ = faces_ = faces;
  seam_scale = kSeamPlaneWeight * double(weight) / (unit * unit * unit * unit);
}

bool AttributeField::seam_rule(const HalfEdgeMesh& m, uint32_t u, uint32_t x) const {
  uint32_t seams = 0;
  bool along = false;
  for_each_neighbour(m, u, [&](uint32_t w, uint32_t h) {
    const uint32_t t = m.twin[h];
    if (t == kNone || !(priced ? is_material_boundary(h, t) : is_seam(m, h))) return;
    ++seams;
    along |= w == x;
  });
  return seams == 0 || (seams == 2 && along);
}

template <class F>
void AttributeField::for_each_moved_corner(const HalfEdgeMesh& m, uint32_t u, uint32_t ha,
                                           uint32_t hb, F&& f) const {
  const uint32_t fb = hb != kNone ? HalfEdgeMesh::face(hb) : kNone;
  if (ha == kNone) {  // only R: every corner takes v's wedge in R
    const uint32_t wr = wedge[hb];
    for_each_outgoing(m, u, [&](uint32_t h) {
      if (HalfEdgeMesh::face(h) != fb) f(h, wr);
    });
    return;
  }
  const uint32_t wl = wedge[HalfEdgeMesh::next(ha)];
  const uint32_t wr = hb != kNone ? wedge[hb] : wl;
  // From L around u away from R: the leading corners naming u's wedge in L form the L arc, the
  // rest the R arc (collapse_left_arc in attr_collapse.hpp, walked here without a buffer since
  // the costs are evaluated on two threads). Only L: all L's.
  const uint32_t u_wedge_l = wedge[ha];
  bool left = true;
  uint32_t last = ha;
  for (uint32_t h = m.rotate(ha); h != kNone && HalfEdgeMesh::face(h) != fb; h = m.rotate(h)) {
    left = left && (hb == kNone || wedge[h] == u_wedge_l);
    f(h, left ? wl : wr);
    last = h;
  }
  if (hb == kNone || m.rotate(last) != kNone) return;
  // The walk met the boundary before R (u on the boundary, (u, v) interior): the faces between
  // R and the other end of the fan, walked back from R, are R's arc.
  for (uint32_t t = m.twin[HalfEdgeMesh::next(hb)]; t != kNone;) {
    const uint32_t h = HalfEdgeMesh::next(t);
    if (HalfEdgeMesh::face(h) == HalfEdgeMesh::face(ha)) break;
    f(h, wr);
    t = m.twin[h];
  }
}

float AttributeField::cost(const HalfEdgeMesh& m, uint32_t u, uint32_t x, uint32_t ha,
                           uint32_t hb) const {
  if (!allowed(m, u, x)) return std::numeric_limits<float>::infinity();
  if (!cost_term) return 0.f;
  const float *pu = m.p(u), *px = m.p(x);
  const uint32_t fb = hb != kNone ? HalfEdgeMesh::face(hb) : kNone;
  double sum = 0, seam_sum = 0;
  for_each_moved_corner(m, u, ha, hb, [&](uint32_t h, uint32_t moved) {
    const float* pb = m.p(m.dest(h));
    const float* pc = m.p(m.vert[HalfEdgeMesh::prev(h)]);
    double e1[3], e2[3], d[3];
    for (int k = 0; k < 3; ++k)
      e1[k] = double(pb[k]) - pu[k], e2[k] = double(pc[k]) - pu[k], d[k] = double(px[k]) - pu[k];
    const double d11 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2];
    const double d12 = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2];
    const double d22 = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2];
    const double r1 = d[0] * e1[0] + d[1] * e1[1] + d[2] * e1[2];
    const double r2 = d[0] * e2[0] + d[1] * e2[1] + d[2] * e2[2];
    const double den = d11 * d22 - d12 * d12;  // (2 * area)^2
    if (!(den > 0)) return;
    // The seam edges at u: each face's outgoing edge, and the incoming edge shared with R
    // (every other one is another moved face's outgoing edge).
    const uint32_t in = HalfEdgeMesh::prev(h);
    const bool seam_out = m.twin[h] != kNone && is_seam(m, h);
    const bool seam_in = fb != kNone && m.twin[in] != kNone &&
                         HalfEdgeMesh::face(m.twin[in]) == fb && is_seam(m, in);
    if (seam_out || seam_in) {
      const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                           e1[0] * e2[1] - e1[1] * e2[0]};
      auto seam_plane = [&](const double* e) {
        const double bn[3] = {e[1] * n[2] - e[2] * n[1], e[2] * n[0] - e[0] * n[2],
                              e[0] * n[1] - e[1] * n[0]};
        const double bl2 = bn[0] * bn[0] + bn[1] * bn[1] + bn[2] * bn[2];
        if (!(bl2 > 0)) return;
        const double dist = d[0] * bn[0] + d[1] * bn[1] + d[2] * bn[2];
        seam_sum += (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) * dist * dist / bl2;
      };
      if (seam_out) seam_plane(e1);
      if (seam_in) seam_plane(e2);
    }
    // p_x in the face's barycentric frame (in its plane; outside the face, so extrapolated),
    // clamped so a needle's huge coordinates do not swamp the sum.
    const double lb = std::clamp((d22 * r1 - d12 * r2) / den, -4.0, 4.0);
    const double lc = std::clamp((d11 * r2 - d12 * r1) / den, -4.0, 4.0);
    const double la = 1 - lb - lc;
    const float* a = &values[size_t(wedge[h]) * dims];
    const float* b = &values[size_t(wedge[HalfEdgeMesh::next(h)]) * dims];
    const float* c = &values[size_t(wedge[HalfEdgeMesh::prev(h)]) * dims];
    const float* n = &values[size_t(moved) * dims];
    double err = 0;
    for (uint32_t i = 0; i < dims; ++i) {
      const double e = la * a[i] + lb * b[i] + lc * c[i] - n[i];
      err += e * e;
    }
    // The cap, kJumpCap times the largest of the face's squared edge changes, read only when
    // it can bite (most corners deviate far less than their face's extent).
    auto edge2 = [&](const float* p, const float* q) {
      double e2 = 0;
      for (uint32_t i = 0; i < dims; ++i) e2 += double(p[i] - q[i]) * (p[i] - q[i]);
      return e2;
    };
    if (err > kJumpCap * edge2(a, b))
      err = std::min(err, kJumpCap * std::max({edge2(a, b), edge2(b, c), edge2(c, a)}));
    sum += 0.5 * std::sqrt(den) * err;
  });
  return float(sum * scale + seam_sum * seam_scale);
}

void AttributeField::collapse(const HalfEdgeMesh& m, uint32_t u, uint32_t ha, uint32_t hb,
                              std::vector<std::pair<uint32_t, uint32_t>>& moved, bool count) {
  // Decided on the wedges as they are, then written (the walk reads u's old wedges).
  moved.clear();
  for_each_moved_corner(m, u, ha, hb, [&](uint32_t h, uint32_t w) { moved.push_back({h, w}); });
  for (const auto& [h, w] : moved) wedge[h] = w;
  if (count) remove_faces((ha != kNone) + (hb != kNone));
}

void AttributeField::remove_faces(uint64_t removed) {
  faces_ -= uint32_t(removed);
  if (cost_term) scale = input_scale_ * std::pow(double(faces_) / input_faces_, kFieldDecay);
}

}  // namespace pmz::detail
