// SPDX-License-Identifier: MIT
// pmz-view's CPU side against the real decoder: the incrementally synced mirror (indices,
// positions, smooth normals) equals one built from scratch, the dirty ranges cover every
// change (a shadow "GPU buffer" patched only with them ends up equal), and the budgeted LOD
// stepper reaches its targets. Attribute wedges the same way, driven by a scripted stream
// that grows, rewrites and shrinks like the decoder's change report says a stream does.
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

// Feeds `bytes` in random slices while moving the level of detail at random (refine, coarsen,
// face targets), at least `min_steps` times; after each move, `after_step(step)` syncs and
// checks. Returns false (with a gtest failure) when the decoder rejects the stream.
template <typename AfterStep>
bool stream_at_random(const std::vector<uint8_t>& bytes, unsigned seed, int min_steps,
                      pmz::Decoder& decoder, AfterStep after_step) {
  std::mt19937 rng(seed);
  size_t at = 0;
  for (int step = 0; at < bytes.size() || step < min_steps; ++step) {
    if (at < bytes.size()) {
      size_t n = std::min<size_t>(bytes.size() - at, 1 + rng() % 1500);  // streaming arrival
      if (decoder.feed(bytes.data() + at, n) != pmz::Status::ok) {
        ADD_FAILURE() << decoder.error_message();
        return false;
      }
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
    after_step(step);
  }
  return decoder.finish() == pmz::Status::ok;
}

TEST(MeshMirror, IncrementalSyncEqualsFullRebuild) {
  const std::vector<uint8_t>& bytes = sample_stream();
  ASSERT_GT(bytes.size(), 1000u);
  for (unsigned seed = 1; seed <= 4; ++seed) {
    pmz::Decoder decoder;
    MeshMirror mirror;
    Shadow shadow;
    ASSERT_TRUE(stream_at_random(bytes, seed, 400, decoder, [&](int step) {
      mirror.sync(decoder, float(step), 0.5f);
      shadow.apply(mirror);
    }));

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

// A mesh with attribute wedges that changes the way a progressive stream does: appended
// vertices, wedges and faces; rewritten faces (wedge and vertex indices) and rewritten wedge
// values; LIFO shrinking back to an earlier state. Changes accumulate until taken, as
// pmz::MeshChanges do between clear_changes() calls.
struct ScriptedWedgeStream {
  struct State {
    std::vector<float> positions, texcoords, normals, colors;
    std::vector<uint32_t> indices, parents, wedge_vertices, wedge_indices, face_materials;
    uint32_t vertices() const { return uint32_t(parents.size()); }
    uint32_t wedges() const { return uint32_t(wedge_vertices.size()); }
    uint32_t faces() const { return uint32_t(face_materials.size()); }
  };
  State now;
  std::vector<State> history;
  bool all = true;
  uint32_t vertex_begin = 0, wedge_begin = 0, face_begin = 0;
  std::vector<uint32_t> modified;
  std::mt19937 rng;

  explicit ScriptedWedgeStream(unsigned seed) : rng(seed) {
    for (int i = 0; i < 8; ++i) add_vertex();
    for (int i = 0; i < 12; ++i) add_wedge(uint32_t(rng() % now.vertices()));
    for (int i = 0; i < 10; ++i) add_face();
  }
  float value() { return float(rng() % 10000) / 1000.0f; }
  void add_vertex() {
    for (int i = 0; i < 3; ++i) now.positions.push_back(value());
    now.parents.push_back(now.vertices() ? uint32_t(rng() % now.vertices()) : UINT32_MAX);
  }
  void set_wedge_values(uint32_t w) {
    for (int i = 0; i < 2; ++i) now.texcoords[2 * w + i] = value();
    for (int i = 0; i < 3; ++i) now.normals[3 * w + i] = value();
    for (int i = 0; i < 3; ++i) now.colors[3 * w + i] = value() / 10;
  }
  void add_wedge(uint32_t vertex) {
    now.wedge_vertices.push_back(vertex);
    now.texcoords.resize(2 * now.wedges());
    now.normals.resize(3 * now.wedges());
    now.colors.resize(3 * now.wedges());
    set_wedge_values(now.wedges() - 1);
  }
  void set_face(uint32_t f) {
    for (int k = 0; k < 3; ++k) {
      uint32_t w = uint32_t(rng() % now.wedges());
      now.wedge_indices[3 * f + k] = w;
      now.indices[3 * f + k] = now.wedge_vertices[w];
    }
    now.face_materials[f] = uint32_t(rng() % 3);
  }
  void add_face() {
    now.indices.resize(3 * (now.faces() + 1));
    now.wedge_indices.resize(3 * (now.faces() + 1));
    now.face_materials.push_back(0);
    set_face(now.faces() - 1);
  }
  void grow() {
    history.push_back(now);
    const uint32_t nv = now.vertices(), nw = now.wedges(), nf = now.faces();
    for (uint32_t i = 1 + rng() % 3; i > 0; --i) add_vertex();
    for (uint32_t v = nv; v < now.vertices(); ++v) add_wedge(v);
    for (uint32_t i = rng() % 4; i > 0; --i) add_wedge(uint32_t(rng() % now.vertices()));
    if (rng() % 3 == 0) {  // rewritten wedge values: the report's wedge_begin goes below nw
      uint32_t from = uint32_t(rng() % nw);
      for (uint32_t w = from; w < nw; ++w) set_wedge_values(w);
      wedge_begin = std::min(wedge_begin, from);
    }
    for (uint32_t i = 1 + rng() % 6; i > 0; --i) add_face();
    for (uint32_t i = rng() % 4; i > 0; --i) {
      uint32_t f = uint32_t(rng() % nf);
      set_face(f);
      modified.push_back(f);
      if (rng() % 2) modified.push_back(f);  // the report may repeat a face
    }
    vertex_begin = std::min(vertex_begin, nv);
    wedge_begin = std::min(wedge_begin, nw);
    face_begin = std::min(face_begin, nf);
  }
  void shrink() {
    if (history.empty()) return;
    State before = history.back();
    history.pop_back();
    for (uint32_t f = 0; f < before.faces(); ++f)
      for (int k = 0; k < 3; ++k)
        if (f < now.faces() && now.wedge_indices[3 * f + k] != before.wedge_indices[3 * f + k])
          modified.push_back(f);
    // Undone wedge rewrites are rewrites too.
    for (uint32_t w = 0; w < std::min(before.wedges(), now.wedges()); ++w) {
      const float* a = before.texcoords.data() + 2 * w;
      const float* b = now.texcoords.data() + 2 * w;
      const float* na = before.normals.data() + 3 * w;
      const float* nb = now.normals.data() + 3 * w;
      if (!std::equal(a, a + 2, b) || !std::equal(na, na + 3, nb)) {
        wedge_begin = std::min(wedge_begin, w);
        break;
      }
    }
    std::swap(now, before);
    vertex_begin = std::min(vertex_begin, now.vertices());
    wedge_begin = std::min(wedge_begin, now.wedges());
    face_begin = std::min(face_begin, now.faces());
  }
  pmzview::MeshFrame frame() const {
    pmzview::MeshFrame f;
    f.vertex_count = now.vertices();
    f.face_count = now.faces();
    f.positions = now.positions.data();
    f.indices = now.indices.data();
    f.split_parents = now.parents.data();
    f.all = all;
    f.vertex_begin = vertex_begin;
    f.wedge_begin = wedge_begin;
    f.face_begin = face_begin;
    f.modified_faces = modified.data();
    f.modified_face_count = modified.size();
    f.wedge_count = now.wedges();
    f.wedge_vertices = now.wedge_vertices.data();
    f.wedge_indices = now.wedge_indices.data();
    f.texcoords = now.texcoords.data();
    f.normals = now.normals.data();
    f.colors = now.colors.data();
    f.color_components = 3;
    f.face_materials = now.face_materials.data();
    return f;
  }
  void clear_changes() {
    all = false;
    vertex_begin = now.vertices();
    wedge_begin = now.wedges();
    face_begin = now.faces();
    modified.clear();
  }
};

// The renderer's wedge-mode buffers patched with exactly the dirty ranges.
struct WedgeShadow {
  std::vector<uint32_t> wedge_vertices, wedge_indices, face_materials;
  std::vector<float> texcoords, colors, wedge_normals;
  std::vector<UploadRun> runs;

  void apply(MeshMirror& m) {
    auto patch = [](auto& dst, const auto& src, size_t width, uint32_t begin, uint32_t end) {
      dst.resize(src.size());
      std::copy(src.begin() + width * begin, src.begin() + width * end,
                dst.begin() + width * begin);
    };
    const uint32_t wedge_begin = m.dirty_all ? 0 : std::min(m.dirty_wedge_begin, m.wedge_count);
    patch(wedge_vertices, m.wedge_vertices, 1, wedge_begin, m.wedge_count);
    patch(texcoords, m.texcoords, 2, wedge_begin, m.wedge_count);
    patch(colors, m.colors, 4, wedge_begin, m.wedge_count);
    patch(wedge_normals, m.wedge_normals, 3, wedge_begin, m.wedge_count);
    if (m.dirty_all)
      runs.assign(1, UploadRun{0, m.face_count});
    else
      m.dirty_faces.take_runs(m.face_count, 16, runs);
    wedge_indices.resize(m.wedge_indices.size());
    face_materials.resize(m.face_materials.size());
    for (const UploadRun& r : runs) {
      patch(wedge_indices, m.wedge_indices, 3, r.begin, r.end);
      patch(face_materials, m.face_materials, 1, r.begin, r.end);
    }
    m.clear_dirty();
  }
};

// A mirror's (or the uploaded shadow's) wedge arrays equal a fresh mirror's.
template <typename Wedges>
void expect_wedges_equal(const Wedges& got, const MeshMirror& fresh, const std::string& what) {
  EXPECT_EQ(got.wedge_vertices, fresh.wedge_vertices) << what;
  EXPECT_EQ(got.texcoords, fresh.texcoords) << what;
  EXPECT_EQ(got.colors, fresh.colors) << what;
  EXPECT_EQ(got.wedge_normals, fresh.wedge_normals) << what;
  EXPECT_EQ(got.wedge_indices, fresh.wedge_indices) << what;
  EXPECT_EQ(got.face_materials, fresh.face_materials) << what;
}

TEST(MeshMirror, WedgeArraysFollowGrowRewriteAndShrink) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    ScriptedWedgeStream stream(seed);
    MeshMirror mirror;
    WedgeShadow shadow;
    std::mt19937 rng(seed * 77);
    for (int step = 0; step < 600; ++step) {
      if (rng() % 5 < 3)
        stream.grow();
      else
        stream.shrink();
      if (rng() % 3 == 0) continue;  // changes accumulate over several steps
      mirror.sync(stream.frame(), float(step), 0.5f);
      stream.clear_changes();
      shadow.apply(mirror);
    }
    mirror.sync(stream.frame(), 600, 0.5f);
    stream.clear_changes();
    shadow.apply(mirror);

    stream.all = true;
    MeshMirror fresh;
    fresh.sync(stream.frame(), 0, 0);
    ASSERT_TRUE(fresh.has_wedges && fresh.has_texcoords && fresh.has_normals && fresh.has_colors);
    ASSERT_TRUE(mirror.has_wedges && mirror.has_face_materials);
    ASSERT_GT(fresh.wedge_count, 12u);
    ASSERT_EQ(mirror.wedge_count, fresh.wedge_count) << "seed " << seed;
    ASSERT_EQ(mirror.face_count, fresh.face_count);
    EXPECT_EQ(mirror.indices, fresh.indices);
    expect_wedges_equal(mirror, fresh, "mirror, seed " + std::to_string(seed));
    expect_wedges_equal(shadow, fresh, "uploaded, seed " + std::to_string(seed));
    // RGB colours are widened to RGBA with alpha 1.
    for (uint32_t w = 0; w < fresh.wedge_count; ++w) {
      EXPECT_EQ(fresh.colors[4 * w + 3], 1.0f);
      EXPECT_EQ(fresh.colors[4 * w], stream.now.colors[3 * w]);
    }
  }
}

TEST(MeshMirror, WedgeAndVertexIdsOutOfRangeAreClamped) {
  ScriptedWedgeStream stream(3);
  stream.now.wedge_vertices[2] = 1000000;  // names no vertex
  stream.now.wedge_indices[4] = 1000000;   // names no wedge
  MeshMirror mirror;
  mirror.sync(stream.frame(), 0, 0);
  EXPECT_EQ(mirror.wedge_vertices[2], 0u);
  EXPECT_EQ(mirror.wedge_indices[3], 0u);  // the whole face falls back to wedge 0
  EXPECT_EQ(mirror.wedge_indices[4], 0u);
  EXPECT_EQ(mirror.wedge_indices[5], 0u);
}

// The sample mesh with attribute wedges: six box-projection charts (texture coordinates with
// seams where they meet), a normal per wedge, an RGB colour per wedge, two materials.
pmz::IndexedMesh textured_sample_mesh() {
  pmz::IndexedMesh mesh = pmz::make_sample_mesh(6000);
  pmz::MeshAttributes& a = mesh.attributes;
  a.texcoords.resize(1);
  std::vector<uint32_t> wedge_of(size_t(mesh.vertex_count()) * 6, UINT32_MAX);
  for (uint32_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* t = &mesh.indices[3 * size_t(f)];
    const float* p[3] = {&mesh.positions[3 * size_t(t[0])], &mesh.positions[3 * size_t(t[1])],
                         &mesh.positions[3 * size_t(t[2])]};
    float e1[3], e2[3], n[3];
    for (int i = 0; i < 3; ++i) e1[i] = p[1][i] - p[0][i], e2[i] = p[2][i] - p[0][i];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    int axis = 0;
    for (int i = 1; i < 3; ++i)
      if (std::fabs(n[i]) > std::fabs(n[axis])) axis = i;
    const uint32_t chart = uint32_t(2 * axis + (n[axis] < 0));
    for (int k = 0; k < 3; ++k) {
      uint32_t& w = wedge_of[6 * size_t(t[k]) + chart];
      if (w == UINT32_MAX) {
        w = a.wedge_count();
        a.wedge_vertices.push_back(t[k]);
        const float* q = p[k];
        a.texcoords[0].push_back(q[(axis + 1) % 3]);
        a.texcoords[0].push_back(q[(axis + 2) % 3]);
        for (int i = 0; i < 3; ++i)
          a.normals.push_back(i == axis ? (n[axis] < 0 ? -1.f : 1.f) : 0.f);
        for (int i = 0; i < 3; ++i) a.colors.push_back(float(chart + i) / 8);
      }
      a.corner_wedges.push_back(w);
    }
    a.face_materials.push_back(axis == 2 ? 1 : 0);
  }
  a.color_components = 3;
  a.materials.resize(2);
  a.materials[0].name = "side";
  a.materials[1].name = "cap";
  a.materials[1].base_color_texture = "cap.png";
  return mesh;
}

TEST(MeshMirror, DecodedWedgesFollowTheStream) {
  pmz::CollapseSequence seq;
  std::string error;
  std::vector<uint8_t> bytes;
  ASSERT_TRUE(pmz::simplify(textured_sample_mesh(), {}, seq, error)) << error;
  ASSERT_TRUE(pmz::write_pmz(seq, {}, bytes, error)) << error;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    pmz::Decoder decoder;
    MeshMirror mirror;
    WedgeShadow shadow;
    ASSERT_TRUE(stream_at_random(bytes, seed, 300, decoder, [&](int step) {
      mirror.sync(decoder, float(step), 0.5f);
      shadow.apply(mirror);
    }));
    ASSERT_GT(decoder.wedge_count(), 0u);
    ASSERT_EQ(decoder.material_count(), 2u);

    MeshMirror fresh;
    fresh.sync(pmzview::frame_of(decoder), 0, 0);
    ASSERT_TRUE(fresh.has_wedges && fresh.has_texcoords && fresh.has_normals && fresh.has_colors &&
                fresh.has_face_materials);
    ASSERT_EQ(mirror.wedge_count, decoder.wedge_count());
    ASSERT_EQ(mirror.face_count, decoder.face_count());
    EXPECT_EQ(mirror.indices, fresh.indices);
    expect_wedges_equal(mirror, fresh, "mirror, seed " + std::to_string(seed));
    expect_wedges_equal(shadow, fresh, "uploaded, seed " + std::to_string(seed));
    // The render vertex is the wedge: every face's wedges sit on that face's vertices.
    for (size_t c = 0; c < fresh.indices.size(); ++c)
      ASSERT_EQ(fresh.wedge_vertices[fresh.wedge_indices[c]], fresh.indices[c]) << "corner " << c;
  }
}

TEST(MeshMirror, GeometryOnlyStreamsHaveNoWedgeArrays) {
  const std::vector<uint8_t>& bytes = sample_stream();
  pmz::Decoder decoder;
  ASSERT_EQ(decoder.feed(bytes.data(), bytes.size()), pmz::Status::ok);
  MeshMirror mirror;
  mirror.sync(decoder, 0, 0);
  EXPECT_FALSE(mirror.has_wedges);
  EXPECT_EQ(mirror.wedge_count, 0u);
  EXPECT_TRUE(mirror.wedge_indices.empty());
  EXPECT_TRUE(mirror.face_materials.empty());
  EXPECT_GT(mirror.face_count, 0u);
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
