// SPDX-License-Identifier: MIT
// STL, ascii and binary: the reader into a PolygonSoup (positions repeated per facet become one
// vertex) and the binary writer.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "mesh_formats.hpp"
#include "reader_support.hpp"
#include "writer_support.hpp"

namespace pmz {

namespace {

uint32_t load_le32(const char* p) {
  const auto* b = reinterpret_cast<const unsigned char*>(p);
  return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
}

// STL repeats positions per facet; bitwise-equal positions (with -0 == +0) become one vertex.
bool add_stl_corner(PolygonSoup& out, std::unordered_map<uint64_t, std::vector<uint32_t>>& buckets,
                    float p[3], uint64_t facet, const std::string& path, std::string& error) {
  if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
    error = path + ": facet " + std::to_string(facet) + " has a NaN or infinite coordinate";
    return false;
  }
  uint64_t h = 1469598103934665603ull;
  for (int k = 0; k < 3; ++k) {
    if (p[k] == 0) p[k] = 0;  // -0 -> +0
    h = (h ^ std::bit_cast<uint32_t>(p[k])) * 1099511628211ull;
  }
  std::vector<uint32_t>& bucket = buckets[h];
  for (uint32_t v : bucket)
    if (std::memcmp(&out.positions[size_t(v) * 3], p, sizeof(float) * 3) == 0) {
      out.corners.push_back(v);
      return true;
    }
  if (out.vertex_count() >= kMaxVertices) {
    error = path + ": too many vertices";
    return false;
  }
  bucket.push_back(out.vertex_count());
  out.corners.push_back(out.vertex_count());
  out.positions.insert(out.positions.end(), p, p + 3);
  return true;
}

}  // namespace

bool read_stl(const std::string& path, ByteSource& data, PolygonSoup& out, std::string& error) {
  std::unordered_map<uint64_t, std::vector<uint32_t>> buckets;
  std::string_view head = data.peek(512);  // a shorter source has a known size from here
  std::string_view first = head.substr(0, 512);
  first = next_token(first);
  // Binary files may start with "solid" too, and then the size decides: a source of unknown
  // size is copied to a temporary file to know it. Any other source of unknown size is binary
  // and read as it comes; its count is checked when its data ends.
  const bool size_known = data.size_known();
  if (!size_known && first == "solid") {
    if (!data.make_seekable(error)) {
      error = path + ": " + error;
      return false;
    }
    head = data.peek(512);
  }
  const uint64_t size = data.remaining();
  const uint32_t declared = size >= 84 && head.size() >= 84 ? load_le32(head.data() + 80) : 0;
  const bool size_matches = size >= 84 && (size - 84) / 50 == declared && (size - 84) % 50 == 0;
  if (!size_matches && first == "solid") {
    Lines lines{data, 0, 0};
    std::string_view line;
    uint64_t facet = 0;
    bool in_loop = false;
    while (lines.next(line)) {
      std::string_view key = next_token(line);
      if (key == "outer") {
        in_loop = true;
      } else if (key == "vertex") {
        float p[3];
        for (float& c : p)
          if (!parse_float(next_token(line), c)) {
            error = line_error(path, lines.number, "vertex needs three numeric coordinates");
            return false;
          }
        if (!in_loop) {
          error = line_error(path, lines.number, "vertex outside 'outer loop'");
          return false;
        }
        if (!add_stl_corner(out, buckets, p, facet, path, error)) return false;
      } else if (key == "endloop") {
        in_loop = false;
        end_face(out);
        ++facet;
      }
    }
    if (in_loop) {
      error = path + ": file ends inside facet " + std::to_string(facet);
      return false;
    }
    return true;
  }
  if (size < 84) {
    error = path + ": not an STL file (too short for binary, no 'solid' header)";
    return false;
  }
  auto too_few = [&](uint64_t total) {
    error = path + ": binary STL declares " + std::to_string(declared) +
            " triangles but holds only " + std::to_string((total - 84) / 50);
    return false;
  };
  if ((size - 84) / 50 < declared) return too_few(size);
  data.skip(std::min<size_t>(84, data.peek(84).size()));
  const size_t reserve = plausible(declared, data.reservable(), 50);  // checked above if known
  out.positions.reserve(reserve * 3);
  out.corners.reserve(reserve * 3);
  out.face_offsets.reserve(reserve + 1);
  buckets.reserve(reserve);
  for (uint32_t t = 0; t < declared; ++t) {
    std::string_view record = data.peek(50);
    if (record.size() < 50) {
      if (!size_known) return too_few(data.learn_size());
      error = path + ": binary STL ends in triangle " + std::to_string(t);
      return false;
    }
    data.skip(50);
    const char* rec = record.data() + 12;  // skip the stored normal
    for (int c = 0; c < 3; ++c) {
      float p[3];
      for (int k = 0; k < 3; ++k) p[k] = std::bit_cast<float>(load_le32(rec + c * 12 + k * 4));
      if (add_stl_corner(out, buckets, p, t, path, error)) continue;
      // A count the data cannot hold is the error reported first, as from a file.
      if (!size_known && (data.learn_size() - 84) / 50 < declared)
        return too_few(data.learn_size());
      return false;
    }
    end_face(out);
  }
  return true;
}

// Binary STL: an 80-byte header, the facet count, per facet the unit normal of its corners (zero
// for a degenerate facet), the three positions and a zero attribute word.
void write_stl(Writer& w, const IndexedMesh& m) {
  const uint32_t nf = m.face_count();
  const float* p = m.positions.data();
  const uint32_t* ix = m.indices.data();
  char header[80] = "binary STL written by pmz";
  w.put(header, 80);
  w.u32le(nf);
  for (uint32_t f = 0; f < nf; ++f) {
    const float* a = p + size_t(ix[f * 3]) * 3;
    const float* b = p + size_t(ix[f * 3 + 1]) * 3;
    const float* c = p + size_t(ix[f * 3 + 2]) * 3;
    float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
          e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                  e1[0] * e2[1] - e1[1] * e2[0]};
    float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (float& x : n) x = len > 0 ? x / len : 0;
    for (float x : n) w.f32le(x);
    for (const float* q : {a, b, c})
      for (int k = 0; k < 3; ++k) w.f32le(q[k]);
    const uint8_t attr[2] = {0, 0};
    w.put(attr, 2);
  }
}

}  // namespace pmz
