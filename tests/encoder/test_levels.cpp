// SPDX-License-Identifier: MIT
// Every level of detail, not only the base and the full mesh:
//  - each level k of a decode is the simplifier's mesh with exactly the collapses of the splits
//    not yet applied (the writer reorders splits within a window, spec "Splits": the set of
//    applied splits is always closed under the splits they depend on, so the collapses left are
//    a valid subset, and at each window boundary they are a prefix of the greedy order);
//  - every byte prefix of a file decodes to the full decode's mesh at the number of splits its
//    complete SPLT chunks hold (counted here from the chunk frames of spec/format.md section 3);
//  - decoded positions are within half a quantization step of the *input*
//    (spec/format.md section 5), not of the quantizer's own output.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "pmz/decoder.hpp"
#include "pmz/sample_mesh.hpp"
#include "pmz/simplify.hpp"
#include "pmz/writer.hpp"
#include "simplify_test_meshes.hpp"

namespace {

using pmz_test::canonical;
using pmz_test::Face;

struct Encoded {
  pmz::CollapseSequence seq;
  pmz::WriteOptions options;
  std::vector<uint8_t> bytes;
  std::vector<uint32_t> input_of;  // decoded vertex -> input vertex
};

Encoded encode(const pmz::IndexedMesh& mesh, uint32_t bits) {
  Encoded e;
  std::string error;
  EXPECT_TRUE(pmz::simplify(mesh, {}, e.seq, error)) << error;
  e.options.position_bits = bits;
  EXPECT_TRUE(pmz::write_pmz(e.seq, e.options, e.bytes, error)) << error;
  e.input_of = pmz::decoded_vertex_order(e.seq, e.options);
  return e;
}

// The decoder's faces in input vertex ids, as a sorted set of rotations.
std::vector<Face> decoded_faces(const pmz::Decoder& d, const std::vector<uint32_t>& input_of) {
  std::vector<Face> out;
  for (uint32_t f = 0; f < d.face_count(); ++f) {
    const uint32_t* t = d.indices() + size_t(f) * 3;
    out.push_back(canonical(input_of[t[0]], input_of[t[1]], input_of[t[2]]));
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The input's faces after the collapses with collapsed[i] set (u -> v followed to the survivor;
// a face whose corners meet is one a collapse deleted).
std::vector<Face> faces_after(const pmz::CollapseSequence& seq,
                              const std::vector<uint8_t>& collapsed) {
  std::vector<uint32_t> parent(seq.mesh.vertex_count());
  for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  for (size_t i = 0; i < seq.collapses.size(); ++i)
    if (collapsed[i]) parent[seq.collapses[i].u] = seq.collapses[i].v;
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x];
    return x;
  };
  std::vector<Face> out;
  for (size_t f = 0; f < seq.mesh.indices.size(); f += 3) {
    const uint32_t a = find(seq.mesh.indices[f]), b = find(seq.mesh.indices[f + 1]),
                   c = find(seq.mesh.indices[f + 2]);
    if (a != b && b != c && c != a) out.push_back(canonical(a, b, c));
  }
  std::sort(out.begin(), out.end());
  return out;
}

// |decoded - input| <= half a step per coordinate, the step from spec/format.md section 5 (range /
// max_q, range the largest extent of the input's bounding box); lossless: bit-identical.
void expect_positions_near_input(const pmz::Decoder& d, const Encoded& e) {
  const auto& pos = e.seq.mesh.positions;
  const uint32_t bits = e.options.position_bits;
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = hi[a] = pos[a];
    for (size_t i = a; i < pos.size(); i += 3) lo[a] = std::min<double>(lo[a], pos[i]);
    for (size_t i = a; i < pos.size(); i += 3) hi[a] = std::max<double>(hi[a], pos[i]);
  }
  const double range = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  const double half_step = bits ? range / double((1u << bits) - 1) / 2 : 0;
  // The decoder computes min + c * scale in float: a few ulps of the coordinates on top.
  double magnitude = 0;
  for (float x : pos) magnitude = std::max(magnitude, double(std::abs(x)));
  const double slack = 4 * magnitude * std::ldexp(1.0, -24);
  double worst = 0;
  for (uint32_t i = 0; i < d.vertex_count(); ++i)
    for (int a = 0; a < 3; ++a) {
      const float got = d.positions()[size_t(i) * 3 + a];
      const float in = pos[size_t(e.input_of[i]) * 3 + a];
      if (bits == 0) {
        ASSERT_EQ(std::memcmp(&got, &in, 4), 0) << "vertex " << i << " axis " << a;
        continue;
      }
      const double error = std::abs(double(got) - double(in));
      worst = std::max(worst, error);
      ASSERT_LE(error, half_step + slack) << "vertex " << i << " axis " << a << ": " << got
                                          << " for input " << in << ", step " << 2 * half_step;
    }
  // The bound is not vacuous: rounding does use most of the half step somewhere.
  if (bits) {
    EXPECT_GT(worst, 0.8 * half_step);
  }
}

