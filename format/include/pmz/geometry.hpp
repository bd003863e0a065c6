// SPDX-License-Identifier: MIT
// Position of a new vertex (spec/format.md section 9.6), shared by writer and decoder: the
// prediction from u's ring with a curvature offset, the axis order (two tangent axes, then the
// normal axis predicted from the tangent plane) and the residual contexts.
#pragma once
#include <cstdint>
#include <span>
#include <utility>

namespace pmz {

inline constexpr uint32_t kResidualContexts = 21;  // per residual slot
// Second contexts of the residual slots (spec/format.md section 9.6, step 5): the ring's largest
// offset from p at half-octave resolution for the tangent slots, v's distance from the plane for
// the normal.
inline constexpr uint32_t kMixTangentContexts = 42, kMixNormalContexts = 21;
inline constexpr uint32_t kMaxCurvature =
    8;  // HEAD curvature and fine_curvature: weights in eighths
inline constexpr uint32_t kNormalBits = 16;  // |n[a]| <= 2^16 after scaling

__extension__ typedef __int128 Int128;
__extension__ typedef unsigned __int128 UInt128;

int64_t round_div_wide(Int128 num, Int128 den);
// round(num / den) with halves rounded up: floor((2 num + den) / (2 den)), den != 0. In 64 bits
// when both are below 2^61 in magnitude (the usual case: a 128-bit division is a library call).
inline int64_t round_div(Int128 num, Int128 den) {
  constexpr int64_t kLimit = int64_t(1) << 61;
  if (num > -kLimit && num < kLimit && den > -kLimit && den < kLimit) {
    int64_t n = int64_t(num), d = int64_t(den);
    if (d < 0) n = -n, d = -d;
    const int64_t x = 2 * n + d, dd = 2 * d;
    int64_t q = x / dd;
    if (x % dd != 0 && x < 0) --q;  // floor, not truncation
    return q;
  }
  return round_div_wide(num, den);
}

struct PositionPrediction {
  int64_t p[3];         // predicted coordinates (before the plane step for the normal axis)
  int64_t n[3];         // scaled normal of u's ring
  uint8_t axis[3];      // coding order: two tangent axes (smallest |n| first), then the normal axis
  uint32_t context[3];  // residual context per slot (coding order)
  uint32_t mix[3];  // second context per slot, mixed with the first (spec/format.md section 9.6)
};

// What the prediction needs from the rings whatever the curvature weights: the centroid sums,
// the scaled normal, the axis order and the umbrella vectors' projections on the normal.
struct RingBasis {
  int64_t sum[3];   // c[v] twice plus u's other neighbours
  int64_t n[3];     // scaled normal of u's ring
  int64_t mag[3];   // |n[a]|
  uint8_t axis[3];  // coding order
  Int128 l_dot_n;   // (k c[v] - sum of v's ring) . n when asked and k in 1..2^24, else 0
  Int128 e_dot_n;   // ((m + 1) c[v] - sum) . n when asked and m in 2..2^24, else 0
};

// u_ring: v, then u's other neighbours in order (ProgressiveMesh::u_ring()); v_ring: v's ring
// before the split (ProgressiveMesh::ring(), any order); curvature and fine: HEAD fields, 0..8.
// extent (optional): a bound on |c[w] - c[v]| per axis over all vertex pairs, e.g. the largest
// side of the coordinates' bounding box; below 2^24 the normal's 64-bit range check per ring
// vertex is skipped (the same results). v_ring_offsets (optional): the sum of c[w] - c[v] over
// v_ring per axis, when the caller has it (WedgeScratch::ring_offsets): saves a ring walk.
void predict_position(const int32_t* coords, std::span<const uint32_t> u_ring,
                      std::span<const uint32_t> v_ring, uint32_t curvature, uint32_t fine,
                      PositionPrediction& out, uint64_t extent = UINT64_MAX,
                      const int64_t* v_ring_offsets = nullptr);
// The same in two steps, for a writer trying several curvature pairs on one split: the ring
// part once, then per pair the offset and the contexts (results identical to predict_position).
// with_l / with_e: whether l_dot_n / e_dot_n are wanted (some pair has curvature / fine > 0).
void ring_basis(const int32_t* coords, std::span<const uint32_t> u_ring,
                std::span<const uint32_t> v_ring, bool with_l, bool with_e, RingBasis& basis);
void predict_from_basis(const int32_t* coords, std::span<const uint32_t> u_ring,
                        uint32_t v_ring_size, const RingBasis& basis, uint32_t curvature,
                        uint32_t fine, PositionPrediction& out);

// Prediction of the normal axis (slot 2) once the tangent residuals r0, r1 (slots 0, 1) are
// known: the plane through p with normal n.
inline int64_t normal_axis_prediction(const PositionPrediction& pp, int32_t r0, int32_t r1) {
  const int a = pp.axis[0], b = pp.axis[1], c = pp.axis[2];
  if (pp.n[c] == 0) return pp.p[c];
  return pp.p[c] - round_div(pp.n[a] * int64_t(r0) + pp.n[b] * int64_t(r1), pp.n[c]);  // |.| < 2^48
}

// Writer: residuals per slot of the actual coordinates cu (int32 differences modulo 2^32).
inline void position_residuals(const PositionPrediction& pp, const int32_t cu[3], int32_t r[3]) {
  for (int s = 0; s < 2; ++s) r[s] = int32_t(uint32_t(cu[pp.axis[s]]) - uint32_t(pp.p[pp.axis[s]]));
  r[2] = int32_t(uint32_t(cu[pp.axis[2]]) - uint32_t(normal_axis_prediction(pp, r[0], r[1])));
}

// Decoder: coordinates from the residuals per slot.
inline void position_from_residuals(const PositionPrediction& pp, const int32_t r[3],
                                    int32_t cu[3]) {
  for (int s = 0; s < 2; ++s) cu[pp.axis[s]] = int32_t(uint32_t(pp.p[pp.axis[s]]) + uint32_t(r[s]));
  cu[pp.axis[2]] = int32_t(uint32_t(normal_axis_prediction(pp, r[0], r[1])) + uint32_t(r[2]));
}

}  // namespace pmz
