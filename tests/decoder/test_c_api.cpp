// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "pmz/coding.hpp"
#include "pmz/decoder.hpp"
#include "pmz/format.hpp"
#include "pmz/pmz.h"

TEST(CApi, RejectsNonPmzBytes) {
  pmz_decoder* d = pmz_decoder_create(0, 0);
  ASSERT_NE(d, nullptr);
  const char junk[] = "this is not a pmz stream";
  EXPECT_NE(pmz_decoder_feed(d, junk, sizeof junk), PMZ_OK);
  EXPECT_STRNE(pmz_decoder_error(d), "");
  EXPECT_EQ(pmz_decoder_face_count(d), 0u);
  pmz_decoder_destroy(d);
}

std::vector<unsigned char> read_sample() {
  std::vector<unsigned char> bytes;
  if (FILE* f = std::fopen(PMZ_SOURCE_DIR "/tests/data/sample.pmz", "rb")) {
    bytes.resize(1 << 16);
    bytes.resize(std::fread(bytes.data(), 1, bytes.size(), f));
    std::fclose(f);
  }
  return bytes;
}

TEST(CApi, DecodesSampleFile) {
  std::vector<unsigned char> bytes = read_sample();
  ASSERT_FALSE(bytes.empty());
  pmz_decoder* d = pmz_decoder_create(0, 0);
  ASSERT_EQ(pmz_decoder_feed(d, bytes.data(), bytes.size()), PMZ_OK);
  ASSERT_EQ(pmz_decoder_finish(d), PMZ_OK);
  uint64_t total = pmz_decoder_total_splits(d);
  EXPECT_GT(total, 0u);
  EXPECT_EQ(pmz_decoder_refine(d, UINT64_MAX), total);
  EXPECT_EQ(pmz_decoder_face_count(d), 128u);
  EXPECT_NE(pmz_decoder_positions(d), nullptr);
  pmz_decoder_set_face_target(d, 10);
  EXPECT_GE(pmz_decoder_face_count(d), 10u);
  EXPECT_LT(pmz_decoder_face_count(d), 128u);
  uint64_t applied = pmz_decoder_splits_applied(d);
  EXPECT_EQ(pmz_decoder_coarsen(d, UINT64_MAX), applied);
  EXPECT_EQ(pmz_decoder_splits_applied(d), 0u);
  pmz_decoder_destroy(d);
}

// Damage in a geometry stream (CRC repaired) passes feed() and finish(): it shows when the split
// is first applied, and pmz_decoder_status() reports it.
TEST(CApi, StatusReportsDamageFoundWhileRefining) {
  std::vector<unsigned char> b = read_sample();
  ASSERT_FALSE(b.empty());
  // First SPLT chunk: fill its geometry stream (the payload after split_count, the connectivity
  // stream's size and that stream) with 0xFF bytes. The code value then stays at the top of the
  // range, so every decision decodes as 1: the first residual's length escape reads 31 (n = 46
  // > 32), corrupt at the first split.
  size_t at = 8;
  pmz::ChunkFrame f;
  while (pmz::parse_chunk_frame(&b[at], b.size() - at, f) == pmz::FrameStatus::ok &&
         f.type != pmz::kChunkSplits)
    at += f.header_size + size_t(f.payload_size);
  ASSERT_EQ(f.type, pmz::kChunkSplits);
  const size_t size = size_t(f.payload_size), payload = at + f.header_size;
  pmz::ByteReader r(&b[payload], size);
  r.varint();
  r.bytes(size_t(r.varint()));
  ASSERT_TRUE(r.ok);
  ASSERT_GT(r.remaining(), 0u);
  for (size_t i = size - r.remaining(); i < size; ++i) b[payload + i] = 0xFF;
  pmz::repair_chunk_crc(&b[at], f);

  pmz_decoder* d = pmz_decoder_create(0, 0);
  ASSERT_EQ(pmz_decoder_feed(d, b.data(), b.size()), PMZ_OK);
  ASSERT_EQ(pmz_decoder_finish(d), PMZ_OK);
  EXPECT_EQ(pmz_decoder_status(d), PMZ_OK);
  const uint64_t applied = pmz_decoder_refine(d, UINT64_MAX);
  EXPECT_LT(applied, pmz_decoder_total_splits(d));
  EXPECT_EQ(pmz_decoder_status(d), PMZ_ERR_CORRUPT);
  EXPECT_STRNE(pmz_decoder_error(d), "");
  EXPECT_EQ(pmz_decoder_splits_applied(d), applied);
  pmz_decoder_destroy(d);
}