// Levels 0..all of a full decode against the simplifier's meshes.
void expect_every_level(const pmz::IndexedMesh& mesh, uint32_t bits) {
  const Encoded e = encode(mesh, bits);
  ASSERT_FALSE(e.bytes.empty());
  pmz::Decoder d;
  ASSERT_EQ(d.feed(e.bytes.data(), e.bytes.size()), pmz::Status::ok) << d.error_message();
  const uint64_t base = d.info().base_vertices, all = d.splits_available();
  ASSERT_EQ(all, e.seq.collapses.size());
  ASSERT_EQ(e.input_of.size(), base + all);
  // Split i re-creates input vertex input_of[base + i]: the u of exactly one collapse.
  std::vector<size_t> collapse_of_u(e.seq.mesh.vertex_count(), SIZE_MAX);
  for (size_t c = 0; c < e.seq.collapses.size(); ++c) collapse_of_u[e.seq.collapses[c].u] = c;
  std::vector<uint8_t> collapsed(e.seq.collapses.size(), 1);
  size_t greedy_prefixes = 0;
  for (uint64_t k = 0;; ++k) {
    ASSERT_EQ(d.splits_applied(), k);
    ASSERT_TRUE(decoded_faces(d, e.input_of) == faces_after(e.seq, collapsed)) << "level " << k;
    // The collapses left are the first all - k of the greedy order: a window boundary.
    greedy_prefixes +=
        size_t(std::find(collapsed.begin(), collapsed.end(), 0) - collapsed.begin()) == all - k;
    if (k == all) break;
    ASSERT_EQ(d.refine(1), 1u);
    const size_t c = collapse_of_u[e.input_of[base + k]];
    ASSERT_NE(c, SIZE_MAX) << "split " << k << " re-creates a vertex no collapse removed";
    ASSERT_TRUE(collapsed[c]) << "split " << k << " twice";
    collapsed[c] = 0;
  }
  EXPECT_TRUE(decoded_faces(d, e.input_of) == faces_after(e.seq, collapsed));
  // The writer's windows grow the vertex count by 1.5x at most: several boundaries here.
  EXPECT_GE(greedy_prefixes, 4u);
  expect_positions_near_input(d, e);
}

pmz::IndexedMesh height_field(int n) {
  pmz::IndexedMesh m;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x)
      m.positions.insert(m.positions.end(),
                         {float(x) * 0.37f, float(y) * 0.29f,
                          float(std::sin(x * 0.4) * std::cos(y * 0.3)) + 0.01f * float(x % 3)});
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const uint32_t a = uint32_t(y * (n + 1) + x), b = a + 1, c = a + n + 1, d = c + 1;
      m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
    }
  return m;
}

