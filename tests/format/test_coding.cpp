// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>

#include "pmz/base_codec.hpp"
#include "pmz/coding.hpp"
#include "pmz/fan_wedge.hpp"
#include "pmz/node_table.hpp"
#include "pmz/progressive_mesh.hpp"
#include "pmz/range_coder.hpp"
#include "pmz/split_chunk.hpp"
#include "pmz/vertex_choice.hpp"

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

// spec/format.md section 11.1's adaptation, written out from the text: probability and count kept
// apart.
struct SpecModel {
  uint32_t p = 16384, count = 0;
  void update(uint32_t b) {
    const uint32_t shift = count < 8 ? 2 : count < 16 ? 3 : count < 48 ? 4 : count < 127 ? 5 : 6;
    if (b == 0)
      p += (32528 - p) >> shift;
    else
      p -= (p - 240) >> shift;
    if (count < 127) ++count;
  }
};

TEST(RangeCoder, AdaptationIsTheSpecSchedule) {
  // By hand: eight 1 bits at shift 2 from 16384, then shift 3: p - 240 = 16144 shrinks by a
  // quarter per step (the step rounded down), then an eighth.
  Prob m = kProbInit;
  const uint32_t want[] = {12348, 9321, 7051, 5349, 4072, 3114, 2396, 1857, 1655};
  for (uint32_t i = 0; i < 9; ++i) {
    m = adapt(m, 1);
    EXPECT_EQ(m & kProbMask, want[i]) << i;
  }
  EXPECT_EQ(adapt(kProbInit, 0) & kProbMask, 20420u);  // 16384 + (32528 - 16384) / 4
  std::mt19937 rng(7);
  for (int run = 0; run < 200; ++run) {
    SpecModel ref;
    Prob model = kProbInit;
    const uint32_t bias = rng() % 100;
    for (int i = 0; i < 300; ++i) {
      const uint32_t b = rng() % 100 < bias ? 1u : 0u;
      ref.update(b);
      model = adapt(model, b);
      ASSERT_EQ(model & kProbMask, ref.p) << run << " " << i;
      ASSERT_EQ(uint32_t(model >> kCountShift), ref.count) << run << " " << i;
    }
  }
}

// Every state reachable from the initial model or a primed one keeps the probability within
// [240, 32528] (the decoders normalise with one shift, which needs a coded bit to keep >= 2^16
// of the range: (2^24 >> 15) * 240 >= 2^16), and it comes within a step of both ends (a step
// moves p toward 240 or 32528 by a rounded-down fraction, so it never quite gets there).
TEST(RangeCoder, ReachableProbabilitiesStayInBounds) {
  static_assert(kProbMin == 240 && kProbMax == 32528 && kProbBits == 15);
  static_assert(((kTop >> kProbBits) * kProbMin) >= (1u << 16));
  // The lowest and highest probability over every state reachable from the starts.
  auto reach = [](std::vector<Prob> todo, uint32_t& lo, uint32_t& hi) {
    std::vector<uint8_t> seen(size_t(kMaxCount + 1) << kCountShift, 0);
    for (Prob m : todo) seen[m] = 1;
    lo = kProbOne, hi = 0;
    while (!todo.empty()) {
      const Prob m = todo.back();
      todo.pop_back();
      lo = std::min(lo, uint32_t(m & kProbMask));
      hi = std::max(hi, uint32_t(m & kProbMask));
      for (uint32_t b = 0; b < 2; ++b) {
        const Prob n = adapt(m, b);
        ASSERT_LT(n, seen.size());
        if (!seen[n]) seen[n] = 1, todo.push_back(n);
      }
    }
  };
  // Every primed start (a prior 240..32528 at count 16, e.g. the choice models') and the
  // initial model: the primed starts at the ends are the ends.
  std::vector<Prob> starts = {kProbInit};
  for (uint32_t p = kProbMin; p <= kProbMax; ++p) starts.push_back(primed_model(p));
  uint32_t lo, hi;
  reach(starts, lo, hi);
  EXPECT_EQ(lo, 240u);
  EXPECT_EQ(hi, 32528u);
  // From the initial model alone the ends are not reached: within 2^shift - 1 of them.
  reach({kProbInit}, lo, hi);
  EXPECT_GT(lo, 240u);
  EXPECT_LT(lo, 240u + 64);
  EXPECT_LT(hi, 32528u);
  EXPECT_GT(hi, 32528u - 64);
}

// Encoder and decoder are inverses at every probability a model can hold: per p in [240, 32528],
// a run of bits at that p (the first after a 1 at p = 16384, so the range is not 2^32 - 1),
// then the ending.
// spec/format.md section 12's count bounds: S bytes hold at most 755.8 (S + 1) adaptive decisions.
// The cheapest decision is a 1 at p = 240 (the rounding of range >> 15 favours it over a 0 at
// 32528): a stream of only those reaches 754.46 per byte of the interval (its ending aside), and
// decodes back. (The BASE bounds, 384 faces and 64 vertices per byte, rest on 755.8 / 2 and
// 755.8 / 12.)
TEST(RangeCoder, CheapestDecisionsPerByteAreTheCountBound) {
  const uint32_t decisions = 400000;
  std::vector<uint8_t> out;
  {
    RangeEncoder rc(out);
    for (uint32_t i = 0; i < decisions; ++i) {
      Prob m = kProbMin;  // the same probability each time
      rc.bit(m, 1);
    }
    rc.finish();
  }
  const double per_byte = double(decisions) / double(out.size() + 1);
  EXPECT_LE(per_byte, 755.8);
  EXPECT_GT(per_byte, 750.0);  // 751.9 here: the ending adds a byte or two
  EXPECT_LT(755.8 / 12, 64.0);
  EXPECT_LT(755.8 / 2, 384.0);
  RangeDecoder rd(out.data(), out.size());
  RangeState st = rd.state();
  for (uint32_t i = 0; i < decisions; ++i) {
    Prob m = kProbMin;
    ASSERT_EQ(st.bit(m), 1u) << i;
  }
  EXPECT_TRUE(st.ok);
}

TEST(RangeCoder, EveryProbabilityRoundTrips) {
  std::mt19937 rng(13);
  for (uint32_t p = kProbMin; p <= kProbMax; ++p) {
    const uint32_t bits = rng();
    std::vector<uint8_t> out;
    {
      RangeEncoder rc(out);
      Prob half = kProbInit;
      rc.bit(half, 1);
      for (int i = 0; i < 6; ++i) {
        Prob m = p;  // the same probability each time (count 0 only matters for adaptation)
        rc.bit(m, (bits >> i) & 1);
      }
      rc.finish();
    }
    RangeDecoder rd(out.data(), out.size());
    RangeState st = rd.state();
    Prob half = kProbInit;
    ASSERT_EQ(st.bit(half), 1u) << p;
    for (int i = 0; i < 6; ++i) {
      Prob m = p;
      ASSERT_EQ(st.bit(m), (bits >> i) & 1) << p << " " << i;
    }
    ASSERT_TRUE(st.ok) << p;
  }
}

TEST(RangeCoder, BitsDirectBitsAndValuesRoundTrip) {
  std::mt19937 rng(11);
  std::vector<uint8_t> out;
  Prob enc_models[4], dec_models[4];
  for (auto& p : enc_models) p = kProbInit;
  for (auto& p : dec_models) p = kProbInit;
  auto enc_uint = std::make_unique<UIntModel>(), dec_uint = std::make_unique<UIntModel>();
  std::vector<uint32_t> bits, values;
  {
    RangeEncoder rc(out);
    for (int i = 0; i < 20000; ++i) {
      const uint32_t k = i % 4, b = rng() % 100 < 10 + 25 * k ? 1u : 0u;
      bits.push_back(b);
      rc.bit(enc_models[k], b);
      const uint32_t x = uint32_t(rng()) >> (rng() % 32);
      values.push_back(x);
      encode_uint(rc, *enc_uint, x);
      rc.direct(x, 7);
    }
    rc.finish();
  }
  RangeDecoder rd(out.data(), out.size());
  RangeState s = rd.state();
  for (int i = 0; i < 20000; ++i) {
    ASSERT_EQ(s.bit(dec_models[i % 4]), bits[size_t(i)]) << i;
    uint32_t x;
    ASSERT_TRUE(decode_uint(s, *dec_uint, x));
    ASSERT_EQ(x, values[size_t(i)]) << i;
    ASSERT_EQ(s.direct(7), x & 127u) << i;
  }
  EXPECT_TRUE(s.ok);
  EXPECT_EQ(std::memcmp(enc_models, dec_models, sizeof enc_models), 0);
}

// spec/format.md section 11.3, "Mixed unsigned value", decoded by a reference written from the
// text: the value's binarization (bit length through the 4-level tree, the escape's 5-level tree,
// two mantissa bits), every modeled bit with the mean (rounded down) of both models' probabilities
// at the same node, both adapting; the rest direct.
TEST(RangeCoder, MixedValuesAreTheSpecRule) {
  struct Ref {
    SpecModel length[16], escape[32], high[33][4];
  };
  std::mt19937 rng(23);
  constexpr int kFirst = 3, kSecond = 4;
  auto enc_first = std::make_unique<UIntModel[]>(kFirst),
       enc_second = std::make_unique<UIntModel[]>(kSecond);
  auto ref_first = std::make_unique<Ref[]>(kFirst), ref_second = std::make_unique<Ref[]>(kSecond);
  std::vector<uint8_t> out;
  std::vector<uint32_t> values, c1, c2;
  {
    RangeEncoder rc(out);
    for (int i = 0; i < 30000; ++i) {
      const uint32_t a = rng() % kFirst, b = rng() % kSecond;
      const uint32_t x = i % 97 == 0 ? uint32_t(rng()) >> (rng() % 18)
                                     : (uint32_t(rng()) >> (24 + a + b)) + (i % 5 == 0 ? 0 : b);
      values.push_back(x), c1.push_back(a), c2.push_back(b);
      encode_uint_mixed(rc, enc_first[a], enc_second[b], x);
    }
    rc.finish();
  }
  RangeDecoder rd(out.data(), out.size());
  RangeState s = rd.state();
  auto bit = [&](SpecModel& m, SpecModel& m2) {
    const uint32_t p = (m.p + m2.p) / 2, bound = (s.range >> 15) * p;
    uint32_t b = 0;
    if (s.code < bound) {
      s.range = bound;
    } else {
      s.code -= bound, s.range -= bound, b = 1;
    }
    m.update(b);
    m2.update(b);
    s.normalize();
    return b;
  };
  for (size_t i = 0; i < values.size(); ++i) {
    Ref &f = ref_first[c1[i]], &g = ref_second[c2[i]];
    uint32_t node = 1;
    for (int level = 0; level < 4; ++level) node = node * 2 + bit(f.length[node], g.length[node]);
    uint32_t n = node - 16;
    if (n == 15) {
      node = 1;
      for (int level = 0; level < 5; ++level) node = node * 2 + bit(f.escape[node], g.escape[node]);
      n = node - 32 + 15;
    }
    ASSERT_LE(n, 32u) << i;
    uint32_t x = n;
    if (n >= 2) {
      uint32_t rest = n - 1, h = 1;
      x = 1;
      for (int j = 0; j < 2 && rest; ++j, --rest) {
        const uint32_t b = bit(f.high[n][h], g.high[n][h]);
        h = h * 2 + b, x = x * 2 + b;
      }
      x = (x << rest) | s.direct(rest);
    }
    ASSERT_EQ(x, values[i]) << i;
  }
  EXPECT_TRUE(s.ok);
  // Every model of the coder ends where the reference's does (which bits touched which model).
  auto same = [](const UIntModel& m, const Ref& r) {
    auto eq = [](Prob x, const SpecModel& y) {
      return (x & kProbMask) == y.p && (x >> kCountShift) == y.count;
    };
    for (int j = 0; j < 16; ++j)
      if (!eq(m.length[j], r.length[j])) return false;
    for (int j = 0; j < 32; ++j)
      if (!eq(m.escape[j], r.escape[j])) return false;
    for (int n = 0; n < 33; ++n)
      for (int j = 0; j < 4; ++j)
        if (!eq(m.high[n][j], r.high[n][j])) return false;
    return true;
  };
  for (int a = 0; a < kFirst; ++a) EXPECT_TRUE(same(enc_first[a], ref_first[a])) << a;
  for (int b = 0; b < kSecond; ++b) EXPECT_TRUE(same(enc_second[b], ref_second[b])) << b;
  // And the decoder agrees with both.
  RangeDecoder rd2(out.data(), out.size());
  auto dec_first = std::make_unique<UIntModel[]>(kFirst),
       dec_second = std::make_unique<UIntModel[]>(kSecond);
  for (size_t i = 0; i < values.size(); ++i) {
    uint32_t x;
    ASSERT_TRUE(decode_uint_mixed(rd2, dec_first[c1[i]], dec_second[c2[i]], x));
    ASSERT_EQ(x, values[i]) << i;
  }
  for (int a = 0; a < kFirst; ++a) EXPECT_TRUE(same(dec_first[a], ref_first[a])) << a;
  for (int b = 0; b < kSecond; ++b) EXPECT_TRUE(same(dec_second[b], ref_second[b])) << b;
}

