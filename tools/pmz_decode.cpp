// pmz-decode: decode a .pmz stream (or its first N bytes, as a partial download would) to
// OBJ/PLY/OFF at a chosen level of detail. Reads a file or stdin (-); writes each format itself
// through a 1 MiB buffer into a safe output (tool_common: temporary + rename, or stdout with -).
// No OpenMesh.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "pmz/decoder.hpp"
#include "tool_common.hpp"

namespace {

namespace tool = pmz::tool;

// Buffered output: a fixed 1 MiB buffer flushed with fwrite (no whole-file copy in memory);
// large contiguous blocks (PLY positions) go straight to fwrite.
class Out {
 public:
  explicit Out(tool::OutputFile& f) : f_(f), buf_(size_t(1) << 20) {}
  ~Out() { flush(); }
  char* room(size_t n) {  // n <= 64 bytes of space at the end of the buffer
    if (buf_.size() - used_ < n) flush();
    return buf_.data() + used_;
  }
  size_t room_left() const { return buf_.size() - used_; }
  void commit(char* end) { used_ = size_t(end - buf_.data()); }
  void put(const char* s, size_t n) {
    if (n > buf_.size() / 2) {
      flush();
      f_.write(s, n);
      return;
    }
    if (buf_.size() - used_ < n) flush();
    std::memcpy(buf_.data() + used_, s, n);
    used_ += n;
  }
  void put(const std::string& s) { put(s.data(), s.size()); }
  void flush() {
    if (used_) f_.write(buf_.data(), used_);
    used_ = 0;
  }

