// SPDX-License-Identifier: MIT
#include "attr_collapse.hpp"

#include <algorithm>

namespace pmz {

namespace {
constexpr uint32_t kNoSlot = 0xFFFFFFFFu;
uint32_t next3(uint32_t k) { return k == 2 ? 0 : k + 1; }
uint32_t prev3(uint32_t k) { return k == 0 ? 2 : k - 1; }
}  // namespace

CollapseReplay::CollapseReplay(const IndexedMesh& mesh)
    : corner_vertex(mesh.indices), face_alive(mesh.face_count(), 1) {
  if (mesh.attributes.corner_wedges.size() == mesh.indices.size())
    corner_wedge = mesh.attributes.corner_wedges;
  vertex_faces_.resize(mesh.vertex_count());
  for (uint32_t f = 0; f < mesh.face_count(); ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t x = mesh.indices[f * 3 + k];
      if (x < vertex_faces_.size()) vertex_faces_[x].push_back(f);
    }
}

uint32_t CollapseReplay::corner_of(uint32_t f, uint32_t x) const {
  for (uint32_t k = 0; k < 3; ++k)
    if (corner_vertex[f * 3 + k] == x) return k;
  return kNoSlot;
}

bool CollapseReplay::collapse(const HalfEdgeCollapse& c, CollapseFan* fan) {
  const uint32_t n = uint32_t(vertex_faces_.size());
  if (c.u >= n || c.v >= n || c.u == c.v) return false;
  std::vector<uint32_t>& uf = vertex_faces_[c.u];
  uint32_t face_l = kNoSlot, face_r = kNoSlot;
  sector_.clear();
  for (uint32_t f : uf) {
    const uint32_t k = corner_of(f, c.u);
    const uint32_t a = corner_vertex[f * 3 + next3(k)], b = corner_vertex[f * 3 + prev3(k)];
    if (a == c.v && b == c.vl && face_l == kNoSlot)
      face_l = f;
    else if (b == c.v && a == c.vr && face_r == kNoSlot)
      face_r = f;
    else if (a == c.v || b == c.v)
      return false;  // a face holding u and v that is neither L nor R
    else
      sector_.push_back(f);
  }
  const bool has_l = c.vl != kNoVertex, has_r = c.vr != kNoVertex;
  if (has_l != (face_l != kNoSlot) || has_r != (face_r != kNoSlot) || (!has_l && !has_r))
    return false;
  if (fan) {
    fan->faces = uf;
    fan->corners.clear();
    fan->wedges.clear();
    for (uint32_t f : uf) {
      fan->corners.insert(fan->corners.end(), &corner_vertex[f * 3], &corner_vertex[f * 3 + 3]);
      if (has_wedges())
        fan->wedges.insert(fan->wedges.end(), &corner_wedge[f * 3], &corner_wedge[f * 3 + 3]);
    }
  }
  // Sector order: counter-clockwise around u from L's side (face (u, w, x) follows the face
  // ending at spoke w), as far as the walk goes; any faces it does not reach follow.
  if (has_l) {
    uint32_t spoke = c.vl;
    for (size_t i = 0; i < sector_.size(); ++i) {
      size_t j = i;
      while (j < sector_.size()) {
        const uint32_t f = sector_[j];
        if (corner_vertex[f * 3 + next3(corner_of(f, c.u))] == spoke) break;
        ++j;
      }
      if (j == sector_.size()) break;
      std::swap(sector_[i], sector_[j]);
      spoke = corner_vertex[sector_[i] * 3 + prev3(corner_of(sector_[i], c.u))];
    }
  }
  if (has_wedges()) {
    sector_wedges_.clear();
    for (uint32_t f : sector_) sector_wedges_.push_back(corner_wedge[f * 3 + corner_of(f, c.u)]);
    const uint32_t u_l = has_l ? corner_wedge[face_l * 3 + corner_of(face_l, c.u)] : 0;
    const uint32_t v_l = has_l ? corner_wedge[face_l * 3 + corner_of(face_l, c.v)] : 0;
    const uint32_t v_r = has_r ? corner_wedge[face_r * 3 + corner_of(face_r, c.v)] : 0;
    const uint32_t arc = collapse_left_arc(sector_wedges_, u_l, has_l, has_r);
    for (size_t i = 0; i < sector_.size(); ++i)
      corner_wedge[sector_[i] * 3 + corner_of(sector_[i], c.u)] = i < arc ? v_l : v_r;
  }
  for (uint32_t f : sector_) corner_vertex[f * 3 + corner_of(f, c.u)] = c.v;
  auto drop = [&](uint32_t x, uint32_t f) {
    std::vector<uint32_t>& list = vertex_faces_[x];
    list.erase(std::find(list.begin(), list.end(), f));
  };
  for (uint32_t f : {face_l, face_r}) {
    if (f == kNoSlot) continue;
    face_alive[f] = 0;
    for (int k = 0; k < 3; ++k)
      if (corner_vertex[f * 3 + k] != c.u) drop(corner_vertex[f * 3 + k], f);
  }
  vertex_faces_[c.v].insert(vertex_faces_[c.v].end(), sector_.begin(), sector_.end());
  uf.clear();
  return true;
}

}  // namespace pmz
