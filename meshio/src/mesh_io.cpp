// Mesh input/output: small readers for OBJ/OFF/PLY/STL into a raw polygon soup, and writers
// from the flat IndexedMesh. OpenMesh is not used here on purpose: its mesh building detaches or
// drops faces it cannot represent (and its OFF reader hangs on huge counts and reads `nan` as
// garbage indices), while pmz must keep every face; repair_mesh does the repair instead.
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string_view>
#include <unordered_map>

#include "pmz/mesh.hpp"

namespace pmz {

namespace {

constexpr uint64_t kMaxVertices = 0xFFFFFFF0u;  // ids must fit uint32 with room for copies

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

bool read_file(const std::string& path, std::string& data, std::string& error) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    error = path + ": no such file";
    return false;
  }
  if (std::filesystem::is_directory(path, ec)) {
    error = path + ": is a directory, not a mesh file";
    return false;
  }
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    error = path + ": cannot open: " + std::strerror(errno);
    return false;
  }
  data.clear();
  char buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) data.append(buf, n);
  bool failed = std::ferror(f);
  std::fclose(f);
  if (failed) {
    error = path + ": read error";
    return false;
  }
  if (data.empty()) {
    error = path + ": empty file";
    return false;
  }
  return true;
}

// ---- text scanning ----

struct Lines {
  std::string_view rest;
  uint64_t number = 0;  // 1-based number of the line last returned
  char comment;         // everything from this character to the end of a line is ignored
  // Next line with the comment stripped; false at the end of the data.
  bool next(std::string_view& line) {
    if (rest.empty()) return false;
    size_t end = rest.find('\n');
    line = rest.substr(0, end);
    rest = end == std::string_view::npos ? std::string_view() : rest.substr(end + 1);
    ++number;
    if (comment) {
      size_t c = line.find(comment);
      if (c != std::string_view::npos) line = line.substr(0, c);
    }
    return true;
  }
  // Next line holding something other than blanks and comments.
  bool next_nonblank(std::string_view& line) {
    while (next(line))
      if (line.find_first_not_of(" \t\r\v\f") != std::string_view::npos) return true;
    return false;
  }
};

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

std::string_view next_token(std::string_view& s) {
  size_t i = 0;
  while (i < s.size() && is_space(s[i])) ++i;
  size_t j = i;
  while (j < s.size() && !is_space(s[j])) ++j;
  std::string_view t = s.substr(i, j - i);
  s = s.substr(j);
  return t;
}

// Whole-token parses; a malformed token is an error, NaN/Inf parse (and are refused later).
bool parse_float(std::string_view t, float& v) {
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  if (t.empty()) return false;
  auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  if (r.ec == std::errc::result_out_of_range)
    v = (t[0] == '-' ? -1.0f : 1.0f) * INFINITY;
  else if (r.ec != std::errc())
    return false;
  return r.ptr == t.data() + t.size() || r.ec == std::errc::result_out_of_range;
}

bool parse_int(std::string_view t, int64_t& v) {
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  return !t.empty() && r.ec == std::errc() && r.ptr == t.data() + t.size();
}

std::string line_error(const std::string& path, uint64_t line, const std::string& what) {
  return path + ": line " + std::to_string(line) + ": " + what;
}

std::string nonfinite_error(const std::string& path, uint64_t vertex, uint64_t line) {
  std::string where = line ? " (line " + std::to_string(line) + ")" : std::string();
  return path + ": vertex " + std::to_string(vertex) + where + " has a NaN or infinite coordinate";
}

std::string range_error(const std::string& path, uint64_t face, uint64_t line, int64_t index,
                        uint64_t vertices) {
  std::string where = line ? " (line " + std::to_string(line) + ")" : std::string();
  return path + ": face " + std::to_string(face) + where + " references vertex " +
         std::to_string(index) + ", but the file has " + std::to_string(vertices) +
         " vertices (0-based)";
}

