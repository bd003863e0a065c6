// SPDX-License-Identifier: MIT
// Fan wedges (spec/format.md sections 9.4 and 9.5): where a split's two new faces go in v's
// ring, coded as the wedge's interior vertex count and its rank among the candidates of that
// count, ordered by a geometric score. The chunk codec (split_chunk.hpp) codes the two symbols
// with the contexts defined here.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "pmz/progressive_mesh.hpp"

namespace pmz {

// Context counts of the wedge_count and wedge_rank models (wedge_context, rank_context).
inline constexpr uint32_t kWedgeContexts = 18, kRankContexts = 4;

__extension__ typedef unsigned __int128 WedgeScore;  // exact squared lengths (GCC/Clang)
__extension__ typedef __int128 WedgeScoreSigned;

// Reusable buffers for the wedge scores (no allocation per split once grown).
struct WedgeScratch {
  std::vector<uint8_t> w;  // end weights m, 12 / m per ring position (extended canonical order)
  std::vector<int64_t> q;  // e (3 axes) and |e|^2 per ring position, when narrow
  std::vector<WedgeScoreSigned> q128;   // the same otherwise
  std::vector<int64_t> score64;         // per candidate, when narrow (the same values, in 64 bits)
  std::vector<WedgeScoreSigned> score;  // per candidate, otherwise
  std::vector<uint32_t> order;
  bool narrow = true;
  uint32_t n = 0;         // candidates scored last
  bool confident = true;  // their best score is over twice the second (spec/format.md section 9.4)
  uint32_t best = 0;      // the candidate at rank 0
  // Optional, set by the caller: a bound on |c[w] - c[v]| (per axis) over all vertex pairs, e.g.
  // the largest side of the coordinates' bounding box. When k (extent + 1) < 2^26 the scores
  // are computed in 64 bits without checking each ring offset. Unknown: UINT64_MAX.
  uint64_t extent = UINT64_MAX;
  // Set by the scoring: the sum of c[w] - c[v] over v's ring (per axis), which the position
  // prediction needs too (its curvature offset L is minus this sum); valid when ring_offsets_ok
  // (rings too large to score leave it unset).
  int64_t ring_offsets[3] = {0, 0, 0};
  bool ring_offsets_ok = false;
  // Room for a ring of k vertices (any count), so scoring it does not allocate.
  void reserve(size_t k) {
    const size_t len = 2 * k + 2;
    w.reserve(len * 2);
    q.reserve((len + 1) * 4);
    q128.reserve((len + 1) * 4);
    score64.reserve(k + 1);
    score.reserve(k + 1);
    order.reserve(k + 1);
  }
};

// wedge_count context: ring size (clamped to 8) and whether the fan is closed.
inline uint32_t wedge_context(uint32_t k, bool closed) {
  return 2 * (k < 8 ? k : 8) + (closed ? 1 : 0);
}
// wedge_rank context: whether the fan is closed, and whether the best candidate's score is over
// twice the second's (WedgeScratch::confident).
inline uint32_t rank_context(bool closed, bool confident) {
  return (closed ? 2u : 0u) + (confident ? 1u : 0u);
}

// The ends (canonical ranks, kNoRank for a missing one) of candidate j with `count` interior
// vertices in a ring of k (spec/format.md section 9.4 step 2); the inverse of wedge_index().
inline void wedge_ends(bool closed, uint32_t k, uint32_t count, uint32_t j, uint32_t& rank_l,
                       uint32_t& rank_r) {
  if (closed) {
    rank_l = j;
    rank_r = (j + count + 1) % k;
  } else {
    rank_l = j == 0 ? kNoRank : j - 1;
    rank_r = j + count == k ? kNoRank : j + count;
  }
}

// Writer: the wedge (canonical ranks, kNoRank for a boundary side) of the ring gathered last in
// pm as its interior count and candidate index j (spec/format.md section 9.4 step 2); false if
// the ranks are not a valid wedge.
bool wedge_index(const ProgressiveMesh& pm, uint32_t rank_l, uint32_t rank_r, uint32_t& count,
                 uint32_t& j);
// degree: VertexChoice::degrees() (the end weights of the score).
// Writer: the wedge (canonical ranks, kNoRank for a boundary side) of the ring gathered last in
// pm as symbols (interior count, rank among the candidates of that count); s.confident then
// gives the rank's context. False if the ranks are not a valid wedge.
bool wedge_symbols(const int32_t* coords, const uint32_t* degree, uint32_t v,
                   const ProgressiveMesh& pm, uint32_t rank_l, uint32_t rank_r, uint32_t& count,
                   uint32_t& rank, WedgeScratch& s);
// Decoder, in two steps around the rank's decoding: the scores of the candidates with `count`
// interior vertices (s.n of them; s.confident: the rank's context); false if count is out of
// range for the ring. Then the ranks of the candidate at position `rank`; false if rank >= s.n.
bool wedge_scores(const int32_t* coords, const uint32_t* degree, uint32_t v,
                  const ProgressiveMesh& pm, uint32_t count, WedgeScratch& s);
bool wedge_pick(const ProgressiveMesh& pm, uint32_t count, uint32_t rank, uint32_t& rank_l,
                uint32_t& rank_r, WedgeScratch& s);
// Both steps.
bool wedge_ranks(const int32_t* coords, const uint32_t* degree, uint32_t v,
                 const ProgressiveMesh& pm, uint32_t count, uint32_t rank, uint32_t& rank_l,
                 uint32_t& rank_r, WedgeScratch& s);

}  // namespace pmz
