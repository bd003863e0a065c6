#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "pmz/coding.hpp"

using namespace pmz;

TEST(Crc32, MatchesZlibCheckValue) {
  const char* s = "123456789";
  EXPECT_EQ(crc32(s, std::strlen(s)), 0xCBF43926u);
  EXPECT_EQ(crc32(nullptr, 0), 0u);
  // Incremental use gives the same value as one call.
  EXPECT_EQ(crc32(s + 4, 5, crc32(s, 4)), 0xCBF43926u);
}

TEST(Varint, RoundTripsEdgeValues) {
  std::vector<uint64_t> values = {0, 1, 127, 128, 255, 16383, 16384, 0xFFFFFFFFull, ~0ull};
  std::mt19937_64 rng(7);
  for (int i = 0; i < 1000; ++i) values.push_back(rng() >> (rng() % 64));
  std::vector<uint8_t> buf;
  for (uint64_t v : values) put_varint(buf, v);
  ByteReader r(buf.data(), buf.size());
  for (uint64_t v : values) EXPECT_EQ(r.varint(), v);
  EXPECT_TRUE(r.ok);
  EXPECT_EQ(r.remaining(), 0u);
}

TEST(Varint, RejectsTruncatedAndOverlong) {
  std::vector<uint8_t> buf;
  put_varint(buf, 1ull << 40);
  ByteReader r(buf.data(), buf.size() - 1);
  r.varint();
  EXPECT_FALSE(r.ok);
  std::vector<uint8_t> overlong(11, 0xFF);
  ByteReader r2(overlong.data(), overlong.size());
  r2.varint();
  EXPECT_FALSE(r2.ok);
}

TEST(ZigZag, RoundTrips) {
  for (int32_t v : {0, 1, -1, 2, -2, 1 << 30, -(1 << 30), INT32_MAX, INT32_MIN})
    EXPECT_EQ(zigzag_decode(zigzag_encode(v)), v);
  EXPECT_EQ(zigzag_encode(-1), 1u);
  EXPECT_EQ(zigzag_encode(1), 2u);
}

TEST(ByteReader, FailsPastEnd) {
  uint8_t b[3] = {1, 2, 3};
  ByteReader r(b, 3);
  EXPECT_EQ(r.u32le(), 0u);
  EXPECT_FALSE(r.ok);
}
