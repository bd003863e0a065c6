// SPDX-License-Identifier: MIT
#include "pmz/fan_wedge.hpp"

#include <algorithm>
#include <span>

#include "pmz/progressive_mesh.hpp"

namespace pmz {

// ---- Wedge candidates (spec/format.md section 9.4) ----

namespace {

constexpr uint32_t kMaxScoredRing = 1u << 24;  // larger rings: all scores 0 (order by index)
constexpr uint32_t kTopSelect = 16;            // ranks below: insertion into the best rank + 1

// End weights (spec/format.md section 9.4): m = 4, 3, 2 for degree <= 4, 5, more, and r = 12 / m (a
// negative G is ordered by G / (m_a m_b)), by degree clamped to 7; a missing end as degree 7.
constexpr uint8_t kWeight[8][2] = {{4, 3}, {4, 3}, {4, 3}, {4, 3}, {4, 3}, {3, 4}, {2, 6}, {2, 6}};

// Whether every score of v's ring fits 64 bits: k (max|e| + 1) < 2^26 (spread: OR of |e| - (e <
// 0) per component, so every |e| <= spread + 1).
bool ring_narrow(const int32_t* coords, const ProgressiveMesh& pm, const int32_t* cv) {
  const std::span<const uint32_t> ring = pm.ring();
  uint64_t spread = 0;
  for (uint32_t w : ring) {
    const int32_t* cw = coords + size_t(w) * 3;
    const int64_t dx = int64_t(cw[0]) - cv[0], dy = int64_t(cw[1]) - cv[1],
                  dz = int64_t(cw[2]) - cv[2];
    spread |= uint64_t(dx ^ (dx >> 63)) | uint64_t(dy ^ (dy >> 63)) | uint64_t(dz ^ (dz >> 63));
  }
  return spread < (uint64_t(1) << 26) && (spread + 1) * ring.size() < (uint64_t(1) << 26);
}

// Scores of the candidates with `count` interior ring vertices, in integer type I (U its unsigned
// twin): 64 bits for a narrow ring (ring_narrow, or shown by s.extent: every |key| fits), 128
// otherwise (rare). Closed: candidate j has a = j, b = (j + count + 1) mod k. Open: interior
// starts at j (0 .. k - count), a = j - 1 (none for j = 0), b = j + count (none for k). One pass
// over the ring for the offsets e, |e|^2 and the weights per position (extended canonical order;
// a closed ring's wrapped positions copied, not recomputed), then one pass over the candidates
// with the interior's sums slid along (add the new end b, drop the first interior position),
// tracking the best two scores (s.confident) and the first best candidate (s.best, rank 0).
// G = |E|^2 + c (4 S - c T) with E = 2 * interior + both ends, S the interior's |e|^2, T = 2 or 4
// times the ends' |e|^2 (0 for a missing end); key = G m_a m_b when G >= 0, else G r_a r_b with
// r = 12 / m (spec/format.md section 9.4).
template <class I, class U>
void score_wedges(const int32_t* coords, const uint32_t* degree, const ProgressiveMesh& pm,
                  uint32_t count, const int32_t* cv, std::vector<I>& qbuf, std::vector<I>& score,
                  WedgeScratch& s) {
  const std::span<const uint32_t> ring = pm.ring();
  const uint32_t k = uint32_t(ring.size()), start = pm.ring_start();
  const bool closed = pm.ring_closed();
  const uint32_t n = closed ? k : k - count + 1;
  // Positions: closed 0 .. k + count (rank x mod k), open 0 .. k + 1 (rank x - 1; 0 and k + 1
  // missing: e = 0, weight as degree 7).
  const uint32_t len = closed ? k + count + 1 : k + 2;
  if (qbuf.size() < size_t(len) * 4) qbuf.resize(size_t(len) * 4);
  if (s.w.size() < size_t(len) * 2) s.w.resize(size_t(len) * 2);
  if (score.size() < n) score.resize(n);
  I* const q0 = qbuf.data();
  uint8_t* const w0 = s.w.data();
  I* q = q0;
  uint8_t* wm = w0;
  const int64_t cx = cv[0], cy = cv[1], cz = cv[2];
  int64_t ox = 0, oy = 0, oz = 0;  // s.ring_offsets (|sum| < 2^57 for rings up to 2^24)
  auto put_vertex = [&](uint32_t w) {
    const int32_t* cw = coords + size_t(w) * 3;
    const int64_t dx = cw[0] - cx, dy = cw[1] - cy, dz = cw[2] - cz;
    ox += dx, oy += dy, oz += dz;
    q[0] = dx;
    q[1] = dy;
    q[2] = dz;
    q[3] = I(U(dx) * U(dx) + U(dy) * U(dy) + U(dz) * U(dz));
    q += 4;
    const uint32_t d = degree[w];
    const uint8_t* m = kWeight[d < 7 ? d : 7];
    wm[0] = m[0];
    wm[1] = m[1];
    wm += 2;
  };
  auto put_missing = [&] {
    q[0] = q[1] = q[2] = q[3] = 0;
    q += 4;
    wm[0] = kWeight[7][0];
    wm[1] = kWeight[7][1];
    wm += 2;
  };
  if (!closed) put_missing();
  for (uint32_t j = start; j < k; ++j) put_vertex(ring[j]);
  for (uint32_t j = 0; j < start; ++j) put_vertex(ring[j]);
  s.ring_offsets[0] = ox, s.ring_offsets[1] = oy, s.ring_offsets[2] = oz;
  s.ring_offsets_ok = true;
  if (closed) {
    for (uint32_t i = 0; i <= count;
         ++i) {  // count + 1 < k: no overlap (a few positions: no memcpy call)
      q[4 * i] = q0[4 * i];
      q[4 * i + 1] = q0[4 * i + 1];
      q[4 * i + 2] = q0[4 * i + 2];
      q[4 * i + 3] = q0[4 * i + 3];
      wm[2 * i] = w0[2 * i];
      wm[2 * i + 1] = w0[2 * i + 1];
    }
  } else {
    put_missing();
  }
  // Candidate j: ends at positions j and j + count + 1, interior j + 1 .. j + count.
  I wx = 0, wy = 0, wz = 0, S = 0;
  for (const I* p = q0 + 4; p < q0 + size_t(count + 1) * 4; p += 4) {
    wx += p[0];
    wy += p[1];
    wz += p[2];
    S += p[3];
  }
  const I c = I(count);
  const size_t span = size_t(count + 1);
  I* const out = score.data();
  const I lowest = I(U(1) << (8 * sizeof(I) - 1));  // the type's minimum (C++20: modular)
  I best = lowest, second = lowest;
  uint32_t best_j = 0;
  for (uint32_t j = 0; j < n; ++j) {
    const I* a = q0 + size_t(j) * 4;
    const I* b = a + span * 4;
    const I ex = 2 * wx + a[0] + b[0], ey = 2 * wy + a[1] + b[1], ez = 2 * wz + a[2] + b[2];
    const I ends = a[3] + b[3];
    const I T = (closed || (j > 0 && j + count < k)) ? 2 * ends : 4 * ends;
    const I G = ex * ex + ey * ey + ez * ez + c * (4 * S - c * T);
    const uint8_t* ma = w0 + size_t(j) * 2;
    const uint8_t* mb = ma + span * 2;
    const I sc = G * I(G >= 0 ? ma[0] * mb[0] : ma[1] * mb[1]);
    out[j] = sc;
    if (sc > best) {
      second = best;
      best = sc;
      best_j = j;
    } else if (sc > second) {
      second = sc;
    }
    wx += b[0] - a[4];
    wy += b[1] - a[5];
    wz += b[2] - a[6];
    S += b[3] - a[7];
  }
  s.confident = n < 2 || second <= 0 || best - second > second;
  s.best = best_j;
  s.n = n;
}

// The two instantiations: 64-bit (every split of a real mesh) and 128-bit (cold, kept small).
void score_narrow(const int32_t* coords, const uint32_t* degree, const ProgressiveMesh& pm,
                  uint32_t count, const int32_t* cv, WedgeScratch& s) {
  score_wedges<int64_t, uint64_t>(coords, degree, pm, count, cv, s.q, s.score64, s);
}
[[gnu::cold]] void score_wide(const int32_t* coords, const uint32_t* degree,
                              const ProgressiveMesh& pm, uint32_t count, const int32_t* cv,
                              WedgeScratch& s) {
  score_wedges<WedgeScoreSigned, WedgeScore>(coords, degree, pm, count, cv, s.q128, s.score, s);
}

uint32_t wedge_candidates(const int32_t* coords, const uint32_t* degree, uint32_t v,
                          const ProgressiveMesh& pm, uint32_t count, WedgeScratch& s) {
  const uint32_t k = uint32_t(pm.ring().size());
  if (k > kMaxScoredRing) {
    const uint32_t n = pm.ring_closed() ? k : k - count + 1;
    s.narrow = true;
    s.ring_offsets_ok = false;
    s.score64.assign(n, 0);
    s.confident = true;
    s.best = 0;
    return s.n = n;
  }
  const int32_t* cv = coords + size_t(v) * 3;
  if ((s.extent < (uint64_t(1) << 26) && (s.extent + 1) * k < (uint64_t(1) << 26)) ||
      ring_narrow(coords, pm, cv)) {
    score_narrow(coords, degree, pm, count, cv, s);
    s.narrow = true;
  } else {
    score_wide(coords, degree, pm, count, cv, s);
    s.narrow = false;
  }
  return s.n;
}

// Candidate order: higher score first, ties by smaller j.
template <class Score>
inline bool better(const Score* score, uint32_t x, uint32_t y) {
  return score[x] > score[y] || (score[x] == score[y] && x < y);
}

// Number of candidates ordered before j.
template <class Score>
uint32_t rank_of(const Score* score, uint32_t n, uint32_t j) {
  uint32_t rank = 0;
  for (uint32_t i = 0; i < n; ++i) rank += better(score, i, j);
  return rank;
}

// The candidate at position rank (< n) of the order.
template <class Score>
uint32_t select(const Score* score, uint32_t n, uint32_t rank, std::vector<uint32_t>& order) {
  if (rank < kTopSelect) {
    // Keep the best rank + 1 candidates sorted while scanning j upwards; a later candidate
    // goes after equal scores, which is the tie-break by smaller j.
    uint32_t top[kTopSelect];
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; ++i) {
      if (m <= rank)
        ++m;
      else if (!(score[i] > score[top[rank]]))
        continue;
      uint32_t p = m - 1;
      for (; p > 0 && score[i] > score[top[p - 1]]; --p) top[p] = top[p - 1];
      top[p] = i;
    }
    return top[rank];
  }
  order.resize(n);
  for (uint32_t i = 0; i < n; ++i) order[i] = i;
  std::nth_element(order.begin(), order.begin() + rank, order.end(),
                   [&](uint32_t x, uint32_t y) { return better(score, x, y); });
  return order[rank];
}

inline uint32_t max_count(const ProgressiveMesh& pm) {
  const uint32_t k = uint32_t(pm.ring().size());
  return pm.ring_closed() ? k - 2 : k - 1;
}

}  // namespace