// spec/format.md section 11.4's ending: the value in [low, low + range) with the most trailing zero
// bits, the stream without its first byte (0) and up to 4 trailing zero bytes; bytes past the end
// read as 0.
TEST(RangeCoder, StreamEndingIsTheShortestValue) {
  std::vector<uint8_t> out;
  {
    RangeEncoder rc(out);
    rc.finish();
  }
  EXPECT_TRUE(out.empty());  // nothing coded: value 0, every byte dropped
  {
    Prob m = kProbInit;
    RangeEncoder rc(out);
    rc.bit(m, 0);
    rc.finish();
  }
  EXPECT_TRUE(out.empty());  // a 0 keeps [0, 2^31): 0 again
  {
    // A 1 at p = 16384: low = (0xFFFFFFFF >> 15) * 16384 = 0x7FFFC000, low + range = 0xFFFFFFFF;
    // 0x80000000 is the value with the most trailing zeros in it: bytes 80 00 00 00 -> 80.
    Prob m = kProbInit;
    RangeEncoder rc(out);
    rc.bit(m, 1);
    rc.finish();
  }
  EXPECT_EQ(out, std::vector<uint8_t>{0x80});
  // An encoder appends after what the vector already holds, and strips only its own bytes.
  std::vector<uint8_t> more = {0, 0};
  {
    RangeEncoder rc(more);
    rc.finish();
  }
  EXPECT_EQ(more, (std::vector<uint8_t>{0, 0}));
}

TEST(RangeCoder, AtMostFourZeroBytesPastTheEnd) {
  std::vector<uint8_t> none;
  RangeDecoder d(none.data(), 0);  // code = 4 implied zero bytes
  RangeState s = d.state();
  EXPECT_TRUE(s.ok);
  Prob m = kProbInit;
  EXPECT_EQ(s.bit(m), 0u);  // range 2^31 - ...: no byte needed yet
  EXPECT_TRUE(s.ok);
  (void)s.direct(8);  // the range falls below 2^24: one more byte, a fifth past the end
  EXPECT_FALSE(s.ok);
  // Random streams decode from what finish() kept.
  std::mt19937 rng(5);
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<uint8_t> out;
    std::vector<uint32_t> bits;
    Prob em = kProbInit;
    {
      RangeEncoder rc(out);
      const int n = int(rng() % 200);
      for (int i = 0; i < n; ++i) {
        bits.push_back(rng() % 8 == 0 ? 1u : 0u);
        rc.bit(em, bits.back());
      }
      rc.finish();
    }
    RangeDecoder rd(out.data(), out.size());
    RangeState st = rd.state();
    Prob dm = kProbInit;
    for (uint32_t b : bits) ASSERT_EQ(st.bit(dm), b) << trial;
    EXPECT_TRUE(st.ok) << trial;
  }
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

// Wedge symbols (spec/format.md section 9.4): every valid wedge of a fan maps to (count, rank)
// and back, on closed and open fans, random and degenerate (all scores tied) geometry, and
// lossless-range coordinates (the scores need 128 bits there).
// Unsigned values (spec/format.md section 11.3): the bytes equal the binarization written out by
// hand (min(n, 15) through a 4-level tree, n - 15 through a 5-level escape tree, two modeled bits
// below the leading one per n, the rest direct), at the edges of the tree and of the escape;
// they round-trip; an escape above 17 (n > 32) is corrupt.
TEST(UIntModel, RoundTripsAndIsTheSpecBinarization) {
  const uint32_t values[] = {0,           1,
                             2,           3,
                             4,           5,
                             7,           8,
                             1000,        (1u << 13) - 1,
                             1u << 13,    (1u << 14) - 1,
                             1u << 14,    (1u << 14) + 5,
                             1u << 15,    (1u << 16) + 3,
                             0x7FFFFFFFu, 0x80000000u,
                             0xFFFFFFFFu};
  std::vector<uint8_t> bytes, manual;
  {
    RangeEncoder e(bytes), m(manual);
    auto a = std::make_unique<UIntModel>();
    Prob length[16], escape[32], high[33][4];
    for (auto& p : length) p = kProbInit;
    for (auto& p : escape) p = kProbInit;
    for (auto& h : high)
      for (auto& p : h) p = kProbInit;
    for (int pass = 0; pass < 3; ++pass)
      for (uint32_t x : values) {
        encode_uint(e, *a, x);
        const uint32_t n = x ? 32 - uint32_t(__builtin_clz(x)) : 0, s = n < 15 ? n : 15;
        for (uint32_t node = 1, i = 4; i-- > 0;) {
          m.bit(length[node], (s >> i) & 1);
          node = node * 2 + ((s >> i) & 1);
        }
        if (s == 15)
          for (uint32_t node = 1, i = 5; i-- > 0;) {
            m.bit(escape[node], ((n - 15) >> i) & 1);
            node = node * 2 + (((n - 15) >> i) & 1);
          }
        if (n >= 2) {
          uint32_t rest = n - 1, node = 1;
          for (int i = 0; i < 2 && rest; ++i) {
            const uint32_t b = (x >> --rest) & 1;
            m.bit(high[n][node], b);
            node = node * 2 + b;
          }
          m.direct(x, rest);
        }
      }
    e.finish();
    m.finish();
  }
  EXPECT_EQ(bytes, manual);
  RangeDecoder d(bytes.data(), bytes.size());
  RangeState st = d.state();
  auto a = std::make_unique<UIntModel>();
  for (int pass = 0; pass < 3; ++pass)
    for (uint32_t x : values) {
      uint32_t got = 0;
      ASSERT_TRUE(decode_uint(st, *a, got));
      EXPECT_EQ(got, x);
    }
  EXPECT_TRUE(st.ok);
  // Length 15 then escape e = 17 (n = 32) decodes; e = 18 .. 31 do not.
  for (uint32_t esc = 17; esc < 32; ++esc) {
    std::vector<uint8_t> out;
    {
      RangeEncoder rc(out);
      Prob length[16], escape[32];
      for (auto& p : length) p = kProbInit;
      for (auto& p : escape) p = kProbInit;
      for (uint32_t node = 1, i = 4; i-- > 0; node = node * 2 + 1) rc.bit(length[node], 1);
      for (uint32_t node = 1, i = 5; i-- > 0;) {
        rc.bit(escape[node], (esc >> i) & 1);
        node = node * 2 + ((esc >> i) & 1);
      }
      rc.direct(0, 31);  // n = 32: the two modeled bits read these as 0 too (any bits do)
      rc.finish();
    }
    RangeDecoder rd(out.data(), out.size());
    RangeState rs = rd.state();
    auto m = std::make_unique<UIntModel>();
    uint32_t x = 0;
    EXPECT_EQ(decode_uint(rs, *m, x), esc == 17) << esc;
  }
}

// Small values (spec/format.md section 11.3): round trip at the edges of the tree and of the
// escape, and the bytes of values below 7 equal three tree bits written out by hand (node from 1,
// most significant first); the escape is the tree's 7 then the uint model.
TEST(SmallModel, RoundTripsAndIsTheSpecTree) {
  const uint32_t values[] = {0,  1,  2,  3,  4,    6,           7,           8,          9,
                             14, 15, 16, 22, 1000, 0xFFFFFFF8u, 0xFFFFFFFEu, 0xFFFFFFFFu};
  std::vector<uint8_t> bytes, manual;
  {
    RangeEncoder e(bytes), m(manual);
    SmallModel a;
    Prob tree[8];
    for (auto& p : tree) p = kProbInit;
    UIntModel escape;
    for (int pass = 0; pass < 3; ++pass)
      for (uint32_t x : values) {
        encode_small(e, a, x);
        const uint32_t s = x < 7 ? x : 7;
        for (uint32_t node = 1, i = 3; i-- > 0;) {
          m.bit(tree[node], (s >> i) & 1);
          node = node * 2 + ((s >> i) & 1);
        }
        if (s == 7) encode_uint(m, escape, x - 7);
      }
    e.finish();
    m.finish();
  }
  EXPECT_EQ(bytes, manual);
  RangeDecoder d(bytes.data(), bytes.size());
  RangeState st = d.state();
  SmallModel a;
  for (int pass = 0; pass < 3; ++pass)
    for (uint32_t x : values) {
      uint32_t got = 0;
      ASSERT_TRUE(decode_small(st, a, got));
      EXPECT_EQ(got, x);
    }
  EXPECT_TRUE(st.ok);
}

// The vertex choice's density class without dividing = bitlen of the quotient.
TEST(VertexChoiceContext, BitlenQuotientIsBitlenOfTheQuotient) {
  auto bitlen = [](uint64_t x) { return x ? 64u - uint32_t(__builtin_clzll(x)) : 0u; };
  std::mt19937_64 rng(3);
  for (int i = 0; i < 200000; ++i) {
    const uint64_t D = rng() >> (rng() % 64), m = std::max<uint64_t>(1, rng() >> (rng() % 64));
    ASSERT_EQ(bitlen_quotient(D, m), bitlen(D / m)) << D << " / " << m;
  }
  for (uint64_t D = 0; D < 300; ++D)
    for (uint64_t m = 1; m < 300; ++m)
      ASSERT_EQ(bitlen_quotient(D, m), bitlen(D / m)) << D << " / " << m;
  EXPECT_EQ(bitlen_quotient(UINT64_MAX, 1), 64u);
  EXPECT_EQ(bitlen_quotient(UINT64_MAX, UINT64_MAX), 1u);
}

TEST(WedgeSymbols, EveryWedgeRoundTrips) {
  std::mt19937 rng(11);
  WedgeScratch scratch;
  for_each_fan(12, [&](ProgressiveMesh& pm, uint32_t k, int closed) {
    for (int geometry = 0; geometry < 3; ++geometry) {
      std::vector<int32_t> coords(size_t(k + 1) * 3, 0);
      for (auto& c : coords)
        c = geometry == 0 ? 0 : geometry == 1 ? int32_t(rng() % 16384) : int32_t(rng());
      std::vector<uint32_t> deg(k + 1);
      for (auto& d : deg) d = rng() % 9;
      ASSERT_TRUE(pm.gather_ring(0));
      ASSERT_EQ(pm.ring().size(), k);
      ASSERT_EQ(pm.ring_closed(), closed == 1);
      uint32_t pairs = 0;
      for (uint32_t a = 0; a <= k; ++a)
        for (uint32_t b = 0; b <= k; ++b) {
          const uint32_t ra = a == k ? kNoRank : a, rb = b == k ? kNoRank : b;
          uint32_t count = 0, rank = 0, ga = 0, gb = 0;
          const bool valid = closed ? (a < k && b < k && a != b)
                                    : !(ra == kNoRank && rb == kNoRank) &&
                                          (ra == kNoRank || rb == kNoRank || ra < rb);
          ASSERT_EQ(wedge_symbols(coords.data(), deg.data(), 0, pm, ra, rb, count, rank, scratch),
                    valid);
          if (!valid) continue;
          ++pairs;
          ASSERT_TRUE(wedge_ranks(coords.data(), deg.data(), 0, pm, count, rank, ga, gb, scratch))
              << "k " << k << " closed " << closed << " count " << count << " rank " << rank;
          EXPECT_EQ(ga, ra);
          EXPECT_EQ(gb, rb);
          // Out of range symbols are refused.
          EXPECT_FALSE(wedge_ranks(coords.data(), deg.data(), 0, pm, closed ? k - 1 : k, 0, ga, gb,
                                   scratch));
          EXPECT_FALSE(
              wedge_ranks(coords.data(), deg.data(), 0, pm, count, k + 1, ga, gb, scratch));
        }
      EXPECT_EQ(pairs, closed ? k * (k - 1) : (k + 1) * k / 2 + k);
    }
  });
}

