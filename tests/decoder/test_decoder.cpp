// SPDX-License-Identifier: MIT
// Streaming decoder behaviour on a committed sample (tests/data/sample.pmz: a 128-face bumpy
// sphere written by pmz-encode; when the bitstream changes, regenerate it with
// `pmz-encode tests/data/sample.obj -o tests/data/sample.pmz`): prefixes, chunkings, level moves,
// change tracking (also on conformance vectors), bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "pmz/attribute_codec.hpp"
#include "pmz/coding.hpp"
#include "pmz/decoder.hpp"
#include "pmz/format.hpp"

namespace {

std::vector<uint8_t> load(const std::string& path) {
  std::vector<uint8_t> out;
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return out;
  uint8_t buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) out.insert(out.end(), buf, buf + n);
  std::fclose(f);
  return out;
}

struct Snapshot {
  std::vector<float> positions;
  std::vector<uint32_t> indices;
  bool operator==(const Snapshot&) const = default;
};
Snapshot snap(const pmz::Decoder& d) {
  Snapshot s;
  if (d.vertex_count()) s.positions.assign(d.positions(), d.positions() + d.vertex_count() * 3);
  if (d.face_count()) s.indices.assign(d.indices(), d.indices() + d.face_count() * 3);
  return s;
}

// A consistent mesh: indices in range, no degenerate face.
void expect_valid(const pmz::Decoder& d) {
  for (uint32_t f = 0; f < d.face_count(); ++f) {
    const uint32_t* t = d.indices() + f * 3;
    for (int k = 0; k < 3; ++k) ASSERT_LT(t[k], d.vertex_count());
    ASSERT_TRUE(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
  }
}

// The frame of the chunk at chunk_at (spec/format.md section 3: type, varint size, CRC).
pmz::ChunkFrame frame_at(const std::vector<uint8_t>& b, size_t chunk_at) {
  pmz::ChunkFrame f;
  EXPECT_EQ(pmz::parse_chunk_frame(b.data() + chunk_at, b.size() - chunk_at, f),
            pmz::FrameStatus::ok);
  return f;
}
// Offsets of every chunk of a file.
std::vector<size_t> chunk_offsets(const std::vector<uint8_t>& b) {
  std::vector<size_t> at;
  for (size_t c = 8; c < b.size(); c += frame_at(b, c).header_size + frame_at(b, c).payload_size)
    at.push_back(c);
  return at;
}

// Rewrites a chunk's CRC so corruption reaches the parser instead of the checksum.
void fix_crc(std::vector<uint8_t>& b, size_t chunk_at) {
  pmz::repair_chunk_crc(&b[chunk_at], frame_at(b, chunk_at));
}

// The file with its HEAD replaced by h (the HEAD chunk re-framed: its size may change).
std::vector<uint8_t> with_head(const std::vector<uint8_t>& file, const pmz::FileHeader& h) {
  const pmz::ChunkFrame f = frame_at(file, 8);
  std::vector<uint8_t> b(file.begin(), file.begin() + 8), payload;
  pmz::write_head_payload(payload, h);
  pmz::append_chunk(b, pmz::kChunkHead, payload);
  b.insert(b.end(), file.begin() + ptrdiff_t(8 + f.header_size + f.payload_size), file.end());
  return b;
}
pmz::FileHeader head_of(const std::vector<uint8_t>& file) {
  const pmz::ChunkFrame f = frame_at(file, 8);
  pmz::FileHeader h;
  EXPECT_TRUE(pmz::read_head_payload(&file[8 + f.header_size], size_t(f.payload_size), h));
  return h;
}

class DecoderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    file = load(PMZ_SOURCE_DIR "/tests/data/sample.pmz");
    ASSERT_GT(file.size(), 100u) << "tests/data/sample.pmz missing";
  }
  std::vector<uint8_t> file;
};

