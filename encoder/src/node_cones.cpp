// SPDX-License-Identifier: MIT
#include "node_cones.hpp"

#include <algorithm>
#include <cmath>

namespace pmz {

bool NodeCones::normal(uint32_t a, uint32_t b, uint32_t c, double n[3]) const {
  double p[3][3];
  const uint32_t v[3] = {a, b, c};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) p[i][k] = quant_.dequantize(coords_[size_t(v[i]) * 3 + k], k);
  const double e[2][3] = {{p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]},
                          {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]}};
  n[0] = e[0][1] * e[1][2] - e[0][2] * e[1][1];
  n[1] = e[0][2] * e[1][0] - e[0][0] * e[1][2];
  n[2] = e[0][0] * e[1][1] - e[0][1] * e[1][0];
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(len > 0) || !std::isfinite(len)) return false;
  for (int k = 0; k < 3; ++k) n[k] /= len;
  return true;
}

void NodeCones::node_done(const ProgressiveMesh& m, uint32_t first, uint32_t end) {
  normals_.clear();
  for (uint32_t u = first; u < end; ++u)
    m.for_each_fan_face(u, [&](uint32_t a, uint32_t b) {
      // Each face once: at its smallest corner among the node's vertices.
      if ((a >= first && a < u) || (b >= first && b < u)) return;
      double n[3];
      if (normal(u, a, b, n)) normals_.insert(normals_.end(), n, n + 3);
    });
  // The axis: the mean of the unit normals, quantized (largest component 127); the cutoff is
  // measured against the quantized axis itself, so its rounding costs no safety.
  Cone cone;
  double sum[3] = {0, 0, 0};
  for (size_t i = 0; i < normals_.size(); ++i) sum[i % 3] += normals_[i];
  const double big = std::max({std::fabs(sum[0]), std::fabs(sum[1]), std::fabs(sum[2])});
  if (big > 1e-9 * double(normals_.size())) {
    double len = 0;
    for (int k = 0; k < 3; ++k) {
      cone.stored[k] = int8_t(std::lround(127 * sum[k] / big));
      len += double(cone.stored[k]) * cone.stored[k];
    }
    for (int k = 0; k < 3; ++k) cone.axis[k] = cone.stored[k] / std::sqrt(len);
    for (size_t i = 0; i < normals_.size(); i += 3)
      cone.min_dot =
          std::min(cone.min_dot, normals_[i] * cone.axis[0] + normals_[i + 1] * cone.axis[1] +
                                     normals_[i + 2] * cone.axis[2]);
  }
  cones_.push_back(cone);
}

void NodeCones::finish(const ProgressiveMesh& m, uint32_t base_vertices, NodeTable& t) {
  std::vector<uint32_t> first_vertex;  // per node
  uint64_t at = base_vertices;
  for (const NodeEntry& e : t.nodes) {
    first_vertex.push_back(uint32_t(at));
    at += e.splits;
  }
  for (uint32_t f = 0; f < m.face_count(); ++f) {
    const uint32_t* c = &m.corner_vertex[size_t(f) * 3];
    uint32_t nodes[3], count = 0;
    for (int i = 0; i < 3; ++i) {
      if (c[i] < base_vertices) continue;
      const uint32_t k = uint32_t(std::upper_bound(first_vertex.begin(), first_vertex.end(), c[i]) -
                                  first_vertex.begin() - 1);
      if (std::find(nodes, nodes + count, k) == nodes + count) nodes[count++] = k;
    }
    double n[3];
    if (count == 0 || !normal(c[0], c[1], c[2], n)) continue;
    for (uint32_t i = 0; i < count; ++i) {
      Cone& cone = cones_[nodes[i]];
      cone.min_dot =
          std::min(cone.min_dot, n[0] * cone.axis[0] + n[1] * cone.axis[1] + n[2] * cone.axis[2]);
    }
  }
  // cutoff = the sine of the cone's half-angle, times 127, rounded up (a margin for the
  // rounding of the dot products); a cone of 90 degrees or more culls nothing: no cone.
  for (size_t k = 0; k < t.nodes.size(); ++k) {
    NodeEntry& e = t.nodes[k];
    const Cone& cone = cones_[k];
    const bool axis = cone.stored[0] | cone.stored[1] | cone.stored[2];
    const double sine = std::sqrt(std::max(0.0, 1 - cone.min_dot * cone.min_dot));
    e.cone_cutoff = axis && cone.min_dot > 0
                        ? uint8_t(std::min(127.0, std::ceil(127 * sine + 1e-6)))
                        : NodeEntry::kNoCone;
    for (int a = 0; a < 3; ++a)
      e.cone_axis[a] = e.cone_cutoff == NodeEntry::kNoCone ? 0 : cone.stored[a];
  }
}

}  // namespace pmz
