// SPDX-License-Identifier: MIT
// Mesh file input/output: every format, every refusal, atomic and checked writes.
#include <signal.h>
#include <sys/resource.h>

#include <bit>
#include <cmath>
#include <cstring>

#include "test_mesh_input_util.hpp"

#if defined(__SANITIZE_ADDRESS__)
#define PMZ_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PMZ_ASAN 1
#endif
#endif

namespace fs = std::filesystem;
using pmz_test::manifold_problem;
using pmz_test::TempDir;

namespace {

// The open unit square as two triangles, in every format.
const std::vector<float> kSquare = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
const std::vector<uint32_t> kSquareFaces = {0, 1, 2, 0, 2, 3};

std::string le32(uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); }
std::string be32(uint32_t v) {
  std::string s = le32(v);
  return std::string(s.rbegin(), s.rend());
}
std::string lef(float f) { return le32(std::bit_cast<uint32_t>(f)); }
std::string bef(float f) { return be32(std::bit_cast<uint32_t>(f)); }

std::string binary_ply(bool big, const std::vector<float>& p, const std::vector<uint32_t>& tris) {
  auto u = big ? be32 : le32;
  auto f = big ? bef : lef;
  std::string s =
      std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
      " 1.0\nelement vertex " + std::to_string(p.size() / 3) +
      "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
      "element face " +
      std::to_string(tris.size() / 3) + "\nproperty list uchar int vertex_indices\nend_header\n";
  for (size_t v = 0; v < p.size() / 3; ++v)
    s += f(p[v * 3]) + f(p[v * 3 + 1]) + f(p[v * 3 + 2]) + char(200);
  for (size_t t = 0; t < tris.size() / 3; ++t)
    s += char(3) + u(tris[t * 3]) + u(tris[t * 3 + 1]) + u(tris[t * 3 + 2]);
  return s;
}

std::string binary_stl(const std::vector<float>& p, const std::vector<uint32_t>& tris) {
  std::string s(80, ' ');
  s += le32(uint32_t(tris.size() / 3));
  for (size_t t = 0; t < tris.size() / 3; ++t) {
    s += lef(0) + lef(0) + lef(1);
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) s += lef(p[tris[t * 3 + k] * 3 + d]);
    s += std::string(2, '\0');
  }
  return s;
}

pmz::IndexedMesh read_ok(const std::string& path) {
  pmz::IndexedMesh m;
  pmz::MeshRepairStats st;
  std::string err;
  EXPECT_TRUE(pmz::read_mesh(path, m, st, err)) << err;
  return m;
}

// Reads the unit square exactly.
void expect_square(const std::string& path) {
  auto m = read_ok(path);
  EXPECT_EQ(m.positions, kSquare) << path;
  EXPECT_EQ(m.indices, kSquareFaces) << path;
}

// Refused, with a one-line message containing `what`.
using pmz_test::expect_refused;

}  // namespace

// ---- each format ----

TEST(MeshIO, ReadsOffAndTriangulatesQuads) {
  TempDir dir;
  auto m = read_ok(dir.write("quad.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"));
  EXPECT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.face_count(), 2u);
}

TEST(MeshIO, ReadsOffVariantsWithCommentsColoursAndInlineCounts) {
  TempDir dir;
  expect_square(
      dir.write("c.off",
                "# comment\nCOFF 4 2 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n\n1 1 0 1 1 1 1 # c\n"
                "0 1 0 0 0 0 0\n3 0 1 2 255 0 0\n3 0 2 3\n"));
}

TEST(MeshIO, ReadsObjWithSlashesNegativeIndicesAndIgnoredRecords) {
  TempDir dir;
  expect_square(
      dir.write("s.obj",
                "# square\nmtllib x.mtl\no sq\nv 0 0 0\nv 1 0 0\nvt 0 0\nvn 0 0 1\nv 1 1 0\n"
                "f 1/1/1 2/1/1 3//1\nv 0 1 0\r\nf -4 -2 -1\r\nl 1 2\n"));
}

TEST(MeshIO, ReadsAsciiPly) {
  TempDir dir;
  expect_square(
      dir.write("a.ply",
                "ply\nformat ascii 1.0\ncomment hi\nelement vertex 4\nproperty float x\n"
                "property float y\nproperty float z\nelement face 1\n"
                "property list uchar int vertex_indices\nelement edge 1\nproperty int vertex1\n"
                "property int vertex2\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n0 1\n"));
}

TEST(MeshIO, ReadsPlyWithFreeTextHeaderLines) {
  // Blender 2.47's exporter writes "Created by Blender3D ..." without "comment" (assimp's
  // Wuson.ply).
  TempDir dir;
  expect_square(
      dir.write("blender.ply",
                "ply\nformat ascii 1.0\nCreated by Blender3D 247 - www.blender.org, source file: \n"
                "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"));
}

