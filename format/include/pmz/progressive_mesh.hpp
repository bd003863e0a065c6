// The progressive-mesh core shared by writer and decoder: a corner table over flat arrays with
// vertex split and its exact inverse. The writer replays this very code to compute wedge ranks
// and predictions, so what it writes is what the decoder does (spec/format.md, "Vertex split").
#pragma once


#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace pmz {

inline constexpr uint32_t kNoCorner = 0xFFFFFFFFu;
inline constexpr uint32_t kNoRank = 0xFFFFFFFFu;  // wedge side on the boundary

class ProgressiveMesh {
 public:
  // Corner c = 3 * face + k. corner_vertex is the triangle index buffer.
  std::vector<uint32_t> corner_vertex;
  std::vector<uint32_t> opposite;       // corner across the edge opposite c, or kNoCorner
  std::vector<uint32_t> vertex_corner;  // any corner of the vertex, or kNoCorner (isolated)

  // Capacity for this many vertices and faces, so refinement does not reallocate.
  void reserve(size_t vertices, size_t faces) {
    corner_vertex.reserve(faces * 3);
    opposite.reserve(faces * 3);
    vertex_corner.reserve(vertices);
  }
  uint32_t vertex_count() const { return uint32_t(vertex_corner.size()); }
  uint32_t face_count() const { return uint32_t(corner_vertex.size() / 3); }

  // Resets to the given mesh. Fails (false + message) on out-of-range indices, degenerate
  // faces, an edge used twice in the same direction or by more than two faces.
  bool build(uint32_t vertex_count, const uint32_t* indices, size_t face_count, std::string& error);

  // Canonical ordered one-ring of v (history-independent): counter-clockwise;
  // closed fan: starting at the smallest neighbour index; open fan: from the boundary, so it
  // holds faces + 1 vertices. Returns false when v has no face.
  bool gather_ring(uint32_t v);
  // The ring in walk order; canonical rank i is ring()[(i + ring_start()) % ring().size()].
  const std::vector<uint32_t>& ring() const { return ring_; }
  uint32_t ring_start() const { return start_; }
  uint32_t rank_of(uint32_t w) const;  // canonical rank of neighbour w, or kNoRank
  bool ring_closed() const { return closed_; }

  // Vertex split at v with wedge ranks into the canonical ring (kNoRank: that side on the
  // boundary). Validates before touching anything; on success appends vertex u =
  // vertex_count() and faces (u,v,vl) then (v,u,vr) (those that exist), and rewrites v->u in
  // the faces of v's fan from vl to vr. u_ring() then holds v and u's other neighbours;
  // sector_faces() the rewritten faces.
  bool split(uint32_t v, uint32_t rank_l, uint32_t rank_r) {
    return gather_ring(v) && split_gathered(v, rank_l, rank_r);
  }
  // The same, right after gather_ring(v) succeeded (saves a walk).
  bool split_gathered(uint32_t v, uint32_t rank_l, uint32_t rank_r);
  const std::vector<uint32_t>& u_ring() const { return u_ring_; }
  const std::vector<uint32_t>& sector_faces() const { return sector_; }

  // Undoes the last split (LIFO), which was at v and created the left/right faces that exist.
  // Buffers return exactly to their state before that split; sector_faces() holds the faces
  // rewritten back.
  void undo_split(uint32_t v, bool has_left, bool has_right);

 private:
  bool gather_fan(uint32_t v);  // fan_ (corners at v, ccw) and closed_; bounded walk
  std::vector<uint32_t> fan_, back_, ring_, u_ring_, sector_;
  uint32_t start_ = 0;
  bool closed_ = false;
};

}  // namespace pmz

namespace pmz {

// floor((sum + floor(n / 2)) / n) for n > 0: the rounded mean both sides compute.
inline int64_t floor_mean(int64_t sum, int64_t n) {
  int64_t x = sum + n / 2;
  int64_t q = x / n;
  if ((x % n) != 0 && x < 0) --q;  // floor, not truncation
  return q;
}

// Position prediction of a new vertex u (spec, section 5), right after split(): per axis the
// floor-rounded mean of u's ring with v counted twice (u starts next to v), in 64-bit integers.
// coords: 3 per vertex.
inline void predict_position(const int32_t* coords, const std::vector<uint32_t>& u_ring, int32_t out[3]) {
  int64_t sum[3] = {0, 0, 0};
  for (uint32_t w : u_ring)
    for (int a = 0; a < 3; ++a) sum[a] += coords[size_t(w) * 3 + a];
  for (int a = 0; a < 3; ++a) sum[a] += coords[size_t(u_ring[0]) * 3 + a];
  for (int a = 0; a < 3; ++a) out[a] = int32_t(floor_mean(sum[a], int64_t(u_ring.size()) + 1));
}

}  // namespace pmz
