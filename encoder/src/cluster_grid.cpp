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

CellGrid cell_grid_for(const std::vector<int32_t>& coords, double area, uint32_t cell_vertices) {
  const size_t n = coords.size() / 3;
  int64_t lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (size_t v = 0; v < n; ++v)
    for (int a = 0; a < 3; ++a) {
      lo[a] = v == 0 ? coords[a] : std::min<int64_t>(lo[a], coords[v * 3 + a]);
      hi[a] = v == 0 ? coords[a] : std::max<int64_t>(hi[a], coords[v * 3 + a]);
    }
  const int64_t extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], int64_t(1)});
  const double side = n > 0 ? std::sqrt(area * double(cell_vertices) / double(n)) : 2.0;
  CellGrid g;
  g.side = std::max<int64_t>(2, (extent >> 20) + 1);
  if (side > double(g.side)) g.side = int64_t(std::min(side, double(extent) + 1));
  for (int a = 0; a < 3; ++a) g.origin[a] = lo[a];
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

bool grid_cuts(const CellGrid& g, const std::vector<int32_t>& coords) {
  const size_t n = coords.size() / 3;
  if (n == 0) return false;
  const uint64_t first = g.cell(&coords[0]);
  for (size_t v = 1; v < n; ++v)
    if (g.cell(&coords[v * 3]) != first) return true;
  return false;
}

}  // namespace pmz::detail