bool push_vertex(PolygonSoup& out, const float p[3], const std::string& path, uint64_t line,
                 std::string& error) {
  uint64_t id = out.vertex_count();
  if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
    error = nonfinite_error(path, id, line);
    return false;
  }
  if (id >= kMaxVertices) {
    error = path + ": too many vertices";
    return false;
  }
  out.positions.insert(out.positions.end(), p, p + 3);
  return true;
}

void end_face(PolygonSoup& out) { out.face_offsets.push_back(uint32_t(out.corners.size())); }

// Capacity to reserve for `declared` items that each take at least `min_bytes` of `available`:
// a header cannot make us allocate more than the data could possibly hold.
size_t plausible(uint64_t declared, size_t available, size_t min_bytes) {
  return size_t(std::min<uint64_t>(declared, available / min_bytes));
}

// ---- OBJ ----

bool read_obj(const std::string& path, const std::string& data, PolygonSoup& out,
              std::string& error) {
  Lines lines{data, 0, '#'};
  std::string_view line;
  // Positive indices are checked once all vertices are known; remember where faces came from.
  std::vector<uint64_t> face_lines;
  while (lines.next(line)) {
    std::string_view key = next_token(line);
    if (key == "v") {
      float p[3];
      for (float& c : p)
        if (!parse_float(next_token(line), c)) {
          error = line_error(path, lines.number, "vertex needs three numeric coordinates");
          return false;
        }
      if (!push_vertex(out, p, path, lines.number, error)) return false;
    } else if (key == "f" || key == "fo") {
      uint64_t face = face_lines.size();
      for (std::string_view t = next_token(line); !t.empty(); t = next_token(line)) {
        int64_t i;
        if (!parse_int(t.substr(0, t.find('/')), i) || i == 0) {
          error = line_error(
              path, lines.number,
              "face " + std::to_string(face) + " has a malformed index '" + std::string(t) + "'");
          return false;
        }
        // Negative indices count back from the last vertex read so far.
        int64_t id = i < 0 ? int64_t(out.vertex_count()) + i : i - 1;
        if (id < 0 || id >= int64_t(kMaxVertices)) {
          error = range_error(path, face, lines.number, id, out.vertex_count());
          return false;
        }
        out.corners.push_back(uint32_t(id));
      }
      end_face(out);
      face_lines.push_back(lines.number);
    }
    // Other records (vt, vn, l, p, g, o, s, usemtl, mtllib, ...) do not describe triangles.
  }
  for (uint32_t f = 0; f < out.face_count(); ++f)
    for (uint32_t c = out.face_offsets[f]; c < out.face_offsets[f + 1]; ++c)
      if (out.corners[c] >= out.vertex_count()) {
        error = range_error(path, f, face_lines[f], out.corners[c], out.vertex_count());
        return false;
      }
  return true;
}

// ---- OFF ----