// The wedge order of spec/format.md section 9.4 written out directly (a second reading of the
// formula, not the codec's prefix sums and packed weights): per candidate, in 128 bits, E = 2 *
// (sum of e over the interior) + e_a + e_b, S = sum of |e|^2 over the interior, T = 2 (|e_a|^2 +
// |e_b|^2) with both ends, 4 |e|^2 of the one end, 0 without; G = |E|^2 + 4 c S - c^2 T; weight
// m = 4 (degree <= 4), 3 (degree 5), 2 (more, or a missing end). Order: G >= 0 before G < 0;
// among G >= 0 by G m_a m_b, among G < 0 by the fraction G / (m_a m_b) (compared by cross
// multiplication, not by the codec's 12 / m weights), highest first; ties by smaller j.
// Returns the candidates j in order; confident: the rank's context bit (n < 2, or the second
// highest score <= 0, or the highest over twice the second; scores G m_a m_b for G >= 0).
std::vector<uint32_t> spec_wedge_order(const std::vector<int32_t>& coords,
                                       const std::vector<uint32_t>& deg, const ProgressiveMesh& pm,
                                       uint32_t count, bool& confident) {
  const uint32_t k = uint32_t(pm.ring().size());
  const bool closed = pm.ring_closed();
  auto vertex = [&](uint32_t r) {
    return pm.ring()[(r + pm.ring_start()) % k];
  };  // canonical rank r
  auto e = [&](uint32_t r, int a) {
    return WedgeScoreSigned(coords[size_t(vertex(r)) * 3 + a]) - coords[a];
  };
  auto len2 = [&](uint32_t r) { return e(r, 0) * e(r, 0) + e(r, 1) * e(r, 1) + e(r, 2) * e(r, 2); };
  auto weight = [&](bool has, uint32_t r) -> WedgeScoreSigned {
    if (!has) return 2;
    const uint32_t d = deg[vertex(r)];
    return d <= 4 ? 4 : d == 5 ? 3 : 2;
  };
  const uint32_t n = closed ? k : k - count + 1;
  std::vector<WedgeScoreSigned> G(n), M(n);
  for (uint32_t j = 0; j < n; ++j) {
    const uint32_t first = closed ? j + 1 : j;
    const bool has_a = closed || j > 0, has_b = closed || j + count < k;
    const uint32_t ra = closed ? j : j - 1, rb = (first + count) % k;
    WedgeScoreSigned S = 0, E2 = 0;
    for (uint32_t i = first; i < first + count; ++i) S += len2(i % k);
    for (int a = 0; a < 3; ++a) {
      WedgeScoreSigned E = 0;
      for (uint32_t i = first; i < first + count; ++i) E += 2 * e(i % k, a);
      if (has_a) E += e(ra, a);
      if (has_b) E += e(rb, a);
      E2 += E * E;
    }
    const WedgeScoreSigned T = has_a && has_b ? 2 * (len2(ra) + len2(rb))
                               : has_a        ? 4 * len2(ra)
                               : has_b        ? 4 * len2(rb)
                                              : 0;
    const WedgeScoreSigned c = count;
    G[j] = E2 + 4 * c * S - c * c * T;
    M[j] = weight(has_a, ra) * weight(has_b, rb);
  }
  std::vector<uint32_t> order(n);
  for (uint32_t j = 0; j < n; ++j) order[j] = j;
  std::stable_sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) {
    const bool px = G[x] >= 0, py = G[y] >= 0;
    if (px != py) return px;
    if (px) return G[x] * M[x] > G[y] * M[y];
    return G[x] * M[y] > G[y] * M[x];  // G[x] / M[x] > G[y] / M[y], M > 0
  });
  confident =
      n < 2 || G[order[1]] <= 0 || G[order[0]] * M[order[0]] > 2 * (G[order[1]] * M[order[1]]);
  return order;
}

// The codec's order is the spec's: coordinates up to the int32 extremes (lossless mode codes
// float bit patterns) so both of the codec's paths (64- and 128-bit) are covered, with random
// degrees (every weight) and geometry with negative G (interior near v, ends far).
TEST(WedgeSymbols, OrderIsTheSpecFormula) {
  std::mt19937 rng(5);
  WedgeScratch scratch;
  uint64_t negative = 0, weighted = 0;
  bool confident_seen[2] = {false, false};
  for_each_fan(10, [&](ProgressiveMesh& pm, uint32_t k, int closed) {
    ASSERT_TRUE(pm.gather_ring(0));
    for (int geometry = 0; geometry < 5; ++geometry) {
      std::vector<int32_t> coords(size_t(k + 1) * 3);
      for (auto& c : coords)
        c = geometry == 0   ? int32_t(rng() % 5)  // many ties
            : geometry == 1 ? int32_t(rng() % 16384)
            : geometry == 2 ? int32_t(rng())
            : geometry == 3
                ? (rng() & 1 ? INT32_MAX : INT32_MIN)
                : int32_t(rng() % 3) + (rng() % 3 == 0 ? 1000 : 0);  // some far, some near
      std::vector<uint32_t> deg(k + 1);
      for (auto& d : deg) d = rng() % 9;
      // The decoder's way: the bounding box's largest side as WedgeScratch::extent (64-bit
      // scores without the per-ring check when it is small enough): the same order.
      WedgeScratch bounded;
      bounded.extent = 0;
      for (int a = 0; a < 3; ++a) {
        int64_t lo = INT64_MAX, hi = INT64_MIN;
        for (size_t i = size_t(a); i < coords.size(); i += 3)
          lo = std::min<int64_t>(lo, coords[i]), hi = std::max<int64_t>(hi, coords[i]);
        bounded.extent = std::max<uint64_t>(bounded.extent, uint64_t(hi - lo));
      }
      const uint32_t max_count = closed ? k - 2 : k - 1;
      for (uint32_t count = 0; count <= max_count; ++count) {
        bool confident;
        const std::vector<uint32_t> order = spec_wedge_order(coords, deg, pm, count, confident);
        const uint32_t n = uint32_t(order.size());
        for (uint32_t rank = 0; rank < n; ++rank) {
          const uint32_t j = order[rank];
          const uint32_t ra = closed ? j : (j == 0 ? kNoRank : j - 1);
          const uint32_t rb = closed ? (j + count + 1) % k : (j + count == k ? kNoRank : j + count);
          uint32_t ga, gb, gc, gr;
          ASSERT_TRUE(wedge_ranks(coords.data(), deg.data(), 0, pm, count, rank, ga, gb, scratch));
          EXPECT_EQ(scratch.confident, confident)
              << "k " << k << " closed " << closed << " count " << count;
          confident_seen[confident] = true;
          EXPECT_EQ(ga, ra) << "k " << k << " closed " << closed << " count " << count << " rank "
                            << rank;
          EXPECT_EQ(gb, rb) << "k " << k << " closed " << closed << " count " << count << " rank "
                            << rank;
          uint32_t ba, bb;
          ASSERT_TRUE(wedge_ranks(coords.data(), deg.data(), 0, pm, count, rank, ba, bb, bounded));
          EXPECT_EQ(ba, ra);
          EXPECT_EQ(bb, rb);
          EXPECT_EQ(bounded.confident, confident);
          ASSERT_TRUE(wedge_symbols(coords.data(), deg.data(), 0, pm, ra, rb, gc, gr, scratch));
          EXPECT_EQ(gc, count);
          EXPECT_EQ(gr, rank);
        }
        negative += !scratch.narrow
                        ? 0
                        : std::count_if(scratch.score64.begin(), scratch.score64.begin() + n,
                                        [](int64_t x) { return x < 0; });
        weighted += n > 1;
      }
    }
  });
  EXPECT_GT(negative, 100u);  // the negative branch is exercised
  EXPECT_GT(weighted, 100u);
  EXPECT_TRUE(confident_seen[0] && confident_seen[1]);
}

// A hand-computed case pinning each term: closed ring of 4 around v = 0 at e = (10,0,0),
// (0,1,0), (-3,0,0), (0,-1,0) (ranks 0..3), count 1. Candidate j: a = j, interior j + 1, b = j + 2.
//  j=0: E = 2 (0,1,0) + (10,0,0) + (-3,0,0) = (7,2,0): |E|^2 53; S 1; T 2 (100 + 9) = 218; G = 53 +
//  4 - 218 = -161 j=1: E = 2 (-3,0,0) + (0,1,0) + (0,-1,0) = (-6,0,0): 36; S 9; T 2 (1 + 1) = 4; G
//  = 36 + 36 - 4 = 68 j=2: E = 2 (0,-1,0) + (-3,0,0) + (10,0,0) = (7,-2,0): 53; S 1; T 218; G =
//  -161 j=3: E = 2 (10,0,0) + (0,-1,0) + (0,1,0) = (20,0,0): 400; S 100; T 4; G = 400 + 400 - 4 =
//  796
// Degrees by rank 5, 4, 6, 4: weights m = 3, 4, 2, 4 (r = 12 / m = 4, 3, 6, 3). Codec keys:
// j=0 (ends ranks 0, 2): -161 * 4 * 6 = -3864; j=1 (1, 3): 68 * 4 * 4 = 1088; j=2 (2, 0): -3864;
// j=3 (3, 1): 796 * 4 * 4 = 12736. Order 3, 1, 0, 2 (0 and 2 tie: smaller j first).
TEST(WedgeSymbols, HandComputedScore) {
  ProgressiveMesh pm;
  ASSERT_TRUE(build_fan(pm, 4, true));
  ASSERT_TRUE(pm.gather_ring(0));
  std::vector<int32_t> coords(5 * 3, 0);
  const int32_t e[4][3] = {{10, 0, 0}, {0, 1, 0}, {-3, 0, 0}, {0, -1, 0}};
  for (uint32_t r = 0; r < 4; ++r)
    for (int a = 0; a < 3; ++a)
      coords[size_t(pm.ring()[(r + pm.ring_start()) % 4]) * 3 + a] = e[r][a];
  std::vector<uint32_t> deg(5, 6);
  const uint32_t want_deg[4] = {5, 4, 6, 4};
  for (uint32_t r = 0; r < 4; ++r) deg[pm.ring()[(r + pm.ring_start()) % 4]] = want_deg[r];
  WedgeScratch scratch;
  const uint32_t want[4] = {3, 1, 0, 2};
  for (uint32_t rank = 0; rank < 4; ++rank) {
    uint32_t ga, gb;
    ASSERT_TRUE(wedge_ranks(coords.data(), deg.data(), 0, pm, 1, rank, ga, gb, scratch));
    EXPECT_EQ(ga, want[rank]) << rank;
  }
  const int64_t want_keys[4] = {-3864, 1088, -3864,
                                12736};  // negative G times r_a r_b = 144 / (m_a m_b)
  for (uint32_t j = 0; j < 4; ++j) EXPECT_EQ(scratch.score64[j], want_keys[j]) << j;
  EXPECT_TRUE(scratch.confident);  // 12736 > 2 * 1088
  // Degrees 5 -> 4 at rank 2 (weight 4): j = 1's key 68 * 4 * 4 unchanged, j = 2's -161 * 144 / 12.
  deg[pm.ring()[(2 + pm.ring_start()) % 4]] = 4;
  uint32_t ga, gb;
  ASSERT_TRUE(wedge_ranks(coords.data(), deg.data(), 0, pm, 1, 2, ga, gb, scratch));
  EXPECT_EQ(scratch.score64[2], -161 * 12);
  EXPECT_EQ(scratch.score64[0], -161 * 12);
  EXPECT_EQ(scratch.score64[1], 68 * 16);
}

