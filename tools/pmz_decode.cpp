// pmz-decode: decode a .pmz stream (or its first N bytes, as a partial download would) to
// OBJ/PLY/OFF at a chosen level of detail. Writes each format itself through a 1 MiB buffer,
// atomically (temporary file + rename). No OpenMesh.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "pmz/decoder.hpp"

namespace {

bool read_file(const std::string& path, std::vector<uint8_t>& out) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  std::fseek(f, 0, SEEK_END);
  long size = std::ftell(f);
  std::fseek(f, 0, SEEK_SET);
  out.resize(size > 0 ? size_t(size) : 0);
  bool ok = size >= 0 && std::fread(out.data(), 1, out.size(), f) == out.size();
  std::fclose(f);
  return ok;
}

// Buffered output: a fixed 1 MiB buffer flushed with fwrite (no whole-file copy in memory);
// large contiguous blocks (PLY positions) go straight to fwrite.
class Out {
 public:
  explicit Out(FILE* f) : f_(f), buf_(size_t(1) << 20) {}
  ~Out() { flush(); }
  bool ok() const { return ok_; }
  char* room(size_t n) {  // n <= 64 bytes of space at the end of the buffer
    if (buf_.size() - used_ < n) flush();
    return buf_.data() + used_;
  }
  size_t room_left() const { return buf_.size() - used_; }
  void commit(char* end) { used_ = size_t(end - buf_.data()); }
  void put(const char* s, size_t n) {
    if (n > buf_.size() / 2) {
      flush();
      ok_ = ok_ && std::fwrite(s, 1, n, f_) == n;
      return;
    }
    if (buf_.size() - used_ < n) flush();
    std::memcpy(buf_.data() + used_, s, n);
    used_ += n;
  }
  void put(const std::string& s) { put(s.data(), s.size()); }
  void flush() {
    if (used_) ok_ = ok_ && std::fwrite(buf_.data(), 1, used_, f_) == used_;
    used_ = 0;
  }

 private:
  FILE* f_;
  std::vector<char> buf_;
  size_t used_ = 0;
  bool ok_ = true;
};

template <typename T>
char* put_number(char* o, T x) {
  return std::to_chars(o, o + 32, x).ptr;
}

