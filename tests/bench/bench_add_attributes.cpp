// SPDX-License-Identifier: MIT
// bench-add-attributes IN OUT [--colors]: gives a geometry-only mesh attributes like a real
// asset's, for the textured benchmark (tests/bench/textured.py): texture coordinates from a
// box projection per chart (faces grouped by their dominant normal axis, smoothed so charts are
// not speckled; the six charts tiled into one atlas, so chart borders are texture seams),
// normals smooth within creases (dihedral angle above 60 degrees), and with --colors vertex
// colours from a mean curvature estimate (concave blue, flat white, convex red). Writes by
// extension (.obj + .mtl, .glb, .ply).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <string>
#include <unordered_map>
#include <vector>

#include "bench_common.hpp"
#include "pmz/mesh.hpp"

namespace {

constexpr float kCreaseCos = 0.5f;  // 60 degrees

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(uint32_t a, uint32_t b) { parent[find(a)] = find(b); }
};

}  // namespace

int main(int argc, char** argv) {
  const char* tool = "bench-add-attributes";
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s IN OUT [--colors]\n", tool);
    return 2;
  }
  const bool colors = argc > 3 && std::string(argv[3]) == "--colors";
  pmz::IndexedMesh mesh;
  std::string error;
  if (!pmz::read_mesh(argv[1], mesh, error)) return pmz_bench::fail(tool, error);
  mesh.attributes = {};
  const uint32_t faces = mesh.face_count(), vertices = mesh.vertex_count();
  const float* pos = mesh.positions.data();
  auto p = [&](uint32_t v) { return pos + size_t(v) * 3; };

  std::vector<float> normal(size_t(faces) * 3), area(faces);
  for (uint32_t f = 0; f < faces; ++f) {
    const float *a = p(mesh.indices[f * 3]), *b = p(mesh.indices[f * 3 + 1]),
                *c = p(mesh.indices[f * 3 + 2]);
    const float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                  e1[0] * e2[1] - e1[1] * e2[0]};
    const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    area[f] = 0.5f * len;
    for (int k = 0; k < 3; ++k) normal[f * 3 + k] = len > 0 ? n[k] / len : 0.f;
  }
  // Corner across each edge: directed edge (a, b) of corner c -> the corner of b->a's face.
  std::unordered_map<uint64_t, uint32_t> edge_corner;
  edge_corner.reserve(size_t(faces) * 3);
  auto key = [](uint32_t a, uint32_t b) { return uint64_t(a) << 32 | b; };
  for (uint32_t c = 0; c < faces * 3; ++c)
    edge_corner[key(mesh.indices[c], mesh.indices[c - c % 3 + (c + 1) % 3])] = c;
  auto opposite = [&](uint32_t c) -> uint32_t {  // corner of the twin edge's origin, or ~0u
    const uint32_t a = mesh.indices[c], b = mesh.indices[c - c % 3 + (c + 1) % 3];
    const auto it = edge_corner.find(key(b, a));
    return it == edge_corner.end() ? ~0u : it->second;
  };

  // Charts: dominant axis and sign of the face normal, then a few majority votes among the
  // edge neighbours so the chart borders are curves rather than speckle.
  std::vector<uint8_t> chart(faces);
  for (uint32_t f = 0; f < faces; ++f) {
    const float* n = &normal[f * 3];
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (std::fabs(n[k]) > std::fabs(n[axis])) axis = k;
    chart[f] = uint8_t(axis * 2 + (n[axis] < 0));
  }
  for (int round = 0; round < 12; ++round) {
    std::vector<uint8_t> next(chart);
    for (uint32_t f = 0; f < faces; ++f) {
      int votes[6] = {};
      votes[chart[f]] += 1;
      for (int k = 0; k < 3; ++k)
        if (const uint32_t o = opposite(f * 3 + k); o != ~0u) votes[chart[o / 3]] += 1;
      int best = chart[f];
      for (int c = 0; c < 6; ++c)
        if (votes[c] > votes[best]) best = c;
      next[f] = uint8_t(best);
    }
    chart.swap(next);
  }

  // Corners of one vertex are joined across an edge when the faces share the chart (texture
  // coordinates) / when the edge is not a crease (normals).
  UnionFind uv(size_t(faces) * 3), nrm(size_t(faces) * 3);
  for (uint32_t c = 0; c < faces * 3; ++c) {
    const uint32_t o = opposite(c);
    if (o == ~0u || o < c) continue;
    const uint32_t f = c / 3, g = o / 3;
    const uint32_t c_next = c - c % 3 + (c + 1) % 3, o_next = o - o % 3 + (o + 1) % 3;
    // Edge (a, b): a is corner c in f and corner o_next in g; b is c_next in f and o in g.
    if (chart[f] == chart[g]) uv.unite(c, o_next), uv.unite(c_next, o);
    const float* nf = &normal[f * 3];
    const float* ng = &normal[g * 3];
    if (nf[0] * ng[0] + nf[1] * ng[1] + nf[2] * ng[2] >= kCreaseCos)
      nrm.unite(c, o_next), nrm.unite(c_next, o);
  }
  // Smooth normals per normal class: face normals weighted by the corner angle.
  std::vector<double> class_normal(size_t(faces) * 9, 0.0);
  for (uint32_t c = 0; c < faces * 3; ++c) {
    const uint32_t f = c / 3;
    const float* a = p(mesh.indices[c]);
    const float* b = p(mesh.indices[f * 3 + (c + 1) % 3]);
    const float* d = p(mesh.indices[f * 3 + (c + 2) % 3]);
    double u[3], w[3];
    for (int k = 0; k < 3; ++k) u[k] = b[k] - a[k], w[k] = d[k] - a[k];
    const double lu = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    const double lw = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    const double cosine =
        lu > 0 && lw > 0 ? (u[0] * w[0] + u[1] * w[1] + u[2] * w[2]) / (lu * lw) : 1.0;
    const double angle = std::acos(std::clamp(cosine, -1.0, 1.0));
    const uint32_t root = nrm.find(c);
    for (int k = 0; k < 3; ++k) class_normal[size_t(root) * 3 + k] += angle * normal[f * 3 + k];
  }

  // Bounding box for the projection.
  float lo[3], hi[3];
  for (int k = 0; k < 3; ++k) lo[k] = hi[k] = pos[k];
  for (uint32_t v = 0; v < vertices; ++v)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p(v)[k]), hi[k] = std::max(hi[k], p(v)[k]);

  // Vertex colours: the mean curvature estimate (Laplacian along the vertex normal over the
  // mean neighbour distance), mapped blue - white - red.
  std::vector<float> vertex_color;
  if (colors) {
    std::vector<double> lap(size_t(vertices) * 3, 0.0), vn(size_t(vertices) * 3, 0.0),
        dist(vertices, 0.0);
    std::vector<uint32_t> count(vertices, 0);
    for (uint32_t c = 0; c < faces * 3; ++c) {
      const uint32_t a = mesh.indices[c], b = mesh.indices[c - c % 3 + (c + 1) % 3];
      double d2 = 0;
      for (int k = 0; k < 3; ++k) {
        lap[size_t(a) * 3 + k] += p(b)[k] - p(a)[k];
        lap[size_t(b) * 3 + k] += p(a)[k] - p(b)[k];
        vn[size_t(a) * 3 + k] += area[c / 3] * normal[(c / 3) * 3 + k];
        d2 += double(p(b)[k] - p(a)[k]) * (p(b)[k] - p(a)[k]);
      }
      dist[a] += std::sqrt(d2), dist[b] += std::sqrt(d2), count[a] += 1, count[b] += 1;
    }
    vertex_color.resize(size_t(vertices) * 3, 1.f);
    for (uint32_t v = 0; v < vertices; ++v) {
      if (count[v] == 0) continue;
      const double* n = &vn[size_t(v) * 3];
      const double ln = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      const double mean_dist = dist[v] / count[v];
      if (!(ln > 0) || !(mean_dist > 0)) continue;
      const double* l = &lap[size_t(v) * 3];
      const double h = -(l[0] * n[0] + l[1] * n[1] + l[2] * n[2]) / (ln * count[v] * mean_dist);
      const float t = float(std::clamp(h * 4.0, -1.0, 1.0));  // > 0 convex
      float* rgb = &vertex_color[size_t(v) * 3];
      rgb[0] = t < 0 ? 1 + t : 1.f, rgb[1] = 1 - std::fabs(t), rgb[2] = t > 0 ? 1 - t : 1.f;
    }
  }

  // Wedges: one per (vertex, texture-coordinate class, normal class).
  pmz::MeshAttributes& at = mesh.attributes;
  at.texcoords.resize(1);
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> wedge_of;
  at.corner_wedges.resize(size_t(faces) * 3);
  for (uint32_t c = 0; c < faces * 3; ++c) {
    const auto [it, added] =
        wedge_of.try_emplace({uv.find(c), nrm.find(c)}, uint32_t(wedge_of.size()));
    at.corner_wedges[c] = it->second;
    if (!added) continue;
    const uint32_t v = mesh.indices[c];
    at.wedge_vertices.push_back(v);
    const int ch = chart[c / 3], axis = ch / 2;
    const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    float s = (p(v)[ua] - lo[ua]) / std::max(hi[ua] - lo[ua], 1e-30f);
    const float t = (p(v)[va] - lo[va]) / std::max(hi[va] - lo[va], 1e-30f);
    if (ch & 1) s = 1 - s;  // the far side mirrored, so every chart keeps its orientation
    at.texcoords[0].push_back((float(ch % 3) + 0.05f + 0.9f * s) / 3.f);
    at.texcoords[0].push_back((float(ch / 3) + 0.05f + 0.9f * t) / 2.f);
    const double* n = &class_normal[size_t(nrm.find(c)) * 3];
    const double ln = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; ++k)
      at.normals.push_back(ln > 0 ? float(n[k] / ln) : k == 2 ? 1.f : 0.f);
    if (colors)
      for (int k = 0; k < 3; ++k) at.colors.push_back(vertex_color[size_t(v) * 3 + k]);
  }
  if (colors) at.color_components = 3;
  at.materials.push_back({});
  at.materials[0].name = "atlas";
  at.materials[0].base_color_texture = "atlas.png";
  at.face_materials.assign(faces, 0);
  if (!pmz::write_mesh(argv[2], mesh, error)) return pmz_bench::fail(tool, error);
  std::printf("{\"faces\": %u, \"vertices\": %u, \"wedges\": %u}\n", faces, vertices,
              at.wedge_count());
  return 0;
}