// Position prediction (spec/format.md section 9.6), recomputed here from the spec's words with
// different arithmetic: the Newell normal over every edge of the closed polygon (the codec skips
// the terms that are 0), floor division as quotient-and-remainder, rounding half up as "remainder
// at least half the divisor", the axis order by a full sort.
namespace spec {

using I128 = Int128;
I128 floor_div(I128 a, I128 b) {  // b > 0
  I128 q = a / b;
  if (q * b > a) --q;
  return q;
}
int64_t round_half_up(I128 num, I128 den) {
  if (den < 0) num = -num, den = -den;
  const I128 q = floor_div(num, den), r = num - q * den;
  return int64_t(2 * r >= den ? q + 1 : q);
}
uint32_t ctx(UInt128 mean) {
  uint32_t b = 0;
  while (b < 128 && (mean >> b) != 0) ++b;
  return std::min(b, 20u);
}
UInt128 mag(I128 x) { return x < 0 ? UInt128(-x) : UInt128(x); }

struct Expected {
  int64_t p[3], n[3];
  int axis[3];
  uint32_t context[3];
  uint32_t mix[3];
};

uint32_t half_octave(UInt128 x) {  // min(2 bitlen(x) + the bit below the leading one, 41)
  uint32_t b = 0;
  while (b < 128 && (x >> b) != 0) ++b;
  const uint32_t h = b >= 2 ? uint32_t(x >> (b - 2)) & 1 : 0;
  return std::min(2 * b + h, 41u);
}

Expected predict(const std::vector<int32_t>& c, const std::vector<uint32_t>& R,
                 const std::vector<uint32_t>& K, uint32_t curvature, uint32_t fine) {
  Expected e;
  const size_t m = R.size();
  const uint32_t v = R[0];
  auto C = [&](uint32_t w, int a) { return int64_t(c[size_t(w) * 3 + a]); };
  for (int a = 0; a < 3; ++a) {
    I128 S = C(v, a);
    for (uint32_t w : R) S += C(w, a);
    e.p[a] =
        int64_t(floor_div(2 * S + I128(m + 1), 2 * I128(m + 1)));  // floor((S + floor(n/2)) / n)
  }
  I128 N[3] = {0, 0, 0};
  for (size_t i = 0; i < m; ++i) {
    const uint32_t x = R[i], y = R[(i + 1) % m];
    const I128 dx[3] = {C(x, 0) - C(v, 0), C(x, 1) - C(v, 1), C(x, 2) - C(v, 2)};
    const I128 dy[3] = {C(y, 0) - C(v, 0), C(y, 1) - C(v, 1), C(y, 2) - C(v, 2)};
    for (int a = 0; a < 3; ++a)
      N[a] += dx[(a + 1) % 3] * dy[(a + 2) % 3] - dx[(a + 2) % 3] * dy[(a + 1) % 3];
  }
  uint32_t bits = 0;
  while (bits < 128 && ((mag(N[0]) | mag(N[1]) | mag(N[2])) >> bits) != 0) ++bits;
  const uint32_t shift = bits > 16 ? bits - 16 : 0;
  for (int a = 0; a < 3; ++a) e.n[a] = int64_t(floor_div(N[a], I128(1) << shift));
  std::vector<int> order = {0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int x, int y) {
    return std::make_pair(mag(e.n[x]), x) < std::make_pair(mag(e.n[y]), y);
  });
  for (int s = 0; s < 3; ++s) e.axis[s] = order[s];
  const I128 q = I128(e.n[0]) * e.n[0] + I128(e.n[1]) * e.n[1] + I128(e.n[2]) * e.n[2];
  // Offset = round((C (L . n) / k + B (E . n) / (M - 1)) n_a / (8 q)): one rational value, here
  // over the common denominator 8 k (M - 1) q (k taken as 1 when the C term is absent).
  const int64_t k = int64_t(K.size());
  const bool c_term = curvature != 0 && k != 0, b_term = fine != 0 && m >= 2;
  if (q != 0 && (c_term || b_term)) {
    const I128 kk = c_term ? k : 1, mm = I128(m) - 1;
    I128 Ln = 0, En = 0;
    for (int a = 0; a < 3; ++a) {
      I128 L = I128(k) * C(v, a);
      for (uint32_t w : K) L -= C(w, a);
      Ln += L * e.n[a];
      I128 E = 0;
      for (size_t i = 1; i < m; ++i) E += C(v, a) - C(R[i], a);
      En += E * e.n[a];
    }
    const I128 X = (c_term ? I128(curvature) * Ln * mm : 0) + (b_term ? I128(fine) * En * kk : 0);
    for (int a = 0; a < 3; ++a) e.p[a] += round_half_up(X * e.n[a], I128(8) * kk * mm * q);
  }
  for (int s = 0; s < 2; ++s) {
    UInt128 D = 0;
    for (uint32_t w : R) D += mag(C(w, e.axis[s]) - e.p[e.axis[s]]);
    e.context[s] = ctx(D / m);
  }
  const int z = e.axis[2];
  UInt128 D = 0;
  for (uint32_t w : R) {
    I128 d = 0;
    for (int a = 0; a < 3; ++a) d += I128(C(w, a) - e.p[a]) * (e.n[z] ? e.n[a] : a == z ? 1 : 0);
    D += mag(d);
  }
  e.context[2] = ctx(D / (mag(e.n[z] ? e.n[z] : 1) * m));
  // Second contexts: the ring's largest offset from p per tangent axis, v's distance from the
  // plane through p in units of the normal axis (0 without a normal).
  for (int s = 0; s < 2; ++s) {
    UInt128 X = 0;
    for (uint32_t w : R) X = std::max(X, mag(C(w, e.axis[s]) - e.p[e.axis[s]]));
    e.mix[s] = half_octave(X);
  }
  I128 dv = 0;
  for (int a = 0; a < 3; ++a) dv += I128(C(v, a) - e.p[a]) * e.n[a];
  e.mix[2] = e.n[z] ? ctx(mag(dv) / mag(e.n[z])) : 0;
  return e;
}

}  // namespace spec

TEST(PositionPrediction, IsTheSpecFormula) {
  std::mt19937 rng(9);
  for (int trial = 0; trial < 20000; ++trial) {
    const uint32_t m = 2 + rng() % 9, extra = rng() % 6, nv = m + extra;
    std::vector<int32_t> coords(size_t(nv) * 3);
    const int shift = int(rng() % 32);
    const int kind = trial % 7;
    for (auto& c : coords)
      c = kind == 0   ? (rng() & 1 ? INT32_MAX : INT32_MIN)
          : kind == 1 ? int32_t(rng() % 16384)
          : kind == 2 ? int32_t(rng() % 3)  // ties in |n|, zero normals
                      : int32_t(rng()) >> shift;
    if (kind == 3) {  // on a plane z = x + 2y
      for (uint32_t w = 0; w < nv; ++w)
        coords[w * 3 + 2] =
            int32_t(uint32_t(coords[w * 3]) + 2u * uint32_t(coords[w * 3 + 1]));  // modulo 2^32
    }
    std::vector<uint32_t> R(m), K;
    for (uint32_t i = 0; i < m; ++i) R[i] = i;
    for (uint32_t w = 1; w < nv; ++w)
      if (w >= m || rng() % 4) K.push_back(w);  // v's ring: most of u's ring and the rest
    if (K.empty()) K.push_back(1);
    const uint32_t curvature = rng() % 9, fine = trial % 3 == 0 ? 0 : rng() % 9;
    PositionPrediction pp;
    predict_position(coords.data(), R, K, curvature, fine, pp);
    const spec::Expected e = spec::predict(coords, R, K, curvature, fine);
    for (int a = 0; a < 3; ++a) {
      ASSERT_EQ(pp.p[a], e.p[a]) << trial << " axis " << a;
      ASSERT_EQ(pp.n[a], e.n[a]) << trial << " axis " << a;
      ASSERT_EQ(pp.axis[a], e.axis[a]) << trial << " slot " << a;
      ASSERT_EQ(pp.context[a], e.context[a]) << trial << " slot " << a;
      ASSERT_EQ(pp.mix[a], e.mix[a]) << trial << " slot " << a;
    }
    // The writer's two-step form (ring part once, then this pair) gives the same prediction.
    RingBasis basis;
    ring_basis(coords.data(), R, K, true, true, basis);
    PositionPrediction two;
    predict_from_basis(coords.data(), R, uint32_t(K.size()), basis, curvature, fine, two);
    for (int a = 0; a < 3; ++a) {
      ASSERT_EQ(two.p[a], e.p[a]) << trial << " axis " << a;
      ASSERT_EQ(two.n[a], e.n[a]) << trial << " axis " << a;
      ASSERT_EQ(two.axis[a], e.axis[a]) << trial << " slot " << a;
      ASSERT_EQ(two.context[a], e.context[a]) << trial << " slot " << a;
      ASSERT_EQ(two.mix[a], e.mix[a]) << trial << " slot " << a;
    }
    // Residuals of a vertex near the prediction, then back: the normal axis from the tangent
    // plane through p (rounded half up), everything modulo 2^32.
    int32_t cu[3], r[3], back[3];
    for (int a = 0; a < 3; ++a)
      cu[a] = int32_t(uint32_t(e.p[a]) + uint32_t(int32_t(rng()) >> (rng() % 32)));
    position_residuals(pp, cu, r);
    const int A = e.axis[0], B = e.axis[1], Z = e.axis[2];
    EXPECT_EQ(r[0], int32_t(uint32_t(cu[A]) - uint32_t(e.p[A])));
    EXPECT_EQ(r[1], int32_t(uint32_t(cu[B]) - uint32_t(e.p[B])));
    const int64_t pz =
        e.n[Z] == 0 ? e.p[Z]
                    : e.p[Z] - spec::round_half_up(
                                   spec::I128(e.n[A]) * r[0] + spec::I128(e.n[B]) * r[1], e.n[Z]);
    EXPECT_EQ(r[2], int32_t(uint32_t(cu[Z]) - uint32_t(pz))) << trial;
    position_from_residuals(pp, r, back);
    for (int a = 0; a < 3; ++a) EXPECT_EQ(back[a], cu[a]) << trial;
  }
}

// Exact rounding of the plane step, by hand: n = (1, 2, 4) (normal axis z), tangent residuals
// r_x = 1, r_y = 1: z = p_z - round((1 + 2) / 4) = p_z - 1 (0.75 rounds up); r_x = 1, r_y = 0:
// 1/4 rounds to 0; r_x = 2, r_y = 0: 2/4 = 0.5 rounds up to 1; r_x = -2: -0.5 rounds up to 0.
TEST(PositionPrediction, PlaneStepRoundsHalfUp) {
  PositionPrediction pp{};
  pp.p[0] = 10, pp.p[1] = 20, pp.p[2] = 30;
  pp.n[0] = 1, pp.n[1] = 2, pp.n[2] = 4;
  pp.axis[0] = 0, pp.axis[1] = 1, pp.axis[2] = 2;
  EXPECT_EQ(normal_axis_prediction(pp, 1, 1), 29);
  EXPECT_EQ(normal_axis_prediction(pp, 1, 0), 30);
  EXPECT_EQ(normal_axis_prediction(pp, 2, 0), 29);
  EXPECT_EQ(normal_axis_prediction(pp, -2, 0), 30);
  EXPECT_EQ(normal_axis_prediction(pp, -3, 0), 31);  // -0.75 -> -1
  pp.n[2] = -4;                                      // a negative normal component flips the step
  EXPECT_EQ(normal_axis_prediction(pp, 1, 1), 31);
  EXPECT_EQ(normal_axis_prediction(pp, 2, 0), 30);   // 2 / -4 = -0.5 rounds up to 0
  EXPECT_EQ(normal_axis_prediction(pp, -2, 0), 29);  // -2 / -4 = 0.5 rounds up to 1
  EXPECT_EQ(round_div(-1, 2), 0);
  EXPECT_EQ(round_div(1, 2), 1);
  EXPECT_EQ(round_div(-3, 2), -1);
  EXPECT_EQ(round_div(3, -2), -1);
  EXPECT_EQ(round_div(-5, 4), -1);
  EXPECT_EQ(round_div(-7, 4), -2);
}