bool read_off(const std::string& path, const std::string& data, PolygonSoup& out,
              std::string& error) {
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
    error = path + ": binary OFF is not supported (convert to ascii OFF, PLY or OBJ)";
    return false;
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
  out.positions.reserve(plausible(uint64_t(nv), lines.rest.size(), 6) * 3);
  out.face_offsets.reserve(plausible(uint64_t(nf), lines.rest.size(), 8) + 1);
  out.corners.reserve(plausible(uint64_t(nf), lines.rest.size(), 8) * 3);
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

// ---- PLY ----

enum class PlyType : uint8_t { i8, u8, i16, u16, i32, u32, f32, f64, invalid };

PlyType ply_type(std::string_view s) {
  if (s == "char" || s == "int8") return PlyType::i8;
  if (s == "uchar" || s == "uint8") return PlyType::u8;
  if (s == "short" || s == "int16") return PlyType::i16;
  if (s == "ushort" || s == "uint16") return PlyType::u16;
  if (s == "int" || s == "int32") return PlyType::i32;
  if (s == "uint" || s == "uint32") return PlyType::u32;
  if (s == "float" || s == "float32") return PlyType::f32;
  if (s == "double" || s == "float64") return PlyType::f64;
  return PlyType::invalid;
}

size_t ply_size(PlyType t) {
  static const size_t sizes[] = {1, 1, 2, 2, 4, 4, 4, 8, 0};
  return sizes[size_t(t)];
}

struct PlyProperty {
  std::string name;
  PlyType type;        // value type (item type for lists)
  PlyType count_type;  // PlyType::invalid for a scalar
};

struct PlyElement {
  std::string name;
  uint64_t count;
  std::vector<PlyProperty> properties;
};

// Reads one value of the body, ascii or binary; false when the data ends or is malformed.
struct PlyBody {
  std::string_view data;
  size_t pos = 0;
  bool ascii, big_endian;

  bool read(PlyType t, double& v) {
    if (ascii) {
      std::string_view rest = data.substr(pos);
      size_t before = rest.size();
      std::string_view tok = next_token(rest);
      pos += before - rest.size();
      if (t == PlyType::f32 || t == PlyType::f64) {
        float f;
        if (!parse_float(tok, f)) return false;
        v = f;
        return true;
      }
      int64_t i;
      if (!parse_int(tok, i)) return false;
      v = double(i);
      return true;
    }
    size_t n = ply_size(t);
    if (data.size() - pos < n) return false;
    unsigned char b[8];
    std::memcpy(b, data.data() + pos, n);
    pos += n;
    if (big_endian != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
    switch (t) {
      case PlyType::i8:
        v = double(int8_t(b[0]));
        break;
      case PlyType::u8:
        v = double(b[0]);
        break;
      case PlyType::i16: {
        int16_t x;
        std::memcpy(&x, b, 2);
        v = x;
        break;
      }
      case PlyType::u16: {
        uint16_t x;
        std::memcpy(&x, b, 2);
        v = x;
        break;
      }
      case PlyType::i32: {
        int32_t x;
        std::memcpy(&x, b, 4);
        v = x;
        break;
      }
      case PlyType::u32: {
        uint32_t x;
        std::memcpy(&x, b, 4);
        v = x;
        break;
      }
      case PlyType::f32: {
        float x;
        std::memcpy(&x, b, 4);
        v = x;
        break;
      }
      case PlyType::f64: {
        double x;
        std::memcpy(&x, b, 8);
        v = x;
        break;
      }
      case PlyType::invalid:
        return false;
    }
    return true;
  }
  size_t remaining() const { return data.size() - pos; }
};

bool read_ply(const std::string& path, const std::string& data, PolygonSoup& out,
              std::string& error) {
  Lines lines{data, 0, 0};
  std::string_view line;
  if (!lines.next(line) || next_token(line) != "ply") {
    error = path + ": not a PLY file (no 'ply' magic)";
    return false;
  }
  std::vector<PlyElement> elements;
  int format = -1;  // 0 ascii, 1 binary little endian, 2 binary big endian
  bool ended = false;
  while (!ended && lines.next(line)) {
    std::string_view key = next_token(line);
    if (key == "format") {
      std::string_view f = next_token(line);
      format = f == "ascii"                  ? 0
               : f == "binary_little_endian" ? 1
               : f == "binary_big_endian"    ? 2
                                             : -1;
      if (format < 0) {
        error = line_error(path, lines.number, "unknown PLY format '" + std::string(f) + "'");
        return false;
      }
    } else if (key == "element") {
      PlyElement e;
      e.name = next_token(line);
      int64_t n;
      if (!parse_int(next_token(line), n) || n < 0) {
        error = line_error(path, lines.number, "PLY element count must be a non-negative integer");
        return false;
      }
      e.count = uint64_t(n);
      elements.push_back(std::move(e));
    } else if (key == "property") {
      if (elements.empty()) {
        error = line_error(path, lines.number, "PLY property before any element");
        return false;
      }
      PlyProperty p;
      std::string_view t = next_token(line);
      p.count_type = PlyType::invalid;
      if (t == "list") {
        p.count_type = ply_type(next_token(line));
        t = next_token(line);
        if (p.count_type == PlyType::invalid || p.count_type == PlyType::f32 ||
            p.count_type == PlyType::f64) {
          error = line_error(path, lines.number, "PLY list count type must be an integer type");
          return false;
        }
      }
      p.type = ply_type(t);
      if (p.type == PlyType::invalid) {
        error =
            line_error(path, lines.number, "unknown PLY property type '" + std::string(t) + "'");
        return false;
      }
      p.name = next_token(line);
      elements.back().properties.push_back(std::move(p));
    } else if (key == "end_header") {
      ended = true;
    } else if (key != "comment" && key != "obj_info" && !key.empty()) {
      error =
          line_error(path, lines.number, "unexpected PLY header line '" + std::string(key) + "'");
      return false;
    }
  }
  if (!ended || format < 0) {
    error = path + ": PLY header has no " + std::string(ended ? "format line" : "end_header");
    return false;
  }
  PlyBody body{lines.rest, 0, format == 0, format == 2};
  bool have_vertices = false, have_faces = false;
  for (const PlyElement& e : elements) {
    if (e.properties.empty()) continue;  // holds no bytes; its count must not drive a loop
    bool is_vertex = e.name == "vertex", is_face = e.name == "face";
    int xyz[3] = {-1, -1, -1}, list = -1;
    size_t min_bytes = 0;  // bytes an instance takes at least (binary)
    for (size_t i = 0; i < e.properties.size(); ++i) {
      const PlyProperty& p = e.properties[i];
      bool scalar = p.count_type == PlyType::invalid;
      min_bytes += scalar ? ply_size(p.type) : ply_size(p.count_type);
      if (is_vertex && scalar && (p.name == "x" || p.name == "y" || p.name == "z"))
        xyz[p.name[0] - 'x'] = int(i);
      if (is_face && !scalar && (p.name == "vertex_indices" || p.name == "vertex_index"))
        list = int(i);
    }
    if (is_vertex && (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0)) {
      error = path + ": PLY vertex element lacks x, y or z";
      return false;
    }
    if (is_face && list < 0) {
      error = path + ": PLY face element has no vertex_indices list";
      return false;
    }
    if (is_vertex && e.count >= kMaxVertices) {
      error = path + ": declares " + std::to_string(e.count) + " vertices, more than supported";
      return false;
    }
    // A count the remaining bytes cannot hold is refused before anything is allocated.
    if (min_bytes == 0) min_bytes = 1;
    if (!body.ascii && e.count > body.remaining() / min_bytes) {
      error = path + ": PLY element '" + e.name + "' declares " + std::to_string(e.count) +
              " entries, more than the file holds";
      return false;
    }
    size_t reserve = plausible(e.count, body.remaining(), body.ascii ? 2 : min_bytes);
    if (is_vertex) out.positions.reserve(out.positions.size() + reserve * 3), have_vertices = true;
    if (is_face)
      out.face_offsets.reserve(reserve + 1), out.corners.reserve(reserve * 3), have_faces = true;
    for (uint64_t n = 0; n < e.count; ++n) {
      float p[3] = {0, 0, 0};
      for (size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& prop = e.properties[i];
        double v;
        if (prop.count_type == PlyType::invalid) {
          if (!body.read(prop.type, v)) {
            error = path + ": PLY data ends or is malformed in " + e.name + " " + std::to_string(n);
            return false;
          }
          for (int k = 0; k < 3; ++k)
            if (int(i) == xyz[k]) p[k] = float(v);
          continue;
        }
        double count;
        if (!body.read(prop.count_type, count) || count < 0 ||
            (!body.ascii && count * double(ply_size(prop.type)) > double(body.remaining()))) {
          error = path + ": PLY data ends or is malformed in " + e.name + " " + std::to_string(n);
          return false;
        }
        for (uint64_t c = 0; c < uint64_t(count); ++c) {
          if (!body.read(prop.type, v)) {
            error = path + ": PLY data ends or is malformed in " + e.name + " " + std::to_string(n);
            return false;
          }
          if (int(i) != list) continue;
          if (v < 0 || v >= double(kMaxVertices) || v != std::floor(v)) {
            error = range_error(path, n, 0, int64_t(v), out.vertex_count());
            return false;
          }
          out.corners.push_back(uint32_t(v));
        }
      }
      if (is_vertex && !push_vertex(out, p, path, 0, error)) return false;
      if (is_face) end_face(out);
    }
  }
  if (!have_vertices || !have_faces) {
    error =
        path + ": PLY file has no " + std::string(have_vertices ? "face" : "vertex") + " element";
    return false;
  }
  // Faces may precede vertices in a PLY file, so indices are checked at the end.
  for (uint32_t f = 0; f < out.face_count(); ++f)
    for (uint32_t c = out.face_offsets[f]; c < out.face_offsets[f + 1]; ++c)
      if (out.corners[c] >= out.vertex_count()) {
        error = range_error(path, f, 0, out.corners[c], out.vertex_count());
        return false;
      }
  return true;
}

// ---- STL ----

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

bool read_stl(const std::string& path, const std::string& data, PolygonSoup& out,
              std::string& error) {
  std::unordered_map<uint64_t, std::vector<uint32_t>> buckets;
  uint32_t declared = data.size() >= 84 ? load_le32(data.data() + 80) : 0;
  bool size_matches =
      data.size() >= 84 && (data.size() - 84) / 50 == declared && (data.size() - 84) % 50 == 0;
  std::string_view head(data.data(), std::min<size_t>(data.size(), 512));
  std::string_view first = next_token(head);
  // Binary files may start with "solid" too; an exact size match decides.
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
  if (data.size() < 84) {
    error = path + ": not an STL file (too short for binary, no 'solid' header)";
    return false;
  }
  if ((data.size() - 84) / 50 < declared) {
    error = path + ": binary STL declares " + std::to_string(declared) +
            " triangles but holds only " + std::to_string((data.size() - 84) / 50);
    return false;
  }
  out.positions.reserve(size_t(declared) * 3);  // bounded by the file size, checked above
  out.corners.reserve(size_t(declared) * 3);
  out.face_offsets.reserve(size_t(declared) + 1);
  buckets.reserve(declared);
  for (uint32_t t = 0; t < declared; ++t) {
    const char* rec = data.data() + 84 + size_t(t) * 50 + 12;  // skip the stored normal
    for (int c = 0; c < 3; ++c) {
      float p[3];
      for (int k = 0; k < 3; ++k) p[k] = std::bit_cast<float>(load_le32(rec + c * 12 + k * 4));
      if (!add_stl_corner(out, buckets, p, t, path, error)) return false;
    }
    end_face(out);
  }
  return true;
}

// ---- writers ----

struct Writer {
  FILE* f;
  bool ok = true;
  void put(const void* p, size_t n) { ok = ok && std::fwrite(p, 1, n, f) == n; }
  void printed(int r) { ok = ok && r > 0; }
  void u32le(uint32_t v) {
    unsigned char b[4] = {uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16), uint8_t(v >> 24)};
    put(b, 4);
  }
  void f32le(float v) { u32le(std::bit_cast<uint32_t>(v)); }
};

void write_body(Writer& w, const std::string& ext, const IndexedMesh& m) {
  const uint32_t nv = m.vertex_count(), nf = m.face_count();
  const float* p = m.positions.data();
  const uint32_t* ix = m.indices.data();
  // %.9g prints every float exactly enough to read back bit-identical.
  if (ext == ".obj") {
    for (uint32_t v = 0; v < nv; ++v)
      w.printed(std::fprintf(w.f, "v %.9g %.9g %.9g\n", p[v * 3], p[v * 3 + 1], p[v * 3 + 2]));
    for (uint32_t f = 0; f < nf; ++f)
      w.printed(
          std::fprintf(w.f, "f %u %u %u\n", ix[f * 3] + 1, ix[f * 3 + 1] + 1, ix[f * 3 + 2] + 1));
  } else if (ext == ".off") {
    w.printed(std::fprintf(w.f, "OFF\n%u %u 0\n", nv, nf));
    for (uint32_t v = 0; v < nv; ++v)
      w.printed(std::fprintf(w.f, "%.9g %.9g %.9g\n", p[v * 3], p[v * 3 + 1], p[v * 3 + 2]));
    for (uint32_t f = 0; f < nf; ++f)
      w.printed(std::fprintf(w.f, "3 %u %u %u\n", ix[f * 3], ix[f * 3 + 1], ix[f * 3 + 2]));
  } else if (ext == ".ply") {
    w.printed(
        std::fprintf(w.f,
                     "ply\nformat binary_little_endian 1.0\ncomment written by pmz\n"
                     "element vertex %u\nproperty float x\nproperty float y\nproperty float z\n"
                     "element face %u\nproperty list uchar uint vertex_indices\nend_header\n",
                     nv, nf));
    for (uint32_t i = 0; i < nv * 3; ++i) w.f32le(p[i]);
    for (uint32_t f = 0; f < nf; ++f) {
      const uint8_t three = 3;
      w.put(&three, 1);
      for (int k = 0; k < 3; ++k) w.u32le(ix[f * 3 + k]);
    }
  } else {  // .stl, binary
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
}

}  // namespace

bool read_polygon_soup(const std::string& path, PolygonSoup& out, std::string& error) {
  out = PolygonSoup();
  out.face_offsets.push_back(0);
  std::string ext = lower_extension(path);
  if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl") {
    error = path + ": unknown mesh format '" + ext + "' (expected .obj, .off, .ply or .stl)";
    return false;
  }
  std::string data;
  if (!read_file(path, data, error)) return false;
  bool ok = ext == ".obj"   ? read_obj(path, data, out, error)
            : ext == ".off" ? read_off(path, data, out, error)
            : ext == ".ply" ? read_ply(path, data, out, error)
                            : read_stl(path, data, out, error);
  if (ok && out.face_count() == 0) {
    error = path + ": mesh has no faces";
    ok = false;
  }
  if (!ok) out = PolygonSoup();
  return ok;
}

