// SPDX-License-Identifier: MIT
// pmz-conformance: makes and checks the conformance vectors of tests/conformance (README.md
// there says how a third-party decoder uses them).
//
//   pmz-conformance meshes DIR          the procedural source meshes (OBJ) of the vectors
//   pmz-conformance expect FILE.pmz     FILE.expected (and FILE.obj, a decoded level) from the
//                                       reference decoder
//   pmz-conformance derive FILE.pmz DIR hand-made valid and invalid files derived from a valid
//                                       vector, each with its .expected
//   pmz-conformance check DIR           decodes every DIR/*.expected's file (whole, and in 1-
//                                       and 7-byte slices) and compares; exit 1 on a mismatch
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "pmz/base_codec.hpp"
#include "pmz/decoder.hpp"
#include "pmz/format.hpp"

namespace fs = std::filesystem;
using Bytes = std::vector<uint8_t>;

namespace {

// ---- SHA-256 (FIPS 180-4), for the level hashes ----
class Sha256 {
 public:
  void update(const uint8_t* p, size_t n) {
    for (size_t i = 0; i < n; ++i) {
      block_[used_++] = p[i];
      if (used_ == 64) compress(), used_ = 0;
    }
    bits_ += uint64_t(n) * 8;
  }
  std::string hex() {
    const uint64_t bits = bits_;
    const uint8_t one = 0x80, zero = 0;
    update(&one, 1);
    while (used_ != 56) update(&zero, 1);
    uint8_t len[8];
    for (int i = 0; i < 8; ++i) len[i] = uint8_t(bits >> (56 - 8 * i));
    update(len, 8);
    std::string s;
    char buf[9];
    for (uint32_t w : h_) std::snprintf(buf, sizeof buf, "%08x", w), s += buf;
    return s;
  }

