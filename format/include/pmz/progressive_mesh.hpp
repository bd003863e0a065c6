// SPDX-License-Identifier: MIT
// The progressive-mesh core shared by writer and decoder: a corner table over flat arrays with
// vertex split and its exact inverse. The writer replays this very code to compute wedge ranks
// and predictions, so what it writes is what the decoder does (spec/format.md sections 6 and 9.5).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "pmz/huge_pages.hpp"
#include "pmz/wasm_hints.hpp"

namespace pmz {

inline constexpr uint32_t kNoCorner = 0xFFFFFFFFu;
inline constexpr uint32_t kNoRank = 0xFFFFFFFFu;  // wedge side on the boundary
// Corner c = 3 * face + k: the face's next and previous corners, counter-clockwise
// (spec/format.md section 6).
inline uint32_t next_corner(uint32_t c) { return c % 3 == 2 ? c - 2 : c + 1; }
inline uint32_t prev_corner(uint32_t c) { return c % 3 == 0 ? c + 2 : c - 1; }

class ProgressiveMesh {
 public:
  // Corner c = 3 * face + k. corner_vertex is the triangle index buffer.
  // (BigVector: refinement reads them at random, huge pages where available)
  BigVector<uint32_t> corner_vertex;
  BigVector<uint32_t> opposite;       // corner across the edge opposite c, or kNoCorner
  BigVector<uint32_t> vertex_corner;  // any corner of the vertex, or kNoCorner (isolated)

  // Capacity for this many vertices and faces, so refinement does not reallocate.
  void reserve(size_t vertices, size_t faces) {
    corner_vertex.reserve(faces * 3);
    opposite.reserve(faces * 3);
    vertex_corner.reserve(vertices);
  }
  uint32_t vertex_count() const { return owner_ ? vn_ : uint32_t(vertex_corner.size()); }
  uint32_t face_count() const { return owner_ ? fn_ : uint32_t(corner_vertex.size() / 3); }
  // Parallel decoding: this object works on owner's arrays (sized beforehand for every vertex and
  // face it adds) instead of its own: its splits write vertex u and their faces at the ids from
  // `vertices` and `faces` on (counted here, not by the arrays' sizes), its undos take them back.
  // Workers whose splits touch disjoint vertices and faces (the nodes of one level of a stream
  // with a node table) may split at once; each has its own ring scratch.
  void attach(ProgressiveMesh& owner, uint32_t vertices, uint32_t faces) {
    owner_ = &owner;
    vn_ = vertices;
    fn_ = faces;
  }

  // Resets to the given mesh. Fails (false + message) on out-of-range indices, degenerate
  // faces, an edge used twice in the same direction or by more than two faces, a vertex whose
  // faces form several fans.
  PMZ_SMALL_IN_WASM bool build(uint32_t vertex_count, const uint32_t* indices, size_t face_count,
                               std::string& error);

  // Canonical ordered one-ring of v (history-independent): counter-clockwise;
  // closed fan: starting at the smallest neighbour index; open fan: from the boundary, so it
  // holds faces + 1 vertices. Returns false when v has no face.
  bool gather_ring(uint32_t v);
  // The ring in walk order; canonical rank i is ring()[(i + ring_start()) % ring().size()].
  std::span<const uint32_t> ring() const { return {ring_.data(), ring_n_}; }
  uint32_t ring_start() const { return start_; }
  uint32_t rank_of(uint32_t w) const;  // canonical rank of neighbour w, or kNoRank
  // Calls f(a, b) for every face (v, a, b) of the fan gather_ring(v) would walk (so every
  // vertex of v's ring is passed at least once), in no particular order; nothing for a vertex
  // without faces. Touches no scratch: cheaper than gather_ring when the order does not matter.
  template <class F>
  void for_each_fan_face(uint32_t v, F&& f) const {
    const ProgressiveMesh& m = arrays();
    const uint32_t c0 = v < m.vertex_corner.size() ? m.vertex_corner[v] : kNoCorner;
    if (c0 == kNoCorner) return;
    const uint32_t* opp = m.opposite.data();
    const uint32_t* cv = m.corner_vertex.data();
    const size_t cap = m.corner_vertex.size();
    // Counter-clockwise from c0 (n = next(c) of the corner c at v, as gather_ring), then, if
    // the fan is open, clockwise from c0 to the other boundary.
    const uint32_t n0 = c0 % 3 == 2 ? c0 - 2 : c0 + 1;
    uint32_t n = n0;
    for (size_t i = 0; i <= cap; ++i) {
      const uint32_t p = n % 3 == 2 ? n - 2 : n + 1;  // prev(c)
      f(cv[n], cv[p]);
      const uint32_t o = opp[n];
      if (o == kNoCorner) break;
      n = o % 3 == 0 ? o + 2 : o - 1;  // prev(o)
      if (n == n0) return;
    }
    uint32_t c = c0;
    for (size_t i = 0; i <= cap; ++i) {
      const uint32_t p = c % 3 == 0 ? c + 2 : c - 1;
      const uint32_t o = opp[p];
      if (o == kNoCorner) return;
      c = o % 3 == 0 ? o + 2 : o - 1;  // the corner at v of the face across (v, cv[p])
      const uint32_t nn = c % 3 == 2 ? c - 2 : c + 1, pp = c % 3 == 0 ? c + 2 : c - 1;
      f(cv[nn], cv[pp]);
    }
  }
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
  std::span<const uint32_t> u_ring() const { return {u_ring_.data(), u_ring_n_}; }
  std::span<const uint32_t> sector_faces() const { return {sector_.data(), sector_n_}; }