TEST_F(DecoderTest, DecodesWholeFile) {
  pmz::Decoder d;
  ASSERT_EQ(d.feed(file.data(), file.size()), pmz::Status::ok) << d.error_message();
  ASSERT_EQ(d.finish(), pmz::Status::ok);
  const pmz::StreamInfo& info = d.info();
  EXPECT_TRUE(info.complete);
  EXPECT_EQ(info.full_faces, 128u);
  EXPECT_EQ(d.face_count(), info.base_faces);
  EXPECT_EQ(d.splits_available(), info.total_splits);
  EXPECT_EQ(d.refine(), info.total_splits);
  EXPECT_EQ(d.vertex_count(), info.full_vertices);
  EXPECT_EQ(d.face_count(), info.full_faces);
  expect_valid(d);
  for (uint32_t i = 0; i < d.vertex_count() * 3; ++i) {
    EXPECT_GE(d.positions()[i], info.bbox_min[i % 3] - 1e-5f);
    EXPECT_LE(d.positions()[i], info.bbox_max[i % 3] + 1e-5f);
  }
  const uint32_t* parents = d.split_parents();
  for (uint32_t i = 0; i < d.vertex_count(); ++i) {
    if (i < info.base_vertices) {
      EXPECT_EQ(parents[i], UINT32_MAX);
    } else {
      EXPECT_LT(parents[i], i);
    }
  }
}

TEST_F(DecoderTest, EveryPrefixDecodesAndNeverShrinks) {
  uint32_t last_faces = 0;
  for (size_t n = 0; n <= file.size(); ++n) {
    pmz::Decoder d;
    ASSERT_EQ(d.feed(file.data(), n), pmz::Status::ok)
        << "prefix " << n << ": " << d.error_message();
    d.refine();
    expect_valid(d);
    ASSERT_GE(d.face_count(), last_faces) << "prefix " << n;
    last_faces = d.face_count();
    EXPECT_EQ(d.finish(), n == file.size() ? pmz::Status::ok : pmz::Status::truncated);
  }
  EXPECT_EQ(last_faces, 128u);
}

TEST_F(DecoderTest, RandomChunkingsGiveIdenticalResults) {
  pmz::Decoder whole;
  whole.feed(file.data(), file.size());
  whole.refine();
  const Snapshot want = snap(whole);
  std::mt19937 rng(11);
  for (int trial = 0; trial < 50; ++trial) {
    pmz::Decoder d;
    size_t at = 0;
    while (at < file.size()) {
      size_t n = std::min(file.size() - at, size_t(rng() % (trial < 5 ? 2 : 200)) + 1);
      ASSERT_EQ(d.feed(file.data() + at, n), pmz::Status::ok);
      at += n;
      d.refine(rng() % 4);  // interleave level moves with arrival
    }
    d.refine();
    EXPECT_EQ(d.bytes_consumed(), file.size());
    EXPECT_TRUE(snap(d) == want) << "trial " << trial;
  }
}

TEST_F(DecoderTest, CoarsenThenRefineReturnsToTheSameMesh) {
  pmz::Decoder d;
  d.feed(file.data(), file.size());
  const Snapshot base = snap(d);
  d.refine();
  const Snapshot full = snap(d);
  std::vector<Snapshot> levels;
  d.coarsen();
  EXPECT_TRUE(snap(d) == base);
  for (uint64_t i = 0; i <= d.splits_available(); ++i) {
    d.set_split_target(i);
    levels.push_back(snap(d));
  }
  EXPECT_TRUE(levels.back() == full);
  std::mt19937 rng(5);
  for (int step = 0; step < 200; ++step) {
    uint64_t target = rng() % levels.size();
    if (rng() % 2) {
      d.set_split_target(target);
    } else {
      // The smallest level with at least the faces asked for (levels only grow).
      const size_t faces = levels[target].indices.size() / 3;
      d.set_face_target(faces);
      EXPECT_GE(d.face_count(), faces) << "step " << step;
      if (d.splits_applied() > 0) {
        EXPECT_LT(levels[d.splits_applied() - 1].indices.size() / 3, faces) << "step " << step;
      }
    }
    ASSERT_TRUE(snap(d) == levels[d.splits_applied()]) << "step " << step;
  }
}

