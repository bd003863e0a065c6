#include <gtest/gtest.h>

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
