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
#include <functional>
#include <string_view>
#include <unordered_map>

#include "mesh_gltf.hpp"
#include "pmz/mesh.hpp"
#include "pmz/output_file.hpp"

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

}  // namespace

// Merges vertices with bitwise-equal positions (-0 == +0) into the first of them: formats that
// store attributes per vertex (PLY, glTF) split vertices at seams, pmz keeps them as wedges.
// Attribute indices keep pointing at the file's entries; only the corners' vertex ids change.
void weld_vertices(PolygonSoup& soup) {
  std::unordered_map<uint64_t, std::vector<uint32_t>> buckets;
  std::vector<uint32_t> map(soup.vertex_count());
  std::vector<float> kept;
  kept.reserve(soup.positions.size());
  for (uint32_t v = 0; v < soup.vertex_count(); ++v) {
    float p[3];
    uint64_t h = 1469598103934665603ull;
    for (int k = 0; k < 3; ++k) {
      p[k] = soup.positions[size_t(v) * 3 + k];
      if (p[k] == 0) p[k] = 0;  // -0 -> +0
      h = (h ^ std::bit_cast<uint32_t>(p[k])) * 1099511628211ull;
    }
    std::vector<uint32_t>& bucket = buckets[h];
    map[v] = kNoAttribute;
    for (uint32_t w : bucket)
      if (std::memcmp(&kept[size_t(w) * 3], p, sizeof p) == 0) map[v] = w;
    if (map[v] == kNoAttribute) {
      map[v] = uint32_t(kept.size() / 3);
      bucket.push_back(map[v]);
      kept.insert(kept.end(), p, p + 3);
    }
  }
  soup.welded_vertices += soup.vertex_count() - kept.size() / 3;
  soup.positions = std::move(kept);
  for (uint32_t& c : soup.corners) c = map[c];
}