TEST_F(DecoderTest, FaceTargetPicksSmallestLevelAtOrAbove) {
  pmz::Decoder d;
  d.feed(file.data(), file.size());
  d.set_face_target(64);
  EXPECT_GE(d.face_count(), 64u);
  EXPECT_LE(d.face_count(), 65u);
  d.set_face_target(1000);
  EXPECT_EQ(d.face_count(), 128u);
  d.set_face_target(0);
  EXPECT_EQ(d.splits_applied(), 0u);
}

TEST_F(DecoderTest, ChangesDescribeEveryDifference) {
  pmz::Decoder d;
  d.feed(file.data(), file.size());
  EXPECT_TRUE(d.changes().all);
  std::mt19937 rng(3);
  for (int step = 0; step < 100; ++step) {
    d.clear_changes();
    const Snapshot before = snap(d);
    if (rng() % 3)
      d.refine(rng() % 6);
    else
      d.coarsen(rng() % 6);
    const Snapshot after = snap(d);
    const pmz::MeshChanges& c = d.changes();
    ASSERT_FALSE(c.all);
    ASSERT_LE(c.face_begin, d.face_count());
    ASSERT_LE(c.vertex_begin, d.vertex_count());
    for (uint32_t f = 0; f < c.face_begin; ++f) {
      bool same = std::equal(after.indices.begin() + f * 3, after.indices.begin() + f * 3 + 3,
                             before.indices.begin() + f * 3);
      bool listed =
          std::find(c.modified_faces.begin(), c.modified_faces.end(), f) != c.modified_faces.end();
      ASSERT_TRUE(same || listed) << "face " << f << " changed but is not listed";
    }
    for (uint32_t v = 0; v < c.vertex_begin * 3; ++v)
      ASSERT_EQ(after.positions[v], before.positions[v]);
  }
}

// The change report (pmz::MeshChanges) against its contract in pmz/decoder.hpp, on the sample
// and conformance vectors (attributes, materials, boundaries, the speed level), through random
// sequences of refine, coarsen, set_face_target and set_split_target with the report cleared
// only now and then, so that it spans several level moves: every listed face lies below
// face_begin, the ranges lie within the counts, and everything the report leaves out (faces
// below face_begin not listed, vertices below vertex_begin, wedges below wedge_begin) is as it
// was when the report was last cleared.
template <class T>
std::vector<T> copy(const T* p, size_t n) {
  return p ? std::vector<T>(p, p + n) : std::vector<T>();
}

// Everything the report speaks for, per face, vertex and wedge.
struct Arrays {
  std::vector<float> positions;
  std::vector<uint32_t> indices, wedge_indices, materials, wedge_vertices;
  std::vector<std::vector<float>> texcoords;
  std::vector<float> normals, colors;
  bool operator==(const Arrays&) const = default;
};
Arrays arrays(const pmz::Decoder& d) {
  Arrays a;
  const size_t v = d.vertex_count(), f = d.face_count(), w = d.wedge_count();
  a.positions = copy(d.positions(), v * 3);
  a.indices = copy(d.indices(), f * 3);
  a.wedge_indices = copy(d.wedge_indices(), w ? f * 3 : 0);
  a.materials = copy(d.face_materials(), f);
  a.wedge_vertices = copy(d.wedge_vertices(), w);
  for (uint32_t s = 0; s < d.texcoord_set_count(); ++s)
    a.texcoords.push_back(copy(d.texcoords(s), w * 2));
  a.normals = copy(d.normals(), w * 3);
  a.colors = copy(d.colors(), w * d.color_components());
  return a;
}

template <class T>
bool same(const std::vector<T>& a, const std::vector<T>& b, size_t i, size_t n) {
  return std::equal(a.begin() + ptrdiff_t(i * n), a.begin() + ptrdiff_t(i * n + n),
                    b.begin() + ptrdiff_t(i * n));
}

