// SPDX-License-Identifier: MIT
// The collapse engine: every recorded collapse replays exactly as the contract says, topology
// is preserved at every step, targets are met, bad input is refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "pmz/compare.hpp"
#include "pmz/simplify.hpp"
#include "simplify_test_meshes.hpp"

using pmz_test::topology;

namespace {

using Face = std::array<uint32_t, 3>;

// The face rotated so its smallest vertex comes first (same cyclic order, same orientation).
Face canonical(Face f) {
  while (f[0] > f[1] || f[0] > f[2]) f = {f[1], f[2], f[0]};
  return f;
}

std::vector<Face> sorted_faces(const std::vector<uint32_t>& indices) {
  std::vector<Face> faces;
  for (size_t i = 0; i < indices.size(); i += 3)
    faces.push_back(canonical({indices[i], indices[i + 1], indices[i + 2]}));
  std::sort(faces.begin(), faces.end());
  return faces;
}

// Replays the sequence literally as the contract states it: collapse i replaces u by v in all
// faces and deletes the faces holding both, which must be exactly (u, v, vl) and (v, u, vr).
// Checks topology after every `check_every` collapses; returns the final faces.
std::vector<uint32_t> replay(const pmz::CollapseSequence& seq, size_t check_every) {
  std::vector<uint32_t> faces = seq.mesh.indices;
  const auto start = topology(seq.mesh);
  const bool failed_before = ::testing::Test::HasFailure();
  std::vector<char> removed(seq.mesh.vertex_count(), 0);
  for (size_t i = 0; i < seq.collapses.size(); ++i) {
    const auto& c = seq.collapses[i];
    EXPECT_FALSE(removed[c.u]) << "collapse " << i << " removes a vertex twice";
    EXPECT_FALSE(removed[c.v]) << "collapse " << i << " keeps a removed vertex";
    removed[c.u] = 1;
    std::vector<Face> deleted;
    std::vector<uint32_t> kept;
    for (size_t f = 0; f < faces.size(); f += 3) {
      Face t{faces[f], faces[f + 1], faces[f + 2]};
      const bool has_u = std::count(t.begin(), t.end(), c.u),
                 has_v = std::count(t.begin(), t.end(), c.v);
      if (has_u && has_v) {
        deleted.push_back(canonical(t));
        continue;
      }
      for (uint32_t& x : t) x = x == c.u ? c.v : x;
      kept.insert(kept.end(), t.begin(), t.end());
    }
    std::vector<Face> expected;
    if (c.vl != pmz::kNoVertex) expected.push_back(canonical({c.u, c.v, c.vl}));
    if (c.vr != pmz::kNoVertex) expected.push_back(canonical({c.v, c.u, c.vr}));
    std::sort(deleted.begin(), deleted.end());
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(deleted, expected) << "collapse " << i << " (" << c.u << " -> " << c.v << ")";
    faces = std::move(kept);
    if ((i + 1) % check_every == 0 || i + 1 == seq.collapses.size()) {
      pmz::IndexedMesh now{seq.mesh.positions, faces};
      const auto t = topology(now);
      EXPECT_TRUE(t.manifold) << "after collapse " << i << ": " << t.error;
      EXPECT_EQ(t.euler, start.euler) << "after collapse " << i;
      EXPECT_EQ(t.boundary_loops, start.boundary_loops) << "after collapse " << i;
      if (!failed_before && ::testing::Test::HasFailure()) return faces;  // one report is enough
    }
  }
  return faces;
}

// target_reachable: the mesh can go down to target (+1 for parity) faces; a mesh with many
// holes cannot, every hole keeps at least three boundary edges.
void expect_valid_sequence(const pmz::IndexedMesh& mesh, pmz::Metric metric, uint64_t target,
                           size_t check_every, bool target_reachable = true) {
  pmz::SimplifyOptions options;
  options.metric = metric;
  options.target_faces = target;
  pmz::CollapseSequence seq;
  std::string error;
  ASSERT_TRUE(pmz::simplify(mesh, options, seq, error)) << error;
  ASSERT_FALSE(seq.collapses.empty());
  const std::vector<uint32_t> faces = replay(seq, check_every);
  EXPECT_EQ(sorted_faces(faces), sorted_faces(seq.base_indices));
  // mesh_after agrees with the literal replay, in compacted ids.
  const pmz::IndexedMesh after = pmz::mesh_after(seq, seq.collapses.size());
  EXPECT_EQ(after.face_count() * 3, seq.base_indices.size());
  EXPECT_EQ(after.vertex_count(), mesh.vertex_count() - seq.collapses.size());
  if (target && target_reachable) {
    EXPECT_LE(after.face_count(), target + 1);
  }
}

}  // namespace

