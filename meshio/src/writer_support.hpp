// SPDX-License-Identifier: MIT
// What the format writers (mesh_obj.cpp, mesh_off.cpp, mesh_ply.cpp, mesh_stl.cpp) and
// mesh_io.cpp share: buffered output to a MeshSink and the numeric text lines of OBJ and OFF.
// Internal to meshio.
#pragma once
#include <bit>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

#include "pmz/mesh.hpp"

namespace pmz {

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

}  // namespace pmz