// The report against the arrays as they were at the last clear_changes() (a report that says
// `all`, as one whose list outgrew the mesh does, asks for everything and is not checked).
void expect_contract(const pmz::Decoder& d, const Arrays& before, const std::string& where,
                     uint64_t& checked) {
  SCOPED_TRACE(where);
  const pmz::MeshChanges& c = d.changes();
  if (c.all) {
    ASSERT_TRUE(c.modified_faces.empty());
    return;
  }
  ++checked;
  ASSERT_LE(c.face_begin, d.face_count());
  ASSERT_LE(c.vertex_begin, d.vertex_count());
  ASSERT_LE(c.wedge_begin, d.wedge_count());
  const Arrays now = arrays(d);
  // face_begin never passes a face the report's calls removed.
  ASSERT_LE(c.face_begin, before.indices.size() / 3);
  ASSERT_LE(c.vertex_begin, before.positions.size() / 3);
  ASSERT_LE(c.wedge_begin, before.wedge_vertices.size());
  std::vector<char> listed(c.face_begin, 0);
  for (uint32_t f : c.modified_faces) {
    ASSERT_LT(f, c.face_begin) << "a listed face is not below face_begin (face count "
                               << d.face_count() << ")";
    listed[f] = 1;
  }
  for (uint32_t f = 0; f < c.face_begin; ++f) {
    if (listed[f]) continue;
    ASSERT_TRUE(same(now.indices, before.indices, f, 3)) << "face " << f << " not listed";
    if (!now.wedge_indices.empty()) {
      ASSERT_TRUE(same(now.wedge_indices, before.wedge_indices, f, 3)) << "face " << f;
    }
    if (!now.materials.empty()) {
      ASSERT_EQ(now.materials[f], before.materials[f]) << "face " << f;
    }
  }
  for (uint32_t v = 0; v < c.vertex_begin; ++v)
    ASSERT_TRUE(same(now.positions, before.positions, v, 3)) << "vertex " << v;
  const uint32_t cn = d.color_components();
  for (uint32_t w = 0; w < c.wedge_begin; ++w) {
    ASSERT_EQ(now.wedge_vertices[w], before.wedge_vertices[w]) << "wedge " << w;
    for (size_t s = 0; s < now.texcoords.size(); ++s) {
      ASSERT_TRUE(same(now.texcoords[s], before.texcoords[s], w, 2)) << "wedge " << w;
    }
    if (!now.normals.empty()) {
      ASSERT_TRUE(same(now.normals, before.normals, w, 3)) << "wedge " << w;
    }
    if (cn) {
      ASSERT_TRUE(same(now.colors, before.colors, w, cn)) << "wedge " << w;
    }
  }
}

void walk(const std::string& name, unsigned seed) {
  SCOPED_TRACE(name);
  const std::vector<uint8_t> bytes = load(PMZ_SOURCE_DIR "/tests/" + name);
  ASSERT_FALSE(bytes.empty()) << "cannot read tests/" << name;
  pmz::Decoder d;
  ASSERT_EQ(d.feed(bytes.data(), bytes.size()), pmz::Status::ok) << d.error_message();
  ASSERT_EQ(d.finish(), pmz::Status::ok);
  const uint64_t total = d.splits_available(), full = d.info().full_faces;
  ASSERT_GT(total, 20u);
  d.set_split_target(total / 2);
  d.clear_changes();
  Arrays before = arrays(d);
  std::mt19937 rng(seed);
  uint64_t coarsened_reports = 0, checked = 0;
  bool coarsened = false;
  for (int step = 0; step < 400; ++step) {
    const uint32_t op = rng() % 8;
    const uint64_t n = rng() % 2 ? rng() % 8 : rng() % (total / 4 + 1);
    std::string what;
    if (op < 3) {
      what = "refine " + std::to_string(n);
      d.refine(n);
    } else if (op < 6) {
      what = "coarsen " + std::to_string(n);
      coarsened = coarsened || d.coarsen(n) > 0;
    } else if (op == 6) {
      const uint64_t faces = rng() % (full + 1);
      what = "face target " + std::to_string(faces);
      const uint64_t applied = d.splits_applied();
      d.set_face_target(faces);
      coarsened = coarsened || d.splits_applied() < applied;
    } else {
      const uint64_t splits = rng() % (total + 1);
      what = "split target " + std::to_string(splits);
      coarsened = coarsened || splits < d.splits_applied();
      d.set_split_target(splits);
    }
    expect_contract(d, before, "step " + std::to_string(step) + ": " + what, checked);
    if (::testing::Test::HasFatalFailure()) return;
    if (rng() % 4 == 0) {  // the report spans several calls until it is cleared
      coarsened_reports += coarsened;
      coarsened = false;
      d.clear_changes();
      before = arrays(d);
    }
  }
  EXPECT_GT(coarsened_reports, 10u);
  EXPECT_GT(checked, 200u);
}