bool read_mesh(const std::string& path, IndexedMesh& out, MeshRepairStats& stats,
               std::string& error) {
  PolygonSoup soup;
  stats = MeshRepairStats();
  if (!read_polygon_soup(path, soup, error)) return false;
  repair_mesh(soup, out, stats);
  if (out.face_count() == 0) {
    error = path + ": no usable faces (all " + std::to_string(stats.degenerate_faces_dropped) +
            " faces are degenerate: fewer than three distinct vertices)";
    return false;
  }
  return true;
}

bool read_mesh(const std::string& path, IndexedMesh& out, std::string& error) {
  MeshRepairStats stats;
  if (!read_mesh(path, out, stats, error)) return false;
  std::string summary = stats.summary();
  if (!summary.empty()) std::fprintf(stderr, "pmz: %s: %s\n", path.c_str(), summary.c_str());
  return true;
}

bool write_mesh(const std::string& path, const IndexedMesh& mesh, std::string& error) {
  std::string ext = lower_extension(path);
  if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl") {
    error = path + ": unknown mesh format '" + ext + "' (expected .obj, .off, .ply or .stl)";
    return false;
  }
  for (uint32_t i : mesh.indices)
    if (i >= mesh.vertex_count()) {
      error = path + ": mesh to write references vertex " + std::to_string(i) + " of " +
              std::to_string(mesh.vertex_count());
      return false;
    }
  // Hidden temporary beside the target (same filesystem, so the rename is atomic).
  std::filesystem::path target(path);
  std::string tmp = (target.parent_path() /
                     ("." + target.filename().string() + ".tmp" + std::to_string(::getpid())))
                        .string();
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) {
    error = path + ": cannot create file: " + std::strerror(errno);
    return false;
  }
  Writer w{f};
  write_body(w, ext, mesh);
  int write_errno = w.ok ? 0 : errno;
  if (std::fflush(f) != 0 && !write_errno) write_errno = errno ? errno : EIO;
  if (std::fclose(f) != 0 && !write_errno) write_errno = errno ? errno : EIO;
  if (!w.ok && !write_errno) write_errno = EIO;
  if (write_errno) {
    std::remove(tmp.c_str());
    error = path + ": write failed: " + std::strerror(write_errno);
    return false;
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    error = path + ": " + ec.message();
    return false;
  }
  return true;
}

}  // namespace pmz
