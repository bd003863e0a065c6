// SPDX-License-Identifier: MIT
#include "pmz/speed_level.hpp"

#include "pmz/fan_wedge.hpp"
#include "pmz/progressive_mesh.hpp"
#include "pmz/range_coder.hpp"

namespace pmz {

bool speed_wedge_pick(const ProgressiveMesh& pm, uint32_t count, uint32_t rank, uint32_t& rank_l,
                      uint32_t& rank_r) {
  const uint32_t k = uint32_t(pm.ring().size());
  if (k < 2) return false;
  if (pm.ring_closed() ? count > k - 2 || rank >= k          // k candidates
                       : count > k - 1 || rank > k - count)  // k - count + 1 candidates
    return false;
  wedge_ends(pm.ring_closed(), k, count, rank, rank_l, rank_r);
  return true;
}

void speed_predict_position(const int32_t* coords, std::span<const uint32_t> u_ring,
                            PositionPrediction& out) {
  const uint32_t m = uint32_t(u_ring.size());
  const int32_t* cv = coords + size_t(u_ring[0]) * 3;
  int64_t sum[3], lo[3], hi[3];
  for (int a = 0; a < 3; ++a) sum[a] = 2 * int64_t(cv[a]), lo[a] = hi[a] = cv[a];
  for (uint32_t i = 1; i < m; ++i) {
    const int32_t* cw = coords + size_t(u_ring[i]) * 3;
    for (int a = 0; a < 3; ++a) {
      sum[a] += cw[a];
      lo[a] = cw[a] < lo[a] ? cw[a] : lo[a];
      hi[a] = cw[a] > hi[a] ? cw[a] : hi[a];
    }
  }
  for (int a = 0; a < 3; ++a) {
    out.p[a] = floor_mean(sum[a], int64_t(m) + 1);
    out.n[a] = 0;
    out.axis[a] = uint8_t(a);
    // ctx(floor(extent / 4)): the extent is below 2^32.
    const uint32_t b = bit_length(uint32_t(uint64_t(hi[a] - lo[a]) >> 2));
    out.context[a] = b < kResidualContexts - 1 ? b : kResidualContexts - 1;
    out.mix[a] = 0;
  }
}

}  // namespace pmz