TEST(ChangeReport, MeetsItsContractThroughLevelMoves) {
  walk("data/sample.pmz", 1);
  walk("conformance/vectors/seamed-q.pmz", 2);  // a-wedges, two materials
  walk("conformance/vectors/seamed-coarse.pmz", 3);
  walk("conformance/vectors/torus-q14.pmz", 4);
  walk("conformance/vectors/terrain-base.pmz", 5);  // boundaries
  walk("conformance/vectors/seamed-speed.pmz", 6);  // the speed level
}

TEST_F(DecoderTest, RejectsWrongMagicAndVersion) {
  std::vector<uint8_t> b = file;
  b[1] = 'X';
  pmz::Decoder d;
  EXPECT_EQ(d.feed(b.data(), b.size()), pmz::Status::bad_magic);
  EXPECT_FALSE(d.error_message().empty());
  EXPECT_EQ(d.face_count(), 0u);

  b = file;
  b[8 + frame_at(b, 8).header_size] =
      6;  // HEAD payload: version_major (6: the previous major, before the compact framing)
  fix_crc(b, 8);
  pmz::Decoder v;
  EXPECT_EQ(v.feed(b.data(), b.size()), pmz::Status::bad_version);
  EXPECT_NE(v.error_message().find("version"), std::string::npos);
}

// A file of format 6.0 or older (chunks framed by four ASCII type bytes, a u32 size and a u32
// CRC) is refused as such, with its version, however its bytes arrive.
TEST_F(DecoderTest, RefusesTheFramingBefore70) {
  std::vector<uint8_t> old(pmz::kSignature, pmz::kSignature + 8);
  const uint8_t chunk[] = {'H', 'E', 'A', 'D', 52, 0, 0, 0, 0x12, 0x34, 0x56, 0x78, 6, 0, 0, 0};
  old.insert(old.end(), chunk, chunk + sizeof chunk);
  old.resize(8 + 12 + 52, 0);
  for (size_t slice : {size_t(1), size_t(3), old.size()}) {
    pmz::Decoder d;
    pmz::Status s = pmz::Status::ok;
    for (size_t at = 0; at < old.size() && s == pmz::Status::ok; at += slice)
      s = d.feed(old.data() + at, std::min(slice, old.size() - at));
    EXPECT_EQ(s, pmz::Status::bad_version) << "slices of " << slice;
    EXPECT_NE(d.error_message().find("format 6.0"), std::string::npos) << d.error_message();
  }
}

TEST_F(DecoderTest, BadChecksumKeepsLastGoodLevel) {
  // Corrupt the last byte of the last split chunk's payload (just before the END chunk: type 4,
  // size 0 and its CRC, 6 bytes).
  std::vector<uint8_t> b = file;
  ASSERT_EQ(b[b.size() - 6], pmz::kChunkEnd);
  b[b.size() - 7] ^= 0x5A;
  pmz::Decoder d;
  EXPECT_EQ(d.feed(b.data(), b.size()), pmz::Status::bad_checksum);
  EXPECT_TRUE(d.info().base_done);
  d.refine();
  expect_valid(d);
  EXPECT_LT(d.face_count(), 128u);
  EXPECT_EQ(d.feed(file.data(), 1), pmz::Status::bad_checksum);  // sticky
  EXPECT_EQ(d.finish(), pmz::Status::bad_checksum);
}