TEST(Simplify, ClosedSphereEveryStepValid) {
  for (auto metric : {pmz::Metric::guarded, pmz::Metric::multifeature, pmz::Metric::qem})
    expect_valid_sequence(pmz_test::icosphere(3), metric, 0, 1);
}

TEST(Simplify, SphereGoesDownToATetrahedron) {
  pmz::CollapseSequence seq;
  std::string error;
  ASSERT_TRUE(pmz::simplify(pmz_test::icosphere(2), {}, seq, error)) << error;
  EXPECT_EQ(seq.base_indices.size(), 4u * 3);
}

// Two faces on the same three vertices, one each way round (a closed two-face component, as a
// glTF base mesh simplified again can be), stay as they are: collapsing one of their edges
// would delete both faces at once.
TEST(Simplify, ClosedTwoFaceComponentStays) {
  pmz::IndexedMesh mesh;
  mesh.positions = {0.6f, 0.8f, 0, -0.6f, 0, 0, -1, 0, 0};
  mesh.indices = {0, 1, 2, 1, 0, 2};
  for (auto metric : {pmz::Metric::guarded, pmz::Metric::multifeature, pmz::Metric::qem}) {
    pmz::SimplifyOptions options;
    options.metric = metric;
    pmz::CollapseSequence seq;
    std::string error;
    ASSERT_TRUE(pmz::simplify(mesh, options, seq, error)) << error;
    EXPECT_TRUE(seq.collapses.empty());
    EXPECT_EQ(sorted_faces(seq.base_indices), sorted_faces(mesh.indices));
  }
}

TEST(Simplify, TorusKeepsItsHandle) {
  const auto mesh = pmz_test::torus(24, 12);
  for (auto metric : {pmz::Metric::guarded, pmz::Metric::multifeature, pmz::Metric::qem})
    expect_valid_sequence(mesh, metric, 0, 1);
  pmz::CollapseSequence seq;
  std::string error;
  ASSERT_TRUE(pmz::simplify(mesh, {}, seq, error)) << error;
  EXPECT_EQ(topology(pmz::mesh_after(seq, seq.collapses.size())).euler, 0);
}

TEST(Simplify, GridWithBoundaryEveryStepValid) {
  for (auto metric : {pmz::Metric::guarded, pmz::Metric::multifeature, pmz::Metric::qem})
    expect_valid_sequence(pmz_test::grid(16), metric, 0, 1);
  // A flat disc goes down to a single triangle.
  pmz::CollapseSequence seq;
  std::string error;
  ASSERT_TRUE(pmz::simplify(pmz_test::grid(6), {}, seq, error)) << error;
  EXPECT_EQ(seq.base_indices.size(), 3u);
}

TEST(Simplify, HitsExactFaceCountWithBoundary) {
  // Odd targets need one boundary collapse at the end.
  for (uint64_t target : {101u, 100u, 37u}) {
    pmz::SimplifyOptions options;
    options.target_faces = target;
    pmz::CollapseSequence seq;
    std::string error;
    ASSERT_TRUE(pmz::simplify(pmz_test::grid(16), options, seq, error)) << error;
    EXPECT_EQ(seq.base_indices.size() / 3, target);
  }
}

