#include <gtest/gtest.h>

#include <algorithm>
#include <climits>
#include <cstdlib>
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

TEST(Crc32, EightByteStepsMatchBitwiseDefinition) {
  // Bit-at-a-time CRC straight from the definition, against every length 0..300 at every
  // alignment 0..7 (the 8-byte steps, the byte tail and their joins), and split calls.
  auto reference = [](const uint8_t* p, size_t n) {
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; ++i) {
      c ^= p[i];
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    }
    return ~c;
  };
  std::mt19937 rng(11);
  std::vector<uint8_t> buf(320);
  for (uint8_t& b : buf) b = uint8_t(rng());
  for (size_t align = 0; align < 8; ++align)
    for (size_t n = 0; n <= 300; ++n) {
      const uint8_t* p = buf.data() + align;
      ASSERT_EQ(crc32(p, n), reference(p, n)) << "length " << n << " at " << align;
      const size_t cut = n / 3;
      ASSERT_EQ(crc32(p + cut, n - cut, crc32(p, cut)), reference(p, n)) << "length " << n;
    }
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

// A fan around vertex 0 with ring 1..k counter-clockwise, closed or open.
bool build_fan(ProgressiveMesh& pm, uint32_t k, bool closed) {
  std::vector<uint32_t> faces;
  const uint32_t m = closed ? k : k - 1;
  for (uint32_t i = 0; i < m; ++i) faces.insert(faces.end(), {0, 1 + i, 1 + (i + 1) % k});
  std::string error;
  return pm.build(k + 1, faces.data(), m, error);
}

// Calls body(pm, k, closed) for the fans around vertex 0 of ring size 2..max_k, open and closed
// (a closed fan needs k >= 3).
template <class Body>
void for_each_fan(uint32_t max_k, Body body) {
  for (uint32_t k = 2; k <= max_k; ++k)
    for (int closed = 0; closed < 2; ++closed) {
      if (closed && k < 3) continue;
      ProgressiveMesh pm;
      ASSERT_TRUE(build_fan(pm, k, closed)) << "k " << k << " closed " << closed;
      body(pm, k, closed);
    }
}

// Wedge symbols (spec section 4): every valid wedge of a fan maps to (count, rank) and back,
// on closed and open fans, random and degenerate (all scores tied) geometry, and lossless-range
// coordinates (the scores need 128 bits there).
TEST(WedgeSymbols, EveryWedgeRoundTrips) {
  std::mt19937 rng(11);
  WedgeScratch scratch;
  for_each_fan(12, [&](ProgressiveMesh& pm, uint32_t k, int closed) {
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
  });
}

// The wedge order against spec/format.md section 4 written out directly (a second reading of
// the formula, not the codec's prefix sums): E = 2 * sum of e over the interior + e_a + e_b,
// score = |E|^2 in 128 bits, highest first, ties by smaller j. Coordinates up to the int32
// extremes (lossless mode codes float bit patterns) so both of the codec's paths are covered.
TEST(WedgeSymbols, OrderIsTheSpecFormula) {
  std::mt19937 rng(5);
  WedgeScratch scratch;
  for_each_fan(10, [&](ProgressiveMesh& pm, uint32_t k, int closed) {
      ASSERT_TRUE(pm.gather_ring(0));
      for (int geometry = 0; geometry < 4; ++geometry) {
        std::vector<int32_t> coords(size_t(k + 1) * 3);
        for (auto& c : coords)
          c = geometry == 0   ? int32_t(rng() % 5)  // many ties
              : geometry == 1 ? int32_t(rng() % 16384)
              : geometry == 2 ? int32_t(rng())
                              : (rng() & 1 ? INT32_MAX : INT32_MIN);
        // e by canonical rank.
        std::vector<WedgeScoreSigned> e(size_t(k) * 3);
        for (uint32_t r = 0; r < k; ++r) {
          const uint32_t w = pm.ring()[(r + pm.ring_start()) % k];
          for (int a = 0; a < 3; ++a) e[r * 3 + a] = WedgeScoreSigned(coords[w * 3 + a]) - coords[a];
        }
        const uint32_t max_count = closed ? k - 2 : k - 1;
        for (uint32_t count = 0; count <= max_count; ++count) {
          const uint32_t n = closed ? k : k - count + 1;
          std::vector<WedgeScore> score(n);
          for (uint32_t j = 0; j < n; ++j) {
            WedgeScoreSigned E[3] = {0, 0, 0};
            for (uint32_t i = 0; i < count; ++i) {
              const uint32_t r = closed ? (j + 1 + i) % k : j + i;
              for (int a = 0; a < 3; ++a) E[a] += 2 * e[r * 3 + a];
            }
            const bool has_a = closed || j > 0, has_b = closed || j + count < k;
            const uint32_t ra = closed ? j : j - 1, rb = closed ? (j + count + 1) % k : j + count;
            for (int a = 0; a < 3; ++a) E[a] += (has_a ? e[ra * 3 + a] : 0) + (has_b ? e[rb * 3 + a] : 0);
            for (int a = 0; a < 3; ++a) score[j] += (WedgeScore)(E[a] * E[a]);
          }
          std::vector<uint32_t> order(n);
          for (uint32_t j = 0; j < n; ++j) order[j] = j;
          std::stable_sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) { return score[x] > score[y]; });
          for (uint32_t rank = 0; rank < n; ++rank) {
            const uint32_t j = order[rank];
            uint32_t ga, gb;
            ASSERT_TRUE(wedge_ranks(coords.data(), 0, pm, count, rank, ga, gb, scratch));
            const uint32_t ra = closed ? j : (j == 0 ? kNoRank : j - 1);
            const uint32_t rb = closed ? (j + count + 1) % k : (j + count == k ? kNoRank : j + count);
            EXPECT_EQ(ga, ra) << "k " << k << " closed " << closed << " count " << count << " rank " << rank;
            EXPECT_EQ(gb, rb) << "k " << k << " closed " << closed << " count " << count << " rank " << rank;
          }
        }
      }
  });
}