  // After split_gathered(): a corner from which resplit() redoes this split without v's ring
  // (the fan entry of the first rewritten face; for an empty sector the fan's first face
  // (right side only) or last face (left side only)), and the number of rewritten faces.
  uint32_t sector_hint() const { return hint_; }
  // Applies again a split that split_gathered() applied to this very state of corner_vertex
  // and opposite (what undo_split() restores), from its sector_hint() and sector count: walks
  // only the rewritten faces, no ring and no canonical order. The buffers end exactly as
  // split_gathered() left them, sector_faces() too; u_ring() is left empty. The caller
  // guarantees the state (nothing is validated); may throw bad_alloc before changing anything.
  void resplit(uint32_t v, uint32_t hint, uint32_t count, bool has_l, bool has_r);
  // The same from the sector's fan entries (sector_corners() after split_gathered(): `count`
  // of them; hint is used only when count is 0): no walk along opposite, so the loads of a
  // split are independent of each other and can be prefetched from the list.
  void resplit_listed(uint32_t v, const uint32_t* sector, uint32_t count, uint32_t hint, bool has_l,
                      bool has_r);
  // After split_gathered() or resplit() (not after resplit_listed() or an undo): the fan entries
  // (next of v's corner) of the rewritten faces, in order (the first is sector_hint() if any).
  std::span<const uint32_t> sector_corners() const { return {sector_corner_.data(), sector_n_}; }

  // Undoes the last split (LIFO), which was at v and created the left/right faces that exist.
  // Buffers return exactly to their state before that split; sector_faces() holds the faces
  // rewritten back.
  void undo_split(uint32_t v, bool has_left, bool has_right);
  // The same for a split applied with the given sector_hint() and sector count: walks only
  // the sector (the same faces, in the same order). May throw bad_alloc before changing anything.
  void undo_resplit(uint32_t v, uint32_t hint, uint32_t count, bool has_left, bool has_right);

 private:
  ProgressiveMesh* owner_ = nullptr;  // attach()'s, or null: the arrays are this object's
  uint32_t vn_ = 0, fn_ = 0;          // attached: the vertex and face counts
  ProgressiveMesh& arrays() { return owner_ ? *owner_ : *this; }
  const ProgressiveMesh& arrays() const { return owner_ ? *owner_ : *this; }
  bool gather_fan(uint32_t v);  // fan_ (per face ccw: next of the corner at v), ring_, closed_
  // The part split_gathered() and resplit() share once the old links are read: the new faces,
  // their links and vertex_corner.
  void link_new_faces(uint32_t v, uint32_t vl, uint32_t vr, uint32_t pl, uint32_t ql, uint32_t pr,
                      uint32_t qr, bool has_l, bool has_r);
  // The rest of an undo once the sector's corners are back to v: links, buffers, vertex_corner.
  void unlink_new_faces(uint32_t v, bool has_l, bool has_r);
  void grow_scratch(size_t need);
  // Scratch sized to scratch_cap_ (no push_back bookkeeping in the hot loops); the first
  // *_n_ entries are in use. fan_ holds at most scratch_cap_ - 2 faces.
  std::vector<uint32_t> fan_, ring_, u_ring_, sector_, sector_corner_;
  size_t scratch_cap_ = 0;
  uint32_t fan_n_ = 0, ring_n_ = 0, u_ring_n_ = 0, sector_n_ = 0;
  uint32_t start_ = 0, hint_ = kNoCorner;
  bool closed_ = false;
};

}  // namespace pmz

