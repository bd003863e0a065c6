// SPDX-License-Identifier: MIT
#include "view_select.hpp"

#include <cmath>
#include <limits>

namespace pmz {

namespace {
#if defined(__wasm__)
// The WebAssembly build takes tan from its host (Math.tan: web/src/pmz_wasm.js): libm's tan and
// its argument reduction tables are 6 KB of the module, 3 KB gzip. (The engines' tan is
// fdlibm's or the system's, as native builds' libm; a last-bit difference moves a projected
// error by a relative 1e-16.)
extern "C" double pmz_host_tan(double);  // (web/wasm_imports.js)
double tangent(double x) { return pmz_host_tan(x); }
#else
double tangent(double x) { return std::tan(x); }
#endif
}  // namespace

View look_at(const float eye[3], const float target[3], float fov_y, uint32_t width,
             uint32_t height, float near, float pixel_error) {
  View v;
  for (int a = 0; a < 3; ++a) v.eye[a] = eye[a];
  v.fov_y = fov_y;
  v.viewport_height = height;
  v.pixel_error = pixel_error;
  // Camera axes: f forward, s right, u up (y up; a view straight up or down takes z as up).
  double f[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
  double fl = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  if (!(fl > 0)) f[2] = -1, fl = 1;
  for (double& x : f) x /= fl;
  double up[3] = {0, 1, 0};
  if (std::fabs(f[1]) > 0.999) up[1] = 0, up[2] = 1;
  double s[3] = {f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2],
                 f[0] * up[1] - f[1] * up[0]};
  const double sl = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
  for (double& x : s) x /= sl;
  const double u[3] = {s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2],
                       s[0] * f[1] - s[1] * f[0]};
  // View matrix rows (s, u, -f) with the eye moved to the origin; projection with an infinite
  // far plane: clip = (x / (a t), y / t, -z - 2 n, -z) for view coordinates (x, y, z).
  const double t = tangent(double(fov_y) / 2), aspect = height ? double(width) / height : 1;
  const double rows[3][3] = {{s[0], s[1], s[2]}, {u[0], u[1], u[2]}, {-f[0], -f[1], -f[2]}};
  double d[3];
  for (int r = 0; r < 3; ++r)
    d[r] = -(rows[r][0] * eye[0] + rows[r][1] * eye[1] + rows[r][2] * eye[2]);
  const double scale[4] = {1 / (aspect * t), 1 / t, -1, -1};
  for (int c = 0; c < 4; ++c) {  // column c of projection * view
    const double vc[3] = {c < 3 ? rows[0][c] : d[0], c < 3 ? rows[1][c] : d[1],
                          c < 3 ? rows[2][c] : d[2]};
    v.view_projection[c * 4 + 0] = float(scale[0] * vc[0]);
    v.view_projection[c * 4 + 1] = float(scale[1] * vc[1]);
    v.view_projection[c * 4 + 2] = float(-vc[2] - (c == 3 ? 2 * double(near) : 0));
    v.view_projection[c * 4 + 3] = float(-vc[2]);
  }
  return v;
}

float projected_error(const View& view, const NodeEntry& n) {
  const float* m = view.view_projection;
  // The frustum's planes (Gribb and Hartmann): row 3 plus and minus rows 0, 1, 2.
  for (int p = 0; p < 6; ++p) {
    const int row = p / 2;
    const float sign = p % 2 ? -1.0f : 1.0f;
    double plane[4];
    for (int c = 0; c < 4; ++c) plane[c] = double(m[c * 4 + 3]) + sign * m[c * 4 + row];
    const double len = std::sqrt(plane[0] * plane[0] + plane[1] * plane[1] + plane[2] * plane[2]);
    if (!(len > 0)) continue;  // (the infinite far plane)
    const double dist =
        (plane[0] * n.center[0] + plane[1] * n.center[1] + plane[2] * n.center[2] + plane[3]) / len;
    if (dist < -double(n.radius)) return -1;
  }
  double dd = 0;
  for (int a = 0; a < 3; ++a) dd += double(n.center[a] - view.eye[a]) * (n.center[a] - view.eye[a]);
  const double dist = std::sqrt(dd) - n.radius;
  if (!(dist > 0)) return std::numeric_limits<float>::infinity();
  const double pixels_per_unit = view.viewport_height / (2 * tangent(double(view.fov_y) / 2));
  return float(n.error * pixels_per_unit / dist);
}

// With d = center - eye, a the unit axis and s = cutoff / 127 >= sin t, t the cone's half-angle:
// dot(d, a) >= s |d| + r puts d at most 90 - t - asin(r / |d|) degrees from a, so that every
// point p of the sphere lies at most 90 - t degrees from it, and dot(n, p - eye) >= 0 for every
// normal n of the cone (a face's plane passes through its corner in the sphere).
bool faces_away(const View& view, const NodeEntry& n) {
  if (!n.has_cone()) return false;
  double dd = 0, da = 0, aa = 0;
  for (int a = 0; a < 3; ++a) {
    const double d = double(n.center[a]) - view.eye[a];
    dd += d * d;
    da += d * n.cone_axis[a];
    aa += double(n.cone_axis[a]) * n.cone_axis[a];
  }
  const double len = std::sqrt(dd);
  return len > n.radius && da >= std::sqrt(aa) * (n.cone_cutoff / 127.0 * len + n.radius);
}

}  // namespace pmz
