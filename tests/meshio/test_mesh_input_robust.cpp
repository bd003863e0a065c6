// SPDX-License-Identifier: MIT
// Corrupted input never crashes the readers, and real meshes come through without losing a face.
#include <bit>
#include <cmath>
#include <cstdlib>
#include <random>

#include "test_mesh_input_util.hpp"

using pmz_test::manifold_problem;
using pmz_test::TempDir;
namespace fs = std::filesystem;

namespace {

// Either a valid manifold mesh with in-range indices, or a refusal on one line.
void expect_read_or_refused(const std::string& path, const std::string& context) {
  pmz::IndexedMesh m;
  pmz::MeshRepairStats st;
  std::string err;
  if (pmz::read_mesh(path, m, st, err)) {
    ASSERT_GT(m.face_count(), 0u) << context;
    for (uint32_t i : m.indices) ASSERT_LT(i, m.vertex_count()) << context;
    for (float x : m.positions) ASSERT_TRUE(std::isfinite(x)) << context;
    ASSERT_EQ(manifold_problem(m), "") << context;
  } else {
    ASSERT_FALSE(err.empty()) << context;
    ASSERT_EQ(err.find('\n'), std::string::npos) << context << ": " << err;
  }
}

std::string le32(uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); }

}  // namespace

TEST(MeshInputRobust, MutatedFilesAreReadOrRefusedNeverCrash) {
  // A small non-manifold mesh (fin + bowtie) in every format.
  const char* obj =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv -1 -1 0\nv -1 -2 0\n"
      "f 1 2 3\nf 2 1 4\nf 1 2 5\nf 1 6 7 3\n";
  const char* off =
      "OFF\n7 4 0\n0 0 0\n1 0 0\n0 1 0\n0 -1 0\n0 0 1\n-1 -1 0\n-1 -2 0\n"
      "3 0 1 2\n3 1 0 3\n3 0 1 4\n4 0 5 6 2\n";
  std::string ply_head =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n"
      "property float y\nproperty float z\nelement face 2\n"
      "property list uchar int vertex_indices\nend_header\n";
  std::string ply = ply_head;
  for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f})
    ply += le32(std::bit_cast<uint32_t>(v));
  for (uint32_t f : {0u, 1u, 2u, 0u, 1u, 3u}) {
    if (f == 0) ply += char(3);
    ply += le32(f);
  }
  std::string stl(80, ' ');
  stl += le32(2);
  for (int t = 0; t < 2; ++t) {
    stl += std::string(12, '\0');
    for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, float(t), 0.f, 1.f, 0.f})
      stl += le32(std::bit_cast<uint32_t>(v));
    stl += std::string(2, '\0');
  }
  const char* stl_ascii =
      "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
      "endloop\nendfacet\nendsolid s\n";
  const std::pair<const char*, std::string> seeds[] = {
      {".obj", obj}, {".off", off}, {".ply", ply}, {".stl", stl}, {".stl", stl_ascii}};

  TempDir dir;
  std::mt19937 rng(12345);
  const char pieces[] = "0123456789 \n-+.eEnaif/#\xff";
  for (const auto& [ext, seed] : seeds) {
    expect_read_or_refused(dir.write(std::string("seed") + ext, seed), "seed");
    for (int round = 0; round < 200; ++round) {
      std::string s = seed;
      int edits = 1 + int(rng() % 4);
      for (int e = 0; e < edits && !s.empty(); ++e) {
        size_t at = rng() % s.size();
        switch (rng() % 4) {
          case 0:
            s[at] = pieces[rng() % (sizeof pieces - 1)];
            break;
          case 1:
            s.insert(at, 1, pieces[rng() % (sizeof pieces - 1)]);
            break;
          case 2:
            s.erase(at, 1 + rng() % 8);
            break;
          default:
            s[at] = char(rng());
            break;
        }
      }
      if (rng() % 8 == 0) s.resize(rng() % (s.size() + 1));
      expect_read_or_refused(dir.write(std::string("m") + ext, s),
                             std::string(ext) + " round " + std::to_string(round));
    }
  }
}

TEST(MeshInputRobust, CorpusMeshesKeepEveryFace) {
  const char* env = std::getenv("PMZ_CORPUS");
  fs::path corpus = env ? fs::path(env) : fs::path(PMZ_SOURCE_DIR) / "corpus";
  std::error_code ec;
  if (!fs::is_directory(corpus, ec)) {
    // scripts/test.sh sets PMZ_REQUIRE_CORPUS once it fetched the corpus: a failure then.
    if (const char* r = std::getenv("PMZ_REQUIRE_CORPUS"); r && *r && std::string(r) != "0")
      FAIL() << "no corpus at " << corpus;
    GTEST_SKIP() << "no corpus at " << corpus << " (scripts/fetch_corpus.sh)";
  }
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(corpus)) {
    // Small meshes only: the manifold check here is a slow reference implementation.
    if (entry.path().extension() != ".off" || entry.file_size() > (2u << 20)) continue;
    pmz::PolygonSoup soup;
    std::string err;
    ASSERT_TRUE(pmz::read_polygon_soup(entry.path().string(), soup, err)) << err;
    pmz::IndexedMesh m;
    pmz::MeshRepairStats st;
    pmz::repair_mesh(soup, m, st);
    uint64_t triangles = 0;
    for (uint32_t f = 0; f < soup.face_count(); ++f)
      triangles += soup.face_offsets[f + 1] - soup.face_offsets[f] - 2;
    EXPECT_EQ(m.face_count(), triangles - st.degenerate_faces_dropped) << entry.path();
    EXPECT_EQ(manifold_problem(m), "") << entry.path();
    ++checked;
  }
  if (checked == 0) GTEST_SKIP() << "no small .off meshes in " << corpus;
}
