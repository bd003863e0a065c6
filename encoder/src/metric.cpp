// SPDX-License-Identifier: MIT
// The multi-feature metric's terms (Wang, Qiao & Zhou): quadrics, C_norm (eq. 1), torsion
// (eq. 2) and the edge-length ratio (eq. 3). The readings the paper leaves open are argued in
// spec/algorithm.md.
#include "metric.hpp"

#include <cmath>

#include "parallel.hpp"

namespace pmz::detail {

namespace {

inline float distance(const float* a, const float* b) {
  float dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

}  // namespace

void initial_quadrics(const HalfEdgeMesh& m, double boundary_weight, std::vector<Quadric>& q) {
  q.assign(m.vertex_count(), Quadric{});
  for (uint32_t f = 0; f < m.face_count(); ++f) {
    const uint32_t* c = &m.vert[HalfEdgeMesh::half_edge(f, 0)];
    const float *p0 = m.p(c[0]), *p1 = m.p(c[1]), *p2 = m.p(c[2]);
    const double e1[3] = {double(p1[0]) - p0[0], double(p1[1]) - p0[1], double(p1[2]) - p0[2]};
    const double e2[3] = {double(p2[0]) - p0[0], double(p2[1]) - p0[1], double(p2[2]) - p0[2]};
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                   e1[0] * e2[1] - e1[1] * e2[0]};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (len == 0) continue;
    for (double& c : n) c /= len;
    const double d = -(n[0] * p0[0] + n[1] * p0[1] + n[2] * p0[2]);
    Quadric face;
    face.add_plane(n, d, 0.5 * len);  // weight = area
    for (int k = 0; k < 3; ++k) q[c[k]].add(face);
    if (boundary_weight <= 0) continue;
    for (uint32_t h = HalfEdgeMesh::half_edge(f, 0); h < HalfEdgeMesh::half_edge(f, 3); ++h) {
      if (m.twin[h] != kNone) continue;
      const float *a = m.p(m.vert[h]), *b = m.p(m.dest(h));
      const double e[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
      double bn[3] = {e[1] * n[2] - e[2] * n[1], e[2] * n[0] - e[0] * n[2],
                      e[0] * n[1] - e[1] * n[0]};
      const double el2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
      const double bl = std::sqrt(bn[0] * bn[0] + bn[1] * bn[1] + bn[2] * bn[2]);
      if (bl == 0) continue;
      for (double& c : bn) c /= bl;
      Quadric edge;
      edge.add_plane(bn, -(bn[0] * a[0] + bn[1] * a[1] + bn[2] * a[2]), boundary_weight * el2);
      q[m.vert[h]].add(edge);
      q[m.dest(h)].add(edge);
    }
  }
}

void current_quadric(const HalfEdgeMesh& m, const Features& f, uint32_t v, double boundary_weight,
                     Quadric& q) {
  q = Quadric{};
  const float* pv = m.p(v);
  // The plane through p_v perpendicular to n, weighted.
  auto add = [&](const double n[3], double weight) {
    q.add_plane(n, -(n[0] * pv[0] + n[1] * pv[1] + n[2] * pv[2]), weight);
  };
  // The boundary plane of edge a -> b of a face with normal fn, as in initial_quadrics.
  auto add_boundary = [&](const float* a, const float* b, const float* fn) {
    const double e[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
    double bn[3] = {e[1] * fn[2] - e[2] * fn[1], e[2] * fn[0] - e[0] * fn[2],
                    e[0] * fn[1] - e[1] * fn[0]};
    const double bl = std::sqrt(bn[0] * bn[0] + bn[1] * bn[1] + bn[2] * bn[2]);
    if (bl == 0) return;
    for (double& c : bn) c /= bl;
    add(bn, boundary_weight * (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]));
  };
  for_each_outgoing(m, v, [&](uint32_t h) {
    const FaceTerms& face = f.face[HalfEdgeMesh::face(h)];
    const double n[3] = {face.normal[0], face.normal[1], face.normal[2]};
    add(n, face.area);
    if (boundary_weight <= 0) return;
    if (m.twin[h] == kNone) add_boundary(pv, m.p(m.dest(h)), face.normal);
    const uint32_t in = HalfEdgeMesh::prev(h);
    if (m.twin[in] == kNone) add_boundary(m.p(m.vert[in]), pv, face.normal);
  });
}

void Features::resize(uint32_t vertex_count, uint32_t face_count) {
  face.assign(face_count, FaceTerms{});
  vertex.assign(vertex_count, VertexTerms{});
}

void Features::update_face(const HalfEdgeMesh& m, uint32_t f) {
  const uint32_t* c = &m.vert[HalfEdgeMesh::half_edge(f, 0)];
  const float *p0 = m.p(c[0]), *p1 = m.p(c[1]), *p2 = m.p(c[2]);
  const float e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
  const float e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
  float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0]};
  const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  const float inv = len > 0 ? 1.f / len : 0.f;
  FaceTerms& out = face[f];
  out.normal[0] = n[0] * inv, out.normal[1] = n[1] * inv, out.normal[2] = n[2] * inv,
  out.area = 0.5f * len;
  out.length[0] = std::sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
  out.length[1] = distance(p1, p2);
  out.length[2] = std::sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]);
}

