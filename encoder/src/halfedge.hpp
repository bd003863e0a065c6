// SPDX-License-Identifier: MIT
// Internal: a triangle mesh as flat half-edge arrays, the collapse engine's working topology.
// Half-edge h = 4 * face + corner (corner 0..2; slot 3 is padding, vert and twin kNone) runs
// from the vertex at corner h to the vertex at next(h); twin[h] is the opposite half-edge in the
// neighbouring face (kNone on the boundary). Four slots per face make next, prev and the face of
// a half-edge bit operations: with three, the modulo by 3 in every step of every fan walk was
// about a tenth of the engine's instructions.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "pmz/mesh.hpp"

namespace pmz::detail {

inline constexpr uint32_t kNone = 0xFFFFFFFFu;

struct HalfEdgeMesh {
  std::vector<float> pos;      // xyz per vertex
  std::vector<uint32_t> vert;  // origin vertex per half-edge slot; kNone once its face is deleted
  std::vector<uint32_t> twin;  // per half-edge slot
  // Per vertex: one outgoing half-edge; for a boundary vertex the one without a twin, so a
  // rotation from it sweeps the whole fan. kNone for isolated or collapsed vertices.
  std::vector<uint32_t> out;

  static uint32_t next(uint32_t h) { return (h & 3) == 2 ? h - 2 : h + 1; }
  static uint32_t prev(uint32_t h) { return (h & 3) == 0 ? h + 2 : h - 1; }
  static uint32_t face(uint32_t h) { return h >> 2; }
  static uint32_t corner(uint32_t h) { return h & 3; }
  static uint32_t half_edge(uint32_t f, uint32_t corner) { return 4 * f + corner; }
  uint32_t dest(uint32_t h) const { return vert[next(h)]; }
  bool face_alive(uint32_t f) const { return vert[4 * f] != kNone; }
  bool is_boundary(uint32_t v) const { return twin[out[v]] == kNone; }
  // The next outgoing half-edge around the origin of h; kNone past the boundary.
  uint32_t rotate(uint32_t h) const { return twin[prev(h)]; }
  uint32_t face_count() const { return uint32_t(vert.size() / 4); }
  // Half-edge slots, padding included (skip h with vert[h] == kNone when iterating).
  uint32_t slot_count() const { return uint32_t(vert.size()); }
  uint32_t vertex_count() const { return uint32_t(out.size()); }
  const float* p(uint32_t v) const { return &pos[size_t(v) * 3]; }
};

// Builds the half-edge arrays. Fails with a one-line message on out-of-range indices, faces
// with a repeated vertex, and non-manifold edges or vertices (the engine needs a
// manifold-with-boundary mesh; mesh_io repairs ordinary input before it gets here).
bool build_halfedge(const IndexedMesh& in, HalfEdgeMesh& m, std::string& error);

// f(h) for each outgoing half-edge of v, one per incident face, in rotation order.
template <class F>
void for_each_outgoing(const HalfEdgeMesh& m, uint32_t v, F&& f) {
  uint32_t start = m.out[v];
  if (start == kNone) return;
  uint32_t h = start;
  do {
    f(h);
    h = m.rotate(h);
  } while (h != kNone && h != start);
}

// Starts the loads of the face of half-edge h: its vert and twin entries (slots 4f .. 4f + 3,
// 16 bytes each, never across a cache line).
inline void prefetch_face_links(const HalfEdgeMesh& m, uint32_t h) {
  __builtin_prefetch(&m.vert[h & ~3u]);
  __builtin_prefetch(&m.twin[h & ~3u]);
}

// f(w, h) for each neighbour w of v; h is a half-edge of the edge (v, w): outgoing v->w, except
// for the last neighbour of a boundary vertex, where it is the incoming boundary half-edge w->v.
template <class F>
void for_each_neighbour(const HalfEdgeMesh& m, uint32_t v, F&& f) {
  uint32_t start = m.out[v];
  if (start == kNone) return;
  uint32_t h = start;
  for (;;) {
    f(m.dest(h), h);
    uint32_t p = HalfEdgeMesh::prev(h);
    uint32_t n = m.twin[p];
    if (n == kNone) {
      f(m.vert[p], p);
      return;
    }
    if (n == start) return;
    h = n;
  }
}

// f(w) for each neighbour w of each vertex in `centres` (a vertex once per centre it neighbours),
// the walks round the centres interleaved: each step of one walk loads the next face of its fan
// (a cache miss on a large mesh), so one step of every walk is taken in turn and the next face
// prefetched, and the misses of the different fans overlap instead of coming one after another.
// `walk` is scratch (pairs of current and start half-edge); prefetch_face(f) may start the loads
// of what the caller keeps per face.
template <class F, class P>
void for_each_neighbour_interleaved(const HalfEdgeMesh& m, const std::vector<uint32_t>& centres,
                                    std::vector<uint32_t>& walk, F&& f, P&& prefetch_face) {
  walk.clear();
  for (uint32_t c : centres)
    if (const uint32_t start = m.out[c]; start != kNone)
      walk.push_back(start), walk.push_back(start);
  while (!walk.empty()) {
    for (size_t i = 0; i < walk.size();) {
      const uint32_t h = walk[i];
      f(m.dest(h));
      const uint32_t p = HalfEdgeMesh::prev(h), n = m.twin[p];
      if (n == kNone || n == walk[i + 1]) {
        if (n == kNone) f(m.vert[p]);
        walk[i] = walk[walk.size() - 2], walk[i + 1] = walk.back();
        walk.resize(walk.size() - 2);
        continue;
      }
      walk[i] = n;
      prefetch_face_links(m, n);
      prefetch_face(HalfEdgeMesh::face(n));
      i += 2;
    }
  }
}

// Starts the loads of the fans of `centres`: walks each from its start forwards and backwards
// at once, all walks interleaved (a step of each in turn, so their misses overlap), prefetching
// each face and calling prefetch_neighbour(w) for the neighbours met; a fan's two walks stop
// where they meet. `walk` is scratch (per centre: forward and backward half-edge).
template <class P>
void prefetch_fans(const HalfEdgeMesh& m, const std::vector<uint32_t>& centres,
                   std::vector<uint32_t>& walk, P&& prefetch_neighbour) {
  auto prefetch = [&](uint32_t h) { prefetch_face_links(m, h); };
  walk.clear();
  for (uint32_t c : centres)
    if (const uint32_t start = m.out[c]; start != kNone)
      walk.push_back(start), walk.push_back(start);
  for (uint32_t round = 0; round < 64 && !walk.empty(); ++round) {
    for (size_t i = 0; i < walk.size();) {
      uint32_t &fwd = walk[i], &back = walk[i + 1];
      prefetch_neighbour(m.dest(fwd));
      bool done = false;
      if (const uint32_t n = m.twin[HalfEdgeMesh::prev(fwd)]; n == kNone || n == back) {
        done = true;
      } else {
        fwd = n;
        prefetch(fwd);
        if (const uint32_t t = m.twin[back]; t != kNone) {
          const uint32_t p = HalfEdgeMesh::next(t);
          if (p == fwd) {
            done = true;
          } else {
            back = p;
            prefetch(back);
            prefetch_neighbour(m.dest(back));
          }
        }
      }
      if (done) {
        walk[i] = walk[walk.size() - 2], walk[i + 1] = walk.back();
        walk.resize(walk.size() - 2);
        continue;
      }
      i += 2;
    }
  }
}

}  // namespace pmz::detail
