// SPDX-License-Identifier: MIT
// OFF, text and binary (Geomview's big-endian layout and OpenMesh's little-endian one): the
// reader into a PolygonSoup and the text writer.
#include <bit>
#include <string>
#include <string_view>

#include "mesh_formats.hpp"
#include "reader_support.hpp"
#include "writer_support.hpp"

namespace pmz {

namespace {

uint32_t load_u32(const char* p, bool big_endian) {
  const auto* b = reinterpret_cast<const unsigned char*>(p);
  return big_endian
             ? uint32_t(b[3]) | uint32_t(b[2]) << 8 | uint32_t(b[1]) << 16 | uint32_t(b[0]) << 24
             : uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
}

// Binary OFF after its header line: counts (vertices, faces, edges) as int32, then per vertex
// 3 + extra float32 (normals, colours, texture coordinates, ignored), per face an int32 corner
// count and the int32 indices. Geomview's definition is big endian with a colour count (and that
// many floats) after each face; OpenMesh writes little endian without it. The first layout that
// reads the whole data is taken.
bool read_off_binary_layout(const std::string& path, ByteSource& data, uint32_t extra,
                            bool big_endian, bool face_colors, PolygonSoup& out,
                            std::string& error) {
  out.positions.clear(), out.corners.clear(), out.face_offsets.assign(1, 0);
  auto u32 = [&](uint32_t& v) {
    std::string_view b = data.peek(4);
    if (b.size() < 4) return false;
    v = load_u32(b.data(), big_endian);
    data.skip(4);
    return true;
  };
  uint32_t nv, nf, ne;
  if (!u32(nv) || !u32(nf) || !u32(ne)) {
    error = path + ": binary OFF ends inside its counts";
    return false;
  }
  const uint64_t vertex_bytes = uint64_t(3 + extra) * 4;
  if (nv >= kMaxVertices || uint64_t(nv) * vertex_bytes > data.remaining() ||
      uint64_t(nf) * 8 > data.remaining() - uint64_t(nv) * vertex_bytes) {
    error = path + ": binary OFF declares " + std::to_string(nv) + " vertices and " +
            std::to_string(nf) + " faces, more than the file holds";
    return false;
  }
  out.positions.reserve(size_t(nv) * 3);
  for (uint32_t v = 0; v < nv; ++v) {
    std::string_view b = data.peek(size_t(vertex_bytes));
    if (b.size() < vertex_bytes) {
      error = path + ": binary OFF ends or is malformed in vertex " + std::to_string(v);
      return false;
    }
    float p[3];
    for (int k = 0; k < 3; ++k)
      p[k] = std::bit_cast<float>(load_u32(b.data() + size_t(k) * 4, big_endian));
    data.skip(size_t(vertex_bytes));
    if (!push_vertex(out, p, path, 0, error)) return false;
  }
  for (uint32_t f = 0; f < nf; ++f) {
    uint32_t n, ix = 0, colors = 0;
    if (!u32(n) || n > data.remaining() / 4) {
      error = path + ": binary OFF ends or is malformed in face " + std::to_string(f);
      return false;
    }
    for (uint32_t c = 0; c < n; ++c) {
      u32(ix);
      if (ix >= nv) {
        error = range_error(path, f, 0, int64_t(int32_t(ix)), nv);
        return false;
      }
      out.corners.push_back(ix);
    }
    if (face_colors && (!u32(colors) || colors > 4 || colors * 4 > data.remaining())) {
      error = path + ": binary OFF ends or is malformed in face " + std::to_string(f);
      return false;
    }
    data.peek(colors * 4);
    data.skip(colors * 4);
    end_face(out);
  }
  if (data.remaining() != 0) {
    error = path + ": binary OFF has " + std::to_string(data.remaining()) +
            " bytes after its last face";
    return false;
  }
  return true;
}

bool read_off_binary(const std::string& path, ByteSource& data, uint32_t extra, PolygonSoup& out,
                     std::string& error) {
  // The reported failure: the first layout whose counts fit the file (else the first one's).
  std::string reported;
  bool counts_fit = false;
  // Each layout is tried from the counts on: a source of unknown size is copied to a temporary
  // file first, to know its size and seek back.
  if (!data.make_seekable(error)) {
    error = path + ": " + error;
    return false;
  }
  const uint64_t start = data.offset();
  for (int layout = 0; layout < 4; ++layout) {
    bool big_endian = layout == 1 || layout == 2, face_colors = layout == 1 || layout == 3;
    if (!data.seek(start)) {
      error = path + ": read error";
      return false;
    }
    if (read_off_binary_layout(path, data, extra, big_endian, face_colors, out, error)) return true;
    bool fit = error.find("more than the file holds") == std::string::npos &&
               error.find("inside its counts") == std::string::npos;
    if (reported.empty() || (fit && !counts_fit)) reported = error, counts_fit = fit;
  }
  error = reported;
  return false;
}

}  // namespace

bool read_off(const std::string& path, ByteSource& data, PolygonSoup& out, std::string& error) {
  Lines lines{data, 0, '#'};
  std::string_view line;
  if (!lines.next_nonblank(line)) {
    error = path + ": empty file";
    return false;
  }
  std::string_view key = next_token(line);
  // [ST][C][N]OFF carry extra per-vertex values after xyz; they are ignored (line-based parse).
  std::string_view k = key;
  if (k.starts_with("ST")) k.remove_prefix(2);
  if (k.starts_with("C")) k.remove_prefix(1);
  if (k.starts_with("N")) k.remove_prefix(1);
  if (k != "OFF") {
    error = path + ": not an OFF file (header '" + std::string(key.substr(0, 16)) +
            "'; 4OFF/nOFF are not supported)";
    return false;
  }
  std::string_view counts = line;
  std::string_view probe = counts;
  if (next_token(probe) == "BINARY") {
    uint32_t extra = 0;
    std::string_view flags = key.substr(0, key.size() - 3);
    if (flags.starts_with("ST")) extra += 2, flags.remove_prefix(2);
    if (flags.starts_with("C")) extra += 4, flags.remove_prefix(1);
    if (flags.starts_with("N")) extra += 3;
    return read_off_binary(path, data, extra, out, error);
  }
  if (probe = counts, next_token(probe).empty() && !lines.next_nonblank(counts)) {
    error = path + ": OFF header has no vertex and face counts";
    return false;
  }
  int64_t nv, nf;
  if (!parse_int(next_token(counts), nv) || !parse_int(next_token(counts), nf) || nv < 0 ||
      nf < 0) {
    error = line_error(path, lines.number, "OFF counts must be non-negative integers");
    return false;
  }
  if (uint64_t(nv) >= kMaxVertices) {
    error = path + ": declares " + std::to_string(nv) + " vertices, more than supported";
    return false;
  }
  // Each vertex line needs at least 6 bytes, each face line at least 8.
  out.positions.reserve(plausible(uint64_t(nv), data.reservable(), 6) * 3);
  out.face_offsets.reserve(plausible(uint64_t(nf), data.reservable(), 8) + 1);
  out.corners.reserve(plausible(uint64_t(nf), data.reservable(), 8) * 3);
  for (int64_t v = 0; v < nv; ++v) {
    if (!lines.next_nonblank(line)) {
      error = path + ": file ends after " + std::to_string(v) + " of " + std::to_string(nv) +
              " vertices";
      return false;
    }
    float p[3];
    for (float& c : p)
      if (!parse_float(next_token(line), c)) {
        error = line_error(path, lines.number,
                           "vertex " + std::to_string(v) + " needs three numeric coordinates");
        return false;
      }
    if (!push_vertex(out, p, path, lines.number, error)) return false;
  }
  for (int64_t f = 0; f < nf; ++f) {
    if (!lines.next_nonblank(line)) {
      error =
          path + ": file ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces";
      return false;
    }
    int64_t n;
    if (!parse_int(next_token(line), n) || n < 0) {
      error = line_error(path, lines.number,
                         "face " + std::to_string(f) + " has a malformed corner count");
      return false;
    }
    for (int64_t c = 0; c < n;
         ++c) {  // the line bounds the loop: a huge n fails on a missing token
      int64_t i;
      std::string_view t = next_token(line);
      if (!parse_int(t, i)) {
        error = line_error(path, lines.number,
                           "face " + std::to_string(f) + " declares " + std::to_string(n) +
                               " corners but has only " + std::to_string(c));
        return false;
      }
      if (i < 0 || i >= nv) {
        error = range_error(path, uint64_t(f), lines.number, i, uint64_t(nv));
        return false;
      }
      out.corners.push_back(uint32_t(i));
    }
    end_face(out);  // trailing values on the line are a face colour
  }
  return true;
}

// Text OFF: the counts, one vertex per line, "3 a b c" per face.
void write_off(Writer& w, const IndexedMesh& m) {
  const uint32_t nv = m.vertex_count(), nf = m.face_count();
  const float* p = m.positions.data();
  const uint32_t* ix = m.indices.data();
  w.str("OFF\n").num(nv).str(" ").num(nf).str(" 0\n");
  for (uint32_t v = 0; v < nv; ++v) put_line(w, "", p + size_t(v) * 3, 3);
  for (uint32_t f = 0; f < nf; ++f) put_line(w, "3 ", ix + size_t(f) * 3, 3);
}

}  // namespace pmz