// Two long thin planar strips meeting at a ridge (a CAD-like bent sheet): the exact
// simplification is 4 long needles, two per plane. Faces that stay in their plane may become
// needles, so the engine gets there with every vertex left at an end of the sheet, at no cost.
TEST(Simplify, BentSheetReachesItsFourExactFaces) {
  const uint32_t n = 128;
  pmz::IndexedMesh mesh;
  for (uint32_t i = 0; i <= n; ++i) {
    pmz_test::add_vertex(mesh, i, 0, 0);  // 3i: outer edge
    pmz_test::add_vertex(mesh, i, 1, 1);  // 3i + 1: ridge
    pmz_test::add_vertex(mesh, i, 2, 0);  // 3i + 2: other outer edge
  }
  for (uint32_t i = 0; i < n; ++i)
    for (uint32_t s = 0; s < 2; ++s) {
      const uint32_t a = 3 * i + s, b = a + 3, c = b + 1, d = a + 1;
      pmz_test::add_face(mesh, a, b, c);
      pmz_test::add_face(mesh, a, c, d);
    }
  for (auto metric : {pmz::Metric::qem, pmz::Metric::multifeature, pmz::Metric::guarded}) {
    pmz::SimplifyOptions options;
    options.metric = metric;
    options.target_faces = 4;
    // Every collapse on the way moves no surface, so none may cost anything under either
    // metric: the torsion at the ridge weights the quadric error, it adds nothing to zero.
    options.max_cost = 1e-6;
    pmz::CollapseSequence seq;
    std::string error;
    ASSERT_TRUE(pmz::simplify(mesh, options, seq, error)) << error;
    ASSERT_EQ(seq.base_indices.size(), 12u)
        << (metric == pmz::Metric::qem ? "qem" : "multifeature or guarded");
    for (uint32_t v : seq.base_indices) {
      const float x = mesh.positions[3 * size_t(v)];
      EXPECT_TRUE(x == 0 || x == float(n)) << "vertex " << v << " at x = " << x;
    }
  }
}

TEST(Simplify, ClosedMeshStopsWithinOneFaceOfTarget) {
  pmz::SimplifyOptions options;
  options.target_faces = 301;  // closed meshes have an even face count
  pmz::CollapseSequence seq;
  std::string error;
  ASSERT_TRUE(pmz::simplify(pmz_test::icosphere(3), options, seq, error)) << error;
  EXPECT_EQ(seq.base_indices.size() / 3, 302u);
}

TEST(Simplify, MeshAfterIntermediateLevels) {
  pmz::CollapseSequence seq;
  std::string error;
  const auto mesh = pmz_test::icosphere(3);
  ASSERT_TRUE(pmz::simplify(mesh, {}, seq, error)) << error;
  EXPECT_EQ(pmz::mesh_after(seq, 0).indices, mesh.indices);
  for (size_t k : {size_t(1), seq.collapses.size() / 2}) {
    const auto m = pmz::mesh_after(seq, k);
    EXPECT_EQ(m.vertex_count(), mesh.vertex_count() - k);
    EXPECT_EQ(m.face_count(), mesh.face_count() - 2 * k);  // closed: every collapse removes two
  }
}

TEST(Simplify, IsolatedVerticesStayInTheBase) {
  auto mesh = pmz_test::grid(4);
  pmz_test::add_vertex(mesh, 9, 9, 9);
  pmz::CollapseSequence seq;
  std::string error;
  ASSERT_TRUE(pmz::simplify(mesh, {}, seq, error)) << error;
  for (const auto& c : seq.collapses) EXPECT_NE(c.u, mesh.vertex_count() - 1);
}

