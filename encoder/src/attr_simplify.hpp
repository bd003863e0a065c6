// SPDX-License-Identifier: MIT
// Internal: attribute wedges on the collapse engine's half-edge mesh (spec/algorithm.md section
// 7). Material boundaries (and, in AttributeMode::seams, texture and normal seams too) are
// discontinuity curves: a collapse moves a vertex along one or not at all, and their corners
// stay. The attribute deviation a collapse causes at the corners it re-points is added to the
// geometric cost; in AttributeMode::full that price is all that holds a texture or normal seam
// (a collapse across it, or moving its corner, costs the jump it makes).
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "halfedge.hpp"
#include "pmz/simplify.hpp"

namespace pmz::detail {

struct AttributeField {
  bool active = false;     // the mesh has wedges or materials and the mode is not geometry_only
  bool cost_term = false;  // wedges, a positive weight, and not geometry_only
  // AttributeMode::full with the cost term: wedge seams are priced, not locked (only material
  // boundaries keep the seam rule).
  bool priced = false;
  // Per half-edge slot: the attribute wedge of the corner at its origin (0 everywhere when the
  // mesh has materials but no wedges).
  std::vector<uint32_t> wedge;
  std::vector<uint32_t> material;  // per face, or empty
  // Per wedge, `dims` values: every attribute divided by its mean change along a non-seam edge
  // of the input, times its weight, so one typical edge's change counts 1 whatever the unit.
  std::vector<float> values;
  uint32_t dims = 0;
  // attribute_weight / L^2 (L: the metric's unit of length) times (faces / input faces)^3,
  // so the field term does not outgrow the geometric one late (spec/algorithm.md section 7).
  double scale = 0;
  double seam_scale = 0;  // the seam planes' weight / L^4 (spec/algorithm.md section 7)

  // corner_wedges / face_materials in the engine's face order; values from `attributes`.
  void init(const HalfEdgeMesh& m, const std::vector<uint32_t>& corner_wedges,
            const std::vector<uint32_t>& face_materials, const MeshAttributes& attributes,
            AttributeMode mode, float weight, double unit);

  // Whether the interior edge of half-edge h (twin present) is a seam: the faces on its two
  // sides name different wedges at either end, or have different materials.
  bool is_seam(const HalfEdgeMesh& m, uint32_t h) const {
    const uint32_t t = m.twin[h];
    return wedge[h] != wedge[HalfEdgeMesh::next(t)] || wedge[HalfEdgeMesh::next(h)] != wedge[t] ||
           is_material_boundary(h, t);
  }
  bool is_material_boundary(uint32_t h, uint32_t t) const {
    return !material.empty() && material[HalfEdgeMesh::face(h)] != material[HalfEdgeMesh::face(t)];
  }
  // The seam rule for u -> x, on the curves it holds (every seam; priced: material boundaries
  // only): u on none moves anywhere; u on exactly two moves along one of them; ends and corners
  // (one, three or more such edges) stay.
  bool allowed(const HalfEdgeMesh& m, uint32_t u, uint32_t x) const {
    return priced && material.empty() ? true : seam_rule(m, u, x);
  }
  // The attribute term of u -> x (ha: u->x in L, hb: x->u in R, either kNone): infinity when
  // the seam rule forbids it, else scale times the sum over u's surviving faces of
  // area * min(|A_f(p_x) - a'|^2, kJumpCap * extent_f^2), A_f the face's linear attribute
  // field (extrapolated in its plane), a' the value the collapse rule gives the corner moved
  // to p_x and extent_f the face's largest attribute change along an edge; plus seam_scale
  // times the squared distances of p_x from the planes of u's seam edges (the plane through
  // the edge perpendicular to its face), each weighted by the edge's squared length.
  float cost(const HalfEdgeMesh& m, uint32_t u, uint32_t x, uint32_t ha, uint32_t hb) const;
  // Applies the collapse rule to u's corners outside L and R; before the topology changes
  // (moved: scratch). With `count`, also counts the faces the collapse removes and rescales
  // the field term (the cells of one level, simplified apart, call remove_faces() after).
  void collapse(const HalfEdgeMesh& m, uint32_t u, uint32_t ha, uint32_t hb,
                std::vector<std::pair<uint32_t, uint32_t>>& moved, bool count);
  void remove_faces(uint64_t removed);

 private:
  bool seam_rule(const HalfEdgeMesh& m, uint32_t u, uint32_t x) const;
  // f(h, w) for each corner h of u outside L and R with the wedge w the collapse rule
  // (attr_collapse.hpp) gives it.
  template <class F>
  void for_each_moved_corner(const HalfEdgeMesh& m, uint32_t u, uint32_t ha, uint32_t hb,
                             F&& f) const;
  double input_scale_ = 0;                // scale at the input
  uint32_t input_faces_ = 0, faces_ = 0;  // faces at the input, and now
};

}  // namespace pmz::detail