TEST(MeshIO, ReadsBinaryPlyBothEndians) {
  TempDir dir;
  for (bool big : {false, true}) {
    expect_square(dir.write(big ? "be.ply" : "le.ply", binary_ply(big, kSquare, kSquareFaces)));
  }
}

TEST(MeshIO, ReadsBinaryStlAndWeldsCorners) {
  TempDir dir;
  auto m = read_ok(dir.write("b.stl", binary_stl(kSquare, kSquareFaces)));
  EXPECT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.positions, kSquare);
  EXPECT_EQ(m.indices, kSquareFaces);
}

TEST(MeshIO, ReadsBinaryStlWhoseHeaderStartsWithSolid) {
  TempDir dir;
  std::string s = binary_stl(kSquare, kSquareFaces);
  s.replace(0, 5, "solid");
  EXPECT_EQ(read_ok(dir.write("solid.stl", s)).indices, kSquareFaces);
}

TEST(MeshIO, ReadsAsciiStl) {
  TempDir dir;
  expect_square(dir.write(
      "a.stl",
      "solid sq\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\n"
      "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 -0\nvertex 1 1 0\n"
      "vertex 0 1 0\nendloop\nendfacet\nendsolid sq\n"));
}

// ---- refusals ----

TEST(MeshIO, RefusesMissingFile) { expect_refused("/nonexistent/x.off", "no such file"); }

TEST(MeshIO, RefusesEmptyFileInEveryFormat) {
  TempDir dir;
  for (const char* ext : {".obj", ".off", ".ply", ".stl"})
    expect_refused(dir.write(std::string("e") + ext, ""), "empty file");
  expect_refused(dir.write("blank.off", "\n# nothing\n\n"), "empty file");
}