 private:
  tool::OutputFile& f_;
  std::vector<char> buf_;
  size_t used_ = 0;
};

template <typename T>
char* put_number(char* o, T x) {
  return std::to_chars(o, o + 32, x).ptr;
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
  tool::init("pmz-decode");
  CLI::App app{
      "pmz-decode: decode a .pmz stream (or its first N bytes) to OBJ/PLY/OFF at a chosen level of "
      "detail",
      "pmz-decode"};
  std::string input, output, format;
  uint64_t faces = 0, vertices = 0, bytes = 0;
  double ratio = 1;
  app.add_option("input", input, "input .pmz (- for stdin)")->required();
  app.add_option("-o,--output", output, "output mesh (.obj, .ply or .off; - for stdout)")
      ->required();
  app.add_option("--format", format, "output format (default: the output's extension)")
      ->check(CLI::IsMember({"obj", "ply", "off"}));
  auto* of =
      app.add_option("--faces", faces, "smallest level with at least N faces (0: the base mesh)");
  auto* orr =
      app.add_option("--ratio", ratio, "this fraction of the full face count (0: the base mesh)")
          ->check(CLI::Range(0.0, 1.0));
  auto* ov = app.add_option("--vertices", vertices,
                            "level with N vertices (clamped to the base and full mesh)");
  app.add_option("--bytes", bytes, "decode only the first N bytes of the input");
  bool salvage = false;
  app.add_flag("--salvage", salvage,
               "on a damaged or truncated stream, still write its last good level (exit 1 even "
               "so)");
  of->excludes(orr)->excludes(ov);
  orr->excludes(ov);
  tool::set_footer(app,
                   "Without --faces, --ratio or --vertices: the finest level the input holds. A "
                   "target beyond what the input holds gets a warning and the finest level it "
                   "holds.");
  if (int rc = tool::parse(app, argc, argv); rc >= 0) return rc;

  if (format.empty()) format = tool::extension(output);
  if (format != "obj" && format != "ply" && format != "off") {
    tool::print_error(output == "-" ? "writing to stdout needs --format obj|ply|off (see --help)"
                                    : output +
                                          ": output must end in .obj, .ply or .off, or give "
                                          "--format (see --help)");
    return tool::kExitUsage;
  }
  if (tool::same_file(input, output)) {
    tool::print_error(output, "is the input file; not overwriting it");
    return tool::kExitFailure;
  }
  const std::string shown = input == "-" ? "stdin" : input;
  // Opened first: an unwritable output fails before the work, and the temporary (removed on
  // error and on SIGINT/SIGTERM) exists while the input streams in.
  tool::OutputFile out;
  std::string error;
  if (!out.open(output, format == "ply", error)) {
    tool::print_error(error);
    return tool::kExitFailure;
  }
  std::vector<uint8_t> data;
  if (!tool::read_input(input, data, error)) {
    tool::print_error(error);
    return tool::kExitFailure;
  }
  size_t n = bytes ? std::min<size_t>(bytes, data.size()) : data.size();
  pmz::Decoder d;
  pmz::Status s = d.feed(data.data(), n);
  if (s == pmz::Status::ok && !bytes) s = d.finish();
  const char* nothing_written = "nothing written (--salvage writes the last good level)";
  if (s != pmz::Status::ok) {
    // A damaged stream still has a last good level, but writing it unasked would pass a coarse
    // mesh off as the file's content: only --salvage writes it (and still exits 1).
    tool::print_error(shown, tool::library_message(d.error_message()));
    if (!salvage) {
      tool::print_error(shown, nothing_written);
      return tool::kExitFailure;
    }
    if (!d.info().base_done) return tool::kExitFailure;
  }
  if (!d.info().base_done) {
    tool::print_error(shown, "the first " + std::to_string(n) + " bytes do not hold the base mesh");
    return tool::kExitFailure;
  }
  const pmz::StreamInfo& info = d.info();
  // 0 is a level like any other (the base mesh), not "unset": options are told apart by count.
  uint64_t wanted_faces = 0;
  if (of->count())
    d.set_face_target(wanted_faces = faces);
  else if (orr->count())
    d.set_face_target(wanted_faces = uint64_t(ratio * double(info.full_faces) + 0.5));
  else if (ov->count())
    d.set_split_target(vertices > info.base_vertices ? vertices - info.base_vertices : 0);
  else
    d.refine();
  // Wedge and residual symbols are decoded as splits are first applied: damage there shows
  // only now, and is treated like damage found while reading.
  const bool refine_failed = s == pmz::Status::ok && d.status() != pmz::Status::ok;
  if (d.status() != pmz::Status::ok && d.status() != s)
    tool::print_error(shown, tool::library_message(d.error_message()));
  if (refine_failed) {
    s = d.status();
    if (!salvage) {
      tool::print_error(shown, nothing_written);
      return tool::kExitFailure;
    }
  }
  // A target the given bytes cannot reach: say what it asked and what was written.
  const bool all_available = d.splits_available() == info.total_splits;
  const std::string held = all_available ? "the file holds"
                                         : "the " + std::string(bytes ? "first " : "") +
                                               std::to_string(n) + " bytes hold";
  if ((of->count() || orr->count()) && d.face_count() < wanted_faces)
    tool::print_error(shown, "warning: " + std::to_string(wanted_faces) + " faces asked; " + held +
                                 " " + std::to_string(d.face_count()) +
                                 (all_available ? "" : " of " + std::to_string(info.full_faces)) +
                                 ": writing those");
  if (ov->count() && d.vertex_count() < vertices)
    tool::print_error(shown,
                      "warning: " + std::to_string(vertices) + " vertices asked; " + held + " " +
                          std::to_string(d.vertex_count()) +
                          (all_available ? "" : " of " + std::to_string(info.full_vertices)) +
                          ": writing those");
  {
    Out buffered(out);
    write_mesh(format, d, buffered);
  }
  if (!out.commit(error)) {
    tool::print_error(error);
    return tool::kExitFailure;
  }
  std::fprintf(stderr, "pmz-decode: %u faces, %u vertices (%llu of %llu splits)\n", d.face_count(),
               d.vertex_count(), (unsigned long long)d.splits_applied(),
               (unsigned long long)info.total_splits);
  return s == pmz::Status::ok || (bytes && !refine_failed) ? tool::kExitOk : tool::kExitFailure;
}