std::string extension(const std::string& path) {
  size_t dot = path.rfind('.');
  std::string e = dot == std::string::npos ? "" : path.substr(dot + 1);
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

void write_mesh(const std::string& ext, const pmz::Decoder& d, Out& out) {
  const uint32_t nv = d.vertex_count(), nf = d.face_count();
  const float* p = d.positions();
  const uint32_t* t = d.indices();
  if (ext == "ply") {
    out.put("ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(nv) +
            "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
            std::to_string(nf) + "\nproperty list uchar int vertex_indices\nend_header\n");
    if (nv)
      out.put(reinterpret_cast<const char*>(p),
              size_t(nv) * 12);  // little-endian host assumed (x86, ARM)
    // 13 bytes per face, written a buffer's worth at a time (no per-face room check).
    for (uint32_t f = 0; f < nf;) {
      char* o = out.room(13);
      const uint32_t n = uint32_t(std::min<size_t>(nf - f, out.room_left() / 13));
      for (const uint32_t e = f + n; f < e; ++f, o += 13) {
        *o = 3;
        std::memcpy(o + 1, t + size_t(f) * 3, 12);
      }
      out.commit(o);
    }
    return;
  }
  const bool obj = ext == "obj";
  if (!obj) out.put("OFF\n" + std::to_string(nv) + " " + std::to_string(nf) + " 0\n");
  for (uint32_t i = 0; i < nv; ++i) {
    char* o = out.room(64);  // 3 shortest floats (<= 15 chars each), separators
    if (obj) *o++ = 'v', *o++ = ' ';
    for (int a = 0; a < 3; ++a) {
      o = put_number(o, p[size_t(i) * 3 + a]);
      *o++ = a == 2 ? '\n' : ' ';
    }
    out.commit(o);
  }
  for (uint32_t f = 0; f < nf; ++f) {
    char* o = out.room(64);  // "f " + 3 indices (<= 10 digits each) + separators
    *o++ = obj ? 'f' : '3';
    *o++ = ' ';
    for (int a = 0; a < 3; ++a) {
      o = put_number(o, t[size_t(f) * 3 + a] + (obj ? 1u : 0u));
      *o++ = a == 2 ? '\n' : ' ';
    }
    out.commit(o);
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "pmz-decode: decode a .pmz stream (or its first N bytes) to OBJ/PLY/OFF at a chosen level of "
      "detail"};
  std::string input, output;
  uint64_t faces = 0, vertices = 0, bytes = 0;
  double ratio = -1;
  app.add_option("input", input, "input .pmz")->required();
  app.add_option("-o,--output", output, "output mesh (.obj, .ply or .off)")->required();
  auto* of = app.add_option("--faces", faces, "smallest level with at least N faces");
  auto* orr = app.add_option("--ratio", ratio, "fraction of the full face count")
                  ->check(CLI::Range(0.0, 1.0));
  auto* ov = app.add_option("--vertices", vertices, "level with N vertices (clamped)");
  app.add_option("--bytes", bytes, "decode only the first N bytes of the file");
  bool salvage = false;
  app.add_flag("--salvage", salvage,
               "on a damaged or truncated stream, still write its last good level (exit 2)");
  of->excludes(orr)->excludes(ov);
  orr->excludes(ov);
  CLI11_PARSE(app, argc, argv);

  const std::string ext = extension(output);
  if (ext != "obj" && ext != "ply" && ext != "off") {
    std::fprintf(stderr, "pmz-decode: output must end in .obj, .ply or .off: %s\n", output.c_str());
    return 1;
  }
  std::vector<uint8_t> data;
  if (!read_file(input, data)) {
    std::fprintf(stderr, "pmz-decode: cannot read %s\n", input.c_str());
    return 1;
  }
  size_t n = bytes ? std::min<size_t>(bytes, data.size()) : data.size();
  pmz::Decoder d;
  pmz::Status s = d.feed(data.data(), n);
  if (s == pmz::Status::ok && !bytes) s = d.finish();
  if (s != pmz::Status::ok) {
    // A damaged stream still has a last good level, but writing it unasked would pass a coarse
    // mesh off as the file's content: only --salvage writes it (and still exits non-zero).
    std::fprintf(stderr, "pmz-decode: %s\n", d.error_message().c_str());
    if (!salvage) {
      std::fprintf(stderr, "pmz-decode: nothing written (--salvage writes the last good level)\n");
      return 1;
    }
    if (!d.info().base_done) return 1;
  }
  if (!d.info().base_done) {
    std::fprintf(stderr, "pmz-decode: the first %zu bytes do not hold the base mesh\n", n);
    return 1;
  }
  if (of->count())
    d.set_face_target(faces);
  else if (orr->count())
    d.set_face_target(uint64_t(ratio * double(d.info().full_faces) + 0.5));
  else if (ov->count())
    d.set_split_target(vertices > d.info().base_vertices ? vertices - d.info().base_vertices : 0);
  else
    d.refine();
  // Wedge and residual symbols are decoded as splits are first applied: damage there shows
  // only now, and is treated like damage found while reading.
  const bool refine_failed = s == pmz::Status::ok && d.status() != pmz::Status::ok;
  if (d.status() != pmz::Status::ok && d.status() != s)
    std::fprintf(stderr, "pmz-decode: %s\n", d.error_message().c_str());
  if (refine_failed) {
    s = d.status();
    if (!salvage) {
      std::fprintf(stderr, "pmz-decode: nothing written (--salvage writes the last good level)\n");
      return 1;
    }
  }

  std::string tmp = output + ".tmp";
  FILE* f = std::fopen(tmp.c_str(), "wb");
  bool ok = f != nullptr;
  if (f) {
    {
      Out out(f);
      write_mesh(ext, d, out);
      out.flush();
      ok = out.ok();
    }
    ok = std::fclose(f) == 0 && ok;
  }
  if (!ok || std::rename(tmp.c_str(), output.c_str()) != 0) {
    std::remove(tmp.c_str());
    std::fprintf(stderr, "pmz-decode: cannot write %s\n", output.c_str());
    return 1;
  }
  std::fprintf(stderr, "pmz-decode: %u faces, %u vertices (%llu of %llu splits)\n", d.face_count(),
               d.vertex_count(), (unsigned long long)d.splits_applied(),
               (unsigned long long)d.info().total_splits);
  return s == pmz::Status::ok || (bytes && !refine_failed) ? 0 : 2;
}
