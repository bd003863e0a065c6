// SPDX-License-Identifier: MIT
// Internal: the collapse rule for attribute wedges (one definition for the simplifier's
// legality and cost code and for the writer), and a literal replay of a collapse sequence that
// applies it to a mesh's faces and corner wedges.
//
// The rule. A half-edge collapse u -> v (faces L = (u, v, vl) and R = (v, u, vr), either may be
// missing) keeps v's position and v's wedges with their values; L and R disappear, and u's
// corners in the other faces of its fan (the sector: contiguous, from L's side to R's side
// counter-clockwise around u) are re-pointed to a wedge of v:
//   - only L exists: every sector corner takes the wedge of v's corner in L;
//   - only R exists: every sector corner takes the wedge of v's corner in R;
//   - both: the L arc, the longest run of sector faces from L's side whose u corner names the
//     same wedge as u's corner in L, takes v's wedge in L; the rest (the R arc) v's wedge in R.
// It is total: a collapse across a seam still leaves a valid mesh, only with distorted
// attributes. The decoder undoes a split with the same rule (spec/format.md, attributes).
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "pmz/attribute_codec.hpp"
#include "pmz/mesh.hpp"
#include "pmz/simplify.hpp"

namespace pmz {

// collapse_left_arc() (pmz/attribute_codec.hpp, shared with the decoder, which undoes splits
// with it) is the rule's one definition.

// The faces of u's fan as they were right before a collapse (the mesh a split of it restores):
// vertices and corner wedges per face, in input ids.
struct CollapseFan {
  std::vector<uint32_t> faces;    // input face slots
  std::vector<uint32_t> corners;  // 3 vertices per face, as the face is stored
  std::vector<uint32_t> wedges;   // the corners' wedges (empty without wedges)
};

// A collapse sequence applied to faces and corner wedges literally (faces keep their input
// slots; a face is dead once a collapse removed it).
class CollapseReplay {
 public:
  explicit CollapseReplay(const IndexedMesh& mesh);
  // Applies c; false (nothing changed) when the faces holding u and v are not exactly
  // (u, v, vl) and (v, u, vr), or u's other faces are not one fan between them. fan
  // (optional) receives u's faces before the collapse.
  bool collapse(const HalfEdgeCollapse& c, CollapseFan* fan = nullptr);
  bool has_wedges() const { return !corner_wedge.empty(); }
  std::vector<uint32_t> corner_vertex;  // 3 per input face
  std::vector<uint32_t> corner_wedge;   // 3 per input face, or empty
  std::vector<uint8_t> face_alive;

 private:
  // u's corner slot in face f (or kNoCorner).
  uint32_t corner_of(uint32_t f, uint32_t x) const;
  std::vector<std::vector<uint32_t>> vertex_faces_;
  std::vector<uint32_t> sector_, sector_wedges_;
};

}  // namespace pmz