// A flat ring: the normal axis is predicted exactly for a vertex on the plane (residual 0),
// whatever the tangent residuals; with curvature 0 the prediction is the v-twice centroid.
TEST(PositionPrediction, FlatRingPredictsTheNormalAxisExactly) {
  // Plane z = 3 (normal along z); v = 0 at the origin of the fan, ring around it.
  std::vector<int32_t> coords = {0, 0,  3, 10, 0,   3, 7, 7, 3,   0, 10,
                                 3, -7, 7, 3,  -10, 0, 3, 0, -10, 3};
  std::vector<uint32_t> R = {0, 1, 2, 3, 4}, K = {1, 2, 3, 4, 5, 6};
  PositionPrediction pp;
  predict_position(coords.data(), R, K, 8, 8, pp);
  EXPECT_EQ(pp.axis[2], 2);
  EXPECT_EQ(pp.n[0], 0);
  EXPECT_EQ(pp.n[1], 0);
  EXPECT_GT(pp.n[2], 0);
  EXPECT_EQ(pp.p[2], 3);  // the umbrella vector of v lies in the plane: no offset
  EXPECT_EQ(pp.p[0], floor_mean(0 + 0 + 10 + 7 + 0 - 7, 6));
  EXPECT_EQ(pp.p[1], floor_mean(0 + 0 + 0 + 7 + 10 + 7, 6));
  const int32_t cu[3] = {5, 4, 3};
  int32_t r[3];
  position_residuals(pp, cu, r);
  EXPECT_EQ(r[2], 0);
  EXPECT_EQ(pp.context[2], 0u);  // the ring lies in the plane
}

// Curvature offset on a cap: v above its ring, u's ring below v. The offset is curvature / 8 of
// the umbrella vector's projection on n, rounded half up per axis.
TEST(PositionPrediction, CurvatureOffsetMovesAlongTheNormal) {
  // v = (0, 0, 8); ring of v: four points at z = 0; u's ring: v and two of them.
  std::vector<int32_t> coords = {0, 0, 8, 16, 0, 0, 0, 16, 0, -16, 0, 0, 0, -16, 0};
  std::vector<uint32_t> R = {0, 1, 2}, K = {1, 2, 3, 4};
  PositionPrediction p0, p4, p8;
  predict_position(coords.data(), R, K, 0, 0, p0);
  predict_position(coords.data(), R, K, 4, 0, p4);
  predict_position(coords.data(), R, K, 8, 0, p8);
  // Umbrella vector (0, 0, 8); n = (16*8, 16*8, 256) up to scale: projection 8 * n_z^2 / |n|^2
  // = 8 * 4/6 on z and 8 * 2/6 on x and y (shared scale cancels).
  EXPECT_EQ(p0.p[2], floor_mean(8 + 8 + 0 + 0, 4));
  EXPECT_EQ(p8.p[2] - p0.p[2], 5);  // round(16/3) = 5
  EXPECT_EQ(p8.p[0] - p0.p[0], 3);  // round(8/3) = 3
  EXPECT_EQ(p4.p[2] - p0.p[2], 3);  // round(8/3) = 3
  EXPECT_EQ(p4.p[0] - p0.p[0], 1);  // round(4/3) = 1
}

// The fine offset (HEAD fine_curvature B): B / 8 of v's umbrella vector over u's other
// neighbours, projected on n, rounded once together with the C term. v = (0, 0, 8); u's ring
// v, (16, 0, 0), (0, 16, 0), (-16, 0, 0): E / 3 = (0, -16/3, 8), n ~ (0, 1, 2), projection
// (32/3) / 5 (0, 1, 2) = (0, 32/15, 64/15). v's ring adds (0, -16, 0): L / 4 = (0, 0, 8),
// projection 16/5 (0, 1, 2).
TEST(PositionPrediction, FineOffsetAndOneRounding) {
  std::vector<int32_t> coords = {0, 0, 8, 16, 0, 0, 0, 16, 0, -16, 0, 0, 0, -16, 0};
  std::vector<uint32_t> R = {0, 1, 2, 3}, K = {1, 2, 3, 4};
  PositionPrediction p0, b4, b8, both;
  predict_position(coords.data(), R, K, 0, 0, p0);
  predict_position(coords.data(), R, K, 0, 4, b4);
  predict_position(coords.data(), R, K, 0, 8, b8);
  predict_position(coords.data(), R, K, 8, 8, both);
  EXPECT_EQ(p0.n[0], 0);
  EXPECT_EQ(p0.n[2], 2 * p0.n[1]);
  EXPECT_EQ(p0.p[1], 3);  // floor((16 + 2) / 5)
  EXPECT_EQ(p0.p[2], 3);
  for (int a = 0; a < 3; ++a) {
    const int64_t want8[3] = {0, 2, 4}, want4[3] = {0, 1, 2}, want_both[3] = {0, 5, 11};
    EXPECT_EQ(b8.p[a] - p0.p[a], want8[a]) << a;  // round(32/15), round(64/15)
    EXPECT_EQ(b4.p[a] - p0.p[a], want4[a]) << a;  // round(16/15), round(32/15)
    // One rounding of 16/5 + 32/15 = 16/3 and 32/5 + 64/15 = 32/3 (rounding each term apart
    // would give 3 + 2 = 5 and 6 + 4 = 10).
    EXPECT_EQ(both.p[a] - p0.p[a], want_both[a]) << a;
  }
}

// Larger rings than above, up to 40 (the selection switches to nth_element from rank 16): the
// codec gives exactly the spec order (spec_wedge_order). Rings up to 40 cover both selection
// paths (ranks below 16 and nth_element), coordinates small (64-bit scores), tied (all zero)
// and full-range (128-bit scores), random degrees.
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
          c = geometry == 0   ? 0
              : geometry == 1 ? int32_t(rng() % 16384)
              : geometry == 2 ? int32_t(rng() % 5)
                              : int32_t(rng());
        std::vector<uint32_t> deg(k + 1);
        for (auto& d : deg) d = rng() % 9;
        ASSERT_TRUE(pm.gather_ring(0));
        const uint32_t max_count = closed ? k - 2 : k - 1;
        for (uint32_t count = 0; count <= max_count; ++count) {
          bool confident;
          const std::vector<uint32_t> order = spec_wedge_order(coords, deg, pm, count, confident);
          const uint32_t n = uint32_t(order.size());
          for (uint32_t rank = 0; rank < n; ++rank) {
            const uint32_t j = order[rank];
            const uint32_t ra = closed ? j : (j == 0 ? kNoRank : j - 1);
            const uint32_t rb =
                closed ? (j + count + 1) % k : (j + count == k ? kNoRank : j + count);
            uint32_t ga = 0, gb = 0, gc = 0, gr = 0;
            ASSERT_TRUE(
                wedge_ranks(coords.data(), deg.data(), 0, pm, count, rank, ga, gb, scratch));
            ASSERT_EQ(scratch.confident, confident)
                << "k " << k << " closed " << closed << " count " << count;
            ASSERT_EQ(ga, ra) << "k " << k << " closed " << closed << " count " << count << " rank "
                              << rank;
            ASSERT_EQ(gb, rb);
            ASSERT_TRUE(wedge_symbols(coords.data(), deg.data(), 0, pm, ra, rb, gc, gr, scratch));
            ASSERT_EQ(gc, count);
            ASSERT_EQ(gr, rank);
          }
        }
      }
    }
}

// ---- Vertex choice (spec/format.md section 9.2) ----

namespace {
// Octahedron (closed) or the octahedron less one face (open: a boundary of three edges).
void build_octahedron(ProgressiveMesh& pm, bool open) {
  const uint32_t faces[] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  std::string error;
  ASSERT_TRUE(pm.build(6, faces, open ? 7 : 8, error)) << error;
}

// A random valid wedge of the ring gathered last (canonical ranks, kNoRank for a boundary side).
void random_wedge(const ProgressiveMesh& pm, std::mt19937& rng, uint32_t& a, uint32_t& b) {
  const uint32_t k = uint32_t(pm.ring().size());
  if (pm.ring_closed()) {
    a = rng() % k;
    b = (a + 1 + rng() % (k - 1)) % k;
    return;
  }
  do {
    a = rng() % (k + 1);
    b = rng() % (k + 1);
    a = a == k ? kNoRank : a;
    b = b == k ? kNoRank : b;
  } while ((a == kNoRank && b == kNoRank) || (a != kNoRank && b != kNoRank && a >= b));
}

// Random coordinates below 2^bits for n vertices (lossless files: any int32, bits = 32).
std::vector<int32_t> random_coords(std::mt19937& rng, size_t n, uint32_t bits) {
  std::vector<int32_t> c(n * 3);
  for (int32_t& x : c) x = bits >= 32 ? int32_t(rng()) : int32_t(rng() & ((1u << bits) - 1));
  return c;
}

// The spec's umbrella class of w from its ring in pm (spec "Vertex choice"), in exact integers:
// c' = c >> shift, e = c'[x] - c'[w] over the ring, D = sum of e, L = sum of |e_x| + |e_y| +
// |e_z|, both mod 2^32 (D signed); 0 if 64 |D|^2 < L^2, 1 if 16 |D|^2 < L^2, else 2.
uint32_t spec_class(ProgressiveMesh& pm, const std::vector<int32_t>& c, uint32_t w,
                    uint32_t shift) {
  int64_t d[3] = {0, 0, 0};
  uint64_t l = 0;
  if (pm.gather_ring(w))
    for (uint32_t x : pm.ring())
      for (int a = 0; a < 3; ++a) {
        const int64_t e =
            int64_t(c[size_t(x) * 3 + a] >> shift) - int64_t(c[size_t(w) * 3 + a] >> shift);
        d[a] += e;
        l += uint64_t(e < 0 ? -e : e);
      }
  __extension__ typedef unsigned __int128 U;
  U d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const int64_t x = int32_t(uint32_t(d[a]));
    d2 += U(x * x);
  }
  const U l2 = U(uint32_t(l)) * uint32_t(l);
  return 64 * d2 < l2 ? 0 : 16 * d2 < l2 ? 1 : 2;
}

// The spec's context of candidate w: ((min(bitlen(floor(rem / left)), 20) * 2 + near) * 9 +
// min(degree, 8)) * 3 + umbrella class, rem = candidates from w to the end of the list, left =
// splits still to find.
uint32_t spec_context(uint64_t rem, uint64_t left, bool near, uint32_t degree, uint32_t shape) {
  const uint64_t e = rem / left;
  uint32_t bits = 0;
  while (bits < 64 && (e >> bits) != 0) ++bits;
  return ((std::min(bits, 20u) * 2 + (near ? 1 : 0)) * 9 + std::min(degree, 8u)) * 3 + shape;
}
}  // namespace

// Degrees (base: ring sizes; per split: v gets k - |R| + 2 + [vl] + [vr], u gets |R|, vl and vr
// one more) stay the ring sizes of a manifold mesh under random splits, closed and open; the
// umbrella sums stay the sums over the rings and the classes the spec's, for coordinates of 14
// bits (no shift), 20 bits (shift 4) and lossless patterns (any int32, shift 16).
TEST(VertexChoice, DegreesAndUmbrellaSumsAreTheRings) {
  std::mt19937 rng(5);
  for (uint32_t bits : {14u, 20u, 0u})
    for (int open = 0; open < 2; ++open) {
      ProgressiveMesh pm;
      build_octahedron(pm, open);
      std::vector<int32_t> coords = random_coords(rng, 6, bits ? bits : 32);
      const uint32_t shift = umbrella_shift(bits);
      EXPECT_EQ(shift, bits == 14 ? 0u : bits == 20 ? 4u : 16u);
      VertexChoice choice;
      choice.reset(pm, coords.data(), bits);
      std::vector<uint32_t> seen(3, 0);
      for (int step = 0; step < 300; ++step) {
        const uint32_t v = rng() % pm.vertex_count();
        ASSERT_TRUE(pm.gather_ring(v));
        const uint32_t k = uint32_t(pm.ring().size());
        uint32_t a, b;
        random_wedge(pm, rng, a, b);
        choice.reserve(k);
        ASSERT_TRUE(pm.split_gathered(v, a, b));
        const std::vector<int32_t> cu = random_coords(rng, 1, bits ? bits : 32);
        coords.insert(coords.end(), cu.begin(), cu.end());
        choice.applied(pm, coords.data(), a != kNoRank, b != kNoRank);
        const uint32_t r = uint32_t(pm.u_ring().size());
        EXPECT_EQ(choice.degree(v), k - r + 2 + (a != kNoRank) + (b != kNoRank));
        for (uint32_t w = 0; w < pm.vertex_count(); ++w) {
          const uint32_t want = spec_class(pm, coords, w, shift);
          ASSERT_TRUE(pm.gather_ring(w));
          ASSERT_EQ(choice.degree(w), pm.ring().size())
              << "open " << open << " step " << step << " w " << w;
          ASSERT_EQ(choice.shape(w), want)
              << "bits " << bits << " open " << open << " step " << step << " w " << w;
          ++seen[want];
        }
      }
      if (bits == 14) {  // every class occurs
        EXPECT_GT(seen[0], 0u);
        EXPECT_GT(seen[1], 0u);
        EXPECT_GT(seen[2], 0u);
      }
    }
}