bool wedge_index(const ProgressiveMesh& pm, uint32_t rank_l, uint32_t rank_r, uint32_t& count,
                 uint32_t& j) {
  const uint32_t k = uint32_t(pm.ring().size());
  if (pm.ring_closed()) {
    if (rank_l >= k || rank_r >= k || rank_l == rank_r) return false;
    count = (rank_r + k - rank_l) % k - 1;
    j = rank_l;
    return true;
  }
  if ((rank_l == kNoRank && rank_r == kNoRank) || (rank_l != kNoRank && rank_l >= k) ||
      (rank_r != kNoRank && rank_r >= k) ||
      (rank_l != kNoRank && rank_r != kNoRank && rank_l >= rank_r))
    return false;
  j = rank_l == kNoRank ? 0 : rank_l + 1;
  count = (rank_r == kNoRank ? k : rank_r) - j;
  return true;
}

bool wedge_symbols(const int32_t* coords, const uint32_t* degree, uint32_t v,
                   const ProgressiveMesh& pm, uint32_t rank_l, uint32_t rank_r, uint32_t& count,
                   uint32_t& rank, WedgeScratch& s) {
  uint32_t j;
  if (!wedge_index(pm, rank_l, rank_r, count, j)) return false;
  const uint32_t n = wedge_candidates(coords, degree, v, pm, count, s);
  rank = s.narrow ? rank_of(s.score64.data(), n, j) : rank_of(s.score.data(), n, j);
  return true;
}

