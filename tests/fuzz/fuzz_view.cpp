// SPDX-License-Identifier: MIT
// Decoding for a view (Decoder::update_view, feed_node): a .pmz stream whose chunk CRCs are
// repaired (as fuzz_container does) is fed in order up to its node table, then node by node
// from the ranges the table states, or from wrong ones, while views come and go with small
// budgets; the rest may then arrive in order. The mesh must stay consistent throughout: faces
// of nodes not applied degenerate (0, 0, 0), every other face three distinct vertices in range.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "fuzz_common.hpp"
#include "pmz/format.hpp"
#include "pmz/node_table.hpp"

namespace {

void check_view_mesh(const pmz::Decoder& d) {
  const uint32_t nv = d.vertex_count(), nf = d.face_count();
  PMZ_FUZZ_CHECK(nf == 0 || d.indices() != nullptr);
  const uint32_t* parents = d.split_parents();
  for (uint32_t f = 0; f < nf; ++f) {
    const uint32_t* t = d.indices() + size_t(f) * 3;
    if (t[0] == 0 && t[1] == 0 && t[2] == 0) continue;  // (a node not applied)
    PMZ_FUZZ_CHECK(t[0] < nv && t[1] < nv && t[2] < nv);
    PMZ_FUZZ_CHECK(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
    for (int c = 0; c < 3; ++c)
      PMZ_FUZZ_CHECK(t[c] < d.info().base_vertices ? parents[t[c]] == UINT32_MAX
                                                   : parents[t[c]] < t[c]);
  }
  PMZ_FUZZ_CHECK(d.splits_applied() <= d.info().total_splits);
  PMZ_FUZZ_CHECK(d.nodes_applied() <= std::max<uint64_t>(d.info().nodes, 1));
  PMZ_FUZZ_CHECK((d.status() == pmz::Status::ok) == d.error_message().empty());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  const uint8_t how = data[0];  // bits: budget, view, wrong ranges, rest in order
  std::vector<uint8_t> b;
  if (size - 1 < 8 || std::memcmp(data + 1, pmz::kSignature, 8) != 0)
    b.assign(pmz::kSignature, pmz::kSignature + 8);
  b.insert(b.end(), data + 1, data + size);
  size_t table_end = b.size();
  for (size_t at = 8; at < b.size();) {
    pmz::ChunkFrame f;
    if (pmz::parse_chunk_frame(&b[at], b.size() - at, f) != pmz::FrameStatus::ok) break;
    if (f.payload_size > b.size() - at - f.header_size) break;
    pmz::repair_chunk_crc(&b[at], f);
    at += f.header_size + size_t(f.payload_size);
    if (f.type == pmz::kChunkNodes && table_end == b.size()) table_end = at;
  }

  pmz::DecoderLimits limits;
  limits.max_vertices = 1u << 20;
  limits.max_faces = 1u << 21;
  limits.max_chunk_bytes = 1u << 22;
  pmz::Decoder d(limits);
  d.feed(b.data(), table_end);
  const pmz::StreamInfo& info = d.info();
  // Views around the box: close to one corner at a few pixels, then everything at 0 pixels.
  float lo[3], hi[3], mid[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::isfinite(info.bbox_min[a]) ? info.bbox_min[a] : 0;
    hi[a] = std::isfinite(info.bbox_max[a]) ? info.bbox_max[a] : 1;
    mid[a] = (lo[a] + hi[a]) / 2;
  }
  const float far[3] = {mid[0], mid[1], mid[2] + 4 * (hi[2] - lo[2] + hi[0] - lo[0] + 1)};
  const float near[3] = {lo[0], lo[1], hi[2] + (hi[2] - lo[2]) / 4 + 0.01f};
  const pmz::View views[3] = {pmz::look_at(near, lo, 1.0f, 640, 480, 1e-4f, float(how >> 5)),
                              pmz::look_at(far, mid, 1.0f, 640, 480, 1e-4f, 0),
                              pmz::look_at(near, mid, 0.5f, 640, 480, 1e-4f, 0.5f)};
  const uint64_t budget = (how & 3) == 0 ? UINT64_MAX : uint64_t(1) << (4 * (how & 3));
  size_t fed = 0;
  for (const pmz::View& v : views)
    for (int round = 0; round < 6; ++round) {
      d.update_view(v, budget);
      check_view_mesh(d);
      const std::vector<uint32_t> fetch = d.nodes_to_fetch();
      for (size_t i = 0; i < fetch.size() && i < 16; ++i) {
        uint64_t offset = 0, bytes = 0;
        PMZ_FUZZ_CHECK(d.node_range(fetch[i], offset, bytes));
        if ((how & 4) && (i + round) % 3 == 0) offset += 1;  // a range answered with other bytes
        if (offset >= b.size()) continue;
        const size_t n = size_t(std::min<uint64_t>(bytes, b.size() - offset));
        d.feed_node(fetch[i], b.data() + offset, n);
        check_view_mesh(d);
        if (++fed > 200) break;
      }
    }
  if (how & 8) {  // the rest in order too
    d.feed(b.data() + table_end, b.size() - table_end);
    d.update_view(views[1]);
    check_view_mesh(d);
  }
  return 0;
}
