// SPDX-License-Identifier: MIT
#include "pmz/triangle_distance.hpp"

#include <algorithm>

namespace pmz {

namespace {

inline double dot3(const double* a, const double* b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

inline double ratio(double num, double den) { return den != 0 ? num / den : 0.0; }

double segment_distance2(const double p[3], const double a[3], const double b[3]) {
  double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  double ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
  double t = std::clamp(ratio(dot3(ap, ab), dot3(ab, ab)), 0.0, 1.0);
  double d[3] = {ap[0] - t * ab[0], ap[1] - t * ab[1], ap[2] - t * ab[2]};
  return dot3(d, d);
}

}  // namespace

double point_triangle_distance2(const double p[3], const float* fa, const float* fb,
                                const float* fc) {
  const double a[3] = {fa[0], fa[1], fa[2]}, b[3] = {fb[0], fb[1], fb[2]},
               c[3] = {fc[0], fc[1], fc[2]};
  const double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
  auto dist2_to = [&](double x, double y, double z) {
    double d[3] = {p[0] - x, p[1] - y, p[2] - z};
    return dot3(d, d);
  };
  double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
  if (d1 <= 0 && d2 <= 0) return dot3(ap, ap);  // vertex region a
  const double bp[3] = {p[0] - b[0], p[1] - b[1], p[2] - b[2]};
  double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
  if (d3 >= 0 && d4 <= d3) return dot3(bp, bp);  // vertex region b
  double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {  // edge region ab
    double v = ratio(d1, d1 - d3);
    return dist2_to(a[0] + v * ab[0], a[1] + v * ab[1], a[2] + v * ab[2]);
  }
  const double cp[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
  double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
  if (d6 >= 0 && d5 <= d6) return dot3(cp, cp);  // vertex region c
  double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {  // edge region ac
    double w = ratio(d2, d2 - d6);
    return dist2_to(a[0] + w * ac[0], a[1] + w * ac[1], a[2] + w * ac[2]);
  }
  double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {  // edge region bc
    double w = ratio(d4 - d3, (d4 - d3) + (d5 - d6));
    return dist2_to(b[0] + w * (c[0] - b[0]), b[1] + w * (c[1] - b[1]), b[2] + w * (c[2] - b[2]));
  }
  double sum = va + vb + vc;
  if (!(sum > 0)) {  // degenerate (zero-area) triangle: nearest of its edges
    return std::min(
        {segment_distance2(p, a, b), segment_distance2(p, b, c), segment_distance2(p, c, a)});
  }
  double v = vb / sum, w = vc / sum;
  return dist2_to(a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w,
                  a[2] + ab[2] * v + ac[2] * w);
}

}  // namespace pmz
