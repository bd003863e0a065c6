// SPDX-License-Identifier: MIT
// bench-view-surface MESH EX,EY,EZ,TX,TY,TZ [--surface F] [--onto-surface] [--size WxH]
// [--fov DEG]: how much of MESH's surface a camera shows, as a fraction of its area: the faces that
// face the eye, whose centroid lies in the frustum and is not hidden behind other faces (a depth
// buffer at a quarter of the viewport's resolution; a face too small to cover a pixel centre is
// drawn at its centroid's pixel). With --surface, the eye slides along the line from the target
// through the given eye to where the camera shows fraction F of the surface (the close-up of a view
// benchmark, found the same way on any mesh). With --onto-surface, the target first moves to where
// the ray from the eye through it first meets the surface (a user looks at the surface and zooms
// in; a target inside a flat model's box may lie under its surface). Prints one JSON line with the
// camera and the fraction.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "pmz/decoder.hpp"
#include "pmz/mesh.hpp"

namespace {

constexpr const char* kTool = "bench-view-surface";

struct Camera {
  float eye[3], target[3];
  float fov = 60;
  uint32_t width = 1920, height = 1080;
};

// The fraction of the area of `mesh` that `cam` shows.
double visible_fraction(const pmz::IndexedMesh& mesh, const Camera& cam) {
  const pmz::View view = pmz::look_at(cam.eye, cam.target, cam.fov * float(M_PI / 180), cam.width,
                                      cam.height, 1e-4f, 1);
  const float* m = view.view_projection;
  const int w = int(std::max(1u, cam.width / 4)), h = int(std::max(1u, cam.height / 4));
  const size_t nv = mesh.positions.size() / 3, nf = mesh.indices.size() / 3;
  // Screen x, y in pixels and clip w per vertex (w <= 0: behind the eye).
  std::vector<float> sx(nv), sy(nv), sw(nv);
  for (size_t v = 0; v < nv; ++v) {
    const float* p = &mesh.positions[v * 3];
    const float cx = m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12];
    const float cy = m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13];
    const float cw = m[3] * p[0] + m[7] * p[1] + m[11] * p[2] + m[15];
    sw[v] = cw;
    sx[v] = cw > 0 ? (cx / cw * 0.5f + 0.5f) * float(w) : 0;
    sy[v] = cw > 0 ? (cy / cw * 0.5f + 0.5f) * float(h) : 0;
  }
  auto in_view = [&](float x, float y, float cw) {
    return cw > 1e-4f && x >= 0 && y >= 0 && x < float(w) && y < float(h);
  };
  std::vector<float> depth(size_t(w) * size_t(h), std::numeric_limits<float>::infinity());
  auto centroid = [&](size_t f, float& x, float& y, float& cw) {
    const uint32_t* t = &mesh.indices[f * 3];
    float p[3] = {0, 0, 0};
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a) p[a] += mesh.positions[size_t(t[c]) * 3 + a] / 3;
    const float cx = m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12];
    const float cy = m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13];
    cw = m[3] * p[0] + m[7] * p[1] + m[11] * p[2] + m[15];
    x = cw > 0 ? (cx / cw * 0.5f + 0.5f) * float(w) : -1;
    y = cw > 0 ? (cy / cw * 0.5f + 0.5f) * float(h) : -1;
  };
  // Depth buffer of view depth (clip w), interpolating 1/w across the screen.
  for (size_t f = 0; f < nf; ++f) {
    const uint32_t* t = &mesh.indices[f * 3];
    if (sw[t[0]] <= 1e-4f || sw[t[1]] <= 1e-4f || sw[t[2]] <= 1e-4f) continue;
    const float x0 = sx[t[0]], y0 = sy[t[0]], x1 = sx[t[1]], y1 = sy[t[1]], x2 = sx[t[2]],
                y2 = sy[t[2]];
    const float area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
    const int xa = std::max(0, int(std::ceil(std::min({x0, x1, x2}) - 0.5f)));
    const int xb = std::min(w - 1, int(std::floor(std::max({x0, x1, x2}) - 0.5f)));
    const int ya = std::max(0, int(std::ceil(std::min({y0, y1, y2}) - 0.5f)));
    const int yb = std::min(h - 1, int(std::floor(std::max({y0, y1, y2}) - 0.5f)));
    bool drawn = false;
    if (area != 0)
      for (int y = ya; y <= yb; ++y)
        for (int x = xa; x <= xb; ++x) {
          const float px = float(x) + 0.5f, py = float(y) + 0.5f;
          const float b0 = ((x1 - px) * (y2 - py) - (x2 - px) * (y1 - py)) / area;
          const float b1 = ((x2 - px) * (y0 - py) - (x0 - px) * (y2 - py)) / area;
          const float b2 = 1 - b0 - b1;
          if (b0 < 0 || b1 < 0 || b2 < 0) continue;
          const float inv = b0 / sw[t[0]] + b1 / sw[t[1]] + b2 / sw[t[2]];
          float& d = depth[size_t(y) * size_t(w) + size_t(x)];
          d = std::min(d, 1 / inv);
          drawn = true;
        }
    if (!drawn) {
      float x, y, cw;
      centroid(f, x, y, cw);
      if (in_view(x, y, cw)) {
        float& d = depth[size_t(y) * size_t(w) + size_t(x)];
        d = std::min(d, cw);
      }
    }
  }
  double shown = 0, total = 0;
  for (size_t f = 0; f < nf; ++f) {
    const uint32_t* t = &mesh.indices[f * 3];
    const float* a = &mesh.positions[size_t(t[0]) * 3];
    const float* b = &mesh.positions[size_t(t[1]) * 3];
    const float* c = &mesh.positions[size_t(t[2]) * 3];
    const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                         e1[0] * e2[1] - e1[1] * e2[0]};
    const double area = 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    total += area;
    const double toward =
        n[0] * (cam.eye[0] - a[0]) + n[1] * (cam.eye[1] - a[1]) + n[2] * (cam.eye[2] - a[2]);
    if (toward <= 0) continue;
    float x, y, cw;
    centroid(f, x, y, cw);
    if (!in_view(x, y, cw)) continue;
    if (cw <= depth[size_t(y) * size_t(w) + size_t(x)] * 1.01f + 1e-6f) shown += area;
  }
  return total > 0 ? shown / total : 0;
}

