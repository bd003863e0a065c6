// SPDX-License-Identifier: MIT
// Reading a mesh file as a stream (pmz/mesh_stream.hpp): through a window of any size, down to
// one byte, the readers give the soup (or the error) that the same bytes give from memory, for
// files whose lines, tokens and records cross the window's boundaries; a file cut at any byte
// gives the same one line; a file larger than the default window reads as from memory. A pipe,
// whose size cannot be told, gives the same, and a header that declares far more than a pipe
// brings allocates nothing for it.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <new>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "pmz/mesh.hpp"
#include "pmz/mesh_stream.hpp"
#include "test_mesh_input_util.hpp"

namespace {

using pmz_test::TempDir;
namespace fs = std::filesystem;

void expect_same_soup(const pmz::PolygonSoup& a, const pmz::PolygonSoup& b) {
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.corners, b.corners);
  EXPECT_EQ(a.face_offsets, b.face_offsets);
  EXPECT_EQ(a.welded_vertices, b.welded_vertices);
  const pmz::SoupAttributes &x = a.attributes, &y = b.attributes;
  EXPECT_EQ(x.texcoords, y.texcoords);
  EXPECT_EQ(x.corner_texcoords, y.corner_texcoords);
  EXPECT_EQ(x.normals, y.normals);
  EXPECT_EQ(x.corner_normals, y.corner_normals);
  EXPECT_EQ(x.colors, y.colors);
  EXPECT_EQ(x.color_components, y.color_components);
  EXPECT_EQ(x.corner_colors, y.corner_colors);
  EXPECT_EQ(x.face_materials, y.face_materials);
  EXPECT_EQ(x.materials, y.materials);
  EXPECT_EQ(x.material_library, y.material_library);
}

// `bytes` served through a pipe by a thread, in writes of 1 to 97 bytes (the reader sees short
// reads); the read end as a FILE, whose size cannot be told. The writer stops when the reader
// closes its end early.
class PipeFeed {
 public:
  explicit PipeFeed(std::string bytes) : bytes_(std::move(bytes)) {
    std::signal(SIGPIPE, SIG_IGN);
    int fds[2];
    if (::pipe(fds) != 0) return;
    file_ = ::fdopen(fds[0], "rb");
    writer_ = std::thread([this, fd = fds[1]] {
      for (size_t at = 0, step = 1; at < bytes_.size(); step = step % 97 + 13) {
        const ssize_t n = ::write(fd, bytes_.data() + at, std::min(step, bytes_.size() - at));
        if (n <= 0) break;
        at += size_t(n);
      }
      ::close(fd);
    });
  }
  ~PipeFeed() {
    if (file_) std::fclose(file_);
    if (writer_.joinable()) writer_.join();
  }
  std::FILE* file() const { return file_; }

 private:
  std::string bytes_;
  std::FILE* file_ = nullptr;
  std::thread writer_;
};

// Where expect_stream_as_memory reads the bytes from.
enum class Via { disk, memory_file, pipe };

// `bytes` as the file `name` read through a window of `window` bytes, against the same bytes
// parsed from memory: the same result, soup or error. Returns whether it read. `via`: a file
// written to the temporary directory, the bytes through fmemopen (a seekable FILE), or a pipe.
bool expect_stream_as_memory(const TempDir& tmp, const std::string& name, std::string bytes,
                             size_t window, Via via = Via::disk) {
  const bool on_disk = via == Via::disk || (via == Via::memory_file && bytes.empty());
  const std::string path = on_disk ? tmp.write(name, bytes) : tmp.path(name);
  pmz::PolygonSoup memory, streamed;
  std::string memory_error, stream_error;
  const bool memory_ok = pmz::parse_polygon_soup(path, bytes, memory, memory_error);
  PipeFeed feed(via == Via::pipe ? bytes : std::string());
  std::FILE* f = via == Via::pipe ? feed.file()
                 : on_disk        ? std::fopen(path.c_str(), "rb")
                                  : ::fmemopen(bytes.data(), bytes.size(), "rb");
  EXPECT_NE(f, nullptr);
  if (!f) return false;
  const bool stream_ok = pmz::read_polygon_soup(path, f, streamed, stream_error, {}, window);
  if (via != Via::pipe) std::fclose(f);
  const char* how = via == Via::pipe ? " (pipe)" : "";
  EXPECT_EQ(stream_ok, memory_ok) << name << how << " window " << window << ": " << stream_error;
  EXPECT_EQ(stream_error, memory_error) << name << how << " window " << window;
  if (memory_ok && stream_ok) expect_same_soup(streamed, memory);
  return stream_ok;
}

