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
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pmz/mesh.hpp"

namespace pmz {

inline constexpr uint64_t kMaxVertices = 0xFFFFFFF0u;  // ids must fit uint32 with room for copies

// The file opened for reading, or null with error "path: no such file", "path: is a
// directory, not a mesh file" or "path: cannot open: reason".
std::FILE* open_file(const std::string& path, std::string& error);
// The whole file into `data`. error: open_file's, "path: empty file", "path: read error".
bool read_file(const std::string& path, std::string& data, std::string& error);

// The bytes of a mesh file, read forward: from memory (the whole data, never copied) or from an
// open file through a window refilled as the cursor reaches its end (a line or token longer
// than the window grows it). A view it returns stays valid until the next peek or seek.
class ByteSource {
 public:
  static constexpr uint64_t kUnknownSize = UINT64_MAX;
  explicit ByteSource(std::string_view data)
      : data_(data), end_(data.size()), size_(data.size()), spilled_(nullptr, &std::fclose) {}
  // `file` from its current position, which holds `size` bytes from there (a regular file's
  // size: a file that ends sooner ends the source there), or kUnknownSize (a pipe): the source
  // then ends where the file does, and its size is known from then on. `progress`, if set, is
  // told the fraction read at each refill of a source of known size.
  ByteSource(std::FILE* file, uint64_t size, size_t window, std::function<void(double)> progress);
  ByteSource(const ByteSource&) = delete;
  ByteSource& operator=(const ByteSource&) = delete;
  // The bytes from the cursor, at least min(n, remaining()) of them (fewer: a read failed).
  std::string_view peek(size_t n) { return end_ - pos_ >= n ? view() : fill(n); }
  // What is in the window from the cursor (all of it from memory).
  std::string_view view() const { return data_.substr(pos_, end_ - pos_); }
  // Every byte from the cursor to the end of the input (a whole file into the window).
  std::string_view rest();
  void skip(size_t n) { pos_ += n; }  // n <= view().size()
  uint64_t offset() const { return base_ + pos_; }
  bool size_known() const { return size_ != kUnknownSize; }
  // The bytes from the cursor to the end; while the size is unknown, kUnknownSize - offset():
  // more may come, and no count is refused for the bytes it needs.
  uint64_t remaining() const { return size_ - offset(); }
  // What a reservation may count on the input still holding: remaining() when the size is
  // known; else what the window holds, at least one window's worth (containers reserved that
  // much grow as the data arrives, so that a count in a header allocates nothing by itself).
  uint64_t reservable() const {
    return size_known() ? remaining() : std::max<uint64_t>(end_ - pos_, window_);
  }
  // The size of the input. A source of unknown size is read to its end first, the bytes
  // dropped (the cursor then is at the end): for an error message that needs the size.
  uint64_t learn_size();
  // Makes the size known and seek() work: a source of unknown size is copied from the cursor
  // on into an unnamed temporary file and read from there (memory stays bounded; the disk holds
  // the copy). False with `error` set ("cannot buffer the input: reason") when the copy fails;
  // a failed read is read_errno()'s.
  bool make_seekable(std::string& error);
  // Back (or on) to `offset` from the start. False when the file cannot seek.
  bool seek(uint64_t offset);
  // The errno of a failed read (the source then ends where it failed), or 0.
  int read_errno() const { return errno_; }

 private:
  std::string_view fill(size_t n);
  std::string_view data_;  // the window (from memory: the whole data)
  size_t pos_ = 0, end_ = 0;
  uint64_t base_ = 0;  // offset of data_[0]
  uint64_t size_;
  std::FILE* file_ = nullptr;
  long start_ = 0;  // the file's position at offset 0
  size_t window_ = 0;
  bool eof_ = false;
  int errno_ = 0;
  std::vector<char> buffer_;
  std::function<void(double)> progress_;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> spilled_;  // make_seekable's copy
};

// ---- text scanning ----

struct Lines {
  ByteSource& in;
  uint64_t number = 0;  // 1-based number of the line last returned
  char comment;         // everything from this character to the end of a line is ignored
  // Next line with the comment stripped; false at the end of the data.
  bool next(std::string_view& line) {
    std::string_view w = in.peek(1);
    if (w.empty()) return false;
    size_t end = w.find('\n');
    while (end == std::string_view::npos && w.size() < in.remaining()) {
      const size_t searched = w.size();
      w = in.peek(searched * 2);
      if (w.size() == searched) break;  // a read failed
      end = w.find('\n', searched);
    }
    line = w.substr(0, end);
    in.skip(end == std::string_view::npos ? w.size() : end + 1);
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

// The next token of a source (spaces and line ends skip); empty at the end of the data.
std::string_view next_token(ByteSource& in);

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

// Capacity to reserve for `declared` items that each take at least `min_bytes` of `available`
// (a ByteSource's reservable()): a header cannot make us allocate more than the data could
// possibly hold, or, from a source of unknown size, more than a window's worth.
inline size_t plausible(uint64_t declared, uint64_t available, size_t min_bytes) {
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