TEST(Simplify, RefusesNonManifoldInput) {
  pmz::IndexedMesh fin;  // three triangles on one edge
  for (auto p : {std::array<float, 3>{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}})
    pmz_test::add_vertex(fin, p[0], p[1], p[2]);
  fin.indices = {0, 1, 2, 1, 0, 3, 0, 1, 4};
  pmz::CollapseSequence seq;
  std::string error;
  EXPECT_FALSE(pmz::simplify(fin, {}, seq, error));
  EXPECT_NE(error.find("non-manifold"), std::string::npos) << error;

  pmz::IndexedMesh bowtie;  // two triangles meeting at one vertex
  for (auto p : {std::array<float, 3>{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}})
    pmz_test::add_vertex(bowtie, p[0], p[1], p[2]);
  bowtie.indices = {0, 1, 2, 0, 3, 4};
  EXPECT_FALSE(pmz::simplify(bowtie, {}, seq, error));
  EXPECT_NE(error.find("non-manifold vertex"), std::string::npos) << error;

  pmz::IndexedMesh bad = pmz_test::grid(2);
  bad.indices[4] = 1000;
  EXPECT_FALSE(pmz::simplify(bad, {}, seq, error));
  EXPECT_NE(error.find("out of range"), std::string::npos) << error;
}

TEST(Simplify, MaxCostStopsEarly) {
  pmz::SimplifyOptions options;
  options.max_cost = 0;  // flat regions cost nothing under QEM; curved ones cost more
  options.metric = pmz::Metric::qem;
  pmz::CollapseSequence seq;
  std::string error;
  ASSERT_TRUE(pmz::simplify(pmz_test::icosphere(3), options, seq, error)) << error;
  EXPECT_TRUE(seq.collapses.empty());
  ASSERT_TRUE(pmz::simplify(pmz_test::grid(8), options, seq, error)) << error;
  EXPECT_FALSE(seq.collapses.empty());
  for (const auto& c : seq.collapses) EXPECT_LE(c.cost, 0.f);
}

// Real meshes of the corpus (libcgal-demo): both metrics, topology checked along the way.
TEST(Simplify, CorpusMeshesStayManifold) {
  bool any = false;
  for (const char* name : {"fandisk", "elephant-with-holes", "mushroom", "cow"}) {
    const std::string path = pmz_test::corpus_mesh(name);
    if (path.empty()) {
      if (pmz_test::corpus_required()) ADD_FAILURE() << name << " missing from the corpus";
      continue;
    }
    pmz::IndexedMesh mesh;
    std::string error;
    ASSERT_TRUE(pmz::read_mesh(path, mesh, error)) << error;
    any = true;
    SCOPED_TRACE(name);
    for (auto metric : {pmz::Metric::guarded, pmz::Metric::multifeature, pmz::Metric::qem})
      expect_valid_sequence(mesh, metric, mesh.face_count() / 50,
                            std::max<size_t>(1, mesh.vertex_count() / 40),
                            std::string(name) != "elephant-with-holes");
  }
  if (!any) GTEST_SKIP() << "no corpus meshes (set PMZ_CORPUS or run scripts/fetch_corpus.sh)";
}

// The guard is a stage on top of the paper's metric, not a change of its terms: when it never
// holds a collapse back (unbounded slack) the sequence is the paper's, collapse for collapse.
TEST(Simplify, GuardWithUnboundedSlackIsThePaperAlone) {
  for (const auto& mesh : {pmz_test::icosphere(3), pmz_test::torus(24, 12), pmz_test::grid(12)}) {
    pmz::SimplifyOptions paper, guarded;
    paper.metric = pmz::Metric::multifeature;
    guarded.metric = pmz::Metric::guarded;
    guarded.params.guard_slack = 1e30f;
    pmz::CollapseSequence a, b;
    std::string error;
    ASSERT_TRUE(pmz::simplify(mesh, paper, a, error)) << error;
    ASSERT_TRUE(pmz::simplify(mesh, guarded, b, error)) << error;
    ASSERT_EQ(a.collapses.size(), b.collapses.size());
    for (size_t i = 0; i < a.collapses.size(); ++i) {
      const auto &x = a.collapses[i], &y = b.collapses[i];
      ASSERT_TRUE(x.u == y.u && x.v == y.v && x.vl == y.vl && x.vr == y.vr && x.cost == y.cost)
          << "collapse " << i;
    }
    EXPECT_EQ(a.base_indices, b.base_indices);
  }
}