TEST_F(DecoderTest, TruncationIsReportedByFinish) {
  pmz::Decoder d;
  EXPECT_EQ(d.feed(file.data(), file.size() - 5), pmz::Status::ok);
  EXPECT_EQ(d.finish(), pmz::Status::truncated);
  EXPECT_FALSE(d.error_message().empty());
}

TEST_F(DecoderTest, AbsurdCountsHitLimitsBeforeAllocating) {
  pmz::FileHeader h = head_of(file);
  h.total_splits = 0xFFFFFFF0u;
  h.full_faces = 0xFFFFFFF0u;
  std::vector<uint8_t> b = with_head(file, h);
  pmz::Decoder d;
  EXPECT_EQ(d.feed(b.data(), b.size()), pmz::Status::limit_exceeded);

  h = head_of(file);
  h.full_faces = h.base_faces + 2 * h.total_splits + 1;  // more faces than the splits can add
  b = with_head(file, h);
  pmz::Decoder c;
  EXPECT_EQ(c.feed(b.data(), b.size()), pmz::Status::corrupt);

  // A chunk claiming a huge payload is refused from its header alone (the size varint, even
  // before the CRC bytes arrive: nothing of the payload is buffered).
  b.assign(file.begin(), file.begin() + ptrdiff_t(8 + frame_at(file, 8).header_size +
                                                  frame_at(file, 8).payload_size));
  const uint8_t huge[] = {
      pmz::kChunkSplits, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x01, 0, 0, 0, 0};
  b.insert(b.end(), huge, huge + sizeof huge);
  pmz::DecoderLimits small;
  small.max_chunk_bytes = 1 << 20;
  pmz::Decoder l(small);
  EXPECT_EQ(l.feed(b.data(), b.size()), pmz::Status::limit_exceeded);
  // Just above the limit: a 3-byte varint.
  b.resize(b.size() - sizeof huge);
  const uint8_t above[] = {pmz::kChunkSplits, 0x81, 0x80, 0x40, 0, 0, 0, 0};  // 2^20 + 1
  b.insert(b.end(), above, above + sizeof above);
  pmz::Decoder a(small);
  EXPECT_EQ(a.feed(b.data(), b.size()), pmz::Status::limit_exceeded);
}

// The chunk frame (spec/format.md section 3): a varint size of more than 10 bytes is malformed, a
// CRC that does not cover type, size and payload is refused, and a frame header cut anywhere across
// two feed() calls decodes as the whole.
TEST_F(DecoderTest, ChunkFrameFields) {
  const size_t head_end = 8 + frame_at(file, 8).header_size + frame_at(file, 8).payload_size;
  std::vector<uint8_t> b(file.begin(), file.begin() + ptrdiff_t(head_end));
  const uint8_t eleven[] = {pmz::kChunkSplits,
                            0x80,
                            0x80,
                            0x80,
                            0x80,
                            0x80,
                            0x80,
                            0x80,
                            0x80,
                            0x80,
                            0x80,
                            0x00,
                            0,
                            0,
                            0,
                            0};
  b.insert(b.end(), eleven, eleven + sizeof eleven);
  pmz::Decoder m;
  EXPECT_EQ(m.feed(b.data(), b.size()), pmz::Status::corrupt);
  EXPECT_NE(m.error_message().find("varint"), std::string::npos);

  for (size_t at : chunk_offsets(file)) {
    const pmz::ChunkFrame f = frame_at(file, at);
    for (size_t i = 0; i < f.header_size; ++i) {  // each byte of the frame header: type, size, CRC
      if (i == 0 && at == 8) continue;            // HEAD's type: "first chunk is not HEAD"
      b = file;
      b[at + i] ^= i == 0 ? 0x40 : 0x01;  // another type, size or CRC (a size 1 off stays a varint)
      pmz::Decoder d;
      pmz::Status s = d.feed(b.data(), b.size());
      if (s == pmz::Status::ok) s = d.finish();
      EXPECT_NE(s, pmz::Status::ok) << "chunk at " << at << ", header byte " << i;
    }
  }

  pmz::Decoder whole;
  ASSERT_EQ(whole.feed(file.data(), file.size()), pmz::Status::ok);
  whole.refine();
  const Snapshot want = snap(whole);
  for (size_t at : chunk_offsets(file))
    for (size_t cut = at; cut <= at + frame_at(file, at).header_size; ++cut) {
      pmz::Decoder d;
      ASSERT_EQ(d.feed(file.data(), cut), pmz::Status::ok);
      ASSERT_EQ(d.feed(file.data() + cut, file.size() - cut), pmz::Status::ok) << d.error_message();
      ASSERT_EQ(d.finish(), pmz::Status::ok);
      d.refine();
      EXPECT_TRUE(snap(d) == want) << "cut at " << cut;
    }
}

