// SPDX-License-Identifier: MIT
#include "cluster_grid.hpp"

#include <algorithm>
#include <cmath>

namespace pmz::detail {

double triangle_area(const int32_t p[3], const int32_t q[3], const int32_t r[3]) {
  const double e1[3] = {double(q[0]) - p[0], double(q[1]) - p[1], double(q[2]) - p[2]};
  const double e2[3] = {double(r[0]) - p[0], double(r[1]) - p[1], double(r[2]) - p[2]};
  const double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2],
               z = e1[0] * e2[1] - e1[1] * e2[0];
  return 0.5 * std::sqrt(x * x + y * y + z * z);
}

CellGrid cell_grid_for(const CoordBox& box, double area, uint32_t cell_vertices) {
  const uint64_t n = box.vertices;
  const int64_t extent =
      std::max({box.hi[0] - box.lo[0], box.hi[1] - box.lo[1], box.hi[2] - box.lo[2], int64_t(1)});
  const double side = n > 0 ? std::sqrt(area * double(cell_vertices) / double(n)) : 2.0;
  CellGrid g;
  g.side = std::max<int64_t>(2, (extent >> 20) + 1);
  if (side > double(g.side)) g.side = int64_t(std::min(side, double(extent) + 1));
  for (int a = 0; a < 3; ++a) g.origin[a] = box.lo[a];
  return g;
}

CellGrid next_cell_grid(const CellGrid& g, double area, uint32_t cell_vertices, uint64_t live) {
  CellGrid next;
  const double fitted =
      std::sqrt(area * double(cell_vertices) / double(std::max<uint64_t>(live, 1)));
  const int64_t least = g.side + (g.side + 3) / 4;  // ceil(5/4 side)
  // (least <= 2 side for every side >= 1; fitted is clamped before the conversion, where a
  // handful of live vertices would overflow it)
  next.side = std::max(least, int64_t(std::min(fitted, double(g.side) * 2)));
  for (int a = 0; a < 3; ++a) next.origin[a] = g.origin[a] + g.side / 2;
  return next;
}

bool grid_cuts(const CellGrid& g, const CoordBox& box) {
  if (box.vertices == 0 || g.side <= 0) return false;
  // A cell's index along an axis does not decrease with the coordinate, so the vertices span more
  // than one cell exactly when the box's two corners do.
  const int32_t lo[3] = {int32_t(box.lo[0]), int32_t(box.lo[1]), int32_t(box.lo[2])};
  const int32_t hi[3] = {int32_t(box.hi[0]), int32_t(box.hi[1]), int32_t(box.hi[2])};
  return g.cell(lo) != g.cell(hi);
}

}  // namespace pmz::detail
