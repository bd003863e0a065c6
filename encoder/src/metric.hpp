// Internal: the terms of the paper's multi-feature metric (spec/algorithm.md) on the half-edge
// mesh, cached per face and per vertex so that a collapse recomputes only its neighbourhood.
#pragma once
#include <cstdint>
#include <vector>

#include "halfedge.hpp"

namespace pmz::detail {

// Garland-Heckbert quadric: symmetric 3x3 A (xx xy xz yy yz zz), b, c; error(p) = pAp + 2bp + c.
struct Quadric {
  double a[10] = {};
  void add_plane(const double n[3], double d, double weight);
  void add(const Quadric& q) {
    for (int i = 0; i < 10; ++i) a[i] += q.a[i];
  }
  double error(const float p[3]) const;
};

// Q(v) of every vertex: area-weighted planes of its faces, plus, on each boundary edge, the
// plane through the edge perpendicular to its face weighted by boundary_weight * length^2.
void initial_quadrics(const HalfEdgeMesh& m, double boundary_weight, std::vector<Quadric>& q);

struct Features {
  std::vector<float> face;         // per face: unit normal xyz (zero if degenerate), area
  std::vector<float> length;       // per half-edge: its length (sigma and T read it, no sqrt)
  std::vector<float> normal;       // n(v): area-weighted unit vertex normal
  std::vector<float> c_norm;       // eq. 1
  std::vector<float> b;            // B(v) of eq. 2 (mean over the faces of v)
  std::vector<float> torsion;      // T(v), eq. 2, in 1 / length
  float epsilon = 0;
  std::vector<uint32_t> scratch_faces;

  const float* face_normal(uint32_t f) const { return &face[size_t(f) * 4]; }
  float face_area(uint32_t f) const { return face[size_t(f) * 4 + 3]; }

  void resize(uint32_t vertex_count, uint32_t face_count);
  void update_face(const HalfEdgeMesh& m, uint32_t f);
  // n(v), C_norm(v), B(v) from the cached face normals around v.
  void update_normal_terms(const HalfEdgeMesh& m, uint32_t v);
  // T(v) from B of v and of its neighbours.
  void update_torsion(const HalfEdgeMesh& m, uint32_t v);
  // All terms for the whole mesh.
  void compute_all(const HalfEdgeMesh& m);
};

// eq. 3: length of the edge of half-edge h over the sum of the other edges of its one or two
// triangles, from the cached half-edge lengths of f.
float edge_length_ratio(const HalfEdgeMesh& m, const Features& f, uint32_t h);

// Mean length of the mesh's edges (each edge once); the metric's unit of length.
double mean_edge_length(const HalfEdgeMesh& m);

}  // namespace pmz::detail