namespace {

// ---- OBJ ----

Material named_material(std::string name) {
  Material m;
  m.name = std::move(name);
  return m;
}

// Texture file of an MTL map statement: what follows the options (-bm 1, -s 1 1 1, -clamp on,
// each a dash word and its numeric or on/off arguments); file names may hold spaces.
std::string_view map_file(std::string_view rest) {
  for (;;) {
    std::string_view probe = rest, t = next_token(probe);
    float ignored;
    if (t.empty() || !(t[0] == '-' || parse_float(t, ignored) || t == "on" || t == "off")) break;
    rest = probe;
  }
  size_t begin = rest.find_first_not_of(" \t"), end = rest.find_last_not_of(" \t\r");
  return begin == std::string_view::npos ? std::string_view() : rest.substr(begin, end - begin + 1);
}

// Fills the named materials from an MTL file beside the OBJ. A missing or unreadable MTL keeps
// the names only: the geometry does not depend on it (and OBJ files often ship without theirs).
void read_mtl(const std::string& obj_path, const std::string& library,
              std::vector<Material>& materials) {
  std::string data, ignored;
  std::filesystem::path mtl = std::filesystem::path(obj_path).parent_path() / library;
  if (!read_file(mtl.string(), data, ignored)) return;
  Lines lines{data, 0, '#'};
  std::string_view line;
  Material* m = nullptr;
  while (lines.next(line)) {
    std::string_view key = next_token(line);
    if (key == "newmtl") {
      std::string_view name = next_token(line);
      m = nullptr;
      for (Material& x : materials)
        if (x.name == name) m = &x;
    } else if (!m) {
      continue;
    } else if (key == "Kd") {
      for (int k = 0; k < 3; ++k) {
        float v;
        if (parse_float(next_token(line), v) && std::isfinite(v)) m->base_color[k] = v;
      }
    } else if (key == "d") {
      float v;
      if (parse_float(next_token(line), v) && std::isfinite(v)) m->base_color[3] = v;
    } else if (key == "map_Kd") {
      m->base_color_texture = map_file(line);
    } else if (key == "norm" || key == "map_Bump" || key == "map_bump" || key == "bump") {
      m->normal_texture = map_file(line);
    }
  }
}

// Parses `count` floats of an OBJ record; false when one is missing or malformed.
bool parse_floats(std::string_view& line, float* v, int count) {
  for (int k = 0; k < count; ++k)
    if (!parse_float(next_token(line), v[k])) return false;
  return true;
}

bool all_finite(const float* v, int count) {
  for (int k = 0; k < count; ++k)
    if (!std::isfinite(v[k])) return false;
  return true;
}

bool read_obj(const std::string& path, std::string_view data, PolygonSoup& out,
              std::string& error) {
  Lines lines{data, 0, '#'};
  std::string_view line;
  // Positive indices are checked once all vertices are known; remember where faces came from.
  std::vector<uint64_t> face_lines;
  std::vector<float> texcoords, normals, colors;  // pools; colours per vertex (v x y z r g b)
  std::vector<uint32_t> corner_texcoords, corner_normals, face_materials;
  bool any_texcoord = false, any_normal = false, any_material = false;
  uint32_t material = kNoAttribute;
  SoupAttributes& attrs = out.attributes;
  auto fail = [&](const std::string& what) {
    error = line_error(path, lines.number, what);
    return false;
  };
  while (lines.next(line)) {
    std::string_view key = next_token(line);
    if (key == "v") {
      float p[3];
      if (!parse_floats(line, p, 3)) return fail("vertex needs three numeric coordinates");
      if (!push_vertex(out, p, path, lines.number, error)) return false;
      float c[3];
      std::string_view probe = line;
      if (!next_token(probe).empty()) {  // vertex colour extension: v x y z r g b
        if (!parse_floats(line, c, 3)) return fail("vertex colour needs three numbers");
        if (!all_finite(c, 3))
          return fail("vertex " + std::to_string(out.vertex_count() - 1) +
                      " has a NaN or infinite colour");
        colors.resize(size_t(out.vertex_count() - 1) * 3, 0.0f);
        colors.insert(colors.end(), c, c + 3);
      }
    } else if (key == "vt") {
      float t[2] = {0, 0};
      if (!parse_float(next_token(line), t[0])) return fail("texture coordinate needs a numeric u");
      std::string_view probe = line;
      if (!next_token(probe).empty() && !parse_float(next_token(line), t[1]))
        return fail("texture coordinate has a malformed v");
      if (!all_finite(t, 2))
        return fail("texture coordinate " + std::to_string(texcoords.size() / 2) +
                    " is NaN or infinite");
      texcoords.insert(texcoords.end(), t, t + 2);
    } else if (key == "vn") {
      float n[3];
      if (!parse_floats(line, n, 3)) return fail("normal needs three numeric coordinates");
      if (!all_finite(n, 3))
        return fail("normal " + std::to_string(normals.size() / 3) + " is NaN or infinite");
      normals.insert(normals.end(), n, n + 3);
    } else if (key == "usemtl") {
      std::string_view name = next_token(line);
      material = uint32_t(attrs.materials.size());
      for (uint32_t m = 0; m < attrs.materials.size(); ++m)
        if (attrs.materials[m].name == name) material = m;
      if (material == attrs.materials.size())
        attrs.materials.push_back(named_material(std::string(name)));
    } else if (key == "mtllib") {
      if (attrs.material_library.empty()) attrs.material_library = next_token(line);
    } else if (key == "f" || key == "fo") {
      uint64_t face = face_lines.size();
      for (std::string_view t = next_token(line); !t.empty(); t = next_token(line)) {
        // v, v/vt, v//vn or v/vt/vn; negative indices count back from the last entry so far.
        int64_t ids[3] = {0, 0, 0};
        const uint64_t pools[3] = {out.vertex_count(), texcoords.size() / 2, normals.size() / 3};
        std::string_view rest = t;
        for (int k = 0; k < 3 && !rest.empty(); ++k) {
          size_t slash = rest.find('/');
          std::string_view part = rest.substr(0, slash);
          rest = slash == std::string_view::npos ? std::string_view() : rest.substr(slash + 1);
          if (k > 0 && part.empty()) continue;  // v//vn: no texture coordinate
          if (!parse_int(part, ids[k]) || ids[k] == 0)
            return fail("face " + std::to_string(face) + " has a malformed index '" +
                        std::string(t) + "'");
          if (ids[k] < 0) ids[k] += int64_t(pools[k]) + 1;
          if (ids[k] <= 0 || ids[k] > int64_t(kMaxVertices)) {
            if (k == 0) {
              error = range_error(path, face, lines.number, ids[0] - 1, out.vertex_count());
              return false;
            }
            return fail("face " + std::to_string(face) + " references a " +
                        (k == 1 ? "texture coordinate" : "normal") + " before the first");
          }
        }
        out.corners.push_back(uint32_t(ids[0] - 1));
        corner_texcoords.push_back(ids[1] ? uint32_t(ids[1] - 1) : kNoAttribute);
        corner_normals.push_back(ids[2] ? uint32_t(ids[2] - 1) : kNoAttribute);
        any_texcoord |= ids[1] != 0, any_normal |= ids[2] != 0;
      }
      end_face(out);
      face_lines.push_back(lines.number);
      face_materials.push_back(material);
      any_material |= material != kNoAttribute;
    }
    // Other records (l, p, g, o, s, ...) do not describe triangles or their attributes.
  }
  for (uint32_t f = 0; f < out.face_count(); ++f)
    for (uint32_t c = out.face_offsets[f]; c < out.face_offsets[f + 1]; ++c) {
      if (out.corners[c] >= out.vertex_count()) {
        error = range_error(path, f, face_lines[f], out.corners[c], out.vertex_count());
        return false;
      }
      if ((corner_texcoords[c] != kNoAttribute && corner_texcoords[c] >= texcoords.size() / 2) ||
          (corner_normals[c] != kNoAttribute && corner_normals[c] >= normals.size() / 3)) {
        error = line_error(
            path, face_lines[f],
            "face " + std::to_string(f) + " references a " +
                (corner_normals[c] == kNoAttribute || corner_normals[c] < normals.size() / 3
                     ? "texture coordinate"
                     : "normal") +
                " the file does not have");
        return false;
      }
    }
  if (any_texcoord) {
    attrs.texcoords.push_back(std::move(texcoords));
    attrs.corner_texcoords.push_back(std::move(corner_texcoords));
  }
  if (any_normal) {
    attrs.normals = std::move(normals);
    attrs.corner_normals = std::move(corner_normals);
  }
  if (!colors.empty()) {
    colors.resize(size_t(out.vertex_count()) * 3, 0.0f);
    attrs.colors = std::move(colors);
    attrs.color_components = 3;
    attrs.corner_colors = out.corners;
  }
  if (any_material) {
    // Faces before the first usemtl get a material of their own.
    uint32_t fallback = kNoAttribute;
    for (uint32_t& m : face_materials)
      if (m == kNoAttribute) {
        if (fallback == kNoAttribute) {
          fallback = uint32_t(attrs.materials.size());
          attrs.materials.push_back(named_material("default"));
        }
        m = fallback;
      }
    attrs.face_materials = std::move(face_materials);
  }
  if (!attrs.material_library.empty()) read_mtl(path, attrs.material_library, attrs.materials);
  return true;
}

// ---- OFF ----

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
bool read_off_binary_layout(const std::string& path, std::string_view data, uint32_t extra,
                            bool big_endian, bool face_colors, PolygonSoup& out,
                            std::string& error) {
  out.positions.clear(), out.corners.clear(), out.face_offsets.assign(1, 0);
  size_t pos = 0;
  auto u32 = [&](uint32_t& v) {
    if (data.size() - pos < 4) return false;
    v = load_u32(data.data() + pos, big_endian);
    pos += 4;
    return true;
  };
  uint32_t nv, nf, ne;
  if (!u32(nv) || !u32(nf) || !u32(ne)) {
    error = path + ": binary OFF ends inside its counts";
    return false;
  }
  const uint64_t vertex_bytes = uint64_t(3 + extra) * 4;
  if (nv >= kMaxVertices || uint64_t(nv) * vertex_bytes > data.size() - pos ||
      uint64_t(nf) * 8 > data.size() - pos - uint64_t(nv) * vertex_bytes) {
    error = path + ": binary OFF declares " + std::to_string(nv) + " vertices and " +
            std::to_string(nf) + " faces, more than the file holds";
    return false;
  }
  out.positions.reserve(size_t(nv) * 3);
  for (uint32_t v = 0; v < nv; ++v) {
    float p[3];
    for (int k = 0; k < 3; ++k)
      p[k] = std::bit_cast<float>(load_u32(data.data() + pos + size_t(k) * 4, big_endian));
    pos += size_t(vertex_bytes);
    if (!push_vertex(out, p, path, 0, error)) return false;
  }
  for (uint32_t f = 0; f < nf; ++f) {
    uint32_t n, ix = 0, colors = 0;
    if (!u32(n) || n > (data.size() - pos) / 4) {
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
    if (face_colors && (!u32(colors) || colors > 4 || colors * 4 > data.size() - pos)) {
      error = path + ": binary OFF ends or is malformed in face " + std::to_string(f);
      return false;
    }
    pos += colors * 4;
    end_face(out);
  }
  if (pos != data.size()) {
    error = path + ": binary OFF has " + std::to_string(data.size() - pos) +
            " bytes after its last face";
    return false;
  }
  return true;
}

bool read_off_binary(const std::string& path, std::string_view data, uint32_t extra,
                     PolygonSoup& out, std::string& error) {
  // The reported failure: the first layout whose counts fit the file (else the first one's).
  std::string reported;
  bool counts_fit = false;
  for (int layout = 0; layout < 4; ++layout) {
    bool big_endian = layout == 1 || layout == 2, face_colors = layout == 1 || layout == 3;
    if (read_off_binary_layout(path, data, extra, big_endian, face_colors, out, error)) return true;
    bool fit = error.find("more than the file holds") == std::string::npos &&
               error.find("inside its counts") == std::string::npos;
    if (reported.empty() || (fit && !counts_fit)) reported = error, counts_fit = fit;
  }
  error = reported;
  return false;
}

bool read_off(const std::string& path, std::string_view data, PolygonSoup& out,
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
    uint32_t extra = 0;
    std::string_view flags = key.substr(0, key.size() - 3);
    if (flags.starts_with("ST")) extra += 2, flags.remove_prefix(2);
    if (flags.starts_with("C")) extra += 4, flags.remove_prefix(1);
    if (flags.starts_with("N")) extra += 3;
    return read_off_binary(path, lines.rest, extra, out, error);
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

// Scale of an integer colour channel (uchar 0..255, ushort 0..65535); floats are 0..1 already.
double color_scale(PlyType t) {
  return t == PlyType::f32 || t == PlyType::f64 ? 1.0 : t == PlyType::u16 ? 1.0 / 65535 : 1.0 / 255;
}

bool read_ply(const std::string& path, std::string_view data, PolygonSoup& out,
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
    } else if (key == "comment" && next_token(line) == "TextureFile") {
      // MeshLab's texture reference; the face property texnumber picks one.
      std::string_view file = line.substr(std::min(line.find_first_not_of(" \t"), line.size()));
      while (!file.empty() && is_space(file.back())) file.remove_suffix(1);
      Material m = named_material("texture" + std::to_string(out.attributes.materials.size()));
      m.base_color_texture = file;
      out.attributes.materials.push_back(std::move(m));
    }
    // Any other line ("comment", "obj_info", or free text such as Blender 2.4x's "Created by
    // Blender3D ...") is skipped: only format, element and property lines shape the body, and
    // Blender, MeshLab and assimp read such files.
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
    // Which property feeds which value: xyz, normal, colour (rgba), uv; per face the corner list,
    // per-corner uvs (MeshLab's texcoord list) and the texture number.
    int xyz[3] = {-1, -1, -1}, normal[3] = {-1, -1, -1}, rgba[4] = {-1, -1, -1, -1},
        uv[2] = {-1, -1}, list = -1, face_uv = -1, texnumber = -1;
    size_t min_bytes = 0;  // bytes an instance takes at least (binary)
    for (size_t i = 0; i < e.properties.size(); ++i) {
      const PlyProperty& p = e.properties[i];
      bool scalar = p.count_type == PlyType::invalid;
      min_bytes += scalar ? ply_size(p.type) : ply_size(p.count_type);
      const std::string& n = p.name;
      if (is_vertex && scalar) {
        if (n == "x" || n == "y" || n == "z") xyz[n[0] - 'x'] = int(i);
        if (n == "nx" || n == "ny" || n == "nz") normal[n[1] - 'x'] = int(i);
        static const char* const color_names[2][4] = {
            {"red", "green", "blue", "alpha"},
            {"diffuse_red", "diffuse_green", "diffuse_blue", "diffuse_alpha"}};
        static const char* const uv_names[4][2] = {
            {"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}};
        for (int k = 0; k < 4; ++k)
          if (n == color_names[0][k] || n == color_names[1][k]) rgba[k] = int(i);
        for (int k = 0; k < 2; ++k)
          for (const auto& names : uv_names)
            if (n == names[k]) uv[k] = int(i);
      }
      if (is_face && !scalar && (n == "vertex_indices" || n == "vertex_index")) list = int(i);
      if (is_face && !scalar && n == "texcoord") face_uv = int(i);
      if (is_face && scalar && n == "texnumber") texnumber = int(i);
    }
    SoupAttributes& attrs = out.attributes;
    const bool has_normals = is_vertex && normal[0] >= 0 && normal[1] >= 0 && normal[2] >= 0;
    const bool has_uv = is_vertex && uv[0] >= 0 && uv[1] >= 0;
    const uint32_t color_components =
        is_vertex && rgba[0] >= 0 && rgba[1] >= 0 && rgba[2] >= 0 ? (rgba[3] >= 0 ? 4 : 3) : 0;
    if (is_vertex) {
      // Bounded by the bytes left, as the positions below (a huge count threw length_error).
      if (has_normals) attrs.normals.reserve(plausible(e.count, body.remaining(), 2) * 3);
      if (has_uv) attrs.texcoords.assign(1, {});
      attrs.color_components = color_components;
    }
    if (is_face && face_uv >= 0) {
      attrs.texcoords.assign(1, {});
      attrs.corner_texcoords.assign(1, {});
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
      float p[3] = {0, 0, 0}, nrm[3] = {0, 0, 0}, color[4] = {0, 0, 0, 1}, t[2] = {0, 0};
      uint32_t face_texture = kNoAttribute;
      const size_t uv_before = face_uv >= 0 ? attrs.texcoords[0].size() : 0;
      for (size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& prop = e.properties[i];
        double v;
        if (prop.count_type == PlyType::invalid) {
          if (!body.read(prop.type, v)) {
            error = path + ": PLY data ends or is malformed in " + e.name + " " + std::to_string(n);
            return false;
          }
          for (int k = 0; k < 3; ++k) {
            if (int(i) == xyz[k]) p[k] = float(v);
            if (int(i) == normal[k]) nrm[k] = float(v);
          }
          for (int k = 0; k < 4; ++k)
            if (int(i) == rgba[k]) color[k] = float(v * color_scale(prop.type));
          for (int k = 0; k < 2; ++k)
            if (int(i) == uv[k]) t[k] = float(v);
          if (int(i) == texnumber) {
            if (!(v >= 0 && v < double(attrs.materials.size()))) {
              error = path + ": PLY face " + std::to_string(n) + " has texture number " +
                      std::to_string(v) + " but the header names " +
                      std::to_string(attrs.materials.size()) + " texture files";
              return false;
            }
            face_texture = uint32_t(v);
          }
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
          if (int(i) == face_uv) {
            if (!std::isfinite(v)) {
              error = path + ": PLY face " + std::to_string(n) +
                      " has a NaN or infinite texture coordinate";
              return false;
            }
            attrs.texcoords[0].push_back(float(v));
          }
          if (int(i) != list) continue;
          if (v < 0 || v >= double(kMaxVertices) || v != std::floor(v)) {
            // A float index may be fractional, NaN or beyond int64_t: only a whole number in
            // range converts (anything else is undefined behaviour) and is named as a vertex.
            if (v == std::floor(v) && std::fabs(v) < 0x1p62) {
              error = range_error(path, n, 0, int64_t(v), out.vertex_count());
            } else {
              char text[32];
              std::snprintf(text, sizeof text, "%g", v);
              error = path + ": PLY face " + std::to_string(n) + " has vertex index " + text +
                      ", not a whole vertex number";
            }
            return false;
          }
          out.corners.push_back(uint32_t(v));
        }
      }
      if (is_vertex) {
        if (!push_vertex(out, p, path, 0, error)) return false;
        if (!all_finite(nrm, 3) || !all_finite(color, 4) || !all_finite(t, 2)) {
          error = path + ": vertex " + std::to_string(out.vertex_count() - 1) +
                  " has a NaN or infinite attribute";
          return false;
        }
        if (has_normals) attrs.normals.insert(attrs.normals.end(), nrm, nrm + 3);
        if (has_uv) attrs.texcoords[0].insert(attrs.texcoords[0].end(), t, t + 2);
        attrs.colors.insert(attrs.colors.end(), color, color + color_components);
      }
      if (is_face) {
        end_face(out);
        if (face_uv >= 0) {
          // One u v pair per corner, in corner order; a face with another count has none.
          std::vector<float>& pool = attrs.texcoords[0];
          std::vector<uint32_t>& ids = attrs.corner_texcoords[0];
          size_t corners = out.corners.size() - ids.size();
          bool matches = pool.size() - uv_before == corners * 2;
          if (!matches) pool.resize(uv_before);
          for (size_t c = 0; c < corners; ++c)
            ids.push_back(matches ? uint32_t(uv_before / 2 + c) : kNoAttribute);
        }
        if (texnumber >= 0) attrs.face_materials.push_back(face_texture);
      }
    }
  }
  SoupAttributes& attrs = out.attributes;
  const bool per_vertex = !attrs.normals.empty() || attrs.color_components ||
                          (!attrs.texcoords.empty() && attrs.corner_texcoords.empty());
  if (!attrs.normals.empty()) attrs.corner_normals = out.corners;
  if (attrs.color_components) attrs.corner_colors = out.corners;
  if (!attrs.texcoords.empty() && attrs.corner_texcoords.empty())
    attrs.corner_texcoords.assign(1, out.corners);
  if (attrs.face_materials.size() != out.face_count()) attrs.face_materials.clear();
  if (attrs.face_materials.empty()) attrs.materials.clear();
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
  if (per_vertex) weld_vertices(out);
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

bool read_stl(const std::string& path, std::string_view data, PolygonSoup& out,
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

// Buffered output to a MeshSink: a 1 MiB buffer handed over when full (no copy of the whole file
// in memory), numbers printed with std::to_chars (the shortest text that reads back to the same
// float: exact, and much faster than printf), large binary blocks passed through directly.
class Writer {
 public:
  explicit Writer(const MeshSink& sink) : sink_(sink), buf_(size_t(1) << 20) {}
  // Room for n <= kMaxRoom bytes at the end of the buffer; commit() says how many were used.
  static constexpr size_t kMaxRoom = 256;
  char* room(size_t n) {
    if (buf_.size() - used_ < n) flush();
    return buf_.data() + used_;
  }
  size_t room_left() const { return buf_.size() - used_; }
  void commit(char* end) { used_ = size_t(end - buf_.data()); }
  void put(const void* p, size_t n) {
    if (n > buf_.size() / 2) {
      flush();
      ok_ = ok_ && sink_(p, n);
      return;
    }
    if (buf_.size() - used_ < n) flush();
    std::memcpy(buf_.data() + used_, p, n);
    used_ += n;
  }
  Writer& str(std::string_view s) {
    put(s.data(), s.size());
    return *this;
  }
  template <typename T>
  Writer& num(T x) {
    commit(number(room(32), x));
    return *this;
  }
  template <typename T>
  static char* number(char* o, T x) {
    return std::to_chars(o, o + 32, x).ptr;
  }
  void u32le(uint32_t v) {
    unsigned char b[4] = {uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16), uint8_t(v >> 24)};
    put(b, 4);
  }
  void f32le(float v) { u32le(std::bit_cast<uint32_t>(v)); }
  // Hands over what is buffered; false if the sink refused anything.
  bool finish() {
    flush();
    return ok_;
  }

 private:
  void flush() {
    if (used_) ok_ = ok_ && sink_(buf_.data(), used_);
    used_ = 0;
  }
  const MeshSink& sink_;
  std::vector<char> buf_;
  size_t used_ = 0;
  bool ok_ = true;
};

void write_mtl(Writer& w, const std::vector<Material>& materials) {
  w.str("# written by pmz\n");
  for (const Material& m : materials) {
    w.str("newmtl ").str(m.name.empty() ? "unnamed" : m.name).str("\nKd ");
    w.num(m.base_color[0]).str(" ").num(m.base_color[1]).str(" ").num(m.base_color[2]).str("\n");
    if (m.base_color[3] != 1) w.str("d ").num(m.base_color[3]).str("\n");
    if (!m.base_color_texture.empty()) w.str("map_Kd ").str(m.base_color_texture).str("\n");
    if (!m.normal_texture.empty()) w.str("norm ").str(m.normal_texture).str("\n");
  }
}

// One text line of up to six numbers (plus `add` each, for OBJ's 1-based indices) after a
// prefix ("v ", "3 ", "f "): the hot loops of the OBJ and OFF writers, with room for the longest
// line checked once.
template <typename T>
void put_line(Writer& w, std::string_view prefix, const T* x, int n, T add = 0) {
  char* o = w.room(Writer::kMaxRoom);
  std::memcpy(o, prefix.data(), prefix.size());
  o += prefix.size();
  for (int a = 0; a < n; ++a) {
    o = Writer::number(o, add ? T(x[a] + add) : x[a]);  // (-0.0f + 0 would lose its sign)
    *o++ = a == n - 1 ? '\n' : ' ';
  }
  w.commit(o);
}

// OBJ: positions per vertex (with the colour of the vertex's first wedge: OBJ colours are per
// vertex), texture coordinates (set 0) and normals per wedge, usemtl where the material changes.
void write_obj(Writer& w, const IndexedMesh& m, const std::string& mtl) {
  const MeshAttributes& a = m.attributes;
  const uint32_t nv = m.vertex_count(), nf = m.face_count();
  const float* p = m.positions.data();
  const uint32_t* ix = m.indices.data();
  if (!mtl.empty()) w.str("mtllib ").str(mtl).str("\n");
  std::vector<uint32_t> vertex_wedge;
  if (a.color_components) {
    vertex_wedge.assign(nv, kNoAttribute);
    for (uint32_t wd = a.wedge_count(); wd-- > 0;) vertex_wedge[a.wedge_vertices[wd]] = wd;
  }
  for (uint32_t v = 0; v < nv; ++v) {
    if (!a.color_components) {
      put_line(w, "v ", p + size_t(v) * 3, 3);
      continue;
    }
    const float* c = vertex_wedge[v] == kNoAttribute
                         ? nullptr
                         : &a.colors[size_t(vertex_wedge[v]) * a.color_components];
    const float xyzrgb[6] = {p[v * 3],        p[v * 3 + 1],    p[v * 3 + 2],
                             c ? c[0] : 0.0f, c ? c[1] : 0.0f, c ? c[2] : 0.0f};
    put_line(w, "v ", xyzrgb, 6);
  }
  const bool uv = !a.texcoords.empty(), normals = !a.normals.empty();
  for (uint32_t wd = 0; uv && wd < a.wedge_count(); ++wd)
    put_line(w, "vt ", &a.texcoords[0][size_t(wd) * 2], 2);
  for (uint32_t wd = 0; normals && wd < a.wedge_count(); ++wd)
    put_line(w, "vn ", &a.normals[size_t(wd) * 3], 3);
  uint32_t material = kNoAttribute;
  const bool wedges = uv || normals;
  for (uint32_t f = 0; f < nf; ++f) {
    if (!a.face_materials.empty() && a.face_materials[f] != material) {
      material = a.face_materials[f];
      const std::string& name = a.materials[material].name;
      w.str("usemtl ").str(name.empty() ? "unnamed" : name).str("\n");
    }
    if (!wedges) {
      put_line(w, "f ", ix + size_t(f) * 3, 3, 1u);
      continue;
    }
    char* o = w.room(Writer::kMaxRoom);
    *o++ = 'f';
    for (int k = 0; k < 3; ++k) {
      const uint32_t wd = a.corner_wedges[f * 3 + k] + 1;
      *o++ = ' ';
      o = Writer::number(o, ix[f * 3 + k] + 1);
      if (uv) *o++ = '/', o = Writer::number(o, wd);
      if (normals) {
        if (!uv) *o++ = '/';
        *o++ = '/', o = Writer::number(o, wd);
      }
    }
    *o++ = '\n';
    w.commit(o);
  }
}

// PLY with attributes: one vertex per wedge (normals, 8-bit colours, texture coordinates set 0),
// the texture files as MeshLab's TextureFile comments with a texnumber per face.
void write_ply_wedges(Writer& w, const IndexedMesh& m) {
  const MeshAttributes& a = m.attributes;
  const uint32_t nw = a.wedge_count(), nf = m.face_count();
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by pmz\n";
  for (const Material& mat : a.materials)
    header += "comment TextureFile " + mat.base_color_texture + "\n";
  header += "element vertex " + std::to_string(nw) +
            "\nproperty float x\nproperty float y\nproperty float z\n";
  if (!a.normals.empty()) header += "property float nx\nproperty float ny\nproperty float nz\n";
  if (a.color_components)
    header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (a.color_components == 4) header += "property uchar alpha\n";
  if (!a.texcoords.empty()) header += "property float texture_u\nproperty float texture_v\n";
  header += "element face " + std::to_string(nf) + "\nproperty list uchar uint vertex_indices\n";
  if (!a.face_materials.empty()) header += "property int texnumber\n";
  header += "end_header\n";
  w.put(header.data(), header.size());
  for (uint32_t wd = 0; wd < nw; ++wd) {
    for (int k = 0; k < 3; ++k) w.f32le(m.positions[size_t(a.wedge_vertices[wd]) * 3 + k]);
    if (!a.normals.empty())
      for (int k = 0; k < 3; ++k) w.f32le(a.normals[size_t(wd) * 3 + k]);
    for (uint32_t k = 0; k < a.color_components; ++k) {
      float c = a.colors[size_t(wd) * a.color_components + k];
      uint8_t b = uint8_t(std::lround(std::clamp(c, 0.0f, 1.0f) * 255));
      w.put(&b, 1);
    }
    if (!a.texcoords.empty())
      for (int k = 0; k < 2; ++k) w.f32le(a.texcoords[0][size_t(wd) * 2 + k]);
  }
  for (uint32_t f = 0; f < nf; ++f) {
    const uint8_t three = 3;
    w.put(&three, 1);
    for (int k = 0; k < 3; ++k) w.u32le(a.corner_wedges[f * 3 + k]);
    if (!a.face_materials.empty()) w.u32le(a.face_materials[f]);
  }
}

// PLY without attributes: the positions as one block (the float array is the file's layout on a
// little-endian host), the faces 13 bytes each, a buffer's worth at a time.
void write_ply(Writer& w, const IndexedMesh& m) {
  const uint32_t nv = m.vertex_count(), nf = m.face_count();
  w.str("ply\nformat binary_little_endian 1.0\ncomment written by pmz\nelement vertex ")
      .num(nv)
      .str("\nproperty float x\nproperty float y\nproperty float z\nelement face ")
      .num(nf)
      .str("\nproperty list uchar uint vertex_indices\nend_header\n");
  if constexpr (std::endian::native == std::endian::little) {
    w.put(m.positions.data(), size_t(nv) * 12);
  } else {
    for (size_t i = 0; i < size_t(nv) * 3; ++i) w.f32le(m.positions[i]);
  }
  const uint32_t* ix = m.indices.data();
  for (uint32_t f = 0; f < nf;) {
    char* o = w.room(13);
    const uint32_t n = uint32_t(std::min<size_t>(nf - f, w.room_left() / 13));
    for (const uint32_t e = f + n; f < e; ++f, o += 13) {
      *o = 3;
      if constexpr (std::endian::native == std::endian::little) {
        std::memcpy(o + 1, ix + size_t(f) * 3, 12);  // the file's layout: one copy per face
      } else {
        for (int k = 0; k < 3; ++k) {
          const uint32_t v = ix[size_t(f) * 3 + k];
          const unsigned char b[4] = {uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16),
                                      uint8_t(v >> 24)};
          std::memcpy(o + 1 + 4 * k, b, 4);
        }
      }
    }
    w.commit(o);
  }
}

void write_body(Writer& w, const std::string& ext, const IndexedMesh& m, const std::string& mtl) {
  const uint32_t nv = m.vertex_count(), nf = m.face_count();
  const float* p = m.positions.data();
  const uint32_t* ix = m.indices.data();
  if (ext == ".obj") {
    write_obj(w, m, mtl);
  } else if (ext == ".ply" && m.attributes.has_wedges()) {
    write_ply_wedges(w, m);
  } else if (ext == ".ply") {
    write_ply(w, m);
  } else if (ext == ".off") {
    w.str("OFF\n").num(nv).str(" ").num(nf).str(" 0\n");
    for (uint32_t v = 0; v < nv; ++v) put_line(w, "", p + size_t(v) * 3, 3);
    for (uint32_t f = 0; f < nf; ++f) put_line(w, "3 ", ix + size_t(f) * 3, 3);
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

bool known_input(const std::string& ext) {
  return ext == ".obj" || ext == ".off" || ext == ".ply" || ext == ".stl" || ext == ".gltf" ||
         ext == ".glb";
}

const char* const kInputFormats = ".obj, .off, .ply, .stl, .gltf or .glb";

// One check of every reader's attribute output before repair indexes into it: each corner
// array covers every corner and each index is kNoAttribute or names an entry of its pool.
// (fuzz_mesh_ply found a PLY header whose attribute pools and corner indices disagreed.)
static bool check_attribute_indices(const std::string& path, const PolygonSoup& soup,
                                    std::string& error) {
  const SoupAttributes& a = soup.attributes;
  const size_t corners = soup.corners.size();
  auto bad = [&](const char* what) {
    error = path + ": " + what + " attribute index out of range";
    return false;
  };
  auto check = [&](const std::vector<uint32_t>& corner, size_t pool, size_t width,
                   const char* what) {
    if (corner.empty()) return true;
    if (corner.size() != corners || width == 0) return bad(what);
    for (uint32_t i : corner)
      if (i != kNoAttribute && (uint64_t(i) + 1) * width > pool) return bad(what);
    return true;
  };
  if (a.corner_texcoords.size() != a.texcoords.size()) return bad("texture coordinate");
  for (size_t s = 0; s < a.texcoords.size(); ++s)
    if (!check(a.corner_texcoords[s], a.texcoords[s].size(), 2, "texture coordinate")) return false;
  if (!check(a.corner_normals, a.normals.size(), 3, "normal")) return false;
  if (!check(a.corner_colors, a.colors.size(), a.color_components, "colour")) return false;
  if (!a.face_materials.empty() && a.face_materials.size() != soup.face_count())
    return bad("material");
  return true;
}

bool parse_polygon_soup(const std::string& path, std::string_view data, PolygonSoup& out,
                        std::string& error) {
  out = PolygonSoup();
  out.face_offsets.push_back(0);
  std::string ext = lower_extension(path);
  if (!known_input(ext)) {
    error = path + ": unknown mesh format '" + ext + "' (expected " + kInputFormats + ")";
    return false;
  }
  if (data.empty()) {
    error = path + ": empty file";
    return false;
  }
  bool ok = ext == ".obj"   ? read_obj(path, data, out, error)
            : ext == ".off" ? read_off(path, data, out, error)
            : ext == ".ply" ? read_ply(path, data, out, error)
            : ext == ".stl" ? read_stl(path, data, out, error)
                            : read_gltf(path, data, out, error);
  if (ok && out.face_count() == 0) {
    error = path + ": mesh has no faces";
    ok = false;
  }
  if (ok) ok = check_attribute_indices(path, out, error);
  if (!ok) out = PolygonSoup();
  return ok;
}

bool read_polygon_soup(const std::string& path, PolygonSoup& out, std::string& error) {
  out = PolygonSoup();
  std::string ext = lower_extension(path);
  if (!known_input(ext)) {
    error = path + ": unknown mesh format '" + ext + "' (expected " + kInputFormats + ")";
    return false;
  }
  std::string data;
  if (!read_file(path, data, error)) return false;
  return parse_polygon_soup(path, data, out, error);
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

namespace {

// Through OutputFile (pmz/output_file.hpp): a temporary renamed over the target when `body` has
// written everything, removed on any error; symlinks, devices and FIFOs as every tool does.
bool write_atomic(const std::string& path, const std::function<void(Writer&)>& body,
                  std::string& error) {
  OutputFile out;
  if (!out.open(path, false, error)) return false;
  const MeshSink sink = [&](const void* p, size_t n) { return out.write(p, n); };
  Writer w(sink);
  body(w);
  w.finish();  // a failed write is remembered by `out` and reported by commit()
  return out.commit(error);
}

// A mesh's attribute arrays must agree with its geometry before anything is written.
bool check_attributes(const std::string& path, const IndexedMesh& m, std::string& error) {
  const MeshAttributes& a = m.attributes;
  const size_t wedges = a.wedge_count();
  auto bad = [&](const std::string& what) {
    error = path + ": mesh to write has " + what;
    return false;
  };
  if (a.has_wedges() && a.corner_wedges.size() != m.indices.size())
    return bad("attributes for " + std::to_string(a.corner_wedges.size()) + " of " +
               std::to_string(m.indices.size()) + " corners");
  for (size_t c = 0; c < a.corner_wedges.size(); ++c)
    if (a.corner_wedges[c] >= wedges || a.wedge_vertices[a.corner_wedges[c]] != m.indices[c])
      return bad("corner " + std::to_string(c) + " with a wedge of another vertex");
  for (const std::vector<float>& t : a.texcoords)
    if (t.size() != wedges * 2) return bad("texture coordinates not one pair per wedge");
  if (!a.normals.empty() && a.normals.size() != wedges * 3) return bad("normals not one per wedge");
  if (a.colors.size() != wedges * a.color_components) return bad("colours not one per wedge");
  if (!a.face_materials.empty() && a.face_materials.size() != m.face_count())
    return bad("material ids not one per face");
  for (uint32_t id : a.face_materials)
    if (id >= a.materials.size()) return bad("a face with material " + std::to_string(id));
  return true;
}

}  // namespace

namespace {

// What both writers check first: a known format (ext with its dot), indices and attributes that
// agree with the geometry.
bool check_writable(const std::string& path, const std::string& ext, const IndexedMesh& mesh,
                    std::string& error) {
  if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl" && ext != ".glb") {
    error = path + ": unknown mesh format '" + ext + "' (expected .obj, .off, .ply, .stl or .glb)";
    return false;
  }
  for (uint32_t i : mesh.indices)
    if (i >= mesh.vertex_count()) {
      error = path + ": mesh to write references vertex " + std::to_string(i) + " of " +
              std::to_string(mesh.vertex_count());
      return false;
    }
  return check_attributes(path, mesh, error);
}

}  // namespace

bool write_mesh_to(const std::string& name, const std::string& format, const IndexedMesh& mesh,
                   const MeshSink& sink, std::string& error, const std::string& mtl_name) {
  const std::string ext = "." + format;
  if (!check_writable(name, ext, mesh, error)) return false;
  Writer w(sink);
  if (ext == ".glb") {
    std::string bytes;
    if (!write_glb(mesh, bytes, error)) {
      error = name + ": " + error;
      return false;
    }
    w.put(bytes.data(), bytes.size());
  } else {
    write_body(w, ext, mesh, ext == ".obj" ? mtl_name : "");
  }
  if (w.finish()) return true;
  error = name + ": write failed";
  return false;
}

bool write_material_library_to(const std::string& name, const std::vector<Material>& materials,
                               const MeshSink& sink, std::string& error) {
  Writer w(sink);
  write_mtl(w, materials);
  if (w.finish()) return true;
  error = name + ": write failed";
  return false;
}

bool write_material_library(const std::string& path, const std::vector<Material>& materials,
                            std::string& error) {
  return write_atomic(
      path, [&](Writer& w) { write_mtl(w, materials); }, error);
}

bool write_mesh(const std::string& path, const IndexedMesh& mesh, std::string& error) {
  std::string ext = lower_extension(path);
  if (!check_writable(path, ext, mesh, error)) return false;
  if (ext == ".glb") {
    std::string bytes;
    if (!write_glb(mesh, bytes, error)) {
      error = path + ": " + error;
      return false;
    }
    return write_atomic(
        path, [&](Writer& w) { w.put(bytes.data(), bytes.size()); }, error);
  }
  std::string mtl;
  if (ext == ".obj" && !mesh.attributes.materials.empty()) {
    // The MTL goes first, beside the OBJ, named after it (mtllib names it relative to the OBJ).
    std::filesystem::path target(path);
    mtl = target.stem().string() + ".mtl";
    if (!write_material_library((target.parent_path() / mtl).string(), mesh.attributes.materials,
                                error))
      return false;
  }
  return write_atomic(
      path, [&](Writer& w) { write_body(w, ext, mesh, mtl); }, error);
}

}  // namespace pmz