TEST_F(DecoderTest, CorruptedPayloadsNeverCrash) {
  // Flip bytes inside chunks and repair the CRCs, so the parser sees the damage.
  const std::vector<size_t> chunks = chunk_offsets(file);
  std::mt19937 rng(99);
  int errors = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<uint8_t> b = file;
    size_t c = chunks[rng() % chunks.size()];
    const pmz::ChunkFrame f = frame_at(b, c);
    const size_t size = size_t(f.payload_size);
    if (!size) continue;
    for (int k = 0; k < 1 + int(rng() % 3); ++k)
      b[c + f.header_size + rng() % size] ^= uint8_t(1 + rng() % 255);
    fix_crc(b, c);
    pmz::Decoder d;
    pmz::Status s = d.feed(b.data(), b.size());
    d.refine();
    d.coarsen(rng() % 10);
    d.refine();
    expect_valid(d);
    errors += s != pmz::Status::ok || d.status() != pmz::Status::ok;
  }
  EXPECT_GT(errors, 100);  // most damage is detected, none crashes
}

TEST_F(DecoderTest, UnknownChunksAreSkipped) {
  // Insert unknown chunks right after HEAD: a small one, and one of 300 bytes (a 2-byte size).
  const size_t head_end = 8 + frame_at(file, 8).header_size + frame_at(file, 8).payload_size;
  std::vector<uint8_t> b(file.begin(), file.begin() + ptrdiff_t(head_end));
  pmz::append_chunk(b, 0x7F, {1, 2, 3});
  pmz::append_chunk(b, 0xFF, std::vector<uint8_t>(300, 0xAB));
  ASSERT_EQ(b[head_end + 9 + 1], 0xAC);  // the first takes 9 bytes; 300 = varint AC 02
  b.insert(b.end(), file.begin() + ptrdiff_t(head_end), file.end());
  for (size_t cut = head_end; cut <= head_end + 9 + 7; ++cut) {  // cuts inside both frame headers
    pmz::Decoder d;
    ASSERT_EQ(d.feed(b.data(), cut), pmz::Status::ok);
    ASSERT_EQ(d.feed(b.data() + cut, b.size() - cut), pmz::Status::ok) << d.error_message();
    d.refine();
    EXPECT_EQ(d.face_count(), 128u);
  }
  pmz::Decoder d;
  ASSERT_EQ(d.feed(b.data(), b.size()), pmz::Status::ok) << d.error_message();
  d.refine();
  EXPECT_EQ(d.face_count(), 128u);
}