 private:
  static uint32_t rotr(uint32_t x, int n) { return x >> n | x << (32 - n); }
  void compress() {
    static constexpr uint32_t k[64] = {
        0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4,
        0xab1c5ed5, 0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe,
        0x9bdc06a7, 0xc19bf174, 0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f,
        0x4a7484aa, 0x5cb0a9dc, 0x76f988da, 0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7,
        0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967, 0x27b70a85, 0x2e1b2138, 0x4d2c6dfc,
        0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85, 0xa2bfe8a1, 0xa81a664b,
        0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070, 0x19a4c116,
        0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
        0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7,
        0xc67178f2};
    uint32_t w[64];
    for (int i = 0; i < 16; ++i)
      w[i] = uint32_t(block_[4 * i]) << 24 | uint32_t(block_[4 * i + 1]) << 16 |
             uint32_t(block_[4 * i + 2]) << 8 | block_[4 * i + 3];
    for (int i = 16; i < 64; ++i) {
      const uint32_t s0 = rotr(w[i - 15], 7) ^ rotr(w[i - 15], 18) ^ (w[i - 15] >> 3);
      const uint32_t s1 = rotr(w[i - 2], 17) ^ rotr(w[i - 2], 19) ^ (w[i - 2] >> 10);
      w[i] = w[i - 16] + s0 + w[i - 7] + s1;
    }
    uint32_t a = h_[0], b = h_[1], c = h_[2], d = h_[3], e = h_[4], f = h_[5], g = h_[6], h = h_[7];
    for (int i = 0; i < 64; ++i) {
      const uint32_t t1 =
          h + (rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25)) + ((e & f) ^ (~e & g)) + k[i] + w[i];
      const uint32_t t2 = (rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
      h = g, g = f, f = e, e = d + t1, d = c, c = b, b = a, a = t1 + t2;
    }
    const uint32_t add[8] = {a, b, c, d, e, f, g, h};
    for (int i = 0; i < 8; ++i) h_[i] += add[i];
  }
  std::array<uint32_t, 8> h_ = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                                0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
  uint8_t block_[64] = {};
  size_t used_ = 0;
  uint64_t bits_ = 0;
};

// The level hash of the README: SHA-256 of the positions (three f32 per vertex) then the
// indices (three u32 per face), all little-endian, in the decoder's order.
std::string mesh_hash(const pmz::Decoder& d) {
  Sha256 sha;
  auto put = [&](uint32_t u) {
    const uint8_t b[4] = {uint8_t(u), uint8_t(u >> 8), uint8_t(u >> 16), uint8_t(u >> 24)};
    sha.update(b, 4);
  };
  for (size_t i = 0; i < size_t(d.vertex_count()) * 3; ++i) {
    uint32_t u;
    std::memcpy(&u, d.positions() + i, 4);
    put(u);
  }
  for (size_t i = 0; i < size_t(d.face_count()) * 3; ++i) put(d.indices()[i]);
  // With attributes (spec/format.md section 14), then: the a-wedges' vertices, the faces' a-wedges,
  // the texture coordinates set by set, the normals, the colours (f32 bit patterns) and the faces'
  // materials.
  const uint32_t w = d.wedge_count();
  auto floats = [&](const float* p, size_t n) {
    for (size_t i = 0; i < n; ++i) {
      uint32_t u;
      std::memcpy(&u, p + i, 4);
      put(u);
    }
  };
  if (w) {
    for (uint32_t i = 0; i < w; ++i) put(d.wedge_vertices()[i]);
    for (size_t i = 0; i < size_t(d.face_count()) * 3; ++i) put(d.wedge_indices()[i]);
    for (uint32_t t = 0; t < d.texcoord_set_count(); ++t) floats(d.texcoords(t), size_t(w) * 2);
    if (d.normals()) floats(d.normals(), size_t(w) * 3);
    if (d.colors()) floats(d.colors(), size_t(w) * d.color_components());
  }
  if (d.face_materials())
    for (uint32_t f = 0; f < d.face_count(); ++f) put(d.face_materials()[f]);
  return sha.hex();
}

// spec/format.md section 12's status names (the README's; pmz::status_name gives prose).
const char* status_token(pmz::Status s) {
  switch (s) {
    case pmz::Status::ok:
      return "ok";
    case pmz::Status::bad_magic:
      return "bad_magic";
    case pmz::Status::bad_version:
      return "bad_version";
    case pmz::Status::bad_checksum:
      return "bad_checksum";
    case pmz::Status::corrupt:
      return "corrupt";
    case pmz::Status::limit_exceeded:
      return "limit_exceeded";
    case pmz::Status::truncated:
      return "truncated";
    case pmz::Status::out_of_memory:
      return "out_of_memory";
  }
  return "unknown";
}

bool read_file(const fs::path& p, Bytes& out) {
  std::ifstream in(p, std::ios::binary);
  if (!in) return false;
  out.assign(std::istreambuf_iterator<char>(in), {});
  return true;
}

bool write_file(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
  return bool(out);
}

bool write_bytes(const fs::path& p, const Bytes& b) {
  std::ofstream out(p, std::ios::binary);
  out.write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
  return bool(out);
}

// Splits applied at each checked level: the base, about a tenth, a quarter and a half of the
// splits, all of them (or of those the decoder reached).
std::vector<uint64_t> default_levels(uint64_t reached) {
  std::vector<uint64_t> l = {0, reached / 10, reached / 4, reached / 2, reached};
  l.erase(std::unique(l.begin(), l.end()), l.end());
  return l;
}

// The README's decoding procedure, as text: feed every byte (in slices of `slice` bytes, 0 =
// all at once), finish, apply every available split, then visit each level.
std::string describe(const Bytes& file, const std::string& name, size_t slice,
                     const std::vector<uint64_t>* levels_in, std::vector<uint64_t>* levels_out) {
  pmz::Decoder d;
  const size_t step = slice ? slice : std::max<size_t>(file.size(), 1);
  for (size_t at = 0; at < file.size() && d.status() == pmz::Status::ok; at += step)
    d.feed(file.data() + at, std::min(step, file.size() - at));
  d.finish();
  std::ostringstream o;
  o << "file " << name << "\n";
  o << "stream " << status_token(d.status()) << "\n";
  const pmz::StreamInfo& i = d.info();
  if (i.header_done)
    o << "head version " << i.version_major << "." << i.version_minor << " level " << i.level
      << " position_bits " << i.position_bits << " curvature " << i.curvature << " fine_curvature "
      << i.fine_curvature << " base_vertices " << i.base_vertices << " base_faces " << i.base_faces
      << " total_splits " << i.total_splits << " full_faces " << i.full_faces << "\n";
  o << "available " << d.splits_available() << "\n";
  if (!i.base_done) return o.str();
  d.refine();
  o << "refined " << status_token(d.status()) << " " << d.splits_applied() << "\n";
  const std::vector<uint64_t> levels = levels_in ? *levels_in : default_levels(d.splits_applied());
  if (levels_out) *levels_out = levels;
  for (uint64_t l : levels) {
    d.set_split_target(l);
    o << "level " << l << " vertices " << d.vertex_count() << " faces " << d.face_count()
      << " sha256 " << mesh_hash(d) << "\n";
  }
  return o.str();
}

std::string obj_of_level(const Bytes& file, uint64_t level) {
  pmz::Decoder d;
  d.feed(file.data(), file.size());
  d.refine();
  d.set_split_target(level);
  std::string s;
  char buf[96];
  for (uint32_t v = 0; v < d.vertex_count(); ++v) {
    const float* p = d.positions() + size_t(v) * 3;
    std::snprintf(buf, sizeof buf, "v %.9g %.9g %.9g\n", double(p[0]), double(p[1]), double(p[2]));
    s += buf;
  }
  for (uint32_t f = 0; f < d.face_count(); ++f) {
    const uint32_t* t = d.indices() + size_t(f) * 3;
    std::snprintf(buf, sizeof buf, "f %u %u %u\n", t[0] + 1, t[1] + 1, t[2] + 1);
    s += buf;
  }
  return s;
}

// Writes FILE.expected (with the comment line `note`) and, if with_obj and the file decodes,
// FILE.obj: the level a quarter of the way.
bool expect(const fs::path& pmz_path, const std::string& note, bool with_obj) {
  Bytes file;
  if (!read_file(pmz_path, file)) return false;
  std::vector<uint64_t> levels;
  const std::string name = pmz_path.filename().string();
  std::string text = "# " + note + "\n" + describe(file, name, 0, nullptr, &levels);
  fs::path out = pmz_path;
  if (!write_file(out.replace_extension(".expected"), text)) return false;
  if (with_obj && levels.size() >= 3) {
    const uint64_t level = levels[levels.size() >= 4 ? 2 : 1];
    const std::string obj = "# " + name + " decoded at level " + std::to_string(level) +
                            " (splits applied), as the reference decoder outputs it\n" +
                            obj_of_level(file, level);
    fs::path o = pmz_path;
    if (!write_file(o.replace_extension(".obj"), obj)) return false;
  }
  return true;
}

// ---- procedural source meshes ----
struct Mesh {
  std::vector<double> v;  // xyz
  std::vector<uint32_t> f;
  uint32_t add(double x, double y, double z) {
    v.insert(v.end(), {x, y, z});
    return uint32_t(v.size() / 3 - 1);
  }
  void tri(uint32_t a, uint32_t b, uint32_t c) { f.insert(f.end(), {a, b, c}); }
  void append(const Mesh& m) {
    const uint32_t o = uint32_t(v.size() / 3);
    v.insert(v.end(), m.v.begin(), m.v.end());
    for (uint32_t i : m.f) f.push_back(i + o);
  }
};

// Icosahedron subdivided `levels` times, projected on the unit sphere.
Mesh icosphere(int levels) {
  Mesh m;
  const double t = (1 + std::sqrt(5.0)) / 2;
  const double p[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                           {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                           {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& q : p) {
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    m.add(q[0] / n, q[1] / n, q[2] / n);
  }
  m.f = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
         4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
         6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
  for (int l = 0; l < levels; ++l) {
    std::vector<std::pair<uint64_t, uint32_t>> mids;
    auto mid = [&](uint32_t a, uint32_t b) {
      const uint64_t key = uint64_t(std::min(a, b)) << 32 | std::max(a, b);
      for (auto& [k, i] : mids)
        if (k == key) return i;
      double x = m.v[3 * a] + m.v[3 * b], y = m.v[3 * a + 1] + m.v[3 * b + 1],
             z = m.v[3 * a + 2] + m.v[3 * b + 2];
      const double n = std::sqrt(x * x + y * y + z * z);
      const uint32_t i = m.add(x / n, y / n, z / n);
      mids.push_back({key, i});
      return i;
    };
    std::vector<uint32_t> f;
    for (size_t i = 0; i < m.f.size(); i += 3) {
      const uint32_t a = m.f[i], b = m.f[i + 1], c = m.f[i + 2];
      const uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      f.insert(f.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    m.f = f;
  }
  return m;
}

// Torus, major radius 1, minor 0.35, with a ripple so the curvature varies.
Mesh torus(uint32_t nu, uint32_t nv) {
  Mesh m;
  const double pi = 3.14159265358979323846;
  for (uint32_t i = 0; i < nu; ++i)
    for (uint32_t j = 0; j < nv; ++j) {
      const double u = 2 * pi * i / nu, w = 2 * pi * j / nv;
      const double r = 0.35 + 0.04 * std::sin(5 * u) * std::cos(3 * w);
      m.add((1 + r * std::cos(w)) * std::cos(u), (1 + r * std::cos(w)) * std::sin(u),
            r * std::sin(w));
    }
  for (uint32_t i = 0; i < nu; ++i)
    for (uint32_t j = 0; j < nv; ++j) {
      const uint32_t a = i * nv + j, b = ((i + 1) % nu) * nv + j,
                     c = ((i + 1) % nu) * nv + (j + 1) % nv, d = i * nv + (j + 1) % nv;
      m.tri(a, b, c);
      m.tri(a, c, d);
    }
  return m;
}

// Height field over an n x n grid with two square holes: boundary loops, open fans.
Mesh terrain(uint32_t n) {
  Mesh m;
  for (uint32_t i = 0; i <= n; ++i)
    for (uint32_t j = 0; j <= n; ++j) {
      const double x = double(i) / n, y = double(j) / n;
      m.add(x, y, 0.1 * std::sin(7 * x) * std::cos(5 * y) + 0.03 * std::sin(23 * x * y));
    }
  auto hole = [&](uint32_t i, uint32_t j) {
    return (i >= 4 && i < 8 && j >= 5 && j < 9) || (i >= 14 && i < 17 && j >= 12 && j < 18);
  };
  for (uint32_t i = 0; i < n; ++i)
    for (uint32_t j = 0; j < n; ++j) {
      if (hole(i, j)) continue;
      const uint32_t a = i * (n + 1) + j, b = a + n + 1;
      m.tri(a, b, b + 1);
      m.tri(a, b + 1, a + 1);
    }
  return m;
}

// A closed cone with `n` rim vertices: apex and base centre of valence n (large rings).
Mesh cone(uint32_t n) {
  Mesh m;
  const double pi = 3.14159265358979323846;
  const uint32_t apex = m.add(0, 0, 1.5), centre = m.add(0, 0, 0);
  for (uint32_t i = 0; i < n; ++i) {
    const double a = 2 * pi * i / n, r = 1 + 0.05 * std::sin(9 * a);
    m.add(r * std::cos(a), r * std::sin(a), 0.02 * std::cos(4 * a));
  }
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t a = 2 + i, b = 2 + (i + 1) % n;
    m.tri(apex, a, b);
    m.tri(centre, b, a);
  }
  return m;
}

// A flat disc: a centre joined to `n` rim vertices. The centre collapses onto a rim vertex
// first (it moves no surface), so splits there have rings of n - 1 and wedge counts of n - 3:
// beyond the small-value escape and the context clamps, on an open fan.
Mesh disc(uint32_t n) {
  Mesh m;
  const double pi = 3.14159265358979323846;
  const uint32_t centre = m.add(0, 0, 0);
  for (uint32_t i = 0; i < n; ++i) m.add(std::cos(2 * pi * i / n), std::sin(2 * pi * i / n), 0);
  for (uint32_t i = 0; i < n; ++i) m.tri(centre, 1 + i, 1 + (i + 1) % n);
  return m;
}

std::string obj_text(const Mesh& m, const std::string& what) {
  std::string s = "# " + what + "\n";
  char buf[128];
  for (size_t i = 0; i < m.v.size(); i += 3) {
    std::snprintf(buf, sizeof buf, "v %.6f %.6f %.6f\n", m.v[i], m.v[i + 1], m.v[i + 2]);
    s += buf;
  }
  for (size_t i = 0; i < m.f.size(); i += 3) {
    std::snprintf(buf, sizeof buf, "f %u %u %u\n", m.f[i] + 1, m.f[i + 1] + 1, m.f[i + 2] + 1);
    s += buf;
  }
  return s;
}

// A bumpy n x n grid with every attribute spec/format.md section 14 codes: a texture seam down
// column `seam` (two charts, the right one mirrored), normals with a crease along the seam, RGB
// vertex colours, and two materials (left and right of the seam), as OBJ with its MTL.
std::string seamed_obj(uint32_t n, uint32_t seam) {
  std::string s = "# bumpy grid with a texture seam, a normal crease, colours, 2 materials\n";
  s += "mtllib seamed.mtl\n";
  char buf[160];
  auto height = [](double x, double y) { return 0.1 * std::sin(3 * x) * std::cos(2 * y); };
  for (uint32_t j = 0; j <= n; ++j)
    for (uint32_t i = 0; i <= n; ++i) {
      const double x = double(i) / n, y = double(j) / n;
      std::snprintf(buf, sizeof buf, "v %.6f %.6f %.6f %.4f %.4f %.4f\n", x, y, height(x, y), x, y,
                    0.5 + 0.5 * std::sin(7 * x * y));
      s += buf;
    }
  // Texture coordinates: the left chart as is, the right chart mirrored and moved (vt per
  // vertex and side; off the seam both sides are the same entry).
  for (uint32_t side = 0; side < 2; ++side)
    for (uint32_t j = 0; j <= n; ++j)
      for (uint32_t i = 0; i <= n; ++i) {
        const double x = double(i) / n, y = double(j) / n;
        std::snprintf(buf, sizeof buf, "vt %.6f %.6f\n", side ? 1.0 - 0.4 * x : 0.45 * x, y);
        s += buf;
      }
  // Normals: the surface's on the left, tilted on the right (a crease along the seam).
  for (uint32_t side = 0; side < 2; ++side)
    for (uint32_t j = 0; j <= n; ++j)
      for (uint32_t i = 0; i <= n; ++i) {
        const double x = double(i) / n, y = double(j) / n;
        const double dx = 0.3 * std::cos(3 * x) * std::cos(2 * y),
                     dy = -0.2 * std::sin(3 * x) * std::sin(2 * y);
        std::snprintf(buf, sizeof buf, "vn %.6f %.6f %.6f\n", -dx + (side ? 0.5 : 0), -dy, 1.0);
        s += buf;
      }
  const uint32_t per_side = (n + 1) * (n + 1);
  for (uint32_t side = 0; side < 2; ++side) {
    s += side ? "usemtl metal\n" : "usemtl paint\n";
    for (uint32_t j = 0; j < n; ++j)
      for (uint32_t i = 0; i < n; ++i) {
        if ((i < seam) != (side == 0)) continue;
        const uint32_t q[4] = {j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1,
                               (j + 1) * (n + 1) + i};
        const uint32_t tris[2][3] = {{q[0], q[1], q[2]}, {q[0], q[2], q[3]}};
        for (const auto& t : tris) {
          s += "f";
          for (uint32_t x : t) {
            const uint32_t a = side * per_side + x + 1;
            std::snprintf(buf, sizeof buf, " %u/%u/%u", x + 1, a, a);
            s += buf;
          }
          s += "\n";
        }
      }
  }
  return s;
}

bool meshes(const fs::path& dir) {
  fs::create_directories(dir);
  bool ok = true;
  auto put = [&](const char* name, const Mesh& m, const std::string& what) {
    ok = write_file(dir / name, obj_text(m, what)) && ok;
  };
  put("sphere.obj", icosphere(2), "icosphere, 2 subdivisions: closed, genus 0");
  put("torus.obj", torus(64, 32),
      "rippled torus 64 x 32: genus 1, enough splits for several SPLT chunks");
  {
    Mesh pieces = icosphere(1);
    Mesh cube;
    for (int i = 0; i < 8; ++i) cube.add(3 + (i & 1), (i >> 1) & 1, (i >> 2) & 1);
    cube.f = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
              2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
    pieces.append(cube);
    Mesh tet;
    tet.add(-3, 0, 0), tet.add(-2, 0, 0), tet.add(-3, 1, 0), tet.add(-3, 0, 1);
    tet.f = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    pieces.append(tet);
    put("pieces.obj", pieces, "three connected components: an icosphere, a cube and a tetrahedron");
  }
  put("terrain.obj", terrain(24), "height field 24 x 24 with two holes: open fans, boundaries");
  put("cone.obj", cone(160), "closed cone with 160 rim vertices");
  put("disc.obj", disc(200), "flat disc, a centre and 200 rim vertices: rings of 199");
  ok = write_file(dir / "seamed.obj", seamed_obj(14, 6)) && ok;
  ok =
      write_file(dir / "seamed.mtl",
                 "# two materials for seamed.obj\nnewmtl paint\nKd 0.8 0.2 0.2\nmap_Kd "
                 "paint.png\nnewmtl metal\nKd 0.6 0.6 0.7\nmap_Kd metal.png\nnorm metal_n.png\n") &&
      ok;
  {
    Mesh spiky = icosphere(2);
    for (uint32_t i = 0; i < spiky.v.size() / 3; i += 17)
      for (int a = 0; a < 3; ++a) spiky.v[3 * i + a] *= 40;
    put("spiky.obj", spiky, "icosphere with every 17th vertex pushed 40 times out: long residuals");
  }
  return ok;
}

// ---- derived files: chunk surgery on a valid vector ----
struct Chunk {
  uint8_t type;
  Bytes payload;
};

bool chunks_of(const Bytes& file, std::vector<Chunk>& out) {
  if (file.size() < 8 || std::memcmp(file.data(), pmz::kSignature, 8) != 0) return false;
  size_t at = 8;
  while (at < file.size()) {
    pmz::ChunkFrame f;
    if (pmz::parse_chunk_frame(file.data() + at, file.size() - at, f) != pmz::FrameStatus::ok)
      return false;
    const uint8_t* p = file.data() + at + f.header_size;
    out.push_back({f.type, Bytes(p, p + f.payload_size)});
    at += f.header_size + size_t(f.payload_size);
  }
  return true;
}

Bytes assemble(const std::vector<Chunk>& chunks) {
  Bytes out(pmz::kSignature, pmz::kSignature + 8);
  for (const Chunk& c : chunks) pmz::append_chunk(out, c.type, c.payload);
  return out;
}

bool derive(const fs::path& src, const fs::path& dir) {
  Bytes file;
  std::vector<Chunk> chunks;
  if (!read_file(src, file) || !chunks_of(file, chunks) || chunks.size() < 4 ||
      chunks[0].type != pmz::kChunkHead || chunks[1].type != pmz::kChunkBase)
    return false;
  pmz::FileHeader h;
  if (!pmz::read_head_payload(chunks[0].payload.data(), chunks[0].payload.size(), h)) return false;
  fs::create_directories(dir);
  const std::string from = src.filename().string();
  bool ok = true;
  auto emit = [&](const std::string& name, const Bytes& bytes, const std::string& what) {
    const fs::path p = dir / (name + ".pmz");
    ok = write_bytes(p, bytes) && expect(p, what + " (derived from " + from + ")", false) && ok;
  };
  auto with_head = [&](const std::function<void(pmz::FileHeader&)>& edit) {
    pmz::FileHeader e = h;
    edit(e);
    std::vector<Chunk> c = chunks;
    c[0].payload.clear();
    pmz::write_head_payload(c[0].payload, e);
    return assemble(c);
  };
  const size_t head_end = 8 + 1 + 1 + 4 + chunks[0].payload.size();  // HEAD's payload < 128

  // Valid edge cases a writer may produce and a decoder must accept.
  {
    std::vector<Chunk> c = chunks;
    c.insert(c.begin() + 2, Chunk{200, {1, 2, 3}});
    c.insert(c.end() - 1, Chunk{5, {}});
    emit("valid-unknown-chunks", assemble(c), "valid: chunks of unknown types 200 and 5, skipped");
  }
  {
    Bytes b = file;
    // A SPLT frame with a wrong CRC, then a frame whose size varint has 11 bytes.
    for (uint8_t x : {3, 1, 0, 0, 0, 0, 0x5a, 1}) b.push_back(x);
    b.insert(b.end(), 10, 0x80);
    emit("valid-trailing-bytes", b, "valid: bytes after END (malformed frames), ignored");
  }
  {
    std::vector<Chunk> c = chunks;
    c.back().payload = {9, 9, 9};
    emit("valid-end-payload", assemble(c), "valid: an END payload, ignored");
  }
  {
    std::vector<Chunk> c = chunks;
    c[0].payload.insert(c[0].payload.end(), {0xAB, 0xCD});
    c[0].payload[1] = 3;
    emit("valid-minor-and-head-tail", assemble(c),
         "valid: minor version 3 with two bytes after bbox_max, ignored");
  }
  {
    // HEAD's counts as over-long (but at most 10-byte) varints: allowed.
    std::vector<Chunk> c = chunks;
    Bytes p(c[0].payload.begin(), c[0].payload.begin() + 2);
    auto padded = [&](uint64_t v) {
      for (int i = 0; i < 9; ++i, v >>= 7) p.push_back(uint8_t(0x80 | (v & 0x7F)));
      p.push_back(uint8_t(v));
    };
    padded(h.flags);
    p.insert(p.end(), {uint8_t(h.position_bits), uint8_t(h.curvature), uint8_t(h.fine_curvature),
                       uint8_t(h.level)});
    for (uint64_t v : {h.base_vertices, h.base_faces, h.total_splits, h.full_faces}) padded(v);
    for (float f : h.bbox_min) pmz::put_f32le(p, f);
    for (float f : h.bbox_max) pmz::put_f32le(p, f);
    c[0].payload = p;
    emit("valid-long-varints", assemble(c), "valid: HEAD varints written in 10 bytes each");
  }
  {
    // An empty chunk of an unknown type after every chunk (also after END).
    std::vector<Chunk> c;
    for (const Chunk& k : chunks) c.push_back(k), c.push_back(Chunk{255, {}});
    c.pop_back();
    emit("valid-interleaved-unknown", assemble(c), "valid: an empty chunk of type 255 after each");
  }

  {
    // A base of vertices only (no faces) and no splits: BASE codes them as vertices without
    // faces, each from the one before.
    const std::vector<int32_t> coords = {
        5, 9, 1, 1000, -3, 77, 1000, 1000, 0, -2147483647 - 1, 2147483647, 12};
    Bytes stream;
    std::vector<uint32_t> given_of;
    pmz::BaseMesh decoded;
    std::string error;
    if (!pmz::encode_base(coords.data(), 4, nullptr, 0, stream, given_of, decoded, error))
      return false;
    pmz::FileHeader e;
    e.position_bits = 0;
    e.base_vertices = 4;
    for (int a = 0; a < 3; ++a) e.bbox_min[a] = -1, e.bbox_max[a] = 1;
    std::vector<Chunk> c(3);
    c[0].type = pmz::kChunkHead;
    pmz::write_head_payload(c[0].payload, e);
    c[1] = {pmz::kChunkBase, stream};
    c[2] = {pmz::kChunkEnd, {}};
    emit("valid-points-only", assemble(c),
         "valid: lossless, a base of 4 vertices without faces (int32 extremes), no splits");
  }

  // Invalid: each MUST be refused with the status named in its .expected.
  {
    Bytes b = file;
    b[1] = 'Q';
    emit("bad-signature", b, "invalid: signature byte 1 is not 'P'");
  }
  {
    Bytes b(pmz::kSignature, pmz::kSignature + 8);
    const char old[] = "HEAD";
    b.insert(b.end(), old, old + 4);
    pmz::put_u32le(b, 52);
    pmz::put_u32le(b, 0);
    b.insert(b.end(), {6, 0});
    b.resize(b.size() + 50, 0);
    emit("bad-version-6", b, "invalid: a format 6.0 frame (ASCII chunk type HEAD)");
  }
  emit("bad-version-8", with_head([](pmz::FileHeader& e) { e.version_major = 8; }),
       "invalid: version_major 8");
  {
    Bytes b = file;
    b[head_end + 8] ^= 0x01;  // a byte of BASE's payload (its header is at most 7 bytes here)
    emit("bad-checksum", b, "invalid: a BASE payload byte changed, CRC not");
  }
  emit("bad-level", with_head([](pmz::FileHeader& e) { e.level = 2; }), "invalid: level 2");
  emit("bad-flags", with_head([](pmz::FileHeader& e) { e.flags = 1; }), "invalid: flags 1");
  emit("bad-position-bits", with_head([](pmz::FileHeader& e) { e.position_bits = 31; }),
       "invalid: position_bits 31");
  emit("bad-curvature", with_head([](pmz::FileHeader& e) { e.curvature = 9; }),
       "invalid: curvature 9");
  emit("bad-fine-curvature", with_head([](pmz::FileHeader& e) { e.fine_curvature = 9; }),
       "invalid: fine_curvature 9");
  emit("bad-bbox-nan", with_head([](pmz::FileHeader& e) { e.bbox_max[1] = std::nanf(""); }),
       "invalid: bbox_max.y NaN");
  emit("bad-bbox-inf", with_head([](pmz::FileHeader& e) {
         e.bbox_min[0] = -std::numeric_limits<float>::infinity();
       }),
       "invalid: bbox_min.x -infinity");
  emit("bad-bbox-order",
       with_head([](pmz::FileHeader& e) { std::swap(e.bbox_min[2], e.bbox_max[2]); }),
       "invalid: bbox_min.z > bbox_max.z");
  emit("bad-full-faces-low", with_head([](pmz::FileHeader& e) { e.full_faces = e.base_faces - 1; }),
       "invalid: full_faces below base_faces");
  emit("bad-full-faces-high",
       with_head([](pmz::FileHeader& e) { e.full_faces = e.base_faces + 2 * e.total_splits + 1; }),
       "invalid: full_faces above base_faces + 2 total_splits");
  emit("bad-vertex-count-2-32", with_head([](pmz::FileHeader& e) {
         e.total_splits = 0xFFFFFFFFu - e.base_vertices + 1;
         e.full_faces = e.base_faces;
       }),
       "invalid: base_vertices + total_splits = 2^32");
  {
    std::vector<Chunk> c = chunks;
    c[0].payload.resize(c[0].payload.size() - 1);
    emit("bad-head-short", assemble(c), "invalid: HEAD payload ends inside bbox_max");
  }
  {
    std::vector<Chunk> c = chunks;
    Bytes p(c[0].payload.begin(), c[0].payload.begin() + 2);
    for (int i = 0; i < 10; ++i) p.push_back(0x80);
    p.push_back(0);  // flags in 11 bytes
    p.insert(p.end(), c[0].payload.begin() + 3, c[0].payload.end());
    c[0].payload = p;
    emit("bad-head-varint-11", assemble(c), "invalid: HEAD flags varint of 11 bytes");
  }
  {
    Bytes b(file.begin(), file.begin() + 8);
    b.push_back(pmz::kChunkHead);
    for (int i = 0; i < 10; ++i) b.push_back(0x80);
    b.push_back(0);
    b.insert(b.end(), 4, 0);
    emit("bad-frame-varint-11", b, "invalid: chunk payload_size varint of 11 bytes");
  }
  {
    std::vector<Chunk> c = chunks;
    std::swap(c[0], c[1]);
    emit("bad-order-base-first", assemble(c), "invalid: BASE before HEAD");
  }
  {
    std::vector<Chunk> c = chunks;
    c.insert(c.begin() + 1, Chunk{77, {}});
    std::swap(c[0], c[1]);
    emit("bad-order-unknown-first", assemble(c), "invalid: an unknown chunk before HEAD");
  }
  {
    std::vector<Chunk> c = chunks;
    c.insert(c.begin() + 1, c[0]);
    emit("bad-order-two-heads", assemble(c), "invalid: HEAD twice");
  }
  {
    std::vector<Chunk> c = chunks;
    std::swap(c[1], c[2]);
    emit("bad-order-splt-first", assemble(c), "invalid: SPLT before BASE");
  }
  {
    std::vector<Chunk> c = chunks;
    c.insert(c.begin() + 3, c[1]);
    emit("bad-order-two-bases", assemble(c), "invalid: BASE twice");
  }
  {
    std::vector<Chunk> c = chunks;
    c.erase(c.end() - 2);
    emit("bad-end-early", assemble(c), "invalid: the last SPLT chunk missing before END");
  }
  {
    std::vector<Chunk> c = chunks;
    c.pop_back();
    emit("truncated-no-end", assemble(c), "truncated: every chunk but END");
  }
  {
    Bytes b(file.begin(), file.begin() + std::ptrdiff_t(file.size() / 2));
    emit("truncated-half", b, "truncated: the first half of the bytes");
  }
  {
    std::vector<Chunk> c = chunks;
    c[1].payload.resize(c[1].payload.size() / 2);
    emit("bad-base-short", assemble(c), "invalid: BASE payload cut in half");
  }
  {
    std::vector<Chunk> c = chunks;
    c[2].payload[0] = 0;  // split_count 0 (a one-byte varint in every vector)
    emit("bad-splt-zero", assemble(c), "invalid: a SPLT chunk with split_count 0");
  }
  {
    std::vector<Chunk> c = chunks;
    Bytes p;
    pmz::put_varint(p, uint64_t(h.total_splits) + 1);
    size_t n = 0;
    while (c[2].payload[n] & 0x80) ++n;
    p.insert(p.end(), c[2].payload.begin() + std::ptrdiff_t(n + 1), c[2].payload.end());
    c[2].payload = p;
    emit("bad-splt-too-many", assemble(c),
         "invalid: a SPLT chunk's split_count above the splits still missing");
  }
  {
    std::vector<Chunk> c = chunks;
    size_t n = 0;
    while (c[2].payload[n] & 0x80) ++n;
    Bytes p(c[2].payload.begin(), c[2].payload.begin() + std::ptrdiff_t(n + 1));
    pmz::put_varint(p, c[2].payload.size());  // connectivity_size beyond the payload
    size_t m = n + 1;
    while (c[2].payload[m] & 0x80) ++m;
    p.insert(p.end(), c[2].payload.begin() + std::ptrdiff_t(m + 1), c[2].payload.end());
    c[2].payload = p;
    emit("bad-splt-connectivity-size", assemble(c),
         "invalid: a SPLT chunk's connectivity_size beyond its payload");
  }
  {
    // A byte of the first SPLT chunk inverted (CRC repaired): the first offset from the middle
    // of its payload on that the reference refuses at some split; the splits before it apply.
    const size_t size = chunks[2].payload.size();
    for (size_t at = size / 2; at < size; ++at) {
      std::vector<Chunk> c = chunks;
      c[2].payload[at] ^= 0xFF;
      const Bytes b = assemble(c);
      pmz::Decoder d;
      d.feed(b.data(), b.size());
      d.refine();
      if (d.status() == pmz::Status::corrupt && d.splits_applied() > 0) {
        emit("bad-splt-stream", b,
             "invalid: the first SPLT chunk's payload byte " + std::to_string(at) + " of " +
                 std::to_string(size) + " inverted (CRC repaired): refused at a split");
        break;
      }
    }
  }
  {
    // A BASE vertex in two fans: two triangles sharing a vertex, coded as BASE codes it.
    const std::vector<uint32_t> faces = {0, 1, 2, 0, 3, 4};
    const std::vector<int32_t> coords = {0, 0, 0, 100, 0, 0, 0, 100, 0, -100, 0, 0, 0, -100, 0};
    Bytes stream;
    std::vector<uint32_t> given_of;
    pmz::BaseMesh decoded;
    std::string error;
    if (!pmz::encode_base(coords.data(), 5, faces.data(), 2, stream, given_of, decoded, error))
      return false;
    pmz::FileHeader e;
    e.position_bits = 8;
    e.base_vertices = 5, e.base_faces = 2, e.full_faces = 2;
    for (int a = 0; a < 3; ++a) e.bbox_min[a] = 0, e.bbox_max[a] = 1;
    std::vector<Chunk> c(3);
    c[0].type = pmz::kChunkHead;
    pmz::write_head_payload(c[0].payload, e);
    c[1] = {pmz::kChunkBase, stream};
    c[2] = {pmz::kChunkEnd, {}};
    emit("bad-base-several-fans", assemble(c), "invalid: a BASE vertex in two fans (a bow tie)");
  }
  return ok;
}

bool check(const fs::path& dir, int& failures, int& checked) {
  std::vector<fs::path> expected;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().extension() == ".expected") expected.push_back(e.path());
  std::sort(expected.begin(), expected.end());
  for (const fs::path& x : expected) {
    Bytes text_bytes;
    read_file(x, text_bytes);
    const std::string text(text_bytes.begin(), text_bytes.end());
    std::string want;  // without comment lines
    std::vector<uint64_t> levels;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
      if (line.empty() || line[0] == '#') continue;
      want += line + "\n";
      if (line.rfind("level ", 0) == 0) levels.push_back(std::stoull(line.substr(6)));
    }
    fs::path pmz_path = x;
    pmz_path.replace_extension(".pmz");
    Bytes file;
    if (!read_file(pmz_path, file)) {
      std::printf("FAIL %s: cannot read\n", pmz_path.string().c_str());
      ++failures;
      continue;
    }
    ++checked;
    const std::string name = pmz_path.filename().string();
    for (size_t slice : {size_t(0), size_t(1), size_t(7)}) {
      const std::string got = describe(file, name, slice, &levels, nullptr);
      if (got != want) {
        std::printf("FAIL %s (slices of %zu bytes; 0 = whole)\n--- expected\n%s--- decoded\n%s",
                    pmz_path.string().c_str(), slice, want.c_str(), got.c_str());
        ++failures;
        break;
      }
    }
  }
  return true;
}

int usage() {
  std::fprintf(stderr,
               "usage: pmz-conformance meshes DIR | expect FILE.pmz NOTE | derive FILE.pmz DIR | "
               "check DIR\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) return usage();
  const std::string cmd = argv[1];
  if (cmd == "meshes" && argc == 3) {
    if (meshes(argv[2])) return 0;
    std::fprintf(stderr, "pmz-conformance: %s: cannot write the meshes\n", argv[2]);
    return 1;
  }
  if (cmd == "expect" && argc == 4) {
    if (expect(argv[2], argv[3], true)) return 0;
    std::fprintf(stderr, "pmz-conformance: %s: cannot read it or write its .expected\n", argv[2]);
    return 1;
  }
  if (cmd == "derive" && argc == 4) {
    if (derive(argv[2], argv[3])) return 0;
    std::fprintf(stderr, "pmz-conformance: %s: not a valid vector with 2+ SPLT chunks\n", argv[2]);
    return 1;
  }
  if (cmd == "check" && argc == 3) {
    int failures = 0, checked = 0;
    check(argv[2], failures, checked);
    std::printf("%d files checked, %d failed\n", checked, failures);
    return failures || !checked ? 1 : 0;
  }
  return usage();
}