// The class boundaries: strictly below 2^-6 and 2^-4 (64 |D|^2 and 16 |D|^2 against L^2), D
// signed 32-bit, L unsigned 32-bit, no overflow at the extremes.
TEST(VertexChoice, UmbrellaClassIsTheSpecFormula) {
  auto cls = [](int32_t x, int32_t y, int32_t z, uint32_t l) {
    return umbrella_class(RingSums{{uint32_t(x), uint32_t(y), uint32_t(z)}, l});
  };
  EXPECT_EQ(cls(1, 0, 0, 8), 1u);   // 64 = 64: not below 2^-6
  EXPECT_EQ(cls(1, 0, 0, 9), 0u);   // 64 < 81
  EXPECT_EQ(cls(0, -1, 0, 4), 2u);  // 16 = 16: not below 2^-4
  EXPECT_EQ(cls(0, 0, -1, 5), 1u);  // 16 < 25
  EXPECT_EQ(cls(3, 4, 0, 40), 1u);  // |D|^2 = 25: 1600 = 1600, 400 < 1600
  EXPECT_EQ(cls(3, 4, 0, 41), 0u);
  EXPECT_EQ(cls(3, 4, 0, 20), 2u);  // 400 = 400
  EXPECT_EQ(cls(0, 0, 0, 0), 2u);   // L = 0
  EXPECT_EQ(cls(0, 0, 0, 1), 0u);
  EXPECT_EQ(cls(INT32_MIN, INT32_MIN, INT32_MIN, UINT32_MAX), 2u);  // 3 * 2^62: no wrap
  // L^2 = 2^64 - 2^33 + 1: 64 * 2^58 above it, 64 (2^29 - 1)^2 = 2^64 - 2^36 + 64 below.
  EXPECT_EQ(cls(1 << 29, 0, 0, UINT32_MAX), 1u);
  EXPECT_EQ(cls((1 << 29) - 1, 0, 0, UINT32_MAX), 0u);
  EXPECT_EQ(cls(0, 1 << 30, 0, UINT32_MAX), 2u);  // 16 * 2^60 = 2^64
  EXPECT_EQ(cls(0, -(1 << 30) + 1, 0, UINT32_MAX), 1u);
}

// choice_bits() codes exactly the spec's candidates and contexts: every vertex below the
// vertex count, or (near) the previous group's neighbourhood (v's ring before each split, v,
// u; ascending, distinct), one bit per candidate up to the group's last split.
TEST(VertexChoice, CandidatesAndContextsAreTheSpecFormula) {
  std::mt19937 rng(8);
  ProgressiveMesh pm;
  build_octahedron(pm, false);
  std::vector<int32_t> coords = random_coords(rng, 6, 14);
  VertexChoice choice;
  choice.reset(pm, coords.data(), 14);
  std::vector<uint32_t> noted;  // the neighbourhood of the group just applied
  size_t skipped_total = 0;     // candidates skipped by exclusion (the test must exercise it)
  for (int group = 0; group < 60; ++group) {
    const uint32_t limit = pm.vertex_count();
    // The next group: a few random vertices, from the neighbourhood or anywhere.
    std::vector<uint32_t> pool = noted, vs;
    std::sort(pool.begin(), pool.end());
    pool.erase(std::unique(pool.begin(), pool.end()), pool.end());
    const bool want_near = !pool.empty() && group % 3 != 0;
    if (!want_near) {
      pool.clear();
      for (uint32_t w = 0; w < limit; ++w) pool.push_back(w);
    }
    // Exclusion: no vertex in the closed one-ring (now) of one taken before.
    std::vector<uint8_t> taken_ring(limit, 0);
    auto take = [&](uint32_t w) {
      vs.push_back(w);
      taken_ring[w] = 1;
      if (pm.gather_ring(w))
        for (uint32_t x : pm.ring()) taken_ring[x] = 1;
    };
    for (uint32_t w : pool)
      if (vs.size() < 24 && !taken_ring[w] && rng() % 2 == 0) take(w);
    if (vs.empty()) take(pool[rng() % pool.size()]);
    choice.start_group();
    std::vector<uint32_t> bits;
    bool near = false;
    ASSERT_TRUE(choice_bits(choice, pm, limit, vs, bits, near));
    // Near exactly when the neighbourhood holds every vertex of the group.
    EXPECT_EQ(near, std::all_of(vs.begin(), vs.end(), [&](uint32_t v) {
                return std::find(noted.begin(), noted.end(), v) != noted.end();
              }));
    if (want_near) {
      EXPECT_TRUE(near);
    }
    std::vector<uint32_t> cand;
    if (near) {
      cand = noted;
      std::sort(cand.begin(), cand.end());
      cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
    } else {
      for (uint32_t w = 0; w < limit; ++w) cand.push_back(w);
    }
    // The spec's exclusion: no bit for a candidate in the closed one-ring (here: at the group's
    // start) of the group's j-th vertex found, j <= found - 1 - 8.
    std::vector<uint32_t> want, found;
    uint64_t left = vs.size();
    size_t skipped = 0;
    for (size_t i = 0; i < cand.size() && left; ++i) {
      bool excluded = false;
      for (size_t j = 0; j + 1 + 8 <= found.size() && !excluded; ++j) {
        excluded = cand[i] == found[j];
        ASSERT_TRUE(pm.gather_ring(found[j]));
        for (uint32_t x : pm.ring()) excluded = excluded || x == cand[i];
      }
      if (excluded) {
        ++skipped;
        continue;
      }
      const bool hit = std::find(vs.begin(), vs.end(), cand[i]) != vs.end();
      want.push_back(spec_context(cand.size() - i, left, near, choice.degree(cand[i]),
                                  spec_class(pm, coords, cand[i], 0))
                         << 1 |
                     (hit ? 1u : 0u));
      left -= hit;
      if (hit) found.push_back(cand[i]);
    }
    skipped_total += skipped;
    ASSERT_EQ(left, 0u);
    ASSERT_EQ(bits, want) << "group " << group;
    // Apply the group (splits of one group need not be independent for the coding).
    noted.clear();
    for (uint32_t v : vs) {
      ASSERT_TRUE(pm.gather_ring(v));
      noted.insert(noted.end(), pm.ring().begin(), pm.ring().end());
      noted.push_back(v);
      noted.push_back(pm.vertex_count());
      uint32_t a, b;
      random_wedge(pm, rng, a, b);
      choice.reserve(pm.ring().size());
      ASSERT_TRUE(pm.split_gathered(v, a, b));
      const std::vector<int32_t> cu = random_coords(rng, 1, 14);
      coords.insert(coords.end(), cu.begin(), cu.end());
      choice.applied(pm, coords.data(), a != kNoRank, b != kNoRank);
    }
  }
  EXPECT_GT(skipped_total, 0u);
}

// A group whose vertices violate exclusion (one in the closed one-ring of an earlier one)
// cannot be coded: choice_bits() says so instead of writing bits a decoder would read
// differently. Also a vertex repeated.
TEST(VertexChoice, AdjacentVerticesInAGroupAreRefused) {
  ProgressiveMesh pm;
  build_octahedron(pm, false);
  const std::vector<int32_t> coords(6 * 3, 0);
  VertexChoice choice;
  choice.reset(pm, coords.data(), 14);
  for (const std::vector<uint32_t>& vs :
       {std::vector<uint32_t>{0, 2}, std::vector<uint32_t>{2, 4}, std::vector<uint32_t>{0, 0}}) {
    choice.start_group();
    std::vector<uint32_t> bits;
    bool near = true;
    EXPECT_FALSE(choice_bits(choice, pm, pm.vertex_count(), vs, bits, near))
        << vs[0] << " " << vs[1];
  }
  choice.start_group();
  std::vector<uint32_t> bits;
  bool near = true;
  const std::vector<uint32_t> opposite_apexes{0, 1};  // 0 and 1 are not adjacent on the octahedron
  EXPECT_TRUE(choice_bits(choice, pm, pm.vertex_count(), opposite_apexes, bits, near));
  EXPECT_FALSE(near);
  // Vertex 0's bit, then 1's (not in 0's ring); none after the group's last split.
  ASSERT_EQ(bits.size(), 2u);
  EXPECT_EQ(bits[0] & 1, 1u);
  EXPECT_EQ(bits[1] & 1, 1u);
}

// Exclusion lags kChoiceLag splits behind: the writer and the whole-group reader agree on an
// independent group long enough for it to act, and a stream coding a vertex that exclusion
// removed (as a writer ignoring it would) runs out of candidates and is refused, not misread.
// A 9 x 9 grid, vertex (x, y) numbered y * 9 + x except that (1, 0) and (8, 8) swap numbers:
// the ten smallest even-even vertices (pairwise non-adjacent) are 0, 1 (= (8, 8)), 2, 4, 6, 8,
// 18, 20, 22, 24, and 80 = (1, 0) is a neighbour of 0, excluded once ten are found.
TEST(VertexChoice, ExclusionLagsAndAViolatingStreamIsRefused) {
  constexpr uint32_t kN = 9;
  auto id = [](uint32_t x, uint32_t y) {
    const uint32_t i = y * kN + x;
    return i == 1 ? kN * kN - 1 : i == kN * kN - 1 ? 1 : i;
  };
  std::vector<uint32_t> faces;
  for (uint32_t y = 0; y + 1 < kN; ++y)
    for (uint32_t x = 0; x + 1 < kN; ++x) {
      const uint32_t a = id(x, y), b = id(x + 1, y), c = id(x, y + 1), d = id(x + 1, y + 1);
      faces.insert(faces.end(), {a, b, d, a, d, c});
    }
  ProgressiveMesh pm;
  std::string error;
  ASSERT_TRUE(pm.build(kN * kN, faces.data(), faces.size() / 3, error)) << error;
  const uint32_t limit = kN * kN;
  const std::vector<int32_t> coords(limit * 3, 0);
  const std::vector<uint32_t> vs{0, 1, 2, 4, 6, 8, 18, 20, 22, 24};
  ASSERT_TRUE(pm.gather_ring(0));
  ASSERT_NE(std::find(pm.ring().begin(), pm.ring().end(), 80u), pm.ring().end());
  auto decode = [&](const std::vector<uint32_t>& bits, uint32_t size, std::vector<uint32_t>& got) {
    std::vector<uint8_t> payload;
    SplitModels em, dm;
    std::vector<SplitSymbols> codes(size,
                                    SplitSymbols{0, 0, 0, 0, 0, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}});
    encode_split_chunk({{size, false}}, bits, codes.data(), codes.size(), em, payload);
    SplitChunkReader r;
    EXPECT_TRUE(r.open(payload.data(), payload.size(), size, dm, error)) << error;
    VertexChoice dec;
    dec.reset(pm, coords.data(), 14);
    std::vector<SplitSymbols> out;
    return r.group_symbols(
        dec, pm, out, [](SplitSymbols&) {}, &got);
  };
  {  // the independent group: coded and decoded back
    VertexChoice enc;
    enc.reset(pm, coords.data(), 14);
    enc.start_group();
    std::vector<uint32_t> bits, got;
    bool near = true;
    ASSERT_TRUE(choice_bits(enc, pm, limit, vs, bits, near));
    EXPECT_FALSE(near);
    EXPECT_EQ(bits.size(), 25u);  // candidates 0 .. 24, none excluded before the tenth is found
    ASSERT_TRUE(decode(bits, uint32_t(vs.size()), got));
    EXPECT_EQ(got, vs);
  }
  // The group plus 80: the writer refuses it (80 is in 0's ring); the bits of a writer that
  // ignores exclusion (hits at vs and 80) decode to no group: after the tenth vertex, 80 gets
  // no bit, and the bits read for the candidates 25 .. 79 are 0.
  std::vector<uint32_t> bad = vs;
  bad.push_back(80);
  {
    VertexChoice enc;
    enc.reset(pm, coords.data(), 14);
    enc.start_group();
    std::vector<uint32_t> bits;
    bool near = true;
    EXPECT_FALSE(choice_bits(enc, pm, limit, bad, bits, near));
  }
  VertexChoice naive;
  naive.reset(pm, coords.data(), 14);
  naive.start_group();
  naive.begin_scan(false, limit, uint32_t(bad.size()));
  std::vector<uint32_t> bits;
  uint32_t last_ctx = 0;
  EXPECT_EQ(naive.scan(&pm, uint32_t(bad.size()),
                       [&](uint32_t w, uint32_t ctx) {
                         const bool hit = std::find(bad.begin(), bad.end(), w) != bad.end();
                         EXPECT_NE(w, 80u);  // excluded: never offered
                         bits.push_back(ctx << 1 | (hit ? 1u : 0u));
                         last_ctx = ctx;
                         return hit ? 1 : 0;
                       }),
            0);
  EXPECT_EQ(bits.size(), 77u);        // 0 .. 79 less 70, 71, 79 (in the ring of 1 = (8, 8))
  bits.push_back(last_ctx << 1 | 1);  // the naive writer's bit for 80
  std::vector<uint32_t> got;
  EXPECT_FALSE(decode(bits, uint32_t(bad.size()), got));
  EXPECT_EQ(got, vs);  // what it found before running out
}