TEST(CApi, InfoProgressAndStatusNames) {
  std::vector<unsigned char> bytes = read_sample();
  ASSERT_FALSE(bytes.empty());
  pmz_decoder* d = pmz_decoder_create(0, 0);
  pmz_stream_info info;
  pmz_decoder_info(d, &info);
  EXPECT_EQ(info.header_done, 0u);
  ASSERT_EQ(pmz_decoder_feed(d, bytes.data(), bytes.size()), PMZ_OK);
  EXPECT_EQ(pmz_decoder_bytes_consumed(d), bytes.size());
  pmz_decoder_info(d, &info);
  EXPECT_EQ(info.header_done, 1u);
  EXPECT_EQ(info.base_done, 1u);
  EXPECT_EQ(info.complete, 1u);
  EXPECT_EQ(info.full_faces, 128u);
  EXPECT_EQ(info.total_splits, pmz_decoder_total_splits(d));
  EXPECT_EQ(info.full_vertices, info.base_vertices + info.total_splits);
  EXPECT_LE(info.bbox_min[0], info.bbox_max[0]);
  pmz_decoder_set_split_target(d, info.total_splits);
  EXPECT_EQ(pmz_decoder_splits_applied(d), info.total_splits);
  const uint32_t* parents = pmz_decoder_split_parents(d);
  const uint32_t base = uint32_t(info.base_vertices), n = pmz_decoder_vertex_count(d);
  for (uint32_t v = 0; v < n; ++v) EXPECT_EQ(parents[v] == UINT32_MAX, v < base) << v;
  EXPECT_STREQ(pmz_status_name(PMZ_OK), "ok");
  EXPECT_STREQ(pmz_status_name(PMZ_ERR_TRUNCATED), "truncated stream");
  EXPECT_STREQ(pmz_status_name(99), "unknown");
  EXPECT_STREQ(pmz_status_name(-1), "unknown");
  pmz_decoder_destroy(d);
}

// The change report after each refinement step names exactly what differs from the mesh
// before it: applying it to a copy of the old buffers reproduces the new ones.
TEST(CApi, ChangeReportCoversEveryDifference) {
  std::vector<unsigned char> bytes = read_sample();
  ASSERT_FALSE(bytes.empty());
  pmz_decoder* d = pmz_decoder_create(0, 0);
  ASSERT_EQ(pmz_decoder_feed(d, bytes.data(), bytes.size()), PMZ_OK);
  pmz_changes c;
  pmz_decoder_changes(d, &c);
  EXPECT_EQ(c.all, 1u);
  pmz_decoder_clear_changes(d);
  std::vector<float> pos(pmz_decoder_positions(d),
                         pmz_decoder_positions(d) + 3 * pmz_decoder_vertex_count(d));
  std::vector<uint32_t> idx(pmz_decoder_indices(d),
                            pmz_decoder_indices(d) + 3 * pmz_decoder_face_count(d));
  while (pmz_decoder_refine(d, 3) > 0) {
    pmz_decoder_changes(d, &c);
    ASSERT_EQ(c.all, 0u);
    const uint32_t nv = pmz_decoder_vertex_count(d), nf = pmz_decoder_face_count(d);
    ASSERT_LE(c.vertex_begin, nv);
    ASSERT_LE(c.face_begin, nf);
    pos.resize(3 * size_t(nv));
    idx.resize(3 * size_t(nf));
    const float* p = pmz_decoder_positions(d);
    const uint32_t* f = pmz_decoder_indices(d);
    for (size_t k = 3 * size_t(c.vertex_begin); k < pos.size(); ++k) pos[k] = p[k];
    for (size_t k = 3 * size_t(c.face_begin); k < idx.size(); ++k) idx[k] = f[k];
    for (size_t m = 0; m < c.modified_count; ++m)
      for (size_t k = 0; k < 3; ++k)
        idx[3 * size_t(c.modified_faces[m]) + k] = f[3 * size_t(c.modified_faces[m]) + k];
    EXPECT_EQ(std::memcmp(pos.data(), p, pos.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(idx.data(), f, idx.size() * sizeof(uint32_t)), 0);
    pmz_decoder_clear_changes(d);
  }
  EXPECT_EQ(pmz_decoder_face_count(d), 128u);
  pmz_decoder_destroy(d);
}

// One version everywhere: the header's macros, the CMake project's version (read from them),
// and what the C and C++ libraries report at run time.
TEST(CApi, VersionIsTheHeadersAndTheProjects) {
  EXPECT_EQ(PMZ_VERSION_NUMBER,
            PMZ_VERSION_MAJOR * 10000 + PMZ_VERSION_MINOR * 100 + PMZ_VERSION_PATCH);
  const std::string header = std::to_string(PMZ_VERSION_MAJOR) + "." +
                             std::to_string(PMZ_VERSION_MINOR) + "." +
                             std::to_string(PMZ_VERSION_PATCH);
  EXPECT_EQ(header, PMZ_PROJECT_VERSION);
  EXPECT_EQ(pmz_version(), uint32_t(PMZ_VERSION_NUMBER));
  EXPECT_EQ(pmz::version(), pmz_version());
}
