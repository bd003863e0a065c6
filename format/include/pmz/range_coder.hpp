// SPDX-License-Identifier: MIT
// Adaptive binary range coder (LZMA's, 15-bit probabilities, adaptation shift 2 growing to 6) and
// the binarization of unsigned integers used by SPLT streams (spec/format.md section 11).
// Header-only so the per-bit work inlines into the stream loops.
#pragma once
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "pmz/wasm_hints.hpp"

namespace pmz {

inline constexpr uint32_t kProbBits = 15, kProbOne = 1u << kProbBits, kTop = 1u << 24;
// A stream's bytes past its end read as 0, up to this many; reading further is an error.
inline constexpr uint32_t kStreamPad = 4;

// A bit model (Prob) is one uint32: the 15-bit probability of a 0 in bits 0..14, and from bit 16
// how many bits it has coded, saturating at 127. The adaptation shift grows with that count: 2
// for the model's first 8 bits, 3 for the next 8, 4 for the next 32, 5 for the next 79, then 6
// (spec/format.md section 11.1). A step moves p toward kProbMin or kProbMax, not 0 or 1, so p stays
// within [kProbMin, kProbMax] whatever the bits (the range coders' one-shift normalisation relies
// on it) and a decision costs at least log2(32768 / 32528) > 0.01 bit (the count bounds of
// spec/format.md section 12). kProbInit is the initial model (probability 1/2, count 0).
using Prob = uint32_t;
inline constexpr uint32_t kProbMin = 240, kProbMax = kProbOne - kProbMin, kProbInit = kProbOne / 2;
inline constexpr uint32_t kCountShift = 16, kProbMask = (1u << kCountShift) - 1, kMaxCount = 127;
inline constexpr uint32_t model_shift(uint32_t count) {
  return 2 + (count >= 8) + (count >= 16) + (count >= 48) + (count >= kMaxCount);
}
// Per count: the shift, and the next count in bits 16.. (two loads per coded bit, no masking).
struct AdaptTable {
  uint8_t shift[kMaxCount + 1];
  uint32_t next[kMaxCount + 1];
  constexpr AdaptTable() : shift(), next() {
    for (uint32_t c = 0; c <= kMaxCount; ++c) {
      shift[c] = uint8_t(model_shift(c));
      next[c] = (c < kMaxCount ? c + 1 : kMaxCount) << kCountShift;
    }
  }
};
inline constexpr AdaptTable kAdapt{};
// A model that starts from a prior probability p (kProbMin..kProbMax) other than 1/2 starts at
// count 16 (shift 4): the fast first steps would forget the prior.
inline constexpr uint32_t kPriorCount = 16;
inline Prob primed_model(uint32_t p) { return p | kPriorCount << kCountShift; }
inline Prob adapt(uint32_t model, uint32_t b) {
  const uint32_t pr = model & kProbMask, c = model >> kCountShift, shift = kAdapt.shift[c];
  const uint32_t np = b ? pr - ((pr - kProbMin) >> shift) : pr + ((kProbMax - pr) >> shift);
  return kAdapt.next[c] | np;
}

// The probability of a bit coded with two models: the mean of theirs, rounded down. Both stay
// within [kProbMin, kProbMax], so the mean does too (the coders' one-shift normalization holds).
inline uint32_t mix_probability(uint32_t p, uint32_t q) {
  return ((p & kProbMask) + (q & kProbMask)) >> 1;
}

inline uint32_t bit_length(uint32_t x) { return x ? 32u - uint32_t(__builtin_clz(x)) : 0u; }

class RangeEncoder {
 public:
  explicit RangeEncoder(std::vector<uint8_t>& out) : out_(out), start_(out.size()) {}
  // The code length of what was coded so far, in bits: 8 per byte shifted out of the interval,
  // plus how far it narrowed within the current 32 bits (the writer's accounting per symbol
  // kind takes differences; the stream's ending comes on top).
  double position() const { return 8.0 * double(shifts_) + 32.0 - std::log2(double(range_)); }
  void bit(Prob& p, uint32_t b) {
    code(p & kProbMask, b);
    p = adapt(p, b);
  }
  // A bit with the mean of two models' probabilities (both adapt): spec/format.md section 11.3,
  // "mixed".
  void bit2(Prob& p, Prob& q, uint32_t b) {
    code(mix_probability(p, q), b);
    p = adapt(p, b);
    q = adapt(q, b);
  }
  void direct(uint32_t value, uint32_t bits) {
    while (bits--) {
      range_ >>= 1;
      if ((value >> bits) & 1) low_ += range_;
      while (range_ < kTop) {
        range_ <<= 8;
        shift_low();
      }
    }
  }
  // Ends the stream with the value in [low, low + range) that has the most trailing zero bits
  // (range >= 2^24 here, so at least 24), flushes it, then drops the stream's first byte (always
  // 0) and up to kStreamPad trailing zero bytes, which the decoder reads back as zeros
  // (spec/format.md section 11.4).
  void finish() {
    for (uint32_t k = 32;; --k) {
      const uint64_t mask = (uint64_t(1) << k) - 1, v = (low_ + mask) & ~mask;
      if (v - low_ < range_) {
        low_ = v;
        break;
      }
    }
    for (int i = 0; i < 5; ++i) shift_low();
    out_.erase(out_.begin() + std::ptrdiff_t(start_));
    for (uint32_t i = 0; i < kStreamPad && out_.size() > start_ && out_.back() == 0; ++i)
      out_.pop_back();
  }