// The choice models start from the expected gap (spec "Vertex choice"): probability of a 0,
// scaled to 32768, min(32768 - floor(131072 / (3 * 2^d)), 31744) for class d >= 1, 16384 for
// d = 0.
TEST(VertexChoice, ModelPriorsAreTheSpecTable) {
  const SplitModels m;
  const uint32_t want[21] = {16384, 10923, 21846, 27307, 30038, 31403, 31744,
                             31744, 31744, 31744, 31744, 31744, 31744, 31744,
                             31744, 31744, 31744, 31744, 31744, 31744, 31744};
  ASSERT_EQ(kChoiceContexts, 21u * 2 * 9 * 3);  // density x near x degree x umbrella class
  for (uint32_t c = 0; c < kChoiceContexts; ++c) {
    const uint32_t d = c / (2 * 9 * 3);
    EXPECT_EQ(m.choice[c] & kProbMask, want[d]) << c;
    EXPECT_EQ(uint32_t(m.choice[c] >> kCountShift), d == 0 ? 0u : 16u) << c;  // primed: count 16
  }
}

// ---- BASE (spec/format.md section 7) ----

namespace {

using Tri = std::array<uint32_t, 3>;
Tri rotated(uint32_t a, uint32_t b, uint32_t c) {  // smallest first, orientation kept
  if (b < a && b < c) return {b, c, a};
  if (c < a && c < b) return {c, a, b};
  return {a, b, c};
}

// encode_base then decode_base: the decoder gets exactly the writer's decoded mesh, which is
// the input renumbered by given_of (faces as a set, each up to rotation; coordinates equal).
void base_round_trip(const std::vector<int32_t>& coords, const std::vector<uint32_t>& faces) {
  const uint32_t n = uint32_t(coords.size() / 3), fn = uint32_t(faces.size() / 3);
  std::vector<uint8_t> stream;
  std::vector<uint32_t> given_of;
  BaseMesh enc, dec;
  std::string error;
  ASSERT_TRUE(encode_base(coords.data(), n, faces.data(), fn, stream, given_of, enc, error))
      << error;
  ASSERT_EQ(decode_base(stream.data(), stream.size(), n, fn, dec, error), Status::ok) << error;
  EXPECT_EQ(dec.coords, enc.coords);
  EXPECT_EQ(dec.faces, enc.faces);
  ASSERT_EQ(given_of.size(), n);
  std::vector<uint8_t> seen(n, 0);
  for (uint32_t d = 0; d < n; ++d) {
    ASSERT_LT(given_of[d], n);
    EXPECT_FALSE(seen[given_of[d]]++);
    for (int a = 0; a < 3; ++a) EXPECT_EQ(dec.coords[d * 3 + a], coords[given_of[d] * 3 + a]);
  }
  std::vector<Tri> want, got;
  for (uint32_t f = 0; f < fn; ++f) {
    want.push_back(rotated(faces[f * 3], faces[f * 3 + 1], faces[f * 3 + 2]));
    got.push_back(rotated(given_of[dec.faces[f * 3]], given_of[dec.faces[f * 3 + 1]],
                          given_of[dec.faces[f * 3 + 2]]));
  }
  std::sort(want.begin(), want.end());
  std::sort(got.begin(), got.end());
  EXPECT_EQ(want, got);
  // Counts the stream cannot hold are refused. Every shorter stream is refused or decodes to
  // another base: the stream ends at the last nonzero byte of the shortest value of its final
  // interval (spec/format.md section 11.4), so a cut value lies outside that interval; the zero
  // bytes read past the end can make it decode (the chunk's CRC is what catches a cut chunk).
  EXPECT_EQ(decode_base(stream.data(), stream.size(), n + 1, fn, dec, error), Status::corrupt);
  size_t refused = 0;
  for (size_t cut = 0; cut < stream.size(); ++cut) {
    BaseMesh other;
    if (decode_base(stream.data(), cut, n, fn, other, error) != Status::ok) {
      ++refused;
      continue;
    }
    EXPECT_TRUE(other.coords != dec.coords || other.faces != dec.faces) << "cut at " << cut;
  }
  EXPECT_GE(refused + 4, stream.size());  // here at most the last 4 cuts decode
}

}  // namespace

TEST(BaseCodec, RoundTripsComponentsBoundariesAndVerticesWithoutFaces) {
  std::mt19937 rng(5);
  // A 6x5 grid with two holes, a separate fan, a bowtie sharing a vertex with the fan (edge-
  // manifold, not vertex-manifold), two vertices without faces; vertices in scattered order.
  const int w = 6, h = 5;
  std::vector<uint32_t> faces;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if ((x == 2 && y == 2) || (x == 4 && y == 1)) continue;
      const uint32_t a = uint32_t(y * (w + 1) + x), b = a + 1, c = a + w + 1, d = c + 1;
      faces.insert(faces.end(), {a, b, d, a, d, c});
    }
  const uint32_t g = (w + 1) * (h + 1);  // fan around g: g+1..g+6, open
  for (uint32_t i = 1; i < 6; ++i) faces.insert(faces.end(), {g, g + i, g + i + 1});
  faces.insert(faces.end(), {g, g + 8, g + 7});  // touches the fan at g only
  const uint32_t n = g + 11;                     // g+9, g+10 without faces
  std::vector<uint32_t> perm(n);
  for (uint32_t i = 0; i < n; ++i) perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), rng);
  for (uint32_t& x : faces) x = perm[x];
  std::vector<int32_t> coords(n * 3);
  for (int32_t& c : coords) c = int32_t(rng() % 16384);
  base_round_trip(coords, faces);
  // Lossless coordinates are any int32 patterns: differences wrap modulo 2^32.
  for (size_t i = 0; i < coords.size(); ++i) coords[i] = int32_t(rng()) | (i % 2 ? INT32_MIN : 0);
  coords[0] = INT32_MAX, coords[1] = INT32_MIN;
  base_round_trip(coords, faces);
  // No faces at all; a closed octahedron.
  base_round_trip({1, 2, 3, -4, 5, 6}, {});
  base_round_trip({9, 0, 0, 0, 9, 0, 0, 0, 9, 1, 1, 1, 5, 5, 5, 7, 7, 7},
                  {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5});
}

// The cheapest vertices (spec/format.md section 7): without faces and all at one point, each codes
// only its residuals' 12 length decisions, 60.4 per byte: more than 48 per byte (the bound when a
// length took six decisions), within the decoder's 64.
TEST(BaseCodec, CheapestVerticesFitTheCountBound) {
  const uint32_t n = 100000;
  const std::vector<int32_t> coords(size_t(n) * 3, 7);
  std::vector<uint8_t> stream;
  std::vector<uint32_t> given_of;
  BaseMesh enc, dec;
  std::string error;
  ASSERT_TRUE(encode_base(coords.data(), n, nullptr, 0, stream, given_of, enc, error)) << error;
  EXPECT_GT(n, 48 * (stream.size() + 1));
  EXPECT_LE(n, 64 * (stream.size() + 1));
  ASSERT_EQ(decode_base(stream.data(), stream.size(), n, 0, dec, error), Status::ok) << error;
  EXPECT_EQ(dec.coords, coords);
}

TEST(BaseCodec, WriterRefusesWhatIsNotEdgeManifold) {
  const std::vector<int32_t> coords(12, 0);
  std::vector<uint8_t> stream;
  std::vector<uint32_t> given_of;
  BaseMesh out;
  std::string error;
  const uint32_t twice[] = {0, 1, 2, 0, 1, 3};  // directed edge 0 -> 1 twice
  EXPECT_FALSE(encode_base(coords.data(), 4, twice, 2, stream, given_of, out, error));
  const uint32_t repeated[] = {0, 1, 1};
  EXPECT_FALSE(encode_base(coords.data(), 4, repeated, 1, stream, given_of, out, error));
  const uint32_t range[] = {0, 1, 4};
  EXPECT_FALSE(encode_base(coords.data(), 4, range, 1, stream, given_of, out, error));
}

// The symbols of two faces coded by hand, in the order and with the models spec/format.md section 7
// gives: the predictor bit (0: parallelogram), the first face (0, 1, 2) with three new
// vertices, then across the first gate, 0 -> 1, a face whose third vertex is new (3); nothing
// after the last face. Then a stream whose second vertex refers to an earlier vertex past the
// one made so far: corrupt.
TEST(BaseCodec, HandCodedStreamIsTheSpec) {
  auto code = [](bool bad_reference) {
    std::vector<uint8_t> out;
    RangeEncoder rc(out);
    rc.direct(0, 1);
    Prob is_new[5] = {kProbInit, kProbInit, kProbInit, kProbInit, kProbInit}, face = kProbInit;
    UIntModel jump[3], par[3], other;
    const int32_t c[4][3] = {{100, 200, 300}, {110, 190, 300}, {105, 210, 301}, {105, 180, 299}};
    int32_t last[3] = {0, 0, 0};
    for (int v = 0; v < 3; ++v) {
      if (bad_reference && v == 1) {
        rc.bit(is_new[0], 0);
        encode_uint(rc, other, 1);  // vertices - 1 - id = 1 with one vertex made: id -1
        break;
      }
      rc.bit(is_new[0], 1);
      for (int a = 0; a < 3; ++a) encode_uint(rc, jump[a], zigzag_encode(c[v][a] - last[a]));
      std::copy(c[v], c[v] + 3, last);
    }
    if (!bad_reference) {
      // Gate 0 -> 1 (face 0's first half-edge): face (1, 0, 3) beyond it. Open into 0: 2 -> 0,
      // so L = 2; out of 1: 1 -> 2, R = 2 = L, so none: context 1 + 1 = 2. The parallelogram
      // predicts vertex 3 exactly (so the writer keeps that predictor).
      rc.bit(face, 1);
      rc.bit(is_new[2], 1);
      for (int a = 0; a < 3; ++a)
        encode_uint(rc, par[a], zigzag_encode(c[3][a] - (c[0][a] + c[1][a] - c[2][a])));
    }
    rc.finish();
    return out;
  };
  const std::vector<uint8_t> good = code(false), bad = code(true);
  BaseMesh m;
  std::string error;
  ASSERT_EQ(decode_base(good.data(), good.size(), 4, 2, m, error), Status::ok) << error;
  EXPECT_EQ(m.faces, (std::vector<uint32_t>{0, 1, 2, 1, 0, 3}));
  EXPECT_EQ(m.coords,
            (std::vector<int32_t>{100, 200, 300, 110, 190, 300, 105, 210, 301, 105, 180, 299}));
  // The writer codes these very bytes.
  std::vector<uint8_t> stream;
  std::vector<uint32_t> given_of;
  BaseMesh enc;
  ASSERT_TRUE(encode_base(m.coords.data(), 4, m.faces.data(), 2, stream, given_of, enc, error))
      << error;
  EXPECT_EQ(stream, good);
  EXPECT_EQ(decode_base(bad.data(), bad.size(), 4, 2, m, error), Status::corrupt);
  EXPECT_NE(error.find("malformed"), std::string::npos) << error;
}