bool wedge_scores(const int32_t* coords, const uint32_t* degree, uint32_t v,
                  const ProgressiveMesh& pm, uint32_t count, WedgeScratch& s) {
  if (pm.ring().size() < 2 || count > max_count(pm)) return false;
  wedge_candidates(coords, degree, v, pm, count, s);
  return true;
}

bool wedge_ranks(const int32_t* coords, const uint32_t* degree, uint32_t v,
                 const ProgressiveMesh& pm, uint32_t count, uint32_t rank, uint32_t& rank_l,
                 uint32_t& rank_r, WedgeScratch& s) {
  return wedge_scores(coords, degree, v, pm, count, s) &&
         wedge_pick(pm, count, rank, rank_l, rank_r, s);
}

bool wedge_pick(const ProgressiveMesh& pm, uint32_t count, uint32_t rank, uint32_t& rank_l,
                uint32_t& rank_r, WedgeScratch& s) {
  const uint32_t k = uint32_t(pm.ring().size()), n = s.n;
  if (rank >= n) return false;
  const uint32_t j = rank == 0  ? s.best
                     : s.narrow ? select(s.score64.data(), n, rank, s.order)
                                : select(s.score.data(), n, rank, s.order);
  wedge_ends(pm.ring_closed(), k, count, j, rank_l, rank_r);
  return true;
}

}  // namespace pmz