// What decoder.hpp promises about input: an empty slice may be null; the caller's buffer is not
// kept (it is overwritten between feeds); after finish() reports truncation, feeding stops and
// the splits decoded before it can still be applied; bytes after the end marker are ignored;
// moving a decoder keeps its arrays.
TEST_F(DecoderTest, InputContract) {
  pmz::Decoder d;
  EXPECT_EQ(d.feed(nullptr, 0), pmz::Status::ok);
  EXPECT_EQ(d.positions(), nullptr);
  EXPECT_EQ(d.vertex_count(), 0u);
  std::vector<uint8_t> slice;
  const size_t cut = file.size() - 5;
  for (size_t at = 0; at < cut; at += 13) {
    slice.assign(file.begin() + ptrdiff_t(at), file.begin() + ptrdiff_t(std::min(at + 13, cut)));
    ASSERT_EQ(d.feed(slice.data(), slice.size()), pmz::Status::ok) << d.error_message();
    std::fill(slice.begin(), slice.end(), uint8_t(0xAB));
  }
  EXPECT_EQ(d.finish(), pmz::Status::truncated);
  const uint64_t consumed = d.bytes_consumed();
  EXPECT_EQ(consumed, cut);
  EXPECT_EQ(d.feed(file.data() + cut, 5), pmz::Status::truncated);
  EXPECT_EQ(d.bytes_consumed(), consumed);
  EXPECT_GT(d.refine(), 0u);
  EXPECT_EQ(d.status(), pmz::Status::truncated);
  EXPECT_EQ(d.splits_applied(), d.splits_available());

  pmz::Decoder whole;
  std::vector<uint8_t> padded = file;
  padded.insert(padded.end(), {1, 2, 3, 4, 5, 6, 7, 8});
  ASSERT_EQ(whole.feed(padded.data(), padded.size()), pmz::Status::ok) << whole.error_message();
  EXPECT_EQ(whole.finish(), pmz::Status::ok);
  EXPECT_TRUE(whole.info().complete);
  whole.refine();
  const float* positions = whole.positions();
  const uint32_t faces = whole.face_count();
  pmz::Decoder moved = std::move(whole);
  EXPECT_EQ(moved.positions(), positions);
  EXPECT_EQ(moved.face_count(), faces);
}

// Counting what each ATTR symbol costs (Decoder::count_attribute_bits, for pmz-info) changes no
// decoded result, and the counts add up to the ATTR chunks' payloads but for the range coder's
// start and end (a few bytes per chunk).
TEST(AttributeBits, CountingChangesNothingAndAddsUp) {
  const std::vector<uint8_t> file = load(PMZ_SOURCE_DIR "/tests/conformance/vectors/seamed-q.pmz");
  ASSERT_FALSE(file.empty());
  pmz::Decoder plain, counted;
  pmz::AttributeBits b;
  counted.count_attribute_bits(&b);
  ASSERT_EQ(plain.feed(file.data(), file.size()), pmz::Status::ok);
  for (size_t at = 0; at < file.size(); at += 7)
    ASSERT_EQ(counted.feed(file.data() + at, std::min<size_t>(7, file.size() - at)),
              pmz::Status::ok);
  ASSERT_EQ(plain.finish(), pmz::Status::ok);
  ASSERT_EQ(counted.finish(), pmz::Status::ok);
  for (uint64_t target : {uint64_t(40), ~uint64_t(0), uint64_t(100), ~uint64_t(0)}) {
    plain.set_split_target(target);
    counted.set_split_target(target);
    ASSERT_GT(plain.wedge_count(), 0u);
    EXPECT_TRUE(arrays(plain) == arrays(counted)) << "at " << target << " splits";
  }
  ASSERT_EQ(counted.splits_applied(), counted.info().total_splits);

  double bits = 0;
  for (double kind : b.bits) {
    EXPECT_GT(kind, 0);
    bits += kind;
  }
  uint64_t payload = 0, chunks = 0, split_chunks = 0;
  for (size_t at : chunk_offsets(file)) {
    const pmz::ChunkFrame f = frame_at(file, at);
    if (f.type == pmz::kChunkAttributes) payload += f.payload_size, ++chunks;
    split_chunks += f.type == pmz::kChunkSplits;
  }
  ASSERT_GT(split_chunks, 0u);
  ASSERT_EQ(chunks, split_chunks + 1);  // the base's and one per SPLT chunk
  const double bytes = bits / 8;
  EXPECT_LE(bytes, double(payload) + 1) << payload << " bytes of ATTR payload";
  EXPECT_GE(bytes, double(payload) - 4 * double(chunks)) << payload << " bytes of ATTR payload";
}

}  // namespace