// A closed capsule around the z axis at (x, 0, 0): radius r, a cylinder from z = -half to half
// in `body` bands, hemispherical caps of `cap` bands, `segments` around; its vertices and faces
// appended to m.
void add_capsule(pmz::IndexedMesh& m, double x, double r, double half, uint32_t cap, uint32_t body,
                 uint32_t segments) {
  std::vector<std::array<double, 2>> ring;  // (radius, z) from the north pole to the south pole
  const double quarter = std::acos(0.0);
  for (uint32_t i = 0; i <= cap; ++i)
    ring.push_back({r * std::sin(quarter * i / cap), half + r * std::cos(quarter * i / cap)});
  for (uint32_t i = 1; i < body; ++i) ring.push_back({r, half - 2 * half * i / body});
  for (uint32_t i = 0; i <= cap; ++i)
    ring.push_back({r * std::cos(quarter * i / cap), -half - r * std::sin(quarter * i / cap)});
  const uint32_t first = m.vertex_count(), rings = uint32_t(ring.size()) - 2;
  for (uint32_t k = 1; k <= rings; ++k)
    for (uint32_t j = 0; j < segments; ++j) {
      const double a = 4 * quarter * j / segments;
      pmz_test::add_vertex(m, x + ring[k][0] * std::cos(a), ring[k][0] * std::sin(a), ring[k][1]);
    }
  const uint32_t north = m.vertex_count(), south = north + 1;
  pmz_test::add_vertex(m, x, 0, ring.front()[1]);
  pmz_test::add_vertex(m, x, 0, ring.back()[1]);
  auto at = [&](uint32_t k, uint32_t j) { return first + (k - 1) * segments + j % segments; };
  for (uint32_t j = 0; j < segments; ++j) {
    pmz_test::add_face(m, north, at(1, j), at(1, j + 1));
    pmz_test::add_face(m, south, at(rings, j + 1), at(rings, j));
    for (uint32_t k = 1; k < rings; ++k) {
      pmz_test::add_face(m, at(k, j), at(k + 1, j), at(k + 1, j + 1));
      pmz_test::add_face(m, at(k, j), at(k + 1, j + 1), at(k, j + 1));
    }
  }
}

// The guard on a small synthetic mesh, no corpus needed: a unit sphere beside two thin capsules
// (fingers). Their little area makes the paper's metric cheap on them, so at 10% and 5% of the
// faces it shortens or thins a finger and loses the worst case (measured: the Hausdorff
// distance 160e-4 and 240e-4 of the diagonal); the guard holds those collapses back (96e-4 and
// 160e-4) at the same face count.
TEST(Simplify, GuardLowersTheWorstCaseOfThinParts) {
  pmz::IndexedMesh mesh = pmz_test::icosphere(3);
  add_capsule(mesh, 2.0, 0.08, 0.8, 5, 20, 12);
  add_capsule(mesh, -2.0, 0.03, 0.5, 4, 20, 10);
  ASSERT_TRUE(topology(mesh).manifold);
  for (uint64_t target : {mesh.face_count() / 10, mesh.face_count() / 20}) {
    double worst[2];
    uint32_t faces[2];
    for (int k = 0; k < 2; ++k) {
      pmz::SimplifyOptions options;
      options.metric = k == 0 ? pmz::Metric::multifeature : pmz::Metric::guarded;
      options.target_faces = target;
      pmz::CollapseSequence seq;
      std::string error;
      ASSERT_TRUE(pmz::simplify(mesh, options, seq, error)) << error;
      const pmz::IndexedMesh simplified = pmz::mesh_after(seq, seq.collapses.size());
      faces[k] = simplified.face_count();
      pmz::CompareResult cmp;
      ASSERT_TRUE(pmz::compare(mesh, simplified, {}, cmp, error)) << error;
      worst[k] = cmp.symmetric.max / cmp.diag;
    }
    EXPECT_EQ(faces[0], faces[1]);
    EXPECT_LT(worst[1], 0.8 * worst[0])
        << target << " faces: paper " << worst[0] << ", guarded " << worst[1];
  }
}

