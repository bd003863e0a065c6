// Streaming decoder behaviour on a committed sample (tests/data/sample.pmz: a 128-face bumpy
// sphere written by pmz-encode): prefixes, chunkings, level moves, change tracking, bad input.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "pmz/coding.hpp"
#include "pmz/decoder.hpp"

namespace {

std::vector<uint8_t> load_sample() {
  std::vector<uint8_t> out;
  FILE* f = std::fopen(PMZ_SOURCE_DIR "/tests/data/sample.pmz", "rb");
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

// Rewrites a chunk's CRC so corruption reaches the parser instead of the checksum.
void fix_crc(std::vector<uint8_t>& b, size_t chunk_at) {
  uint32_t size = uint32_t(b[chunk_at + 4]) | uint32_t(b[chunk_at + 5]) << 8 |
                  uint32_t(b[chunk_at + 6]) << 16 | uint32_t(b[chunk_at + 7]) << 24;
  uint32_t crc = pmz::crc32(b.data() + chunk_at + 12, size, pmz::crc32(b.data() + chunk_at, 8));
  for (int i = 0; i < 4; ++i) b[chunk_at + 8 + i] = uint8_t(crc >> (8 * i));
}

class DecoderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    file = load_sample();
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
    ASSERT_EQ(d.feed(file.data(), n), pmz::Status::ok) << "prefix " << n << ": " << d.error_message();
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
      d.set_face_target(levels[target].indices.size() / 3);
      target = d.splits_applied();
      EXPECT_GE(d.face_count(), levels[target].indices.size() / 3);
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
    if (rng() % 3) d.refine(rng() % 6);
    else d.coarsen(rng() % 6);
    const Snapshot after = snap(d);
    const pmz::MeshChanges& c = d.changes();
    ASSERT_FALSE(c.all);
    ASSERT_LE(c.face_begin, d.face_count());
    ASSERT_LE(c.vertex_begin, d.vertex_count());
    for (uint32_t f = 0; f < c.face_begin; ++f) {
      bool same = std::equal(after.indices.begin() + f * 3, after.indices.begin() + f * 3 + 3,
                             before.indices.begin() + f * 3);
      bool listed = std::find(c.modified_faces.begin(), c.modified_faces.end(), f) != c.modified_faces.end();
      ASSERT_TRUE(same || listed) << "face " << f << " changed but is not listed";
    }
    for (uint32_t v = 0; v < c.vertex_begin * 3; ++v) ASSERT_EQ(after.positions[v], before.positions[v]);
  }
}

TEST_F(DecoderTest, RejectsWrongMagicAndVersion) {
  std::vector<uint8_t> b = file;
  b[1] = 'X';
  pmz::Decoder d;
  EXPECT_EQ(d.feed(b.data(), b.size()), pmz::Status::bad_magic);
  EXPECT_FALSE(d.error_message().empty());
  EXPECT_EQ(d.face_count(), 0u);

  b = file;
  b[8 + 12] = 5;  // HEAD payload: version_major (5: the previous major, before vertex-choice exclusion, the wedge score and the adaptive coder)
  fix_crc(b, 8);
  pmz::Decoder v;
  EXPECT_EQ(v.feed(b.data(), b.size()), pmz::Status::bad_version);
  EXPECT_NE(v.error_message().find("version"), std::string::npos);
}

TEST_F(DecoderTest, BadChecksumKeepsLastGoodLevel) {
  // Corrupt the last byte of the last split chunk's payload (just before the END chunk).
  std::vector<uint8_t> b = file;
  b[b.size() - 13] ^= 0x5A;
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
  std::vector<uint8_t> b = file;
  // HEAD payload offsets: full_vertices at 16, total_splits at 24; base_vertices at 8.
  auto put = [&](size_t off, uint32_t v) {
    for (int i = 0; i < 4; ++i) b[8 + 12 + off + i] = uint8_t(v >> (8 * i));
  };
  put(16, 0xFFFFFFF0u);
  put(24, 0xFFFFFFF0u - 4);
  put(8, 4);
  fix_crc(b, 8);
  pmz::Decoder d;
  EXPECT_EQ(d.feed(b.data(), b.size()), pmz::Status::limit_exceeded);

  b = file;
  put(16, 1000);  // inconsistent with base + splits
  fix_crc(b, 8);
  pmz::Decoder c;
  EXPECT_EQ(c.feed(b.data(), b.size()), pmz::Status::corrupt);

  // A chunk claiming a huge payload is refused from its header alone.
  b.assign(file.begin(), file.begin() + 8);
  const uint8_t huge[12] = {'S', 'P', 'L', 'T', 0xFF, 0xFF, 0xFF, 0x7F, 0, 0, 0, 0};
  b.insert(b.end(), huge, huge + 12);
  pmz::DecoderLimits small;
  small.max_chunk_bytes = 1 << 20;
  pmz::Decoder l(small);
  EXPECT_EQ(l.feed(b.data(), b.size()), pmz::Status::limit_exceeded);
}

TEST_F(DecoderTest, CorruptedPayloadsNeverCrash) {
  // Flip bytes inside chunks and repair the CRCs, so the parser sees the damage.
  std::vector<size_t> chunks;
  for (size_t at = 8; at + 12 <= file.size();) {
    chunks.push_back(at);
    at += 12 + (uint32_t(file[at + 4]) | uint32_t(file[at + 5]) << 8);
  }
  std::mt19937 rng(99);
  int errors = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<uint8_t> b = file;
    size_t c = chunks[rng() % chunks.size()];
    size_t size = uint32_t(b[c + 4]) | uint32_t(b[c + 5]) << 8;
    if (!size) continue;
    for (int k = 0; k < 1 + int(rng() % 3); ++k) b[c + 12 + rng() % size] ^= uint8_t(1 + rng() % 255);
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
  // Insert an unknown chunk right after HEAD.
  size_t head_end = 8 + 12 + (uint32_t(file[12]) | uint32_t(file[13]) << 8);
  std::vector<uint8_t> extra = {'x', 't', 'r', 'a', 3, 0, 0, 0, 0, 0, 0, 0, 1, 2, 3};
  std::vector<uint8_t> b(file.begin(), file.begin() + ptrdiff_t(head_end));
  b.insert(b.end(), extra.begin(), extra.end());
  fix_crc(b, head_end);
  b.insert(b.end(), file.begin() + ptrdiff_t(head_end), file.end());
  pmz::Decoder d;
  ASSERT_EQ(d.feed(b.data(), b.size()), pmz::Status::ok) << d.error_message();
  d.refine();
  EXPECT_EQ(d.face_count(), 128u);
}

}  // namespace