// Residual contexts (spec section 5): min(bitlen(floor(D_a / |R|)), 20), D_a = sum over R of
// |c[w][a] - p[a]| in 64 bits.
TEST(ResidualContexts, AreTheSpecFormula) {
  std::mt19937 rng(9);
  for (int trial = 0; trial < 2000; ++trial) {
    const uint32_t n = 2 + rng() % 9;
    std::vector<int32_t> coords(size_t(n) * 3);
    const int shift = int(rng() % 32);
    for (auto& c : coords) c = trial % 7 == 0 ? (rng() & 1 ? INT32_MAX : INT32_MIN) : int32_t(rng()) >> shift;
    std::vector<uint32_t> ring(n);
    for (uint32_t i = 0; i < n; ++i) ring[i] = i;
    int32_t pred[3];
    predict_position(coords.data(), ring, pred);
    uint32_t ctx[3];
    residual_contexts(coords.data(), ring, pred, ctx);
    for (int a = 0; a < 3; ++a) {
      uint64_t d = 0;
      for (uint32_t w : ring) d += uint64_t(std::llabs(int64_t(coords[w * 3 + a]) - pred[a]));
      const uint64_t mean = d / n;
      uint32_t bits = 0;
      while (bits < 64 && (mean >> bits) != 0) ++bits;
      EXPECT_EQ(ctx[a], std::min(bits, 20u)) << trial;
    }
  }
}

// Larger rings than above, up to 40 (the selection switches to nth_element from rank 16): the
// codec gives exactly the spec order (section 4): scores as
// written there (128-bit, E = 2 * interior sum + e_a + e_b) and a full sort, highest first, ties
// by smaller j. Rings up to 40 cover both selection paths (ranks below 16 and nth_element), coordinates
// small (64-bit scores), tied (all zero) and full-range (128-bit scores).
TEST(WedgeSymbols, OrderMatchesSpecReference) {
  std::mt19937 rng(23);
  WedgeScratch scratch;
  for (uint32_t k : {2u, 3u, 5u, 8u, 13u, 16u, 17u, 18u, 31u, 40u})
    for (int closed = 0; closed < 2; ++closed) {
      if (closed && k < 3) continue;
      ProgressiveMesh pm;
      ASSERT_TRUE(build_fan(pm, k, closed == 1));
      for (int geometry = 0; geometry < 4; ++geometry) {
        std::vector<int32_t> coords(size_t(k + 1) * 3, 0);
        for (auto& c : coords)
          c = geometry == 0 ? 0 : geometry == 1 ? int32_t(rng() % 16384) : geometry == 2 ? int32_t(rng() % 5) : int32_t(rng());
        ASSERT_TRUE(pm.gather_ring(0));
        const uint32_t start = pm.ring_start();
        std::vector<int64_t> e(k * 3);
        for (uint32_t i = 0; i < k; ++i)
          for (int a = 0; a < 3; ++a)
            e[i * 3 + a] = int64_t(coords[size_t(pm.ring()[(start + i) % k]) * 3 + a]) - coords[a];
        const uint32_t max_count = closed ? k - 2 : k - 1;
        for (uint32_t count = 0; count <= max_count; ++count) {
          const uint32_t n = closed ? k : k - count + 1;
          std::vector<WedgeScore> score(n);
          for (uint32_t j = 0; j < n; ++j) {
            const uint32_t first = closed ? j + 1 : j;
            for (int a = 0; a < 3; ++a) {
              WedgeScoreSigned E = 0;
              for (uint32_t i = first; i < first + count; ++i) E += 2 * e[(i % k) * 3 + a];
              if (closed || j > 0) E += e[((closed ? j : j - 1) % k) * 3 + a];
              if (closed || j + count < k) E += e[((first + count) % k) * 3 + a];
              score[j] += WedgeScore(E * E);
            }
          }
          std::vector<uint32_t> order(n);
          for (uint32_t j = 0; j < n; ++j) order[j] = j;
          std::sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) {
            return score[x] > score[y] || (score[x] == score[y] && x < y);
          });
          for (uint32_t rank = 0; rank < n; ++rank) {
            const uint32_t j = order[rank];
            const uint32_t ra = closed ? j : (j == 0 ? kNoRank : j - 1);
            const uint32_t rb = closed ? (j + count + 1) % k : (j + count == k ? kNoRank : j + count);
            uint32_t ga = 0, gb = 0, gc = 0, gr = 0;
            ASSERT_TRUE(wedge_ranks(coords.data(), 0, pm, count, rank, ga, gb, scratch));
            ASSERT_EQ(ga, ra) << "k " << k << " closed " << closed << " count " << count << " rank " << rank;
            ASSERT_EQ(gb, rb);
            ASSERT_TRUE(wedge_symbols(coords.data(), 0, pm, ra, rb, gc, gr, scratch));
            ASSERT_EQ(gc, count);
            ASSERT_EQ(gr, rank);
          }
        }
      }
    }
}
