// SPDX-License-Identifier: MIT
// What the format readers (mesh_obj.cpp, mesh_off.cpp, mesh_ply.cpp, mesh_stl.cpp,
// mesh_gltf.cpp) share: reading a whole file, scanning text line by line and token by token,
// the error messages that name a file and line, and appending to a PolygonSoup within the
// limits every reader keeps. Internal to meshio.
#pragma once
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>

#include "pmz/mesh.hpp"

namespace pmz {

inline constexpr uint64_t kMaxVertices = 0xFFFFFFF0u;  // ids must fit uint32 with room for copies

// The whole file into `data`. error: "path: no such file", "path: empty file", ...
bool read_file(const std::string& path, std::string& data, std::string& error);

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

inline bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

inline std::string_view next_token(std::string_view& s) {
  size_t i = 0;
  while (i < s.size() && is_space(s[i])) ++i;
  size_t j = i;
  while (j < s.size() && !is_space(s[j])) ++j;
  std::string_view t = s.substr(i, j - i);
  s = s.substr(j);
  return t;
}

// Whole-token parses; a malformed token is an error, NaN/Inf parse (and are refused later).
inline bool parse_float(std::string_view t, float& v) {
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  if (t.empty()) return false;
  auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  if (r.ec == std::errc::result_out_of_range)
    v = (t[0] == '-' ? -1.0f : 1.0f) * INFINITY;
  else if (r.ec != std::errc())
    return false;
  return r.ptr == t.data() + t.size() || r.ec == std::errc::result_out_of_range;
}

inline bool parse_int(std::string_view t, int64_t& v) {
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  return !t.empty() && r.ec == std::errc() && r.ptr == t.data() + t.size();
}

// ---- errors, naming the file (and the line when there is one) ----

std::string line_error(const std::string& path, uint64_t line, const std::string& what);
std::string nonfinite_error(const std::string& path, uint64_t vertex, uint64_t line);
std::string range_error(const std::string& path, uint64_t face, uint64_t line, int64_t index,
                        uint64_t vertices);

// ---- building the soup ----

inline bool push_vertex(PolygonSoup& out, const float p[3], const std::string& path, uint64_t line,
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

inline void end_face(PolygonSoup& out) { out.face_offsets.push_back(uint32_t(out.corners.size())); }

// Capacity to reserve for `declared` items that each take at least `min_bytes` of `available`:
// a header cannot make us allocate more than the data could possibly hold.
inline size_t plausible(uint64_t declared, size_t available, size_t min_bytes) {
  return size_t(std::min<uint64_t>(declared, available / min_bytes));
}

inline bool all_finite(const float* v, int count) {
  for (int k = 0; k < count; ++k)
    if (!std::isfinite(v[k])) return false;
  return true;
}

// A material known by its name only (OBJ's usemtl, PLY's TextureFile).
inline Material named_material(std::string name) {
  Material m;
  m.name = std::move(name);
  return m;
}

// Merges vertices with bitwise-equal positions (-0 == +0) into the first of them: formats that
// store attributes per vertex (PLY, glTF) split vertices at seams, pmz keeps them as wedges.
// Attribute indices keep pointing at the file's entries; only the corners' vertex ids change.
void weld_vertices(PolygonSoup& soup);

}  // namespace pmz