void Features::update_normal_terms(const HalfEdgeMesh& m, uint32_t v) {
  // Two walks round v: the second needs n(v) first. Walking again is cheaper than collecting
  // the faces into a buffer (the walk's arrays are in cache by then).
  float n[3] = {0, 0, 0};
  uint32_t k = 0;
  for_each_outgoing(m, v, [&](uint32_t h) {
    const FaceTerms& fd = face[HalfEdgeMesh::face(h)];
    n[0] += fd.area * fd.normal[0], n[1] += fd.area * fd.normal[1], n[2] += fd.area * fd.normal[2];
    ++k;
  });
  const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (len > 0)
    for (float& c : n) c /= len;
  float c_sum = 0, bv[3] = {0, 0, 0};
  for_each_outgoing(m, v, [&](uint32_t h) {
    const float* ni = face[HalfEdgeMesh::face(h)].normal;
    const float dot = n[0] * ni[0] + n[1] * ni[1] + n[2] * ni[2];
    c_sum += 1.f - dot;
    if (dot > epsilon) {
      const float w = (dot - epsilon) * (dot - epsilon);
      for (int i = 0; i < 3; ++i) bv[i] += w * ni[i];
    }
  });
  const float inv_k = k ? 1.f / float(k) : 0.f;
  VertexTerms& t = vertex[v];
  for (int i = 0; i < 3; ++i) t.normal[i] = n[i], t.b[i] = bv[i] * inv_k;
  t.c_norm = c_sum * inv_k;
}

void Features::update_torsion(const HalfEdgeMesh& m, uint32_t v) {
  TorsionSum t;
  for_each_neighbour(m, v, [&](uint32_t w, uint32_t h) { t.add(*this, v, w, h); });
  vertex[v].torsion = t.value();
}

void Features::compute_all(const HalfEdgeMesh& m) {
  resize(m.vertex_count(), m.face_count());
  // Each loop writes only the record of its index (torsion reads the B of the loop before).
  parallel_halves(m.face_count(), [&](uint32_t begin, uint32_t end) {
    for (uint32_t f = begin; f < end; ++f)
      if (m.face_alive(f)) update_face(m, f);
  });
  parallel_halves(m.vertex_count(), [&](uint32_t begin, uint32_t end) {
    for (uint32_t v = begin; v < end; ++v) update_normal_terms(m, v);
  });
  parallel_halves(m.vertex_count(), [&](uint32_t begin, uint32_t end) {
    for (uint32_t v = begin; v < end; ++v) update_torsion(m, v);
  });
}

double mean_edge_length(const HalfEdgeMesh& m) {
  double sum = 0;
  uint64_t count = 0;
  for (uint32_t h = 0; h < m.vert.size(); ++h) {
    if (m.vert[h] == kNone || (m.twin[h] != kNone && m.twin[h] < h)) continue;
    sum += distance(m.p(m.vert[h]), m.p(m.dest(h)));
    ++count;
  }
  return count ? sum / double(count) : 0.0;
}

}  // namespace pmz::detail
