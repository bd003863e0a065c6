// SPDX-License-Identifier: MIT
// Triangle BVH for closest-point queries (binned SAH, flat node array, triangles copied in
// leaf order so a leaf reads one contiguous run). Private to the encoder library.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace pmz {

class TriangleBvh {
 public:
  // positions: xyz per vertex; indices: three per triangle (validated by the caller).
  void build(const float* positions, const uint32_t* indices, size_t face_count);

  // Squared distance from p to the nearest point of the surface. hint is a triangle (leaf
  // order) whose distance seeds the search bound; it is updated to the nearest triangle, so
  // passing the previous result for spatially coherent queries prunes most of the tree.
  double closest_distance2(const double p[3], uint32_t& hint) const;
  // The same over the triangles whose input face f has labels[f] == want (infinity when none
  // has); hint names one of those, or none.
  double closest_distance2(const double p[3], uint32_t& hint, const uint32_t* labels,
                           uint32_t want) const;

  size_t triangle_count() const { return triangles_.size() / 9; }
  // A triangle in leaf order (as closest_distance2's hint names it): its 9 coordinates, and
  // the face it was built from.
  const float* triangle(uint32_t t) const { return &triangles_[size_t(t) * 9]; }
  uint32_t face_of(uint32_t t) const { return faces_[t]; }

 private:
  struct Node {
    float lo[3];
    uint32_t first;  // leaf: first triangle; interior: left child (right child is first + 1)
    float hi[3];
    uint32_t count;  // triangles in a leaf; 0 for an interior node
  };
  template <class Accept>
  double closest(const double p[3], uint32_t& hint, Accept&& accept) const;
  std::vector<Node> nodes_;
  std::vector<float> triangles_;  // 9 floats per triangle, in leaf order
  std::vector<uint32_t> faces_;   // input face of each triangle, in leaf order
};

}  // namespace pmz