// What the guard is for (spec/algorithm.md section 6): on elephant at 2% of the faces the
// paper's metric alone loses the worst case (Hausdorff 1146e-4 of the diagonal, meshoptimizer
// 428e-4); the guard holds the collapses back that would carry an original vertex far from
// the surface (about 500e-4). The guarded sequence is also deterministic.
TEST(Simplify, GuardLowersTheWorstCaseOnElephant) {
  const std::string path = pmz_test::corpus_mesh("elephant");
  if (path.empty()) {
    if (pmz_test::corpus_required()) FAIL() << "elephant missing from the corpus";
    GTEST_SKIP() << "no corpus (set PMZ_CORPUS or run scripts/fetch_corpus.sh)";
  }
  pmz::IndexedMesh mesh;
  std::string error;
  ASSERT_TRUE(pmz::read_mesh(path, mesh, error)) << error;
  double worst[2];
  pmz::CollapseSequence first;
  for (int k = 0; k < 2; ++k) {
    pmz::SimplifyOptions options;
    options.metric = k == 0 ? pmz::Metric::multifeature : pmz::Metric::guarded;
    options.target_faces = mesh.face_count() / 50;
    pmz::CollapseSequence seq;
    ASSERT_TRUE(pmz::simplify(mesh, options, seq, error)) << error;
    pmz::CompareResult cmp;
    ASSERT_TRUE(pmz::compare(mesh, pmz::mesh_after(seq, seq.collapses.size()), {}, cmp, error))
        << error;
    worst[k] = cmp.symmetric.max / cmp.diag;
    if (k == 1) first = std::move(seq);
  }
  EXPECT_LT(worst[1], 0.6 * worst[0]) << "paper " << worst[0] << ", guarded " << worst[1];
  pmz::SimplifyOptions options;
  options.target_faces = mesh.face_count() / 50;  // the default metric is the guarded one
  pmz::CollapseSequence again;
  ASSERT_TRUE(pmz::simplify(mesh, options, again, error)) << error;
  ASSERT_EQ(again.collapses.size(), first.collapses.size());
  for (size_t i = 0; i < first.collapses.size(); ++i)
    ASSERT_TRUE(again.collapses[i].u == first.collapses[i].u &&
                again.collapses[i].v == first.collapses[i].v)
        << "collapse " << i;
}

// The guard's penalty is capped (spec/algorithm.md section 6): on assimp's spider the first
// collapses cost next to nothing and leave the worst bound at about 1e-7 of the diagonal, so
// the first real collapses were penalised by factors near 5e5 whose keys then stayed stale,
// and at 1,030 of 1,312 faces the guarded mean error was 85x the paper's alone.
TEST(Simplify, GuardPenaltyCapKeepsTheMeanErrorOfASmallMesh) {
  const std::string path = std::string(PMZ_SOURCE_DIR) + "/corpus-assimp/OBJ/spider.obj";
  pmz::IndexedMesh mesh;
  std::string error;
  if (!pmz::read_mesh(path, mesh, error)) GTEST_SKIP() << "corpus-assimp not fetched: " << error;
  double mean[2];
  for (int k = 0; k < 2; ++k) {
    pmz::SimplifyOptions options;
    options.metric = k == 0 ? pmz::Metric::multifeature : pmz::Metric::guarded;
    options.target_faces = mesh.face_count() * 3 / 4;
    pmz::CollapseSequence seq;
    ASSERT_TRUE(pmz::simplify(mesh, options, seq, error)) << error;
    pmz::CompareResult cmp;
    ASSERT_TRUE(pmz::compare(mesh, pmz::mesh_after(seq, seq.collapses.size()), {}, cmp, error))
        << error;
    mean[k] = cmp.symmetric.mean / cmp.diag;
  }
  EXPECT_LT(mean[1], 4 * mean[0]) << "paper " << mean[0] << ", guarded " << mean[1];
}
