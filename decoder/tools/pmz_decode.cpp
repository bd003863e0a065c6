// pmz-decode: decode a .pmz stream (or its first N bytes, as a partial download would) to
// OBJ/PLY/OFF at a chosen level of detail. Writes each format itself into one buffer, then
// one fwrite, atomically (temporary file + rename). No OpenMesh.
#include <CLI/CLI.hpp>

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

void append(std::vector<char>& b, const char* s) { b.insert(b.end(), s, s + std::strlen(s)); }
template <typename T>
void append_number(std::vector<char>& b, T x) {
  char tmp[32];
  auto r = std::to_chars(tmp, tmp + sizeof tmp, x);
  b.insert(b.end(), tmp, r.ptr);
}

std::string extension(const std::string& path) {
  size_t dot = path.rfind('.');
  std::string e = dot == std::string::npos ? "" : path.substr(dot + 1);
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

void format_mesh(const std::string& ext, const pmz::Decoder& d, std::vector<char>& b) {
  const uint32_t nv = d.vertex_count(), nf = d.face_count();
  const float* p = d.positions();
  const uint32_t* t = d.indices();
  if (ext == "ply") {
    std::string h = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(nv) +
                    "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                    std::to_string(nf) + "\nproperty list uchar int vertex_indices\nend_header\n";
    b.resize(h.size() + size_t(nv) * 12 + size_t(nf) * 13);
    char* o = b.data();
    std::memcpy(o, h.data(), h.size());
    o += h.size();
    if (nv) std::memcpy(o, p, size_t(nv) * 12);  // little-endian host assumed (x86, ARM)
    o += size_t(nv) * 12;
    for (uint32_t f = 0; f < nf; ++f) {
      *o++ = 3;
      std::memcpy(o, t + size_t(f) * 3, 12);
      o += 12;
    }
    return;
  }
  b.reserve(size_t(nv) * 40 + size_t(nf) * 24);
  const bool obj = ext == "obj";
  if (!obj) {
    append(b, "OFF\n");
    append_number(b, nv);
    b.push_back(' ');
    append_number(b, nf);
    append(b, " 0\n");
  }
  for (uint32_t i = 0; i < nv; ++i) {
    if (obj) append(b, "v ");
    for (int a = 0; a < 3; ++a) {
      append_number(b, p[size_t(i) * 3 + a]);
      b.push_back(a == 2 ? '\n' : ' ');
    }
  }
  for (uint32_t f = 0; f < nf; ++f) {
    append(b, obj ? "f " : "3 ");
    for (int a = 0; a < 3; ++a) {
      append_number(b, t[size_t(f) * 3 + a] + (obj ? 1u : 0u));
      b.push_back(a == 2 ? '\n' : ' ');
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pmz-decode: decode a .pmz stream (or its first N bytes) to OBJ/PLY/OFF at a chosen level of detail"};
  std::string input, output;
  uint64_t faces = 0, vertices = 0, bytes = 0;
  double ratio = -1;
  app.add_option("input", input, "input .pmz")->required();
  app.add_option("-o,--output", output, "output mesh (.obj, .ply or .off)")->required();
  auto* of = app.add_option("--faces", faces, "smallest level with at least N faces");
  auto* orr = app.add_option("--ratio", ratio, "fraction of the full face count")->check(CLI::Range(0.0, 1.0));
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
  if (of->count()) d.set_face_target(faces);
  else if (orr->count()) d.set_face_target(uint64_t(ratio * double(d.info().full_faces) + 0.5));
  else if (ov->count()) d.set_split_target(vertices > d.info().base_vertices ? vertices - d.info().base_vertices : 0);
  else d.refine();
  if (d.status() != pmz::Status::ok && d.status() != s)
    std::fprintf(stderr, "pmz-decode: %s\n", d.error_message().c_str());

  std::vector<char> buf;
  format_mesh(ext, d, buf);
  std::string tmp = output + ".tmp";
  FILE* f = std::fopen(tmp.c_str(), "wb");
  bool ok = f && std::fwrite(buf.data(), 1, buf.size(), f) == buf.size();
  if (f) ok = std::fclose(f) == 0 && ok;
  if (!ok || std::rename(tmp.c_str(), output.c_str()) != 0) {
    std::remove(tmp.c_str());
    std::fprintf(stderr, "pmz-decode: cannot write %s\n", output.c_str());
    return 1;
  }
  std::fprintf(stderr, "pmz-decode: %u faces, %u vertices (%llu of %llu splits)\n", d.face_count(),
               d.vertex_count(), (unsigned long long)d.splits_applied(),
               (unsigned long long)d.info().total_splits);
  return s == pmz::Status::ok || bytes ? 0 : 2;
}
