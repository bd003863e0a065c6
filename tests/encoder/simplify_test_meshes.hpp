// SPDX-License-Identifier: MIT
// Small procedural meshes and a topology summary for the metric and engine tests.
#pragma once
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "../../encoder/src/halfedge.hpp"
#include "pmz/mesh.hpp"

namespace pmz_test {

// A triangle by its corners, rotated to start at the smallest id (orientation kept), so that
// face sets from different numberings compare as sorted vectors.
using Face = std::array<uint32_t, 3>;
inline Face canonical(uint32_t a, uint32_t b, uint32_t c) {
  if (b < a && b < c) return {b, c, a};
  if (c < a && c < b) return {c, a, b};
  return {a, b, c};
}

inline void add_vertex(pmz::IndexedMesh& m, double x, double y, double z) {
  m.positions.insert(m.positions.end(), {float(x), float(y), float(z)});
}
inline void add_face(pmz::IndexedMesh& m, uint32_t a, uint32_t b, uint32_t c) {
  m.indices.insert(m.indices.end(), {a, b, c});
}

// n x n quads in the plane z = 0, spacing `step`, each split along a diagonal; normals +z.
inline pmz::IndexedMesh grid(uint32_t n, double step = 1.0) {
  pmz::IndexedMesh m;
  for (uint32_t j = 0; j <= n; ++j)
    for (uint32_t i = 0; i <= n; ++i) add_vertex(m, i * step, j * step, 0);
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      add_face(m, a, b, d);
      add_face(m, a, d, c);
    }
  return m;
}

// Icosahedron subdivided `levels` times, projected on the unit sphere.
inline pmz::IndexedMesh icosphere(int levels) {
  pmz::IndexedMesh m;
  const double t = (1 + std::sqrt(5.0)) / 2;
  const double v[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                           {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                           {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) {
    const double l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    add_vertex(m, p[0] / l, p[1] / l, p[2] / l);
  }
  m.indices = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
               4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
               6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      double p[3], len = 0;
      for (int k = 0; k < 3; ++k)
        p[k] = (m.positions[a * 3 + k] + m.positions[b * 3 + k]) / 2, len += p[k] * p[k];
      len = std::sqrt(len);
      add_vertex(m, p[0] / len, p[1] / len, p[2] / len);
      return mid[key] = m.vertex_count() - 1;
    };
    std::vector<uint32_t> old = m.indices;
    m.indices.clear();
    for (size_t f = 0; f < old.size(); f += 3) {
      const uint32_t a = old[f], b = old[f + 1], c = old[f + 2];
      const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      add_face(m, a, ab, ca), add_face(m, b, bc, ab), add_face(m, c, ca, bc),
          add_face(m, ab, bc, ca);
    }
  }
  return m;
}

// Torus (genus 1) of nu x nv quads, each split in two.
inline pmz::IndexedMesh torus(uint32_t nu, uint32_t nv, double big = 1.0, double small = 0.35) {
  pmz::IndexedMesh m;
  const double pi2 = 2 * 3.14159265358979;
  for (uint32_t j = 0; j < nv; ++j)
    for (uint32_t i = 0; i < nu; ++i) {
      const double a = pi2 * i / nu, b = pi2 * j / nv;
      add_vertex(m, (big + small * std::cos(b)) * std::cos(a),
                 (big + small * std::cos(b)) * std::sin(a), small * std::sin(b));
    }
  for (uint32_t j = 0; j < nv; ++j)
    for (uint32_t i = 0; i < nu; ++i) {
      const uint32_t a = j * nu + i, b = j * nu + (i + 1) % nu, c = ((j + 1) % nv) * nu + i,
                     d = ((j + 1) % nv) * nu + (i + 1) % nu;
      add_face(m, a, b, d);
      add_face(m, a, d, c);
    }
  return m;
}

struct Topology {
  bool manifold = false;
  std::string error;
  long euler = 0;  // V - E + F over referenced vertices
  int boundary_loops = 0;
  uint32_t faces = 0;
};

inline Topology topology(const pmz::IndexedMesh& mesh) {
  Topology t;
  pmz::detail::HalfEdgeMesh m;
  t.manifold = pmz::detail::build_halfedge(mesh, m, t.error);
  if (!t.manifold) return t;
  long v = 0, e = 0;
  for (uint32_t i = 0; i < m.vertex_count(); ++i) v += m.out[i] != pmz::detail::kNone;
  std::vector<char> seen(m.vert.size(), 0);
  for (uint32_t h = 0; h < m.vert.size(); ++h) {
    if (m.vert[h] == pmz::detail::kNone) continue;  // the padding slot of each face
    e += m.twin[h] == pmz::detail::kNone || m.twin[h] > h;
    if (m.twin[h] != pmz::detail::kNone || seen[h]) continue;
    // Walk the boundary loop: from boundary half-edge a->b, the next boundary half-edge leaves b.
    ++t.boundary_loops;
    uint32_t g = h;
    do {
      seen[g] = 1;
      const uint32_t b = m.dest(g);
      g = m.out[b];  // the boundary vertex's outgoing boundary half-edge
    } while (g != h);
  }
  t.faces = mesh.face_count();
  t.euler = v - e + long(t.faces);
  return t;
}

// Set by scripts/test.sh once the corpus was fetched: a corpus mesh a test asks for and does
// not find is then a failure, not a skip.
inline bool corpus_required() {
  const char* env = std::getenv("PMZ_REQUIRE_CORPUS");
  return env && *env && std::string(env) != "0";
}

// Meshes of the corpus ($PMZ_CORPUS or <source>/corpus) by name, empty when absent.
inline std::string corpus_mesh(const std::string& name) {
  const char* env = std::getenv("PMZ_CORPUS");
  std::filesystem::path dir = env && *env ? env : PMZ_SOURCE_DIR "/corpus";
  for (const char* ext : {".off", ".obj", ".ply"}) {
    auto p = dir / (name + ext);
    if (std::filesystem::exists(p)) return p.string();
  }
  return {};
}

}  // namespace pmz_test
