#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

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

TEST(CApi, DecodesSampleFile) {
  FILE* f = std::fopen(PMZ_SOURCE_DIR "/tests/data/sample.pmz", "rb");
  ASSERT_NE(f, nullptr);
  std::vector<unsigned char> bytes(1 << 16);
  bytes.resize(std::fread(bytes.data(), 1, bytes.size(), f));
  std::fclose(f);
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
