// SPDX-License-Identifier: MIT
// The demo's sample mesh: sharp creases (cap rims, a V-groove) next to smooth curved parts
// (ripples), so both halves of the multi-feature metric have something to do.
#include "pmz/sample_mesh.hpp"

#include <algorithm>
#include <cmath>

namespace pmz {

IndexedMesh make_sample_mesh(uint32_t target_faces) {
  target_faces = std::max<uint32_t>(target_faces, 1000);
  // Faces = 2*nt*nz (side) + 2*nt*(2*rings - 1) (caps); with nz = nt/2, rings = nt/12 this is
  // about nt^2 * (1 + 1/3).
  const uint32_t nt = std::max<uint32_t>(24, uint32_t(std::sqrt(target_faces * 0.75)) / 12 * 12);
  uint32_t nz = nt / 2;
  nz += nz % 2;  // even, so a ring sits exactly on the groove at z = 0
  const uint32_t rings = std::max<uint32_t>(2, nt / 12);
  const double pi = 3.14159265358979323846;

  IndexedMesh m;
  auto add = [&](double x, double y, double z) {
    m.positions.push_back(float(x));
    m.positions.push_back(float(y));
    m.positions.push_back(float(z));
    return m.vertex_count() - 1;
  };
  auto radius = [&](double theta, double z) {
    double r = 1.0 + 0.08 * std::sin(6 * theta) * std::sin(3 * pi * z);  // smooth ripples
    r -= 0.12 * std::max(0.0, 1.0 - std::abs(z) / 0.15);                 // sharp V-groove
    return r;
  };

  // Side: rows i = 0..nz from z = -1 to z = +1, nt vertices each.
  for (uint32_t i = 0; i <= nz; ++i) {
    double z = -1.0 + 2.0 * i / nz;
    for (uint32_t j = 0; j < nt; ++j) {
      double t = 2 * pi * j / nt;
      double r = radius(t, z);
      add(r * std::cos(t), r * std::sin(t), z);
    }
  }
  auto side = [&](uint32_t i, uint32_t j) { return i * nt + j % nt; };
  for (uint32_t i = 0; i < nz; ++i)
    for (uint32_t j = 0; j < nt; ++j) {
      uint32_t a = side(i, j), b = side(i, j + 1), c = side(i + 1, j + 1), d = side(i + 1, j);
      m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
    }

  // Caps: concentric rings from the rim inwards, then a centre vertex; flat, so the rim is a
  // crease. Ring 0 is the side's first/last row.
  for (int cap = 0; cap < 2; ++cap) {
    const double z = cap ? 1.0 : -1.0;
    std::vector<uint32_t> prev(nt);
    for (uint32_t j = 0; j < nt; ++j) prev[j] = side(cap ? nz : 0, j);
    for (uint32_t k = 1; k <= rings; ++k) {
      std::vector<uint32_t> cur(nt);
      const double s = 1.0 - double(k) / (rings + 1);
      for (uint32_t j = 0; j < nt; ++j) {
        double t = 2 * pi * j / nt;
        double r = radius(t, z) * s;
        cur[j] = add(r * std::cos(t), r * std::sin(t), z);
      }
      for (uint32_t j = 0; j < nt; ++j) {
        uint32_t a = prev[j], b = prev[(j + 1) % nt], c = cur[(j + 1) % nt], d = cur[j];
        // The bottom cap faces -z, the top +z: flip the winding accordingly.
        if (cap)
          m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
        else
          m.indices.insert(m.indices.end(), {a, c, b, a, d, c});
      }
      prev = cur;
    }
    uint32_t centre = add(0, 0, z);
    for (uint32_t j = 0; j < nt; ++j) {
      uint32_t a = prev[j], b = prev[(j + 1) % nt];
      if (cap)
        m.indices.insert(m.indices.end(), {a, b, centre});
      else
        m.indices.insert(m.indices.end(), {a, centre, b});
    }
  }
  return m;
}

}  // namespace pmz