// The first point where the ray from `eye` through `target` meets a face of `mesh` (Moller and
// Trumbore), written to `hit`; false when it meets none.
bool first_hit(const pmz::IndexedMesh& mesh, const float eye[3], const float target[3],
               float hit[3]) {
  double d[3], best = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) d[a] = double(target[a]) - eye[a];
  for (size_t f = 0; f < mesh.indices.size() / 3; ++f) {
    const float* p[3];
    for (int c = 0; c < 3; ++c) p[c] = &mesh.positions[size_t(mesh.indices[f * 3 + c]) * 3];
    double e1[3], e2[3], s[3];
    for (int a = 0; a < 3; ++a)
      e1[a] = double(p[1][a]) - p[0][a], e2[a] = double(p[2][a]) - p[0][a],
      s[a] = double(eye[a]) - p[0][a];
    const double h[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2],
                         d[0] * e2[1] - d[1] * e2[0]};
    const double det = e1[0] * h[0] + e1[1] * h[1] + e1[2] * h[2];
    if (det == 0) continue;
    const double u = (s[0] * h[0] + s[1] * h[1] + s[2] * h[2]) / det;
    if (u < 0 || u > 1) continue;
    const double q[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2],
                         s[0] * e1[1] - s[1] * e1[0]};
    const double v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) / det;
    if (v < 0 || u + v > 1) continue;
    const double t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
    if (t > 0 && t < best) best = t;
  }
  if (!std::isfinite(best)) return false;
  for (int a = 0; a < 3; ++a) hit[a] = float(eye[a] + best * d[a]);
  return true;
}

bool parse_floats(const char* text, float* out, int n) {
  std::string s(text);
  for (int i = 0; i < n; ++i) {
    char* end = nullptr;
    out[i] = std::strtof(s.c_str(), &end);
    if (end == s.c_str() || !std::isfinite(out[i])) return false;
    s = end;
    if (i + 1 < n) {
      if (s.empty() || s[0] != ',') return false;
      s.erase(0, 1);
    }
  }
  return s.empty();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: %s MESH EX,EY,EZ,TX,TY,TZ [--surface F] [--onto-surface] [--size WxH] "
                 "[--fov DEG]\n",
                 kTool);
    return 2;
  }
  Camera cam;
  float c[6];
  if (!parse_floats(argv[2], c, 6)) return pmz_bench::fail(kTool, "camera: six numbers");
  std::memcpy(cam.eye, c, sizeof cam.eye);
  std::memcpy(cam.target, c + 3, sizeof cam.target);
  double surface = -1;
  bool onto_surface = false;
  for (int i = 3; i < argc; i += 2) {
    const std::string opt = argv[i];
    if (opt == "--onto-surface") {
      onto_surface = true;
      --i;  // (no value)
    } else if (i + 1 >= argc) {
      return pmz_bench::fail(kTool, opt + " takes a value");
    } else if (opt == "--surface") {
      surface = std::atof(argv[i + 1]);
    } else if (opt == "--fov") {
      cam.fov = float(std::atof(argv[i + 1]));
    } else if (opt == "--size") {
      unsigned sw = 0, sh = 0;
      if (std::sscanf(argv[i + 1], "%ux%u", &sw, &sh) != 2 || !sw || !sh)
        return pmz_bench::fail(kTool, "--size takes WxH");
      cam.width = sw;
      cam.height = sh;
    } else {
      return pmz_bench::fail(kTool, "unknown option " + opt);
    }
  }
  pmz::IndexedMesh mesh;
  std::string error;
  if (!pmz::read_mesh(argv[1], mesh, error)) return pmz_bench::fail(kTool, error);
  if (onto_surface && !first_hit(mesh, cam.eye, cam.target, cam.target))
    return pmz_bench::fail(kTool, "the ray from the eye through the target meets no face");
  double fraction = visible_fraction(mesh, cam);
  if (surface > 0 && surface < 1) {
    // The visible fraction grows with the distance until the whole front is in view: bisect the
    // distance along the line (log scale) between a thousandth of the given one and that one.
    float dir[3];
    for (int a = 0; a < 3; ++a) dir[a] = cam.eye[a] - cam.target[a];
    double lo = std::log(1e-3), hi = 0;
    for (int step = 0; step < 24; ++step) {
      const double mid = 0.5 * (lo + hi), s = std::exp(mid);
      Camera at = cam;
      for (int a = 0; a < 3; ++a) at.eye[a] = cam.target[a] + float(s) * dir[a];
      (visible_fraction(mesh, at) < surface ? lo : hi) = mid;
    }
    const double s = std::exp(0.5 * (lo + hi));
    for (int a = 0; a < 3; ++a) cam.eye[a] = cam.target[a] + float(s) * dir[a];
    fraction = visible_fraction(mesh, cam);
  }
  std::printf("{\"camera\": \"%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\", \"visible\": %.4f}\n", cam.eye[0],
              cam.eye[1], cam.eye[2], cam.target[0], cam.target[1], cam.target[2], fraction);
  return 0;
}
