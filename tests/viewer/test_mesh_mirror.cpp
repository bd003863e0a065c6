// pmz-view's CPU side against the real decoder: the incrementally synced mirror (indices,
// positions, smooth normals) equals one built from scratch, the dirty ranges cover every
// change (a shadow "GPU buffer" patched only with them ends up equal), and the budgeted LOD
// stepper reaches its targets.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "lod.hpp"
#include "mesh_mirror.hpp"
#include "pmz/decoder.hpp"
#include "pmz/sample_mesh.hpp"
#include "pmz/simplify.hpp"
#include "pmz/writer.hpp"

namespace {

using pmzview::DirtyBits;
using pmzview::MeshMirror;
using UploadRun = pmzview::Run;  // "Run" alone would name testing::Test::Run in a TEST body

const std::vector<uint8_t>& sample_stream() {
  static std::vector<uint8_t> bytes = [] {
    pmz::CollapseSequence seq;
    std::string error;
    std::vector<uint8_t> out;
    if (!pmz::simplify(pmz::make_sample_mesh(6000), {}, seq, error) ||
        !pmz::write_pmz(seq, {}, out, error))
      ADD_FAILURE() << error;
    return out;
  }();
  return bytes;
}

// What the renderer's buffers would hold if it uploaded exactly the dirty ranges.
struct Shadow {
  std::vector<float> positions, normals;
  std::vector<uint32_t> indices;
  std::vector<UploadRun> runs;

  void apply(MeshMirror& m) {
    positions.resize(m.positions.size());
    normals.resize(m.normals.size());
    indices.resize(m.indices.size());
    auto copy = [](auto& dst, const auto& src, size_t width, uint32_t begin, uint32_t end) {
      std::copy(src.begin() + width * begin, src.begin() + width * end,
                dst.begin() + width * begin);
    };
    if (m.dirty_all) {
      positions = m.positions;
      normals = m.normals;
      indices = m.indices;
    } else {
      uint32_t begin = std::min(m.dirty_vertex_begin, m.vertex_count);
      copy(positions, m.positions, 3, begin, m.vertex_count);
      copy(normals, m.normals, 3, begin, m.vertex_count);
      m.dirty_normals.take_runs(begin, 16, runs);
      for (const UploadRun& r : runs) copy(normals, m.normals, 3, r.begin, r.end);
      m.dirty_faces.take_runs(m.face_count, 16, runs);
      for (const UploadRun& r : runs) copy(indices, m.indices, 3, r.begin, r.end);
    }
    m.clear_dirty();
  }
};

double normal_mismatch(const float* a, const float* b) {
  double la = std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]);
  double lb = std::sqrt(double(b[0]) * b[0] + double(b[1]) * b[1] + double(b[2]) * b[2]);
  if (la == 0 && lb == 0) return 0;
  return 1 - (double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2]) / (la * lb + 1e-300);
}

TEST(MeshMirror, IncrementalSyncEqualsFullRebuild) {
  const std::vector<uint8_t>& bytes = sample_stream();
  ASSERT_GT(bytes.size(), 1000u);
  for (unsigned seed = 1; seed <= 4; ++seed) {
    std::mt19937 rng(seed);
    pmz::Decoder decoder;
    MeshMirror mirror;
    Shadow shadow;
    size_t at = 0;
    for (int step = 0; at < bytes.size() || step < 400; ++step) {
      if (at < bytes.size()) {
        size_t n = std::min<size_t>(bytes.size() - at, 1 + rng() % 1500);  // streaming arrival
        ASSERT_EQ(decoder.feed(bytes.data() + at, n), pmz::Status::ok) << decoder.error_message();
        at += n;
      }
      if (!decoder.info().base_done) continue;
      uint64_t n = rng() % 2000;
      switch (rng() % 5) {
        case 0:
        case 1:
          decoder.refine(n);
          break;
        case 2:
        case 3:
          decoder.coarsen(n);
          break;
        default:
          decoder.set_face_target(rng() % (decoder.info().full_faces + 1));
          break;
      }
      mirror.sync(decoder, float(step), 0.5f);
      shadow.apply(mirror);
    }
    ASSERT_EQ(decoder.finish(), pmz::Status::ok);

    MeshMirror fresh;
    fresh.sync(decoder, 0, 0);
    ASSERT_EQ(mirror.vertex_count, fresh.vertex_count);
    ASSERT_EQ(mirror.face_count, fresh.face_count);
    ASSERT_GT(fresh.face_count, 0u);
    const size_t nv = 3 * size_t(fresh.vertex_count), nf = 3 * size_t(fresh.face_count);
    for (size_t i = 0; i < nf; ++i) {
      ASSERT_EQ(mirror.indices[i], fresh.indices[i]) << "seed " << seed << " index " << i;
      ASSERT_EQ(shadow.indices[i], fresh.indices[i]) << "seed " << seed << " uploaded index " << i;
    }
    for (size_t i = 0; i < nv; ++i) {
      ASSERT_EQ(mirror.positions[i], fresh.positions[i]);
      ASSERT_EQ(shadow.positions[i], fresh.positions[i]);
    }
    for (size_t v = 0; v < fresh.vertex_count; ++v) {
      // Float sums updated by subtract/add drift only at rounding level.
      ASSERT_LT(normal_mismatch(&mirror.normals[3 * v], &fresh.normals[3 * v]), 1e-4)
          << "vertex " << v;
      ASSERT_LT(normal_mismatch(&shadow.normals[3 * v], &fresh.normals[3 * v]), 1e-4)
          << "uploaded vertex " << v;
    }
  }
}