namespace pmz {

// Refinement is bound by memory latency: a split's fan is anywhere in the buffers, and a fan
// walk is a chain of dependent loads. FanPrefetcher walks the fans of the next few splits
// ahead, one face per call each, issuing prefetches only (it never writes, and every index it
// follows is bounds-checked), so the walks of kWalkers upcoming splits overlap with the work
// of the current one. It may walk a stale fan (a split in between changed it): that only
// costs a useless prefetch.
class FanPrefetcher {
 public:
  // Walks in flight, each one face per call (measured on the 1.2M-face mesh: 6 is slower,
  // 12 or 16, or stepping each walk every 2nd or 3rd call, no better).
  static constexpr uint32_t kWalkers = 8;
  FanPrefetcher() { reset(); }
  void reset() {
    for (uint32_t& n : n_) n = kNoCorner;
  }
  // Once per split, before applying it: advances every walker by one face, then
  // starts one for v_ahead (the split kWalkers further on; kNoCorner for none). coords: 3 per
  // vertex, coord_count entries (the ring's coordinates are prefetched for the prediction);
  // degree (optional): one per vertex below coord_count / 3 (the wedge scores' end weights read
  // the ring's degrees: a cache miss per ring vertex on large meshes otherwise).
  // sums (optional): kSumBytes per vertex below coord_count / 3 (the vertex choice's umbrella
  // sums, updated for most of the ring).
  static constexpr size_t kSumBytes = 16;
  void step(const ProgressiveMesh& m, const int32_t* coords, size_t coord_count, uint32_t v_ahead,
            const uint32_t* degree = nullptr, const uint8_t* sums = nullptr) {
    const uint32_t slot = advance(m, coords, coord_count, degree, sums);
    if (v_ahead >= m.vertex_corner.size()) return;
    // v's own coordinates: the wedge scores and the prediction read them (about 3% on the
    // first refinement of bunny00-loop2, median of 7 alternating runs).
    if (size_t(v_ahead) * 3 < coord_count) {
      PMZ_PREFETCH(coords + size_t(v_ahead) * 3);
      if (sums) PMZ_PREFETCH(sums + size_t(v_ahead) * kSumBytes);
    }
    const uint32_t c0 = m.vertex_corner[v_ahead];
    if (c0 < m.opposite.size()) start(m, slot, c0 % 3 == 2 ? c0 - 2 : c0 + 1, kNoCorner);
  }
  // The same for a split re-applied from its sector hint (ProgressiveMesh::resplit): the walk
  // follows the `count` rewritten faces and the one across the last (whose link changes).
  void step_sector(const ProgressiveMesh& m, uint32_t hint_ahead, uint32_t count) {
    const uint32_t slot = advance(m, nullptr, 0, nullptr, nullptr);
    if (hint_ahead < m.opposite.size()) start(m, slot, hint_ahead, count);
  }

 private:
  // Advances every walker by one face; returns the slot of the split applied now (free).
  uint32_t advance(const ProgressiveMesh& m, const int32_t* coords, size_t coord_count,
                   const uint32_t* degree, const uint8_t* sums) {
    const uint32_t* opp = m.opposite.data();
    const uint32_t* cv = m.corner_vertex.data();
    const size_t corners = m.opposite.size();
    const uint32_t slot = slot_;
    slot_ = slot + 1 == kWalkers ? 0 : slot + 1;
    n_[slot] = kNoCorner;  // its split is the one applied now
    for (uint32_t k = 0; k < kWalkers; ++k) {
      const uint32_t n = n_[k];
      if (n >= corners) continue;
      const uint32_t w = cv[n], o = opp[n];
      if (size_t(w) * 3 < coord_count) {
        PMZ_PREFETCH(coords + size_t(w) * 3);
        if (degree) PMZ_PREFETCH(degree + w);
        if (sums) PMZ_PREFETCH(sums + size_t(w) * kSumBytes);
      }
      uint32_t next = o == kNoCorner ? kNoCorner : (o % 3 == 0 ? o + 2 : o - 1);
      if (next == n0_[k] || left_[k]-- == 0) next = kNoCorner;
      n_[k] = next;
      if (next < corners) {
        PMZ_PREFETCH(opp + next);
        PMZ_PREFETCH(cv + next);
      }
    }
    return slot;
  }
  // A walk from fan entry n0 over at most `faces` more faces (kNoCorner: the whole fan).
  void start(const ProgressiveMesh& m, uint32_t slot, uint32_t n0, uint32_t faces) {
    n_[slot] = n0_[slot] = n0;
    left_[slot] = faces;
    PMZ_PREFETCH(m.opposite.data() + n0);
    PMZ_PREFETCH(m.corner_vertex.data() + n0);
  }

  uint32_t n_[kWalkers] = {};
  uint32_t n0_[kWalkers] = {};
  uint32_t left_[kWalkers] = {};
  uint32_t slot_ = 0;
};

// floor((sum + floor(n / 2)) / n) for n > 0: the rounded mean both sides compute.
inline int64_t floor_mean(int64_t sum, int64_t n) {
  int64_t x = sum + n / 2;
  int64_t q = x / n;
  if ((x % n) != 0 && x < 0) --q;  // floor, not truncation
  return q;
}

}  // namespace pmz