// A SPLT payload coded by hand in the order spec/format.md sections 8 and 9.3 give: split_count,
// the connectivity stream's size, the connectivity stream (the groups; then the group's choice bits
// through its 9th vertex; per split j its wedge count, rank bit and rank - 1, then the choice bits
// through the group's (j + 10)-th vertex), the geometry stream (per split the residual slots t0,
// t1, n). A group of 12 on an 11 x 11 grid (even-even vertices: pairwise non-adjacent), so the
// choice bits run ahead of the wedges and then between them. The writer codes these very bytes,
// and the reader, in the decoder's schedule, gets the symbols back.
TEST(SplitChunk, HandCodedPayloadIsTheSpecOrder) {
  constexpr uint32_t kN = 11;
  std::vector<uint32_t> faces;
  for (uint32_t y = 0; y + 1 < kN; ++y)
    for (uint32_t x = 0; x + 1 < kN; ++x) {
      const uint32_t a = y * kN + x, b = a + 1, c = a + kN, d = c + 1;
      faces.insert(faces.end(), {a, b, d, a, d, c});
    }
  ProgressiveMesh pm;
  std::string error;
  ASSERT_TRUE(pm.build(kN * kN, faces.data(), faces.size() / 3, error)) << error;
  const std::vector<uint32_t> vs{0, 2, 4, 6, 8, 10, 22, 24, 26, 28, 30, 32};
  const uint32_t size = uint32_t(vs.size());
  const std::vector<int32_t> coords(kN * kN * 3,
                                    0);  // (umbrella classes: all 2, no splits applied)
  VertexChoice enc;
  enc.reset(pm, coords.data(), 14);
  enc.start_group();
  std::vector<uint32_t> bits;
  bool near = true;
  ASSERT_TRUE(choice_bits(enc, pm, kN * kN, vs, bits, near));
  ASSERT_FALSE(near);
  std::vector<size_t> ones;  // ones[k]: where the group's (k + 1)-th vertex's bit is
  for (size_t i = 0; i < bits.size(); ++i)
    if (bits[i] & 1) ones.push_back(i);
  ASSERT_EQ(ones.size(), size);
  std::vector<SplitSymbols> codes;
  for (uint32_t i = 0; i < size; ++i)
    codes.push_back(
        {vs[i],
         i % kWedgeContexts,
         i % 5,
         i % 3 == 2 ? 17u : i % 3,
         i % kRankContexts,
         {i % kResidualContexts, (i + 1) % kResidualContexts, (i + 7) % kResidualContexts},
         {int32_t(i) - 6, int32_t(2 * i), -int32_t(i * i)},
         {i % kMixTangentContexts, (i + 3) % kMixTangentContexts, (i + 5) % kMixNormalContexts}});

  SplitModels hm;
  std::vector<uint8_t> conn, geom;
  {
    RangeEncoder cn(conn), ge(geom);
    encode_uint(cn, hm.groups, size - 1);
    cn.bit(hm.near, 0);
    size_t next = 0;
    auto choice_through = [&](uint32_t k) {  // the bits through the group's k-th vertex (1-based)
      for (const size_t last = ones[std::min(k, size) - 1]; next <= last; ++next)
        cn.bit(hm.choice[bits[next] >> 1], bits[next] & 1);
    };
    choice_through(9);
    for (uint32_t j = 0; j < size; ++j) {
      const SplitSymbols& s = codes[j];
      encode_small(cn, hm.wedge_count[s.wedge_context], s.wedge_count);
      cn.bit(hm.rank_zero[s.rank_context], s.wedge_rank > 0);
      if (s.wedge_rank > 0) encode_small(cn, hm.wedge_rank[s.rank_context], s.wedge_rank - 1);
      choice_through(j + 10);
      for (int a = 0; a < 3; ++a)
        encode_uint_mixed(ge, hm.residual[a][s.residual_context[a]], hm.mix(a, s.mix_context[a]),
                          zigzag_encode(s.residual[a]));
    }
    EXPECT_EQ(next, bits.size());
    cn.finish();
    ge.finish();
  }
  std::vector<uint8_t> want;
  put_varint(want, size);
  put_varint(want, conn.size());
  want.insert(want.end(), conn.begin(), conn.end());
  want.insert(want.end(), geom.begin(), geom.end());

  SplitModels em, dm;
  std::vector<uint8_t> payload;
  uint64_t sizes[kSplitStreamCount];
  double kind_bits[kSymbolKinds] = {};
  encode_split_chunk({{size, false}}, bits, codes.data(), codes.size(), em, payload, sizes,
                     kind_bits);
  EXPECT_EQ(payload, want);
  EXPECT_EQ(sizes[kStreamConnectivity], conn.size());
  EXPECT_EQ(sizes[kStreamGeometry], geom.size());
  // The code lengths per kind add up to the streams' sizes, within their endings.
  const double conn_bits = kind_bits[kSymbolGroups] + kind_bits[kSymbolChoice] +
                           kind_bits[kSymbolWedgeCount] + kind_bits[kSymbolWedgeRank];
  const double geom_bits =
      kind_bits[kSymbolResidualT0] + kind_bits[kSymbolResidualT1] + kind_bits[kSymbolResidualN];
  for (double b : kind_bits) EXPECT_GT(b, 0.0);
  EXPECT_NEAR(conn_bits, 8.0 * double(conn.size()), 16.0);
  EXPECT_NEAR(geom_bits, 8.0 * double(geom.size()), 16.0);
  uint64_t count = 0, stream[kSplitStreamCount];
  ASSERT_TRUE(split_chunk_stream_sizes(payload.data(), payload.size(), count, stream));
  EXPECT_EQ(count, size);
  EXPECT_EQ(stream[kStreamConnectivity], conn.size());
  EXPECT_EQ(stream[kStreamGeometry], geom.size());

  SplitChunkReader r;
  ASSERT_TRUE(r.open(payload.data(), payload.size(), size, dm, error)) << error;
  VertexChoice dec;
  dec.reset(pm, coords.data(), 14);
  std::vector<SplitSymbols> got;
  ASSERT_TRUE(r.group_symbols(dec, pm, got, [&](SplitSymbols& s) {
    const SplitSymbols& c = codes[got.size()];
    s.wedge_context = c.wedge_context;
    s.rank_context = c.rank_context;
    std::copy(c.residual_context, c.residual_context + 3, s.residual_context);
    std::copy(c.mix_context, c.mix_context + 3, s.mix_context);
  }));
  ASSERT_EQ(got.size(), codes.size());
  for (uint32_t i = 0; i < size; ++i) {
    EXPECT_EQ(got[i].v, codes[i].v);
    EXPECT_EQ(got[i].wedge_count, codes[i].wedge_count);
    EXPECT_EQ(got[i].wedge_rank, codes[i].wedge_rank);
    EXPECT_EQ(std::vector<int32_t>(got[i].residual, got[i].residual + 3),
              std::vector<int32_t>(codes[i].residual, codes[i].residual + 3));
  }

  // A connectivity size beyond the payload, or a payload cut inside the groups: refused when
  // the chunk arrives.
  std::vector<uint8_t> bad;
  put_varint(bad, size);
  put_varint(bad, payload.size());
  bad.insert(bad.end(), conn.begin(), conn.end());
  SplitModels bm;
  SplitChunkReader br;
  EXPECT_FALSE(br.open(bad.data(), bad.size(), size, bm, error));
  EXPECT_NE(error.find("overrun"), std::string::npos) << error;
  bad.clear();
  put_varint(bad, size);
  put_varint(bad, 0);  // an empty connectivity stream: its groups read past the 4 zero bytes
  SplitModels cm;
  SplitChunkReader cr;
  EXPECT_FALSE(cr.open(bad.data(), bad.size(), size, cm, error));
  EXPECT_NE(error.find("groups"), std::string::npos) << error;
}

// The wedge symbols' contexts, table against spec/format.md's Appendix A: wedge_count
// by `2 min(k, 8) + closed` (18 models), wedge_rank by `2 closed + confident` (4 of each). A
// clamp moved on both writer and decoder changes no round trip, only these values.
TEST(WedgeSymbols, ContextsAreTheSpecTable) {
  EXPECT_EQ(kWedgeContexts, 18u);
  EXPECT_EQ(kRankContexts, 4u);
  EXPECT_EQ(sizeof(SplitModels::wedge_count) / sizeof(SmallModel), 18u);
  EXPECT_EQ(sizeof(SplitModels::wedge_rank) / sizeof(SmallModel), 4u);
  for (uint32_t k : {0u, 1u, 2u, 3u, 4u, 5u, 6u, 7u, 8u, 9u, 10u, 12u, 31u, 1000u, 0xFFFFFFFFu})
    for (bool closed : {false, true}) {
      const uint32_t want = 2 * (k < 8 ? k : 8) + (closed ? 1 : 0);
      EXPECT_EQ(wedge_context(k, closed), want) << "k " << k << " closed " << closed;
    }
  // Spelled out where the clamp bites: k = 7, 8, 9 on both fans.
  EXPECT_EQ(wedge_context(7, false), 14u);
  EXPECT_EQ(wedge_context(7, true), 15u);
  EXPECT_EQ(wedge_context(8, false), 16u);
  EXPECT_EQ(wedge_context(9, true), 17u);
  EXPECT_EQ(rank_context(false, false), 0u);
  EXPECT_EQ(rank_context(false, true), 1u);
  EXPECT_EQ(rank_context(true, false), 2u);
  EXPECT_EQ(rank_context(true, true), 3u);
}

// CellBins puts each vertex in the bin of the node whose cell holds it on the level asked, in
// ascending order, and no vertex whose cell has no node: on a level whose cells lie close
// together (looked up in a dense array) and on one whose two cells lie 2^21 cells apart (searched
// instead), both against a test of every vertex against every node's box.
TEST(CellBins, EveryVertexInTheBinOfItsCellsNode) {
  pmz::NodeTable t;
  t.levels.resize(3);
  t.levels[0].side = 10;
  t.levels[0].origin[0] = -3;
  t.levels[1].side = 1;
  t.levels[2].side = 0;
  auto node = [&](uint32_t level, int64_t x, int64_t y, int64_t z) {
    pmz::NodeEntry n;
    n.level = level;
    n.cell[0] = x, n.cell[1] = y, n.cell[2] = z;
    t.nodes.push_back(n);
  };
  node(2, 0, 0, 0);
  node(1, 0, 0, 0);
  node(1, int64_t(1) << 21, 0, 0);
  for (int64_t x = -2; x <= 2; ++x)
    for (int64_t y = 0; y <= 3; ++y) node(0, x, y, (x + y) % 2);
  std::mt19937 rng(7);
  std::vector<int32_t> coords;
  for (int i = 0; i < 3000; ++i) {
    coords.push_back(int32_t(rng() % 80) - 40);
    coords.push_back(int32_t(rng() % 50) - 5);
    coords.push_back(int32_t(rng() % 30) - 10);
  }
  for (int32_t x : {0, 1 << 21, (1 << 21) + 1})  // the level-1 cells and beside one
    coords.insert(coords.end(), {x, 0, 0});
  const uint32_t count = uint32_t(coords.size() / 3);
  pmz::CellBins bins;
  for (uint32_t level = 0; level < 3; ++level) {
    bins.build(t, level, coords.data(), count);
    size_t binned = 0;
    for (uint32_t k = 0; k < t.nodes.size(); ++k) {
      if (t.nodes[k].level != level) continue;
      const pmz::CellBox box(t.levels[level], t.nodes[k].cell);
      std::vector<uint32_t> want;
      for (uint32_t v = 0; v < count; ++v)
        if (box.contains(&coords[size_t(v) * 3])) want.push_back(v);
      EXPECT_EQ(bins.take(k), want) << "level " << level << ", node " << k;
      binned += want.size();
    }
    EXPECT_GT(binned, level == 1 ? 1u : 100u) << "level " << level;
  }
}
