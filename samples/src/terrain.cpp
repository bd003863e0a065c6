// SPDX-License-Identifier: MIT
#include "pmz/terrain.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

namespace pmz {
namespace {

// A hash of a lattice point (splitmix64's finaliser): uniform in [0, 1).
double lattice(int64_t i, int64_t j, uint64_t seed) {
  uint64_t z = seed * 0x9E3779B97F4A7C15ull + uint64_t(i) * 0xBF58476D1CE4E5B9ull +
               uint64_t(j) * 0x94D049BB133111EBull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return double(z >> 11) * (1.0 / 9007199254740992.0);
}

// Value noise in [-1, 1] with a quintic fade (smooth, C2).
double noise(double x, double y, uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const int64_t i = int64_t(fx), j = int64_t(fy);
  const double tx = x - fx, ty = y - fy;
  auto fade = [](double t) { return t * t * t * (t * (t * 6 - 15) + 10); };
  const double sx = fade(tx), sy = fade(ty);
  const double a = lattice(i, j, seed), b = lattice(i + 1, j, seed);
  const double c = lattice(i, j + 1, seed), d = lattice(i + 1, j + 1, seed);
  return 2 * ((a + (b - a) * sx) * (1 - sy) + (c + (d - c) * sx) * sy) - 1;
}

}  // namespace

uint32_t terrain_grid_side(uint64_t faces) {
  const double n = std::sqrt(double(std::max<uint64_t>(faces, 2)) / 2.0) + 1.0;
  return uint32_t(std::clamp(std::llround(n), 2ll, 65535ll));
}

float terrain_height(double x, double y, uint64_t seed) {
  // Rolling relief: fractal value noise, 8 octaves.
  double relief = 0, amp = 0.5, freq = 3;
  for (int o = 0; o < 8; ++o, amp *= 0.5, freq *= 2.03)
    relief += amp * noise(x * freq, y * freq, seed + uint64_t(o));
  // Sharp ridges: folded noise (a crease where it crosses zero).
  double ridges = 0;
  amp = 0.35, freq = 4;
  for (int o = 0; o < 4; ++o, amp *= 0.45, freq *= 2.1)
    ridges += amp * (1 - 2 * std::fabs(noise(x * freq, y * freq, seed + 100 + uint64_t(o))));
  double h = 0.12 * relief + 0.08 * std::max(0.0, ridges);
  // Terraces on the upper slopes: flat steps joined by steep risers, creases at both edges.
  if (h > 0.02) {
    const double step = 0.015, t = (h - 0.02) / step, k = std::floor(t), f = t - k;
    h = 0.02 + step * (k + std::clamp((f - 0.7) / 0.3, 0.0, 1.0));
  }
  // A valley with a V-shaped floor along a meandering line.
  const double line = 0.5 + 0.15 * std::sin(6.0 * x) + 0.05 * noise(x * 8, 0.5, seed + 200);
  const double dist = std::fabs(y - line);
  if (dist < 0.06) h -= 0.04 * (1 - dist / 0.06);
  return float(h);
}

bool write_terrain_ply(const TerrainOptions& options,
                       const std::function<bool(const void*, size_t)>& write) {
  const uint32_t n = terrain_grid_side(options.faces);
  const uint64_t vertices = uint64_t(n) * n, faces = 2 * uint64_t(n - 1) * (n - 1);
  const std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment pmz terrain seed " +
      std::to_string(options.seed) + "\nelement vertex " + std::to_string(vertices) +
      "\nproperty float x\nproperty float y\nproperty float z\n"
      "element face " +
      std::to_string(faces) + "\nproperty list uchar int vertex_indices\nend_header\n";
  if (!write(header.data(), header.size())) return false;
  const double total = double(vertices + faces);
  // Little-endian bytes whatever the host (PLY's declared order).
  auto put32 = [](uint8_t* p, uint32_t v) {
    p[0] = uint8_t(v), p[1] = uint8_t(v >> 8), p[2] = uint8_t(v >> 16), p[3] = uint8_t(v >> 24);
  };
  std::vector<uint8_t> row;
  const double inv = 1.0 / double(n - 1);
  for (uint32_t j = 0; j < n; ++j) {
    row.resize(size_t(n) * 12);
    for (uint32_t i = 0; i < n; ++i) {
      const float p[3] = {float(i * inv), float(j * inv),
                          terrain_height(i * inv, j * inv, options.seed)};
      for (int a = 0; a < 3; ++a) {
        uint32_t bits;
        std::memcpy(&bits, &p[a], 4);
        put32(&row[size_t(i) * 12 + size_t(a) * 4], bits);
      }
    }
    if (!write(row.data(), row.size())) return false;
    if (options.progress && j % 64 == 0) options.progress(double(uint64_t(j) * n) / total);
  }
  for (uint32_t j = 0; j + 1 < n; ++j) {
    row.resize(size_t(n - 1) * 26);
    for (uint32_t i = 0; i + 1 < n; ++i) {
      const uint32_t a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      // The diagonal alternates (a checkerboard), so no direction is favoured.
      const bool flip = ((i ^ j) & 1) != 0;
      const uint32_t t[6] = {a, b, flip ? c : d, flip ? b : a, d, c};
      uint8_t* p = &row[size_t(i) * 26];
      for (int f = 0; f < 2; ++f) {
        p[f * 13] = 3;
        for (int k = 0; k < 3; ++k) put32(&p[f * 13 + 1 + k * 4], t[f * 3 + k]);
      }
    }
    if (!write(row.data(), row.size())) return false;
    if (options.progress && j % 64 == 0)
      options.progress(double(vertices + 2 * uint64_t(j) * (n - 1)) / total);
  }
  if (options.progress) options.progress(1.0);
  return true;
}

}  // namespace pmz