std::string le32(uint32_t v) { return {char(v), char(v >> 8), char(v >> 16), char(v >> 24)}; }
std::string be32(uint32_t v) { return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)}; }
std::string lef(float f) { return le32(std::bit_cast<uint32_t>(f)); }
std::string bef(float f) { return be32(std::bit_cast<uint32_t>(f)); }

// A small grid of n x n vertices (two triangles per cell), its coordinates with many digits so
// that tokens cross small windows.
struct Grid {
  int n;
  float x(int i) const { return float(i % n) * 0.1234567f - 0.5f; }
  float y(int i) const { return float(i / n) * 0.7654321f + 1e-3f; }
  float z(int i) const { return float((i * 7919) % 13) * -0.0625f; }
  int vertices() const { return n * n; }
  int faces() const { return (n - 1) * (n - 1) * 2; }
  template <typename F>
  void each_face(F f) const {
    for (int r = 0; r + 1 < n; ++r)
      for (int c = 0; c + 1 < n; ++c) {
        const int a = r * n + c;
        f(a, a + 1, a + n + 1);
        f(a, a + n + 1, a + n);
      }
  }
};

std::string text(float v) {
  std::ostringstream s;
  s.precision(9);
  s << v;
  return s.str();
}

std::string ascii_ply(const Grid& g) {
  std::string s = "ply\r\nformat ascii 1.0\ncomment crossing windows\nelement vertex " +
                  std::to_string(g.vertices()) +
                  "\nproperty float x\nproperty float y\nproperty float z\n"
                  "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face " +
                  std::to_string(g.faces()) +
                  "\nproperty list uchar int vertex_indices\nend_header\n";
  for (int i = 0; i < g.vertices(); ++i)
    s += text(g.x(i)) + "  " + text(g.y(i)) + "\t" + text(g.z(i)) + " " + std::to_string(i % 256) +
         " 7 " + std::to_string((i * 3) % 256) + "\n";
  g.each_face([&](int a, int b, int c) {
    s += "3 " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(c) + "\n";
  });
  return s;
}

std::string binary_ply(const Grid& g, bool big_endian) {
  auto u32 = big_endian ? be32 : le32;
  auto f32 = big_endian ? bef : lef;
  std::string s =
      std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
      " 1.0\nelement vertex " + std::to_string(g.vertices()) +
      "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\n"
      "property float ny\nproperty float nz\nelement face " +
      std::to_string(g.faces()) + "\nproperty list uchar uint vertex_indices\nend_header\n";
  for (int i = 0; i < g.vertices(); ++i)
    s += f32(g.x(i)) + f32(g.y(i)) + f32(g.z(i)) + f32(0) + f32(0.6f) + f32(0.8f);
  g.each_face([&](int a, int b, int c) {
    s += '\3' + u32(uint32_t(a)) + u32(uint32_t(b)) + u32(uint32_t(c));
  });
  return s;
}

std::string obj(const Grid& g) {
  std::string s = "# grid\nmtllib none.mtl\n";
  for (int i = 0; i < g.vertices(); ++i)
    s += "v " + text(g.x(i)) + " " + text(g.y(i)) + " " + text(g.z(i)) + "\nvt " +
         text(g.x(i) + 0.5f) + " " + text(g.y(i)) + "\n";
  s += "vn 0 0 1\nusemtl first\n";
  int f = 0;
  g.each_face([&](int a, int b, int c) {
    if (f++ == g.faces() / 2) s += "usemtl second # half way\n";
    s += "f " + std::to_string(a + 1) + "/" + std::to_string(a + 1) + "/1 " +
         std::to_string(b + 1) + "/" + std::to_string(b + 1) + "/1 " + std::to_string(c + 1) + "/" +
         std::to_string(c + 1) + "/1\n";
  });
  return s;
}

std::string off(const Grid& g) {
  std::string s = "OFF\n# counts next\n\n" + std::to_string(g.vertices()) + " " +
                  std::to_string(g.faces()) + " 0\n";
  for (int i = 0; i < g.vertices(); ++i)
    s += text(g.x(i)) + " " + text(g.y(i)) + " " + text(g.z(i)) + "\n";
  g.each_face([&](int a, int b, int c) {
    s += "3 " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(c) + "\n";
  });
  return s;
}

// OpenMesh's layout: little endian, no colour count after a face.
std::string binary_off(const Grid& g) {
  std::string s =
      "OFF BINARY\n" + le32(uint32_t(g.vertices())) + le32(uint32_t(g.faces())) + le32(0);
  for (int i = 0; i < g.vertices(); ++i) s += lef(g.x(i)) + lef(g.y(i)) + lef(g.z(i));
  g.each_face([&](int a, int b, int c) {
    s += le32(3) + le32(uint32_t(a)) + le32(uint32_t(b)) + le32(uint32_t(c));
  });
  return s;
}