 private:
  // Codes bit b with probability pr of a 0 (the caller adapts its models).
  void code(uint32_t pr, uint32_t b) {
    const uint32_t bound = (range_ >> kProbBits) * pr;
    if (!b) {
      range_ = bound;
    } else {
      low_ += bound;
      range_ -= bound;
    }
    while (range_ < kTop) {
      range_ <<= 8;
      shift_low();
    }
  }
  void shift_low() {
    ++shifts_;
    if (uint32_t(low_) < 0xFF000000u || (low_ >> 32) != 0) {
      uint8_t carry = uint8_t(low_ >> 32), temp = cache_;
      do {
        out_.push_back(uint8_t(temp + carry));
        temp = 0xFF;
      } while (--cache_size_ != 0);
      cache_ = uint8_t(low_ >> 24);
    }
    ++cache_size_;
    low_ = (low_ & 0x00FFFFFFu) << 8;
  }
  std::vector<uint8_t>& out_;
  size_t start_;
  uint64_t low_ = 0;
  uint32_t range_ = 0xFFFFFFFFu;
  uint8_t cache_ = 0;
  uint64_t cache_size_ = 1;
  uint64_t shifts_ = 0;
};

// Decoder state as plain values: decode_uint works on a local copy, so a whole symbol's bits
// run with range, code and the input pointer in registers, written back once per symbol.
struct RangeState {
  uint32_t range, code;
  const uint8_t* p;
  const uint8_t* end;
  bool ok;
  uint8_t next() {
    if (p < end) return *p++;
    ok = false;
    return 0;
  }
  // One shift always suffices: normalized range >= 2^24, and a coded bit keeps at least
  // (2^24 >> 15) * 240 (probabilities stay within [kProbMin, kProbMax], whatever the input) and
  // a direct bit 2^23, both >= 2^16.
  void normalize() {
    if (range < kTop) {
      range <<= 8;
      code = (code << 8) | next();
    }
  }
  // Decodes a bit with probability pr of a 0 (the caller adapts its models).
  uint32_t code_bit(uint32_t pr) {
    const uint32_t bound = (range >> kProbBits) * pr;
    uint32_t b;
    if (code < bound) {
      range = bound;
      b = 0;
    } else {
      code -= bound;
      range -= bound;
      b = 1;
    }
    normalize();
    return b;
  }
  uint32_t bit(Prob& prob) {
    const uint32_t model = prob, b = code_bit(model & kProbMask);
    prob = adapt(model, b);
    return b;
  }
  uint32_t bit2(Prob& prob, Prob& prob2) {
    const uint32_t model = prob, model2 = prob2, b = code_bit(mix_probability(model, model2));
    prob = adapt(model, b);
    prob2 = adapt(model2, b);
    return b;
  }
  // One direct bit at a time, as the encoder writes them: a single range >>= n for n bits would
  // round differently from n shifts by one, so the bits are not batched.
  uint32_t direct(uint32_t bits) {
    uint32_t r = 0;
    while (bits--) {
      range >>= 1;
      const uint32_t b = code >= range ? 1u : 0u;
      if (b) code -= range;
      r = (r << 1) | b;
      normalize();
    }
    return r;
  }
};

class RangeDecoder {
 public:
  // Decodes its own copy of the size bytes at p followed by kStreamPad zero bytes (the bytes past
  // a stream's end read as 0, up to kStreamPad); reading further yields zeros and clears ok (a
  // valid stream never does).
  PMZ_SMALL_IN_WASM RangeDecoder(const uint8_t* p, size_t size);  // coding.cpp
  RangeState state() const { return s_; }
  void set_state(const RangeState& s) {
    s_.range = s.range;
    s_.code = s.code;
    s_.p = s.p;
    ok = ok && s.ok;
  }
  RangeDecoder(const RangeDecoder&) = delete;
  RangeDecoder& operator=(const RangeDecoder&) = delete;
  bool ok = true;