// Number of splits in the SPLT chunks entirely inside the first n bytes (spec/format.md section 3:
// type, varint payload_size, u32 CRC, payload; a SPLT payload starts with varint split_count).
uint64_t splits_in_prefix(const std::vector<uint8_t>& b, size_t n) {
  auto varint = [&](size_t& at) {
    uint64_t v = 0;
    for (int shift = 0;; shift += 7) {
      const uint8_t byte = b.at(at++);
      v |= uint64_t(byte & 0x7F) << shift;
      if (!(byte & 0x80)) return v;
    }
  };
  uint64_t splits = 0;
  for (size_t at = 8; at < b.size();) {
    const uint8_t type = b[at];
    size_t p = at + 1;
    const uint64_t size = varint(p);
    p += 4;
    const size_t end = p + size_t(size);
    if (end > n) break;
    if (type == 3) splits += varint(p);
    if (type == 4) break;
    at = end;
  }
  return splits;
}

struct Snapshot {
  std::vector<float> positions;
  std::vector<uint32_t> indices;
  bool operator==(const Snapshot&) const = default;
};
Snapshot snap(const pmz::Decoder& d) {
  return {{d.positions(), d.positions() + size_t(d.vertex_count()) * 3},
          {d.indices(), d.indices() + size_t(d.face_count()) * 3}};
}

}  // namespace

TEST(Levels, SampleMeshEveryLevelIsTheSimplifiersMesh) {
  expect_every_level(pmz::make_sample_mesh(2000), 14);
}
TEST(Levels, SampleMeshFewBits) { expect_every_level(pmz::make_sample_mesh(1200), 7); }
TEST(Levels, SampleMeshLossless) { expect_every_level(pmz::make_sample_mesh(1200), 0); }
TEST(Levels, OpenHeightFieldEveryLevel) { expect_every_level(height_field(20), 12); }

// Each prefix, decoded by a fresh decoder (at every chunk boundary and the bytes around it, and
// every 61st byte) and by one decoder fed byte by byte (every prefix), holds exactly the splits
// of its complete SPLT chunks and is the full decode's mesh at that many splits.
TEST(Levels, EveryPrefixIsTheFullDecodeAtItsSplitCount) {
  const Encoded e = encode(pmz::make_sample_mesh(3000), 14);
  const std::vector<uint8_t>& b = e.bytes;
  pmz::Decoder full;
  ASSERT_EQ(full.feed(b.data(), b.size()), pmz::Status::ok);
  std::map<uint64_t, Snapshot> level;
  auto level_at = [&](uint64_t k) -> const Snapshot& {
    auto it = level.find(k);
    if (it != level.end()) return it->second;
    full.set_split_target(k);
    return level[k] = snap(full);
  };
  // The chunk ends: where the expected count changes.
  std::vector<size_t> interesting;
  uint64_t chunks = 0;
  for (size_t n = 1; n <= b.size(); ++n)
    if (splits_in_prefix(b, n) != splits_in_prefix(b, n - 1)) interesting.push_back(n), ++chunks;
  ASSERT_GE(chunks, 3u) << "the test wants several SPLT chunks";
  ASSERT_EQ(splits_in_prefix(b, b.size()), e.seq.collapses.size());
  std::vector<size_t> cuts;
  for (size_t n : interesting)
    for (size_t m : {n - 1, n, n + 1})
      if (m <= b.size()) cuts.push_back(m);
  for (size_t n = 0; n <= b.size(); n += 61) cuts.push_back(n);
  for (size_t n : cuts) {
    pmz::Decoder d;
    ASSERT_EQ(d.feed(b.data(), n), pmz::Status::ok) << "prefix " << n;
    const uint64_t want = splits_in_prefix(b, n);
    ASSERT_EQ(d.splits_available(), want) << "prefix " << n;
    ASSERT_EQ(d.refine(), want) << "prefix " << n;
    if (d.info().base_done) {
      ASSERT_TRUE(snap(d) == level_at(want)) << "prefix " << n;
    }
  }
  pmz::Decoder d;
  for (size_t n = 1; n <= b.size(); ++n) {
    ASSERT_EQ(d.feed(&b[n - 1], 1), pmz::Status::ok) << "byte " << n;
    const uint64_t want = splits_in_prefix(b, n);
    ASSERT_EQ(d.splits_available(), want) << "prefix " << n;
    d.refine();
    ASSERT_EQ(d.splits_applied(), want) << "prefix " << n;
    if (d.info().base_done && (n == b.size() || splits_in_prefix(b, n + 1) != want)) {
      ASSERT_TRUE(snap(d) == level_at(want)) << "prefix " << n;
    }
  }
  ASSERT_EQ(d.finish(), pmz::Status::ok);
  EXPECT_TRUE(snap(d) == level_at(e.seq.collapses.size()));
}