TEST(MeshIO, RefusesUnknownFormatAndUnreadableFiles) {
  TempDir dir;
  expect_refused(dir.write("m.xyz", "1 2 3\n"), "unknown mesh format '.xyz'");
  expect_refused(dir.write("noext", "OFF\n"), "unknown mesh format");
  fs::create_directories(dir.path("d.off"));
  expect_refused(dir.path("d.off"), "is a directory");
  expect_refused(dir.write("g.off", "hello world\n"), "not an OFF file");
  expect_refused(dir.write("g.ply", "\x01\x02garbage"), "not a PLY file");
  expect_refused(dir.write("g.stl", "garbage"), "not an STL file");
  expect_refused(dir.write("b.off", "OFF BINARY\n"), "binary OFF ends inside its counts");
  if (::geteuid() != 0) {  // root reads anything
    auto p = dir.write("locked.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    fs::permissions(p, fs::perms::none);
    expect_refused(p, "cannot open");
  }
}

TEST(MeshIO, RefusesFilesWithoutFaces) {
  TempDir dir;
  expect_refused(dir.write("v.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "mesh has no faces");
  expect_refused(dir.write("v.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"), "mesh has no faces");
  expect_refused(dir.write("d.obj", "v 0 0 0\nv 1 0 0\nf 1 2 2\nf 1 2\n"), "no usable faces");
  expect_refused(
      dir.write("v.ply",
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                "property float z\nend_header\n0 0 0\n"),
      "no face element");
}

TEST(MeshIO, RefusesNanAndInfCoordinatesNamingTheVertex) {
  TempDir dir;
  expect_refused(dir.write("n.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"),
                 "vertex 1 (line 2) has a NaN");
  expect_refused(dir.write("i.obj", "v 0 0 0\nv 1 0 0\nv 0 -inf 0\nf 1 2 3\n"),
                 "vertex 2 (line 3)");
  expect_refused(dir.write("big.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n"),
                 "vertex 1 (line 2)");
  expect_refused(dir.write("n.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 NaN 0\n3 0 1 2\n"),
                 "vertex 2 (line 5) has a NaN");
  expect_refused(
      dir.write("n.ply",
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                "end_header\n0 0 0\ninf 0 0\n0 1 0\n3 0 1 2\n"),
      "vertex 1 has a NaN");
  expect_refused(dir.write("b.ply", binary_ply(false, {0, 0, 0, 1, 0, 0, 0, NAN, 0}, {0, 1, 2})),
                 "vertex 2 has a NaN");
  expect_refused(dir.write("n.stl", binary_stl({0, 0, 0, 1, 0, 0, 0, INFINITY, 0}, {0, 1, 2})),
                 "facet 0 has a NaN");
}

TEST(MeshIO, RefusesOutOfRangeIndicesNamingTheFace) {
  TempDir dir;
  // OBJ: the index as the file writes it (1-based or counting back), and its line.
  expect_refused(dir.write("o.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n"),
                 "o.obj: line 5: face references vertex 9, but the file has 3 vertices");
  expect_refused(dir.write("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n"),
                 "neg.obj: line 4: face references vertex -4, but only 3 vertices precede it");
  const std::string six = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 0 0\nv 2 1 0\n";
  expect_refused(dir.write("seven.obj", six + "f 1 2 7\n"),
                 "seven.obj: line 7: face references vertex 7, but the file has 6 vertices");
  expect_refused(dir.write("back.obj", six + "f 1 2 -9\n"),
                 "back.obj: line 7: face references vertex -9, but only 6 vertices precede it");
  expect_refused(dir.write("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"),
                 "face 0 has a malformed index '0'");
  expect_refused(dir.write("o.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 3\n"),
                 "face 1 (line 7) references vertex 3");
  expect_refused(dir.write("m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n"),
                 "references vertex -1");
  expect_refused(dir.write("o.ply", binary_ply(false, kSquare, {0, 1, 2, 0, 2, 4})),
                 "face 1 references vertex 4");
}

TEST(MeshIO, RefusesTruncatedAndMalformedData) {
  TempDir dir;
  expect_refused(dir.write("t.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n"),
                 "file ends after 2 of 4 vertices");
  expect_refused(dir.write("f.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                 "file ends after 1 of 2 faces");
  expect_refused(dir.write("c.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n5 0 1 2\n"),
                 "declares 5 corners but has only 3");
  expect_refused(dir.write("x.obj", "v 0 zero 0\n"),
                 "line 1: vertex needs three numeric coordinates");
  std::string ply = binary_ply(false, kSquare, kSquareFaces);
  expect_refused(dir.write("t.ply", ply.substr(0, ply.size() - 5)), "PLY data ends");
  std::string stl = binary_stl(kSquare, kSquareFaces);
  expect_refused(dir.write("t.stl", stl.substr(0, stl.size() - 10)),
                 "declares 2 triangles but holds only 1");
  expect_refused(dir.write("t2.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"),
                 "file ends inside facet 0");
}

// Exits 0 when both files are refused while the address space is capped at 512 MB.
[[noreturn]] void read_under_memory_cap(const std::string& a, const std::string& b) {
  rlimit cap{512u << 20, 512u << 20};
  setrlimit(RLIMIT_AS, &cap);
  pmz::IndexedMesh m;
  std::string err;
  bool refused = !pmz::read_mesh(a, m, err) && !pmz::read_mesh(b, m, err);
  std::exit(refused ? 0 : 1);
}

// A header claiming huge counts is refused once the data runs out, without first allocating
// what it claims: run under an address-space cap far below the claimed size.
TEST(MeshIO, HugeDeclaredCountsDoNotAllocate) {
  TempDir dir;
  auto off = dir.write("huge.off", "OFF\n9000000000 9000000000 0\n0 0 0\n");
  auto off2 = dir.write("huge2.off", "OFF\n200000000 200000000 0\n0 0 0\n1 0 0\n");
  auto ply =
      dir.write("huge.ply",
                "ply\nformat binary_little_endian 1.0\nelement vertex 200000000\nproperty float x\n"
                "property float y\nproperty float z\nelement face 1\n"
                "property list uchar int vertex_indices\nend_header\n" +
                    std::string(24, '\0'));
  auto ply2 = dir.write("huge_list.ply",
                        "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
                        "property float y\nproperty float z\nelement face 1\n"
                        "property list uint int vertex_indices\nend_header\n" +
                            std::string(12, '\0') + le32(0xFFFFFFFFu) + std::string(8, '\0'));
  auto ply3 = dir.write("huge.stl", std::string(80, ' ') + le32(300000000) + std::string(50, '\0'));
  auto empty_element = dir.write("empty_element.ply",
                                 "ply\nformat ascii 1.0\nelement junk 9000000000000000000\n"
                                 "element vertex 3\nproperty float x\nproperty float y\n"
                                 "property float z\nelement face 1\n"
                                 "property list uchar int vertex_indices\nend_header\n"
                                 "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(read_ok(empty_element).face_count(),
            1u);  // an element without properties holds nothing
  expect_refused(off, "declares 9000000000 vertices, more than supported");
  expect_refused(off2, "file ends after 2 of 200000000 vertices");
  expect_refused(ply, "declares 200000000 entries, more than the file holds");
  expect_refused(ply2, "PLY data ends");
  expect_refused(ply3, "declares 300000000 triangles but holds only 1");
#ifndef PMZ_ASAN  // ASan reserves terabytes of shadow memory, so no address-space cap
  // 200M vertices would need 2.4 GB; a 512 MB cap makes any such allocation throw or abort.
  EXPECT_EXIT(read_under_memory_cap(off2, ply), testing::ExitedWithCode(0), "");
#endif
}

// ---- writing ----

TEST(MeshIO, WriteThenReadRoundTripsExactlyInEveryFormat) {
  // A non-manifold fin plus an isolated vertex, with coordinates that need all float digits.
  pmz::IndexedMesh m;
  m.positions = {0.1f, 0,  0, 1, 1e-7f, 0, 0,           1,    3.14159274f,
                 0,    -1, 0, 0, 0,     1, 123456.789f, -0.f, 1e30f};
  m.indices = {0, 1, 2, 1, 0, 3, 0, 1, 4};
  TempDir dir;
  for (const char* ext : {".obj", ".off", ".ply"}) {
    std::string p = dir.path(std::string("m") + ext);
    std::string err;
    ASSERT_TRUE(pmz::write_mesh(p, m, err)) << err;
    pmz::PolygonSoup r;
    ASSERT_TRUE(pmz::read_polygon_soup(p, r, err)) << err;
    EXPECT_EQ(std::memcmp(r.positions.data(), m.positions.data(), m.positions.size() * 4), 0)
        << ext;
    EXPECT_EQ(r.positions.size(), m.positions.size()) << ext;
    EXPECT_EQ(r.corners, m.indices) << ext;
  }
  // STL keeps the triangles (welded corners), not isolated vertices.
  std::string err;
  ASSERT_TRUE(pmz::write_mesh(dir.path("m.stl"), m, err)) << err;
  auto r = read_ok(dir.path("m.stl"));
  EXPECT_EQ(r.face_count(), 3u);
  EXPECT_EQ(manifold_problem(r), "");
  for (auto& e : fs::directory_iterator(dir.dir))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos);
}

TEST(MeshIO, WriteReplacesAnExistingFileAtomically) {
  TempDir dir;
  auto p = dir.write("m.off", "old");
  pmz::IndexedMesh m;
  m.positions = kSquare;
  m.indices = kSquareFaces;
  std::string err;
  ASSERT_TRUE(pmz::write_mesh(p, m, err)) << err;
  EXPECT_EQ(read_ok(p).indices, kSquareFaces);
}

TEST(MeshIO, WriteThroughASymlinkUpdatesItsTarget) {
  // The library writes as the tools do (one OutputFile): the link stays a link.
  TempDir dir;
  auto target = dir.write("real.off", "old");
  const std::string link = dir.path("link.off");
  fs::create_symlink("real.off", link);
  pmz::IndexedMesh m;
  m.positions = kSquare;
  m.indices = kSquareFaces;
  std::string err;
  ASSERT_TRUE(pmz::write_mesh(link, m, err)) << err;
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(read_ok(target).indices, kSquareFaces);
}

TEST(MeshIO, WriteErrorsLeaveNoFile) {
  TempDir dir;
  pmz::IndexedMesh m;
  m.positions = kSquare;
  m.indices = kSquareFaces;
  std::string err;
  EXPECT_FALSE(pmz::write_mesh(dir.path("missing/m.obj"), m, err));
  EXPECT_NE(err.find("No such file or directory"), std::string::npos) << err;
  EXPECT_FALSE(pmz::write_mesh(dir.path("m.xyz"), m, err));
  EXPECT_NE(err.find("unknown mesh format"), std::string::npos) << err;
  m.indices.push_back(9), m.indices.push_back(0), m.indices.push_back(1);
  EXPECT_FALSE(pmz::write_mesh(dir.path("bad.obj"), m, err));
  EXPECT_NE(err.find("references vertex 9"), std::string::npos) << err;
  EXPECT_TRUE(fs::is_empty(dir.dir));
}

// Exits 0 when writing fails with a one-line message under a 4 KB file-size limit.
[[noreturn]] void write_under_size_cap(const std::string& target, const pmz::IndexedMesh& m) {
  signal(SIGXFSZ, SIG_IGN);
  rlimit cap{4096, 4096};
  setrlimit(RLIMIT_FSIZE, &cap);
  std::string err;
  bool failed = !pmz::write_mesh(target, m, err) && err.find("cannot write") != std::string::npos &&
                err.find('\n') == std::string::npos;
  std::exit(failed ? 0 : 1);
}

TEST(MeshIO, DiskFullLeavesNoPartialFile) {
  // A file-size limit makes write() fail with EFBIG like a full disk; the temporary is removed.
  TempDir dir;
  pmz::IndexedMesh m;
  for (int i = 0; i < 20000; ++i)
    m.positions.insert(m.positions.end(), {float(i) * 0.1234567f, 1.f, 2.f});
  for (uint32_t i = 0; i + 2 < 20000; ++i) m.indices.insert(m.indices.end(), {i, i + 1, i + 2});
  std::string target = dir.path("full.ply");
  EXPECT_EXIT(write_under_size_cap(target, m), testing::ExitedWithCode(0), "");
  EXPECT_TRUE(fs::is_empty(dir.dir));
}