std::string ascii_stl(const Grid& g) {
  std::string s = "solid grid\n";
  g.each_face([&](int a, int b, int c) {
    s += "  facet normal 0 0 1\n    outer loop\n";
    for (int v : {a, b, c})
      s += "      vertex " + text(g.x(v)) + " " + text(g.y(v)) + " " + text(g.z(v)) + "\n";
    s += "    endloop\n  endfacet\n";
  });
  return s + "endsolid grid\n";
}

std::string binary_stl(const Grid& g) {
  std::string s(80, ' ');
  s += le32(uint32_t(g.faces()));
  g.each_face([&](int a, int b, int c) {
    s += lef(0) + lef(0) + lef(1);
    for (int v : {a, b, c}) s += lef(g.x(v)) + lef(g.y(v)) + lef(g.z(v));
    s += std::string(2, '\0');
  });
  return s;
}

struct Sample {
  std::string name, bytes;
  bool truncation_refused;  // every proper prefix is refused (the format states its counts)
};

std::vector<Sample> samples(const Grid& g) {
  return {{"grid.ply", ascii_ply(g), false},
          {"grid-le.ply", binary_ply(g, false), true},
          {"grid-be.ply", binary_ply(g, true), true},
          {"grid.obj", obj(g), false},
          {"grid.off", off(g), false},
          {"grid-binary.off", binary_off(g), true},
          {"grid-ascii.stl", ascii_stl(g), false},
          {"grid.stl", binary_stl(g), true}};
}

TEST(MeshStream, AnyWindowReadsTheSoupOfMemory) {
  TempDir tmp;
  for (const Sample& s : samples(Grid{6}))
    for (size_t window : {1, 2, 3, 5, 7, 11, 16, 61, 256, 4096}) {
      EXPECT_TRUE(expect_stream_as_memory(tmp, s.name, s.bytes, window)) << s.name;
      EXPECT_TRUE(expect_stream_as_memory(tmp, s.name, s.bytes, window, Via::pipe)) << s.name;
    }
}

TEST(MeshStream, AFileCutAtAnyByteGivesTheErrorOfMemory) {
  TempDir tmp;
  for (const Sample& s : samples(Grid{3}))
    for (size_t cut = 0; cut < s.bytes.size(); ++cut)
      for (size_t window : {1, 7, 64})
        for (Via via : {Via::memory_file, Via::pipe}) {
          const bool ok = expect_stream_as_memory(tmp, s.name, s.bytes.substr(0, cut), window, via);
          if (s.truncation_refused) {
            EXPECT_FALSE(ok) << s.name << " cut at " << cut;
          }
        }
}

TEST(MeshStream, TheFuzzRegressionsReadAsFromMemory) {
  TempDir tmp;
  const fs::path dir = fs::path(PMZ_SOURCE_DIR) / "tests" / "data" / "fuzz-regressions";
  int read = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".ply" && ext != ".obj" && ext != ".off" && ext != ".stl") continue;
    std::ifstream in(entry.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    for (size_t window : {1, 3, 64})
      for (Via via : {Via::disk, Via::pipe})
        expect_stream_as_memory(tmp, entry.path().filename().string(), bytes, window, via);
    ++read;
  }
  EXPECT_GT(read, 0);
}

// Larger than the default window (kReadWindow): read_polygon_soup by path streams it.
TEST(MeshStream, AFileLargerThanTheWindowReadsAsFromMemory) {
  TempDir tmp;
  const Grid g{300};
  for (const std::string& bytes : {ascii_ply(g), binary_ply(g, false)}) {
    ASSERT_GT(bytes.size(), pmz::kReadWindow);
    const std::string path = tmp.write("large.ply", bytes);
    pmz::PolygonSoup memory, streamed;
    std::string error;
    ASSERT_TRUE(pmz::parse_polygon_soup(path, bytes, memory, error)) << error;
    ASSERT_TRUE(pmz::read_polygon_soup(path, streamed, error)) << error;
    EXPECT_EQ(streamed.face_count(), uint32_t(g.faces()));
    expect_same_soup(streamed, memory);
    // Cut inside the last face (a corner short): one line naming the file.
    const std::string cut = tmp.write("cut.ply", bytes.substr(0, bytes.size() - 10));
    EXPECT_FALSE(pmz::read_polygon_soup(cut, streamed, error));
    EXPECT_EQ(error.rfind(cut + ": ", 0), 0u) << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  }
}