// Committed files decoded by this decoder against the meshes they were written from: every
// decoded vertex within half a quantization step (spec/format.md section 5) of a distinct source
// vertex. A change to both writer and decoder that keeps round trips intact (a residual coded one
// off on both sides) decodes the committed bytes wrongly and lands a vertex a step or more away.
TEST(Levels, CommittedFilesDecodeWithinHalfAStepOfTheirSources) {
  const std::pair<const char*, const char*> files[] = {
      {"tests/data/sample.pmz", "tests/data/sample.obj"},
      {"tests/conformance/vectors/torus-q14.pmz", "tests/conformance/meshes/torus.obj"},
      {"tests/conformance/vectors/sphere-q11.pmz", "tests/conformance/meshes/sphere.obj"}};
  for (const auto& [pmz_path, obj_path] : files) {
    SCOPED_TRACE(pmz_path);
    std::vector<uint8_t> bytes;
    if (FILE* f = std::fopen((std::string(PMZ_SOURCE_DIR "/") + pmz_path).c_str(), "rb")) {
      uint8_t buf[4096];
      for (size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;)
        bytes.insert(bytes.end(), buf, buf + n);
      std::fclose(f);
    }
    ASSERT_FALSE(bytes.empty());
    pmz::IndexedMesh source;
    std::string error;
    ASSERT_TRUE(pmz::read_mesh(std::string(PMZ_SOURCE_DIR "/") + obj_path, source, error)) << error;
    pmz::Decoder d;
    ASSERT_EQ(d.feed(bytes.data(), bytes.size()), pmz::Status::ok) << d.error_message();
    ASSERT_EQ(d.finish(), pmz::Status::ok);
    d.refine();
    ASSERT_EQ(d.vertex_count(), source.vertex_count());
    const pmz::StreamInfo& info = d.info();
    ASSERT_GT(info.position_bits, 0u);
    double range = 0;
    for (int a = 0; a < 3; ++a)
      range = std::max(range, double(info.bbox_max[a] - info.bbox_min[a]));
    const double half_step = range / double((1u << info.position_bits) - 1) / 2;
    const double slack = 4 * range * std::ldexp(1.0, -24) + 4 * std::ldexp(1.0, -24);
    std::vector<uint8_t> taken(source.vertex_count(), 0);
    for (uint32_t i = 0; i < d.vertex_count(); ++i) {
      const float* p = d.positions() + size_t(i) * 3;
      uint32_t match = UINT32_MAX;
      for (uint32_t s = 0; s < source.vertex_count() && match == UINT32_MAX; ++s) {
        bool near = !taken[s];
        for (int a = 0; a < 3 && near; ++a)
          near = std::abs(double(p[a]) - double(source.positions[size_t(s) * 3 + a])) <=
                 half_step + slack;
        if (near) match = s;
      }
      ASSERT_NE(match, UINT32_MAX) << "decoded vertex " << i << " (" << p[0] << " " << p[1] << " "
                                   << p[2] << ") is no source vertex within half a step";
      taken[match] = 1;
    }
  }
}
