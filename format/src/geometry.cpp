// SPDX-License-Identifier: MIT
#include "pmz/geometry.hpp"

#include <utility>

#include "pmz/progressive_mesh.hpp"

namespace pmz {

namespace {

inline uint32_t bitlen128(UInt128 x) {
  const uint64_t hi = uint64_t(x >> 64), lo = uint64_t(x);
  return hi ? 128u - uint32_t(__builtin_clzll(hi)) : lo ? 64u - uint32_t(__builtin_clzll(lo)) : 0u;
}
inline UInt128 abs128(Int128 x) { return x < 0 ? (UInt128)(-x) : (UInt128)x; }
inline uint32_t context_of(UInt128 mean) {
  const uint32_t b = bitlen128(mean);
  return b < kResidualContexts - 1 ? b : kResidualContexts - 1;
}
// context_of(floor(sum / div)) without dividing (div > 0): floor(sum / div) >= 2^j exactly when
// sum >= div * 2^j, so its bit length is the largest such j plus one (0 when sum < div).
inline uint32_t context_of_mean(uint64_t sum, uint64_t div) {
  if (sum < div) return 0;
  uint32_t j =
      uint32_t(__builtin_clzll(div)) - uint32_t(__builtin_clzll(sum));  // bitlen(sum) - bitlen(div)
  if (sum < (div << j)) --j;  // div << j < 2^bitlen(sum): no overflow
  return j + 1 < kResidualContexts - 1 ? j + 1 : kResidualContexts - 1;
}

// min(2 bitlen(x) + h, 41), h the bit below the leading one (0 when bitlen(x) < 2).
inline uint32_t half_octave_context(uint64_t x) {
  const uint32_t b = x ? 64u - uint32_t(__builtin_clzll(x)) : 0u;
  const uint32_t h = b >= 2 ? uint32_t(x >> (b - 2)) & 1u : 0u;
  return 2 * b + h < kMixTangentContexts - 1 ? 2 * b + h : kMixTangentContexts - 1;
}

}  // namespace

int64_t round_div_wide(Int128 num, Int128 den) {
  if (den < 0) num = -num, den = -den;
  const Int128 x = 2 * num + den, d = 2 * den;
  Int128 q = x / d;
  if (x % d != 0 && x < 0) --q;  // floor, not truncation
  return int64_t(q);
}

namespace {

// Inlined into predict_position (the decoder's per-split call) and the two exported steps.
[[gnu::always_inline]] inline void ring_basis_impl(const int32_t* coords,
                                                   std::span<const uint32_t> u_ring,
                                                   std::span<const uint32_t> v_ring, bool with_l,
                                                   bool with_e, RingBasis& basis,
                                                   bool narrow_known = false,
                                                   const int64_t* v_ring_offsets = nullptr) {
  const uint32_t m = uint32_t(u_ring.size());
  const int32_t* cv = coords + size_t(u_ring[0]) * 3;
  const int64_t vx = cv[0], vy = cv[1], vz = cv[2];
  // Centroid of u's ring with v counted twice; the largest offset from v decides whether the
  // normal fits 64-bit arithmetic (then the same values as the 128-bit sums).
  int64_t* sum = basis.sum;
  sum[0] = 2 * vx, sum[1] = 2 * vy, sum[2] = 2 * vz;
  // Newell normal of u's ring around v (the first offset, v's own, is 0: N = sum over
  // i = 1 .. m-2 of d_i x d_{i+1}), in 64 bits while every offset is below 2^24 and m < 2^14
  // (|terms| < 2^49: the same values as 128-bit sums), else again in 128 bits; then scaled to
  // at most kNormalBits bits (arithmetic shift: floor).
  // Unsigned (modulo 2^64) so that wide offsets wrap harmlessly before the 128-bit redo.
  uint64_t U[3] = {0, 0, 0}, px = 0, py = 0, pz = 0;
  uint64_t spread_v = 0;
  for (uint32_t i = 1; i < m; ++i) {
    const int32_t* cw = coords + size_t(u_ring[i]) * 3;
    sum[0] += cw[0], sum[1] += cw[1], sum[2] += cw[2];
    const int64_t dx = cw[0] - vx, dy = cw[1] - vy, dz = cw[2] - vz;
    if (!narrow_known)  // (a branch the predictor learns: cheaper than the bit twiddling)
      spread_v |= uint64_t(dx ^ (dx >> 63)) | uint64_t(dy ^ (dy >> 63)) | uint64_t(dz ^ (dz >> 63));
    const uint64_t ux = uint64_t(dx), uy = uint64_t(dy), uz = uint64_t(dz);
    U[0] += py * uz - pz * uy;
    U[1] += pz * ux - px * uz;
    U[2] += px * uy - py * ux;
    px = ux, py = uy, pz = uz;
  }
  int64_t* n = basis.n;
  if (spread_v < (uint64_t(1) << 24) && m < (1u << 14)) {
    const int64_t N[3] = {int64_t(U[0]), int64_t(U[1]), int64_t(U[2])};
    const uint64_t big = uint64_t(N[0] < 0 ? -N[0] : N[0]) | uint64_t(N[1] < 0 ? -N[1] : N[1]) |
                         uint64_t(N[2] < 0 ? -N[2] : N[2]);
    const uint32_t bits = big ? 64u - uint32_t(__builtin_clzll(big)) : 0u;
    const uint32_t shift = bits > kNormalBits ? bits - kNormalBits : 0;
    for (int a = 0; a < 3; ++a) n[a] = N[a] >> shift;
  } else {
    Int128 W[3] = {0, 0, 0};
    int64_t prev[3] = {0, 0, 0};
    for (uint32_t i = 1; i < m; ++i) {
      const int32_t* cw = coords + size_t(u_ring[i]) * 3;
      const int64_t d[3] = {cw[0] - vx, cw[1] - vy, cw[2] - vz};
      W[0] += Int128(prev[1]) * d[2] - Int128(prev[2]) * d[1];
      W[1] += Int128(prev[2]) * d[0] - Int128(prev[0]) * d[2];
      W[2] += Int128(prev[0]) * d[1] - Int128(prev[1]) * d[0];
      for (int a = 0; a < 3; ++a) prev[a] = d[a];
    }
    const uint32_t bits = bitlen128(abs128(W[0]) | abs128(W[1]) | abs128(W[2]));
    const uint32_t shift = bits > kNormalBits ? bits - kNormalBits : 0;
    for (int a = 0; a < 3; ++a) n[a] = int64_t(W[a] >> shift);
  }
  const int64_t n0 = n[0], n1 = n[1], n2 = n[2];
  // Axis order by |n|, smallest first, ties by smaller axis.
  uint8_t* ax = basis.axis;
  ax[0] = 0, ax[1] = 1, ax[2] = 2;
  int64_t* mag = basis.mag;
  mag[0] = n0 < 0 ? -n0 : n0, mag[1] = n1 < 0 ? -n1 : n1, mag[2] = n2 < 0 ? -n2 : n2;
  auto before = [&](int x, int y) { return mag[x] < mag[y] || (mag[x] == mag[y] && x < y); };
  if (before(ax[1], ax[0])) std::swap(ax[0], ax[1]);
  if (before(ax[2], ax[1])) std::swap(ax[1], ax[2]);
  if (before(ax[1], ax[0])) std::swap(ax[0], ax[1]);
  // The curvature offsets' projections on n (spec/format.md section 9.6, step 4): v's umbrella
  // vector over its ring before the split, L = k c[v] - sum of that ring, and over u's other
  // neighbours, E = (m - 1) c[v] - their sum = (m + 1) c[v] - sum. |L|, |E| < 2^56 (k, m <= 2^24).
  basis.l_dot_n = basis.e_dot_n = 0;
  const uint32_t k = uint32_t(v_ring.size());
  if (with_l && k && k <= (1u << 24)) {
    const int64_t kk = int64_t(k);
    int64_t L[3] = {kk * vx, kk * vy, kk * vz};
    if (v_ring_offsets) {  // the same integers: k c[v] - sum c[w] = -sum (c[w] - c[v])
      L[0] = -v_ring_offsets[0], L[1] = -v_ring_offsets[1], L[2] = -v_ring_offsets[2];
    } else {
      for (uint32_t w : v_ring) {
        const int32_t* cw = coords + size_t(w) * 3;
        L[0] -= cw[0], L[1] -= cw[1], L[2] -= cw[2];
      }
    }
    basis.l_dot_n = Int128(L[0]) * n0 + Int128(L[1]) * n1 + Int128(L[2]) * n2;
  }
  if (with_e && m >= 2 && m <= (1u << 24)) {
    const int64_t mm = int64_t(m) - 1;
    const int64_t E[3] = {(mm + 2) * vx - sum[0], (mm + 2) * vy - sum[1], (mm + 2) * vz - sum[2]};
    basis.e_dot_n = Int128(E[0]) * n0 + Int128(E[1]) * n1 + Int128(E[2]) * n2;
  }
}

[[gnu::always_inline]] inline void predict_from_basis_impl(
    const int32_t* coords, std::span<const uint32_t> u_ring, uint32_t v_ring_size,
    const RingBasis& basis, uint32_t curvature, uint32_t fine, PositionPrediction& out) {
  const uint32_t m = uint32_t(u_ring.size());
  const int64_t n0 = basis.n[0], n1 = basis.n[1], n2 = basis.n[2];
  for (int a = 0; a < 3; ++a) {
    out.p[a] = floor_mean(basis.sum[a], int64_t(m) + 1);
    out.n[a] = basis.n[a];
    out.axis[a] = basis.axis[a];
  }
  // Curvature offsets along n, one rounding for both: curvature/8 of L / k and fine/8 of
  // E / (m - 1) projected on n. Numerator < 2^118.
  const int64_t q = n0 * n0 + n1 * n1 + n2 * n2;
  const uint32_t k = v_ring_size;
  const bool use_l = curvature && k && k <= (1u << 24), use_e = fine && m >= 2 && m <= (1u << 24);
  if (q && (use_l || use_e)) {
    const int64_t kk = use_l ? int64_t(k) : 1, mm = int64_t(m) - 1;
    Int128 t = 0;
    if (use_l) t = basis.l_dot_n * (int64_t(curvature) * mm);
    if (use_e) t += basis.e_dot_n * (int64_t(fine) * kk);
    const Int128 den = Int128(8 * kk * mm) * q;
    // |n[a]| <= 2^16: below these bounds every t n[a] and den fit round_div's 64-bit path, so it
    // is taken once for the three axes instead of range-checking each 128-bit product.
    constexpr int64_t kNarrowT = int64_t(1) << 44, kNarrowDen = int64_t(1) << 60;
    if (t > -kNarrowT && t < kNarrowT && den > 0 && den < kNarrowDen) {
      const int64_t t64 = int64_t(t), dd = 2 * int64_t(den);
      for (int a = 0; a < 3; ++a) {
        const int64_t x = 2 * t64 * out.n[a] + int64_t(den);
        int64_t r = x / dd;
        if (x % dd != 0 && x < 0) --r;  // floor, not truncation
        out.p[a] += r;
      }
    } else {
      for (int a = 0; a < 3; ++a) out.p[a] += round_div(t * out.n[a], den);
    }
  }
  // Contexts: tangent slots from the ring's spread along their axis; the normal slot from the
  // ring's spread off the plane through p, in units of the normal axis. Every |c[w] - p| is
  // below 2^34 (p is within the ring's box plus at most |L / k|), so each dot product with n
  // fits 64 bits.
  // The mixing contexts: per axis the largest |c[w] - p| over the ring, and v's (the ring's
  // first vertex) distance from the plane through p.
  const int64_t p0 = out.p[0], p1 = out.p[1], p2 = out.p[2];
  const int32_t* cv = coords + size_t(u_ring[0]) * 3;  // v first
  int64_t dx = cv[0] - p0, dy = cv[1] - p1, dz = cv[2] - p2, dot = dx * n0 + dy * n1 + dz * n2;
  uint64_t spread[3] = {uint64_t(dx < 0 ? -dx : dx), uint64_t(dy < 0 ? -dy : dy),
                        uint64_t(dz < 0 ? -dz : dz)};
  uint64_t far[3] = {spread[0], spread[1], spread[2]};
  const uint64_t v_off = uint64_t(dot < 0 ? -dot : dot);
  UInt128 off = v_off;
  for (uint32_t i = 1; i < m; ++i) {
    const int32_t* cw = coords + size_t(u_ring[i]) * 3;
    dx = cw[0] - p0, dy = cw[1] - p1, dz = cw[2] - p2;
    const uint64_t ex = uint64_t(dx < 0 ? -dx : dx), ey = uint64_t(dy < 0 ? -dy : dy),
                   ez = uint64_t(dz < 0 ? -dz : dz);
    spread[0] += ex, spread[1] += ey, spread[2] += ez;
    far[0] = far[0] < ex ? ex : far[0], far[1] = far[1] < ey ? ey : far[1],
    far[2] = far[2] < ez ? ez : far[2];
    dot = dx * n0 + dy * n1 + dz * n2;
    off += uint64_t(dot < 0 ? -dot : dot);
  }
  const uint8_t* ax = basis.axis;
  const int64_t* mag = basis.mag;
  const int c = ax[2];
  for (int s = 0; s < 2; ++s) {
    out.context[s] = context_of_mean(spread[ax[s]], m);
    out.mix[s] = half_octave_context(far[ax[s]]);
  }
  out.mix[2] = mag[c] ? context_of_mean(v_off, uint64_t(mag[c])) : 0;  // n = 0: no plane
  if (mag[c] == 0) off = spread[c];                        // n = 0: the normal axis' own spread
  const uint64_t div = uint64_t(mag[c] ? mag[c] : 1) * m;  // < 2^17 * 2^32
  out.context[2] = off >> 64 ? context_of(off / div) : context_of_mean(uint64_t(off), div);
}

}  // namespace

void ring_basis(const int32_t* coords, std::span<const uint32_t> u_ring,
                std::span<const uint32_t> v_ring, bool with_l, bool with_e, RingBasis& basis) {
  ring_basis_impl(coords, u_ring, v_ring, with_l, with_e, basis);
}

void predict_from_basis(const int32_t* coords, std::span<const uint32_t> u_ring,
                        uint32_t v_ring_size, const RingBasis& basis, uint32_t curvature,
                        uint32_t fine, PositionPrediction& out) {
  predict_from_basis_impl(coords, u_ring, v_ring_size, basis, curvature, fine, out);
}

void predict_position(const int32_t* coords, std::span<const uint32_t> u_ring,
                      std::span<const uint32_t> v_ring, uint32_t curvature, uint32_t fine,
                      PositionPrediction& out, uint64_t extent, const int64_t* v_ring_offsets) {
  RingBasis basis;
  ring_basis_impl(coords, u_ring, v_ring, curvature != 0, fine != 0, basis,
                  extent < (uint64_t(1) << 24), v_ring_offsets);
  predict_from_basis_impl(coords, u_ring, uint32_t(v_ring.size()), basis, curvature, fine, out);
}

}  // namespace pmz
