// SPDX-License-Identifier: MIT
// Internal: the terms of the paper's multi-feature metric (spec/algorithm.md) on the half-edge
// mesh, cached per face and per vertex so that a collapse recomputes only its neighbourhood.
#pragma once
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "halfedge.hpp"
#include "pmz/simplify.hpp"

namespace pmz::detail {

// Garland-Heckbert quadric: symmetric 3x3 A (xx xy xz yy yz zz), b, c; error(p) = pAp + 2bp + c.
struct Quadric {
  double a[10] = {};
  // Inline: every current-mesh quadric adds one plane per face of the fan.
  void add_plane(const double n[3], double d, double w) {
    a[0] += w * n[0] * n[0], a[1] += w * n[0] * n[1], a[2] += w * n[0] * n[2];
    a[3] += w * n[1] * n[1], a[4] += w * n[1] * n[2], a[5] += w * n[2] * n[2];
    a[6] += w * n[0] * d, a[7] += w * n[1] * d, a[8] += w * n[2] * d;
    a[9] += w * d * d;
  }
  void add(const Quadric& q) {
    for (int i = 0; i < 10; ++i) a[i] += q.a[i];
  }
  // Inline: the engine evaluates it tens of millions of times.
  double error(const float pf[3]) const {
    const double x = pf[0], y = pf[1], z = pf[2];
    return x * (a[0] * x + 2 * (a[1] * y + a[2] * z + a[6])) +
           y * (a[3] * y + 2 * (a[4] * z + a[7])) + z * (a[5] * z + 2 * a[8]) + a[9];
  }
};

// Q(v) of every vertex: area-weighted planes of its faces, plus, on each boundary edge, the
// plane through the edge perpendicular to its face weighted by boundary_weight * length^2.
void initial_quadrics(const HalfEdgeMesh& m, double boundary_weight, std::vector<Quadric>& q);

// Q(v) of the current mesh (the multifeature metric's reading, spec/algorithm.md section 2): the
// area-weighted planes of v's faces as they are now, each through p_v, plus the plane of each
// boundary edge at v as in initial_quadrics. Reads the cached face normals and areas.
struct Features;
void current_quadric(const HalfEdgeMesh& m, const Features& f, uint32_t v, double boundary_weight,
                     Quadric& q);

// Per vertex and per face, the terms a cost evaluation or a torsion update reads together sit
// in one 32-byte record: a collapse lands somewhere random on the mesh, so the engine's time
// is mostly cache misses and each separate array costs one more.
struct alignas(32) VertexTerms {
  float b[3];       // B(v) of eq. 2 (mean over the faces of v)
  float torsion;    // T(v), eq. 2, in 1 / length
  float c_norm;     // eq. 1
  float normal[3];  // n(v): area-weighted unit vertex normal
};
struct alignas(32) FaceTerms {
  float normal[3];  // unit normal (zero if degenerate)
  float area;
  float length[3];  // per half-edge of the face: its length (sigma and T read it, no sqrt)
  float unused;
};

struct Features {
  std::vector<FaceTerms> face;
  std::vector<VertexTerms> vertex;
  float epsilon = 0;

  const float* face_normal(uint32_t f) const { return face[f].normal; }
  float face_area(uint32_t f) const { return face[f].area; }
  float length(uint32_t h) const {
    return face[HalfEdgeMesh::face(h)].length[HalfEdgeMesh::corner(h)];
  }
  const float* normal(uint32_t v) const { return vertex[v].normal; }
  const float* b(uint32_t v) const { return vertex[v].b; }
  float c_norm(uint32_t v) const { return vertex[v].c_norm; }
  float torsion(uint32_t v) const { return vertex[v].torsion; }
  void resize(uint32_t vertex_count, uint32_t face_count);
  void update_face(const HalfEdgeMesh& m, uint32_t f);
  // n(v), C_norm(v), B(v) from the cached face normals around v.
  void update_normal_terms(const HalfEdgeMesh& m, uint32_t v);
  // T(v) from B of v and of its neighbours.
  void update_torsion(const HalfEdgeMesh& m, uint32_t v);
  // T(v) summed over a walk of v's neighbours w (h a half-edge of the edge (v, w)), in that order.
  struct TorsionSum {
    float num = 0, den = 0;
    void add(const Features& f, uint32_t v, uint32_t w, uint32_t h) {
      const float *a = f.vertex[w].b, *b = f.vertex[v].b;
      const float dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
      num += std::sqrt(dx * dx + dy * dy + dz * dz);
      den += f.length(h);
    }
    float value() const { return den > 0 ? num / den : 0.f; }
  };
  // All terms for the whole mesh.
  void compute_all(const HalfEdgeMesh& m);
};

// eq. 3: length of the edge of half-edge h over the sum of the other edges of its one or two
// triangles, from the cached half-edge lengths of f.
inline float edge_length_ratio(const HalfEdgeMesh& m, const Features& f, uint32_t h) {
  // The next and previous corner of h's face: one table lookup each.
  static constexpr uint8_t kNext[3] = {1, 2, 0}, kPrev[3] = {2, 0, 1};
  const float* l = f.face[HalfEdgeMesh::face(h)].length;
  const uint32_t c = HalfEdgeMesh::corner(h);
  float others = l[kNext[c]] + l[kPrev[c]];
  if (const uint32_t t = m.twin[h]; t != kNone) {
    const float* lt = f.face[HalfEdgeMesh::face(t)].length;
    others += lt[kNext[HalfEdgeMesh::corner(t)]] + lt[kPrev[HalfEdgeMesh::corner(t)]];
  }
  return others > 0 ? l[c] / others : 0.f;
}

// Mean length of the mesh's edges (each edge once); the metric's unit of length.
double mean_edge_length(const HalfEdgeMesh& m);

// The engine's own cost of the collapse u -> v on `mesh` before any collapse (simplify.cpp; the
// tests check it against the formula of spec/algorithm.md). NaN if (u, v) is not an edge.
float initial_collapse_cost(const IndexedMesh& mesh, const SimplifyOptions& options, uint32_t u,
                            uint32_t v);

// A collapse u -> v in the engine's queue (input ids). cached: the key the heap holds. current:
// its cost from the engine's cached terms (T recomputed first where flagged stale, as before any
// key). fresh: its cost computed from scratch on the current mesh (every face and vertex term,
// torsion and quadric rebuilt; the accumulated quadric summed anew from the input's over the
// vertices merged into each; the attribute term as the engine holds it). key_stale: the key is
// marked for recomputation when it reaches the top (it may be out of date by design);
// deferred: the key is the guard's penalised cost.
struct QueuedCollapse {
  uint32_t u, v;
  float cached, current, fresh;
  bool key_stale, deferred;
};

// Runs the engine on `mesh` as simplify() does for k collapses (fewer if it stops before) and
// lists every queued collapse: a testing seam, the cached keys against the metric's meaning.
// False with a message on input the engine refuses.
bool queued_collapses(const IndexedMesh& mesh, const SimplifyOptions& options, uint64_t k,
                      std::vector<QueuedCollapse>& out, std::string& error);

}  // namespace pmz::detail
