#include "pmz/split_codec.hpp"

#include <algorithm>
#include <memory>

#include "pmz/coding.hpp"
#include "pmz/format.hpp"
#include "pmz/range_coder.hpp"

namespace pmz {

namespace {

constexpr uint32_t kGapContexts = 16, kWedgeContexts = 4, kResidualContexts = 21;

// Context models, reset for every chunk so each chunk decodes on its own.
struct SplitModels {
  UIntModel groups;
  UIntModel gaps[kGapContexts];
  UIntModel wedge_l;
  UIntModel wedge_r[kWedgeContexts];
  UIntModel residual[3][kResidualContexts];
};

// Residual contexts: the magnitude of the previous split's residuals and of this split's
// axes already coded (residual size follows the local edge length).
inline uint32_t residual_context(int axis, const uint32_t prev[3], const uint32_t cur[3]) {
  uint64_t m = axis == 0   ? (uint64_t(prev[0]) + prev[1] + prev[2]) / 3
               : axis == 1 ? (uint64_t(cur[0]) * 2 + prev[1]) / 3
                           : (uint64_t(cur[0]) + cur[1]) / 2;
  return std::min<uint32_t>(bit_length(uint32_t(std::min<uint64_t>(m, 0xFFFFFFFFu))), kResidualContexts - 1);
}

}  // namespace

void encode_split_chunk(const std::vector<uint32_t>& group_sizes, const SplitCode* splits, size_t count,
                        std::vector<uint8_t>& payload, uint64_t* stream_bytes) {
  auto m = std::make_unique<SplitModels>();
  std::vector<uint8_t> bytes[kSplitStreamCount];
  {
    RangeEncoder groups(bytes[kStreamGroups]), gaps(bytes[kStreamGaps]), wl(bytes[kStreamWedgeL]),
        wr(bytes[kStreamWedgeR]), rx(bytes[kStreamResidualX]), ry(bytes[kStreamResidualY]),
        rz(bytes[kStreamResidualZ]);
    RangeEncoder* res[3] = {&rx, &ry, &rz};
    uint32_t prev_gap = 0, prev[3] = {0, 0, 0};
    size_t at = 0;
    for (uint32_t g : group_sizes) {
      encode_uint(groups, m->groups, g - 1);
      for (uint32_t i = 0; i < g; ++i, ++at) {
        const SplitCode& s = splits[at];
        uint32_t gap = i == 0 ? s.v : s.v - splits[at - 1].v - 1;
        encode_uint(gaps, m->gaps[std::min(bit_length(prev_gap), kGapContexts - 1)], gap);
        prev_gap = gap;
        encode_uint(wl, m->wedge_l, s.code_l);
        encode_uint(wr, m->wedge_r[std::min(s.code_l, kWedgeContexts - 1)], s.code_r);
        uint32_t cur[3] = {0, 0, 0};
        for (int a = 0; a < 3; ++a) {
          cur[a] = zigzag_encode(s.residual[a]);
          encode_uint(*res[a], m->residual[a][residual_context(a, prev, cur)], cur[a]);
        }
        std::copy(cur, cur + 3, prev);
      }
    }
    for (RangeEncoder* e : {&groups, &gaps, &wl, &wr, &rx, &ry, &rz}) e->finish();
  }
  put_varint(payload, count);
  put_varint(payload, group_sizes.size());
  for (int k = 0; k < kSplitStreamCount; ++k) {
    put_varint(payload, bytes[k].size());
    payload.insert(payload.end(), bytes[k].begin(), bytes[k].end());
    if (stream_bytes) stream_bytes[k] = bytes[k].size();
  }
}

bool split_chunk_stream_sizes(const uint8_t* p, size_t size, uint64_t& count, uint64_t stream_bytes[7]) {
  ByteReader r(p, size);
  count = r.varint();
  r.varint();
  for (int k = 0; k < kSplitStreamCount; ++k) {
    stream_bytes[k] = r.varint();
    r.bytes(stream_bytes[k]);
  }
  return r.ok;
}

bool decode_split_chunk(const uint8_t* p, size_t size, uint64_t vertices_before, uint64_t max_splits,
                        std::vector<SplitCode>& out, std::string& error) {
  ByteReader r(p, size);
  const uint64_t count = r.varint(), group_count = r.varint();
  if (!r.ok || count == 0 || count > max_splits || group_count == 0 || group_count > count)
    return error = "SPLT counts", false;
  const uint8_t* start[kSplitStreamCount];
  size_t len[kSplitStreamCount];
  for (int k = 0; k < kSplitStreamCount; ++k) {
    len[k] = r.varint();
    start[k] = r.bytes(len[k]);
  }
  if (!r.ok) return error = "SPLT streams overrun the chunk", false;
  // A coded split costs well over a bit in total; bound the allocation by the input.
  if (count > uint64_t(size) * 64) return error = "SPLT split count beyond its bytes", false;
  auto m = std::make_unique<SplitModels>();
  RangeDecoder groups(start[0], len[0]), gaps(start[1], len[1]), wl(start[2], len[2]), wr(start[3], len[3]),
      rx(start[4], len[4]), ry(start[5], len[5]), rz(start[6], len[6]);
  RangeDecoder* res[3] = {&rx, &ry, &rz};
  const size_t first = out.size();
  out.resize(first + count);
  uint32_t prev_gap = 0, prev[3] = {0, 0, 0};
  uint64_t done = 0;
  bool ok = true;
  for (uint64_t gi = 0; ok && gi < group_count; ++gi) {
    uint32_t g;
    ok = decode_uint(groups, m->groups, g) && uint64_t(g) + 1 <= count - done;
    if (!ok) break;
    ++g;
    const uint64_t limit = vertices_before + done;
    uint64_t v = 0;
    for (uint32_t i = 0; ok && i < g; ++i) {
      SplitCode& s = out[first + done + i];
      uint32_t gap = 0, cur[3] = {0, 0, 0};
      ok = decode_uint(gaps, m->gaps[std::min(bit_length(prev_gap), kGapContexts - 1)], gap) &&
           decode_uint(wl, m->wedge_l, s.code_l) &&
           decode_uint(wr, m->wedge_r[std::min(s.code_l, kWedgeContexts - 1)], s.code_r);
      prev_gap = gap;
      v = i == 0 ? gap : v + gap + 1;
      ok = ok && v < limit;
      s.v = uint32_t(v);
      for (int a = 0; ok && a < 3; ++a) {
        ok = decode_uint(*res[a], m->residual[a][residual_context(a, prev, cur)], cur[a]);
        s.residual[a] = zigzag_decode(cur[a]);
      }
      std::copy(cur, cur + 3, prev);
    }
    done += g;
  }
  ok = ok && done == count;
  for (RangeDecoder* d : {&groups, &gaps, &wl, &wr, &rx, &ry, &rz}) ok = ok && d->ok;
  if (!ok) {
    out.resize(first);
    return error = "SPLT streams malformed", false;
  }
  return true;
}

}  // namespace pmz
