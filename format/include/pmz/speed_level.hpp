// SPDX-License-Identifier: MIT
// The speed level's models (HEAD level 1, spec/format.md section 9.10): what the default level
// computes from the mesh for its contexts and prediction, replaced by cheaper models. The wedge
// rank is the candidate's index (no scores), the position is the centroid prediction on the
// coordinate axes with contexts from u's ring extent (no normal, curvature or plane step), each
// residual is one adaptive uint (no second model), and the vertex choice contexts have no
// umbrella class (VertexChoice without umbrella sums). Writer and decoder share this code.
#pragma once
#include <cstdint>
#include <span>

#include "pmz/geometry.hpp"

namespace pmz {

class ProgressiveMesh;

// HEAD level values (spec/format.md section 4).
inline constexpr uint32_t kLevelDefault = 0, kLevelSpeed = 1, kMaxLevel = 1;

// (The writer codes the candidate index of fan_wedge.hpp's wedge_index().)
// Decoder: the wedge of candidate `rank` with `count` interior vertices in the ring gathered
// last; false if count or rank is out of range for the ring.
bool speed_wedge_pick(const ProgressiveMesh& pm, uint32_t count, uint32_t rank, uint32_t& rank_l,
                      uint32_t& rank_r);
// The prediction of u (u_ring: v, then u's other neighbours): p the centroid with v counted
// twice, axes 0, 1, 2 in that order, n = 0 (so the normal axis has no plane step), context[a]
// from the extent of u's ring on axis a, mix unused (0).
void speed_predict_position(const int32_t* coords, std::span<const uint32_t> u_ring,
                            PositionPrediction& out);

}  // namespace pmz
