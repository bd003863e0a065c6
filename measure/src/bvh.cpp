// SPDX-License-Identifier: MIT
// Triangle BVH: binned SAH build, nearest-first closest-point traversal with pruning.
#include "bvh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pmz/triangle_distance.hpp"

namespace pmz {

namespace {

constexpr int kBins = 16;
constexpr unsigned kMaxDepth = 80;  // deeper ranges become leaves; the query stack fits it
constexpr unsigned kStackSize = kMaxDepth + 8;
constexpr uint32_t kLeafSize = 4;

struct Box {
  float lo[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                 std::numeric_limits<float>::max()};
  float hi[3] = {-std::numeric_limits<float>::max(), -std::numeric_limits<float>::max(),
                 -std::numeric_limits<float>::max()};
  void grow(const float* p) {
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  }
  void grow(const Box& b) {
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], b.lo[k]), hi[k] = std::max(hi[k], b.hi[k]);
  }
  double half_area() const {
    if (lo[0] > hi[0]) return 0;
    double dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    return dx * dy + dy * dz + dz * dx;
  }
};

template <class Node>
inline double box_distance2(const Node& n, const double p[3]) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    double d = std::max({double(n.lo[k]) - p[k], 0.0, p[k] - double(n.hi[k])});
    d2 += d * d;
  }
  return d2;
}

}  // namespace

void TriangleBvh::build(const float* positions, const uint32_t* indices, size_t face_count) {
  // Primitives are permuted in place (not through an index array): the build's passes then
  // stream through memory instead of gathering.
  struct Prim {
    Box box;
    float centroid[3];
    uint32_t face;
  };
  std::vector<Prim> prims(face_count);
  for (size_t f = 0; f < face_count; ++f) {
    Prim& t = prims[f];
    t.face = uint32_t(f);
    for (int k = 0; k < 3; ++k) t.centroid[k] = 0;
    for (int j = 0; j < 3; ++j) {
      const float* p = positions + size_t(indices[f * 3 + j]) * 3;
      t.box.grow(p);
      for (int k = 0; k < 3; ++k) t.centroid[k] += p[k] * (1.0f / 3.0f);
    }
  }

  nodes_.clear();
  nodes_.reserve(face_count / 2 + 1);
  nodes_.push_back({});
  struct Range {
    uint32_t node, begin, end, depth;
  };
  std::vector<Range> todo;
  todo.push_back({0, 0, uint32_t(face_count), 0});
  while (!todo.empty()) {
    Range r = todo.back();
    todo.pop_back();
    Box bounds, cbounds;
    for (uint32_t i = r.begin; i < r.end; ++i) {
      bounds.grow(prims[i].box);
      cbounds.grow(prims[i].centroid);
    }
    Node& node = nodes_[r.node];
    std::copy(bounds.lo, bounds.lo + 3, node.lo);
    std::copy(bounds.hi, bounds.hi + 3, node.hi);
    const uint32_t count = r.end - r.begin;
    auto make_leaf = [&] {
      nodes_[r.node].first = r.begin;
      nodes_[r.node].count = count;
    };
    if (count <= 2 || r.depth >= kMaxDepth) {
      make_leaf();
      continue;
    }
    int axis = 0;
    float extent[3];
    for (int k = 0; k < 3; ++k) extent[k] = cbounds.hi[k] - cbounds.lo[k];
    if (extent[1] > extent[axis]) axis = 1;
    if (extent[2] > extent[axis]) axis = 2;

    uint32_t mid = r.begin;
    if (extent[axis] > 0) {
      // Binned SAH along the widest centroid axis.
      Box bin_box[kBins];
      uint32_t bin_count[kBins] = {};
      const float scale = kBins / extent[axis];
      auto bin_of = [&](const Prim& t) {
        int b = int((t.centroid[axis] - cbounds.lo[axis]) * scale);
        return std::min(b, kBins - 1);
      };
      for (uint32_t i = r.begin; i < r.end; ++i) {
        int b = bin_of(prims[i]);
        bin_box[b].grow(prims[i].box);
        bin_count[b]++;
      }
      double right_cost[kBins] = {};
      Box acc;
      uint32_t n = 0;
      for (int b = kBins - 1; b > 0; --b) {
        acc.grow(bin_box[b]);
        n += bin_count[b];
        right_cost[b] = acc.half_area() * n;
      }
      acc = Box();
      n = 0;
      double best_cost = std::numeric_limits<double>::max();
      int best_split = -1;
      for (int b = 0; b + 1 < kBins; ++b) {
        acc.grow(bin_box[b]);
        n += bin_count[b];
        if (n == 0 || n == count) continue;
        double cost = acc.half_area() * n + right_cost[b + 1];
        if (cost < best_cost) best_cost = cost, best_split = b;
      }
      // Leaf when splitting does not pay (traversal cost ~ one triangle test).
      const double leaf_cost = bounds.half_area() * count;
      if (count <= kLeafSize && (best_split < 0 || best_cost + bounds.half_area() >= leaf_cost)) {
        make_leaf();
        continue;
      }
      if (best_split >= 0) {
        auto it = std::partition(prims.begin() + r.begin, prims.begin() + r.end,
                                 [&](const Prim& t) { return bin_of(t) <= best_split; });
        mid = uint32_t(it - prims.begin());
      }
    } else if (count <= kLeafSize * 2) {  // coincident centroids: nothing to separate
      make_leaf();
      continue;
    }
    if (mid == r.begin || mid == r.end) {  // no useful SAH split: median by index
      mid = r.begin + count / 2;
      std::nth_element(
          prims.begin() + r.begin, prims.begin() + mid, prims.begin() + r.end,
          [&](const Prim& x, const Prim& y) { return x.centroid[axis] < y.centroid[axis]; });
    }
    const uint32_t left = uint32_t(nodes_.size());
    nodes_[r.node].first = left;
    nodes_[r.node].count = 0;
    nodes_.push_back({});
    nodes_.push_back({});
    todo.push_back({left + 1, mid, r.end, r.depth + 1});
    todo.push_back({left, r.begin, mid, r.depth + 1});
  }

  triangles_.resize(face_count * 9);
  faces_.resize(face_count);
  for (size_t i = 0; i < face_count; ++i) faces_[i] = prims[i].face;
  for (size_t i = 0; i < face_count; ++i)
    for (int j = 0; j < 3; ++j)
      std::copy_n(positions + size_t(indices[size_t(prims[i].face) * 3 + j]) * 3, 3,
                  &triangles_[i * 9 + j * 3]);
}