TEST(MeshMirror, NewVerticesMorphFromTheirParent) {
  const std::vector<uint8_t>& bytes = sample_stream();
  pmz::Decoder decoder;
  ASSERT_EQ(decoder.feed(bytes.data(), bytes.size()), pmz::Status::ok);
  MeshMirror mirror;
  mirror.sync(decoder, 0, 1);
  const uint32_t base_vertices = mirror.vertex_count;
  for (uint32_t v = 0; v < base_vertices; ++v)
    EXPECT_LT(mirror.morph_start[v], -1e20f);  // base: static
  ASSERT_GT(decoder.refine(1), 0u);
  mirror.sync(decoder, 5, 1);
  ASSERT_EQ(mirror.vertex_count, base_vertices + 1);
  const uint32_t v = base_vertices, parent = decoder.split_parents()[v];
  ASSERT_LT(parent, v);
  EXPECT_EQ(mirror.morph_start[v], 5.0f);
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(mirror.morph_from[3 * v + i], mirror.positions[3 * parent + i]);
}

TEST(DirtyBits, RunsAreSortedMergedAndCleared) {
  DirtyBits bits;
  for (uint32_t i : {200u, 3u, 5u, 4u, 70u, 71u, 1000u, 5000u}) bits.mark(i);
  std::vector<UploadRun> runs;
  bits.take_runs(2000, 2, runs);  // 5000 is past the count
  ASSERT_EQ(runs.size(), 4u);
  EXPECT_EQ(runs[0].begin, 3u);
  EXPECT_EQ(runs[0].end, 6u);
  EXPECT_EQ(runs[1].begin, 70u);
  EXPECT_EQ(runs[1].end, 72u);
  EXPECT_EQ(runs[2].begin, 200u);
  EXPECT_EQ(runs[3].begin, 1000u);
  bits.take_runs(10000, 2, runs);
  EXPECT_TRUE(runs.empty());
  bits.mark(10);
  bits.mark(40);
  bits.take_runs(100, 64, runs);  // within the gap: one run
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].begin, 10u);
  EXPECT_EQ(runs[0].end, 41u);
}

TEST(LodStepper, ReachesTargetsBothWaysAndFollowsTheStream) {
  const std::vector<uint8_t>& bytes = sample_stream();
  pmz::Decoder decoder;
  ASSERT_EQ(decoder.feed(bytes.data(), bytes.size()), pmz::Status::ok);
  pmzview::LodStepper stepper;
  pmzview::LodTarget target;
  target.follow = false;
  const uint64_t full = decoder.info().full_faces;
  for (uint64_t faces : {full / 2, full / 50, full, decoder.info().base_faces}) {
    target.faces = faces;
    int frames = 0;
    do stepper.step(decoder, target, 0.0005);  // a tight budget: many small steps
    while (!stepper.settled() && ++frames < 100000);
    ASSERT_TRUE(stepper.settled());
    pmz::Decoder reference;
    ASSERT_EQ(reference.feed(bytes.data(), bytes.size()), pmz::Status::ok);
    reference.set_face_target(faces);
    EXPECT_EQ(decoder.face_count(), reference.face_count()) << "target " << faces;
  }
  target.follow = true;
  stepper.step(decoder, target, -1);
  EXPECT_TRUE(stepper.settled());
  EXPECT_EQ(decoder.face_count(), full);
  EXPECT_EQ(decoder.splits_applied(), decoder.info().total_splits);
}

}  // namespace