// Larger than the default window, through a pipe (popen, as a shell pipeline gives it): the soup
// of the file, in every format; cut inside its last record, the error of the cut file.
TEST(MeshStream, APipeLargerThanTheWindowReadsAsAFile) {
  TempDir tmp;
  for (const Sample& s : samples(Grid{300})) {
    ASSERT_GT(s.bytes.size(), pmz::kReadWindow) << s.name;
    for (const std::string& bytes : {s.bytes, s.bytes.substr(0, s.bytes.size() - 10)}) {
      const std::string path = tmp.write(s.name, bytes);
      pmz::PolygonSoup from_file, piped;
      std::string file_error, pipe_error;
      const bool file_ok = pmz::read_polygon_soup(path, from_file, file_error);
      std::FILE* pipe = ::popen(("cat '" + path + "'").c_str(), "r");
      ASSERT_NE(pipe, nullptr);
      const bool pipe_ok = pmz::read_polygon_soup(path, pipe, piped, pipe_error);
      ::pclose(pipe);
      EXPECT_EQ(pipe_ok, file_ok) << s.name << ": " << pipe_error;
      EXPECT_EQ(pipe_error, file_error) << s.name;
      if (bytes.size() == s.bytes.size()) {
        EXPECT_TRUE(file_ok) << s.name << ": " << file_error;
        EXPECT_EQ(from_file.face_count(), uint32_t(Grid{300}.faces())) << s.name;
      }
      if (file_ok && pipe_ok) expect_same_soup(piped, from_file);
    }
  }
}

// Headers declaring billions of entries over a few bytes of data, through a pipe, in a child
// process whose address space is limited to 256 MB more than it has: each is refused with the
// error the same bytes give from memory, without allocating for its counts (an allocation of
// what a count asks fails in the child).
TEST(MeshStream, AHostileHeaderThroughAPipeAllocatesNothingForItsCounts) {
  TempDir tmp;
  const std::string vertex = lef(0) + lef(0) + lef(0);
  std::string stl(80, ' ');
  stl += le32(0xFFFFFFFFu) + std::string(50 * 20, '\0');
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"huge-le.ply",
       "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
       "property float y\nproperty float z\nproperty float nx\nproperty float ny\n"
       "property float nz\nelement face 4000000000\nproperty list uchar uint vertex_indices\n"
       "end_header\n" +
           vertex + vertex + vertex},
      {"huge-faces.ply",
       "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
       "property float y\nproperty float z\nelement face 4000000000\n"
       "property list uchar uint vertex_indices\nend_header\n" +
           vertex + vertex + vertex + "\3" + le32(0) + le32(1) + le32(2)},
      {"huge-list.ply",
       "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
       "property float y\nproperty float z\nelement face 1\n"
       "property list uint uint vertex_indices\nend_header\n" +
           vertex + vertex + vertex + le32(0xFFFFFFF0u) + le32(0) + le32(1) + le32(2)},
      {"huge.ply",
       "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\n"
       "property float z\nelement face 4000000000\nproperty list uchar int vertex_indices\n"
       "end_header\n0 0 0\n1 0 0\n0 1 0\n"},
      {"huge.off", "OFF\n4000000000 4000000000 0\n0 0 0\n1 0 0\n0 1 0\n"},
      {"huge-binary.off", "OFF BINARY\n" + le32(0x7FFFFFFF) + le32(0x7FFFFFFF) + le32(0) + vertex},
      {"huge.stl", stl},
      {"huge.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 4000000000\n"}};
  for (const auto& [name, bytes] : cases) {
    const std::string path = tmp.path(name);
    pmz::PolygonSoup soup;
    std::string memory_error;
    EXPECT_FALSE(pmz::parse_polygon_soup(path, bytes, soup, memory_error)) << name;
    ASSERT_FALSE(memory_error.empty()) << name;
    std::fflush(nullptr);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      // 0: the memory error; 1: another error; 2: read; 3: no limit could be set; 4: an
      // allocation failed.
      long pages = 0;
      std::FILE* statm = std::fopen("/proc/self/statm", "r");
      if (!statm || std::fscanf(statm, "%ld", &pages) != 1) ::_exit(3);
      std::fclose(statm);
      const rlim_t limit = rlim_t(pages) * rlim_t(::sysconf(_SC_PAGESIZE)) + (rlim_t(256) << 20);
      const rlimit as{limit, limit};
      if (::setrlimit(RLIMIT_AS, &as) != 0) ::_exit(3);
      try {
        PipeFeed feed(bytes);
        pmz::PolygonSoup piped;
        std::string error;
        const bool ok = pmz::read_polygon_soup(path, feed.file(), piped, error);
        ::_exit(ok ? 2 : error == memory_error ? 0 : 1);
      } catch (const std::bad_alloc&) {
        ::_exit(4);
      }
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status)) << name << ": the child ended by signal " << WTERMSIG(status);
    EXPECT_EQ(WEXITSTATUS(status), 0) << name << ": expected \"" << memory_error << "\"";
  }
}

}  // namespace