// The nearest-first traversal; accept(t) says which triangles count.
template <class Accept>
double TriangleBvh::closest(const double p[3], uint32_t& hint, Accept&& accept) const {
  double best = std::numeric_limits<double>::infinity();
  const size_t tri_count = triangle_count();
  if (tri_count == 0) return best;
  auto test = [&](uint32_t t) {
    if (!accept(t)) return;
    const float* v = &triangles_[size_t(t) * 9];
    double d = point_triangle_distance2(p, v, v + 3, v + 6);
    if (d < best) best = d, hint = t;
  };
  if (hint < tri_count) test(hint);

  struct Entry {
    uint32_t node;
    double dist2;
  };
  Entry stack[kStackSize];
  unsigned sp = 0;
  stack[sp++] = {0, box_distance2(nodes_[0], p)};
  while (sp > 0) {
    Entry e = stack[--sp];
    if (e.dist2 >= best) continue;
    const Node& n = nodes_[e.node];
    if (n.count > 0) {
      for (uint32_t t = n.first; t < n.first + n.count; ++t) test(t);
      continue;
    }
    Entry near = {n.first, box_distance2(nodes_[n.first], p)};
    Entry far = {n.first + 1, box_distance2(nodes_[n.first + 1], p)};
    if (far.dist2 < near.dist2) std::swap(near, far);
    if (far.dist2 < best) stack[sp++] = far;
    if (near.dist2 < best) stack[sp++] = near;
  }
  return best;
}

double TriangleBvh::closest_distance2(const double p[3], uint32_t& hint) const {
  return closest(p, hint, [](uint32_t) { return true; });
}

double TriangleBvh::closest_distance2(const double p[3], uint32_t& hint, const uint32_t* labels,
                                      uint32_t want) const {
  return closest(p, hint, [&](uint32_t t) { return labels[faces_[t]] == want; });
}

}  // namespace pmz