 private:
  std::vector<uint8_t> buf_;
  RangeState s_;
};

// An adaptive model for uint32 values: the bit length n (0..32) as min(n, 15) through a
// 4-level binary tree; n >= 15 (an escape: residuals of 14-bit positions stay below it) then
// n - 15 (0..17) through a 5-level tree; then the two bits below the leading one adaptively
// (per n), the rest direct (spec/format.md section 11.3). Without the escape, the top levels of a
// 6-level tree would code bits that are almost always 0, each still costing about 0.01 bit.
inline constexpr uint32_t kLengthEscape = 15;
struct UIntModel {
  Prob length[16];
  Prob escape[32];
  Prob high[33][4];
  PMZ_SMALL_IN_WASM UIntModel() {
    for (auto& p : length) p = kProbInit;
    for (auto& p : escape) p = kProbInit;
    for (auto& h : high)
      for (auto& p : h) p = kProbInit;
  }
};

// The binarization above, shared by the plain and the mixed value: bit(at, b) codes (bit(at)
// decodes) one modeled bit, at(model) picking its probability in a UIntModel.
template <class Bit>
[[gnu::always_inline]] inline void encode_uint_with(RangeEncoder& rc, uint32_t x, Bit&& bit) {
  const uint32_t n = bit_length(x), s = n < kLengthEscape ? n : kLengthEscape;
  uint32_t node = 1;
  for (int i = 3; i >= 0; --i) {
    const uint32_t b = (s >> i) & 1;
    bit([node](UIntModel& m) -> Prob& { return m.length[node]; }, b);
    node = node * 2 + b;
  }
  if (s == kLengthEscape) {
    node = 1;
    for (int i = 4; i >= 0; --i) {
      const uint32_t b = ((n - kLengthEscape) >> i) & 1;
      bit([node](UIntModel& m) -> Prob& { return m.escape[node]; }, b);
      node = node * 2 + b;
    }
  }
  if (n < 2) return;
  uint32_t rest = n - 1, hnode = 1;
  for (uint32_t i = 0; i < 2 && rest; ++i) {
    uint32_t b = (x >> --rest) & 1;
    bit([n, hnode](UIntModel& m) -> Prob& { return m.high[n][hnode]; }, b);
    hnode = hnode * 2 + b;
  }
  rc.direct(x, rest);  // only the low `rest` bits are written
}

// Returns false for a bit length above 32 (corrupt input).
template <class Bit>
[[gnu::always_inline]] inline bool decode_uint_with(RangeState& s, uint32_t& x, Bit&& bit) {
  uint32_t node = 1;
#pragma GCC unroll 4
  for (int i = 0; i < 4; ++i)
    node = node * 2 + bit([node](UIntModel& m) -> Prob& { return m.length[node]; });
  uint32_t n = node - 16;
  if (n == kLengthEscape) [[unlikely]] {
    node = 1;
    for (int i = 0; i < 5; ++i)
      node = node * 2 + bit([node](UIntModel& m) -> Prob& { return m.escape[node]; });
    n = node - 32 + kLengthEscape;
    if (n > 32) return false;
  }
  if (n < 2) {
    x = n;
    return true;
  }
  uint32_t rest = n - 1, hnode = 1, v = 1;
  for (uint32_t i = 0; i < 2 && rest; ++i, --rest) {
    uint32_t b = bit([n, hnode](UIntModel& m) -> Prob& { return m.high[n][hnode]; });
    hnode = hnode * 2 + b;
    v = v * 2 + b;
  }
  x = (v << rest) | s.direct(rest);
  return true;
}

inline void encode_uint(RangeEncoder& rc, UIntModel& m, uint32_t x) {
  encode_uint_with(rc, x, [&](auto at, uint32_t b) { rc.bit(at(m), b); });
}

[[gnu::always_inline]] inline bool decode_uint(RangeState& s, UIntModel& m, uint32_t& x) {
  return decode_uint_with(s, x, [&](auto at) { return s.bit(at(m)); });
}

[[gnu::always_inline]] inline bool decode_uint(RangeDecoder& rc, UIntModel& m, uint32_t& x) {
  RangeState s = rc.state();
  const bool ok = decode_uint(s, m, x);
  rc.set_state(s);
  return ok;
}

// A uint32 coded with two uint models (the position residuals, spec/format.md section 11.3,
// "mixed"): the binarization of encode_uint, every modeled bit with the mean of m's and m2's
// probabilities at the same node, both adapting; the direct bits as there.
inline void encode_uint_mixed(RangeEncoder& rc, UIntModel& m, UIntModel& m2, uint32_t x) {
  encode_uint_with(rc, x, [&](auto at, uint32_t b) { rc.bit2(at(m), at(m2), b); });
}

// Returns false for a bit length above 32 (corrupt input).
[[gnu::always_inline]] inline bool decode_uint_mixed(RangeState& s, UIntModel& m, UIntModel& m2,
                                                     uint32_t& x) {
  return decode_uint_with(s, x, [&](auto at) { return s.bit2(at(m), at(m2)); });
}

[[gnu::always_inline]] inline bool decode_uint_mixed(RangeDecoder& rc, UIntModel& m, UIntModel& m2,
                                                     uint32_t& x) {
  RangeState s = rc.state();
  const bool ok = decode_uint_mixed(s, m, m2, x);
  rc.set_state(s);
  return ok;
}

// An adaptive model for small unsigned values (wedge symbols): min(x, 7) as three bits, most
// significant first, through a binary tree (node from 1, 8 entries); x >= 7 then codes x - 7
// with a uint model.
struct SmallModel {
  Prob tree[8];
  UIntModel escape;
  PMZ_SMALL_IN_WASM SmallModel() {
    for (auto& p : tree) p = kProbInit;
  }
};
inline constexpr uint32_t kSmallEscape = 7;

inline void encode_small(RangeEncoder& rc, SmallModel& m, uint32_t x) {
  const uint32_t s = x < kSmallEscape ? x : kSmallEscape;
  uint32_t node = 1;
  for (int i = 2; i >= 0; --i) {
    const uint32_t b = (s >> i) & 1;
    rc.bit(m.tree[node], b);
    node = node * 2 + b;
  }
  if (s == kSmallEscape) encode_uint(rc, m.escape, x - kSmallEscape);
}

// False when the escaped value is corrupt (bit length above 32, or x beyond uint32).
[[gnu::always_inline]] inline bool decode_small(RangeState& st, SmallModel& m, uint32_t& x) {
  uint32_t node = 1;
  for (int i = 0; i < 3; ++i) node = node * 2 + st.bit(m.tree[node]);
  x = node - 8;
  if (x < kSmallEscape) return true;
  uint32_t rest;
  if (!decode_uint(st, m.escape, rest) || rest > 0xFFFFFFFFu - kSmallEscape) return false;
  x = kSmallEscape + rest;
  return true;
}

}  // namespace pmz
