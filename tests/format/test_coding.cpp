#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "pmz/coding.hpp"
#include "pmz/progressive_mesh.hpp"
#include "pmz/split_codec.hpp"

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

// Wedge symbols (spec section 4): every valid wedge of a fan maps to (count, rank) and back,
// on closed and open fans, random and degenerate (all scores tied) geometry, and lossless-range
// coordinates (the scores need 128 bits there).
TEST(WedgeSymbols, EveryWedgeRoundTrips) {
  std::mt19937 rng(11);
  WedgeScratch scratch;
  for (uint32_t k = 2; k <= 12; ++k)
    for (int closed = 0; closed < 2; ++closed) {
      if (closed && k < 3) continue;
      // Centre 0, ring 1..k counter-clockwise.
      std::vector<uint32_t> faces;
      const uint32_t m = closed ? k : k - 1;
      for (uint32_t i = 0; i < m; ++i) faces.insert(faces.end(), {0, 1 + i, 1 + (i + 1) % k});
      ProgressiveMesh pm;
      std::string error;
      ASSERT_TRUE(pm.build(k + 1, faces.data(), m, error)) << error;
      for (int geometry = 0; geometry < 3; ++geometry) {
        std::vector<int32_t> coords(size_t(k + 1) * 3, 0);
        for (auto& c : coords)
          c = geometry == 0 ? 0 : geometry == 1 ? int32_t(rng() % 16384) : int32_t(rng());
        ASSERT_TRUE(pm.gather_ring(0));
        ASSERT_EQ(pm.ring().size(), k);
        ASSERT_EQ(pm.ring_closed(), closed == 1);
        uint32_t pairs = 0;
        for (uint32_t a = 0; a <= k; ++a)
          for (uint32_t b = 0; b <= k; ++b) {
            const uint32_t ra = a == k ? kNoRank : a, rb = b == k ? kNoRank : b;
            uint32_t count = 0, rank = 0, ga = 0, gb = 0;
            const bool valid = closed ? (a < k && b < k && a != b)
                                      : !(ra == kNoRank && rb == kNoRank) && (ra == kNoRank || rb == kNoRank || ra < rb);
            ASSERT_EQ(wedge_symbols(coords.data(), 0, pm, ra, rb, count, rank, scratch), valid);
            if (!valid) continue;
            ++pairs;
            ASSERT_TRUE(wedge_ranks(coords.data(), 0, pm, count, rank, ga, gb, scratch))
                << "k " << k << " closed " << closed << " count " << count << " rank " << rank;
            EXPECT_EQ(ga, ra);
            EXPECT_EQ(gb, rb);
            // Out of range symbols are refused.
            EXPECT_FALSE(wedge_ranks(coords.data(), 0, pm, closed ? k - 1 : k, 0, ga, gb, scratch));
            EXPECT_FALSE(wedge_ranks(coords.data(), 0, pm, count, k + 1, ga, gb, scratch));
          }
        EXPECT_EQ(pairs, closed ? k * (k - 1) : (k + 1) * k / 2 + k);
      }
    }
}
