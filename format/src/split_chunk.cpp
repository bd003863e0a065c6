// SPDX-License-Identifier: MIT
#include "pmz/split_chunk.hpp"

#include <algorithm>

#include "pmz/coding.hpp"
#include "pmz/format.hpp"
#include "pmz/progressive_mesh.hpp"

namespace pmz {

void encode_split_chunk(const std::vector<GroupCode>& groups, const std::vector<uint32_t>& choice,
                        const SplitSymbols* splits, size_t count, SplitModels& models,
                        std::vector<uint8_t>& payload, uint64_t* stream_bytes, double* symbol_bits,
                        OpenGroup* open, size_t* choice_used) {
  SplitModels* m = &models;
  std::vector<uint8_t> conn, geom;
  {
    RangeEncoder cn(conn), ge(geom);
    // Accounting (symbol_bits): at each change of kind, what the stream took since the last.
    struct Account {
      const RangeEncoder& e;
      double* bits;
      int kind = -1;
      double at = 0;
      void to(int next) {
        if (!bits) return;
        const double now = e.position();
        if (kind >= 0) bits[kind] += now - at;
        at = now;
        kind = next;
      }
    } ca{cn, symbol_bits}, ga{ge, symbol_bits};
    ca.to(kSymbolGroups);
    for (const GroupCode& g : groups) {
      encode_uint(cn, m->groups, g.size - 1);
      cn.bit(m->near, g.near ? 1 : 0);
    }
    // Then each group in the decoder's order of reads (the schedule, spec/format.md section 9.3):
    // its choice bits up to its scan_at_group_start()-th vertex, then per split j the wedge symbols
    // and the choice bits up to the group's scan_after_split(j)-th vertex (those the decoder
    // finds once split j is applied); the residuals in their own stream. A group the chunk's end
    // cuts continues in the next chunk with its next split (its choice bits run ahead in this
    // chunk's stream as they would in one chunk).
    struct Part {
      uint32_t size, done, found;
    };
    std::vector<Part> parts;
    if (open && open->size) parts.push_back({open->size, open->done, open->found});
    for (const GroupCode& g : groups) parts.push_back({g.size, 0, 0});
    if (open) *open = {};
    size_t bit = 0, at = 0;
    for (const Part& g : parts) {
      uint32_t found = g.found;
      const uint32_t cap = uint32_t(std::min<uint64_t>(g.size, g.done + (count - at)));
      auto choose = [&](uint32_t upto) {
        ca.to(kSymbolChoice);
        for (upto = std::min(upto, g.size); found < upto && bit < choice.size(); ++bit) {
          cn.bit(m->choice[choice[bit] >> 1], choice[bit] & 1);
          found += choice[bit] & 1;
        }
      };
      if (!g.done) choose(scan_at_group_start());
      for (uint32_t j = g.done; j < cap && at < count; ++j) {
        const SplitSymbols& s = splits[at++];
        ca.to(kSymbolWedgeCount);
        encode_small(cn, m->wedge_count[s.wedge_context], s.wedge_count);
        ca.to(kSymbolWedgeRank);
        cn.bit(m->rank_zero[s.rank_context], s.wedge_rank > 0 ? 1 : 0);
        if (s.wedge_rank > 0) encode_small(cn, m->wedge_rank[s.rank_context], s.wedge_rank - 1);
        choose(scan_after_split(j));
        for (int a = 0; a < 3; ++a) {
          ga.to(kSymbolResidualT0 + a);
          if (m->speed)
            encode_uint(ge, m->residual[a][s.residual_context[a]], zigzag_encode(s.residual[a]));
          else
            encode_uint_mixed(ge, m->residual[a][s.residual_context[a]],
                              m->mix(a, s.mix_context[a]), zigzag_encode(s.residual[a]));
        }
      }
      if (cap < g.size && open) *open = {g.size, cap, found};
    }
    ca.to(-1);
    ga.to(-1);
    cn.finish();
    ge.finish();
    if (choice_used) *choice_used = bit;
  }
  put_varint(payload, count);
  put_varint(payload, conn.size());
  payload.insert(payload.end(), conn.begin(), conn.end());
  payload.insert(payload.end(), geom.begin(), geom.end());
  if (stream_bytes) {
    stream_bytes[kStreamConnectivity] = conn.size();
    stream_bytes[kStreamGeometry] = geom.size();
  }
}

bool split_chunk_stream_sizes(const uint8_t* p, size_t size, uint64_t& count,
                              uint64_t stream_bytes[kSplitStreamCount]) {
  ByteReader r(p, size);
  count = r.varint();
  stream_bytes[kStreamConnectivity] = r.varint();
  r.bytes(stream_bytes[kStreamConnectivity]);
  stream_bytes[kStreamGeometry] = r.remaining();
  return r.ok;
}

PMZ_SMALL_IN_WASM bool SplitChunkReader::open(const uint8_t* p, size_t size, uint64_t max_splits,
                                              SplitModels& models, std::string& error,
                                              const OpenGroup& carried) {
  ByteReader r(p, size);
  const uint64_t count = r.varint();
  if (!r.ok || count == 0 || count > max_splits) return error = "SPLT counts", false;
  const uint64_t conn_size = r.varint();
  const uint8_t* conn = r.bytes(conn_size);
  if (!r.ok) return error = "SPLT streams overrun the chunk", false;
  // A coded split costs well over a bit in total; bound the allocation by the input.
  if (count > uint64_t(size) * 64) return error = "SPLT split count beyond its bytes", false;
  models_ = &models;
  SplitModels& m = models;
  // The groups open the connectivity stream: decoded now; its decoder then stays for the
  // vertex choice and wedge symbols, decoded as the splits are applied (each decoder keeps a
  // copy of its bytes).
  conn_dec_ = std::make_unique<RangeDecoder>(conn, size_t(conn_size));
  RangeDecoder& gr = *conn_dec_;
  // Twice: first only counting them (from copies of the models and the decoder state), so their
  // list is allocated once, exactly (no count of groups is stored; growing the list would cost
  // up to twice its size).
  const UIntModel size_model = m.groups;
  const Prob near_model = m.near;
  const RangeState start = gr.state();
  // A group the chunk before cut: its remaining splits come first.
  const uint64_t carry = carried.size ? carried.size - carried.done : 0;
  if (carry > max_splits) return error = "SPLT counts", false;
  carried_ = carry > 0;
  carry_ = carry;
  group_size_carried_ = carried.size;
  group_end_ = carry;
  group_size_ = carried.size;
  uint64_t groups = 0, done = std::min(carry, count);
  bool ok = true;
  for (int pass = 0; pass < 2 && ok; ++pass) {
    if (pass == 1) {
      m.groups = size_model;
      m.near = near_model;
      gr.set_state(start);
      groups_.clear();
      groups_.reserve(groups);
      groups = 0;
      done = std::min(carry, count);
    }
    // Each group adds at least one split: at most count groups. The last may pass the chunk's
    // end (it continues in the next chunk), not max_splits.
    while (ok && done < count) {
      uint32_t g;
      ok = decode_uint(gr, m.groups, g) && uint64_t(g) + 1 <= max_splits - done;
      if (!ok) break;
      RangeState st = gr.state();
      const bool near = st.bit(m.near) != 0;
      gr.set_state(st);
      if (pass == 1) groups_.push_back({g + 1, near});
      largest_ = std::max<size_t>(largest_, g + 1);
      done += g + 1;
      ++groups;
    }
    ok = ok && gr.ok;
  }
  if (!ok) return error = "SPLT groups malformed", false;
  geo_dec_ = std::make_unique<RangeDecoder>(r.p, r.remaining());
  count_ = count;
  return true;
}

namespace {
// One symbol per call: inlined into the three-axis loop, GCC recomputes each bit's model
// address from the axis and context (register pressure); here the model is one pointer.
[[gnu::noinline]] bool decode_symbol(RangeDecoder& rc, UIntModel& m, UIntModel& m2, uint32_t& x) {
  return decode_uint_mixed(rc, m, m2, x);
}
// The speed level's residual (one model).
[[gnu::noinline]] bool decode_symbol(RangeDecoder& rc, UIntModel& m, uint32_t& x) {
  return decode_uint(rc, m, x);
}
[[gnu::noinline]] bool decode_small(RangeDecoder& rc, SmallModel& m, uint32_t& x) {
  RangeState st = rc.state();
  const bool ok = decode_small(st, m, x);
  rc.set_state(st);
  return ok && rc.ok;
}
}  // namespace

PMZ_SMALL_IN_WASM SplitModels::SplitModels() {
  for (uint32_t c = 0; c < kChoiceContexts; ++c) {
    const uint32_t d = c / (2 * kChoiceKeys);
    choice[c] = d == 0 ? kProbInit : primed_model(choice_prior(d));
  }
}

uint32_t SplitChunkReader::vertex_count(const ProgressiveMesh& mesh) { return mesh.vertex_count(); }

bool SplitChunkReader::begin_group(VertexChoice& choice, uint32_t limit) {
  if (next_group_ >= groups_.size()) return false;
  const GroupCode g = groups_[next_group_++];
  choice.start_group(g.near);
  choice.begin_scan(g.near, limit, g.size);
  group_end_ += g.size;
  group_size_ = g.size;
  return true;
}

OpenGroup SplitChunkReader::open_group() const {
  uint64_t end = carry_;
  uint32_t size = group_size_carried_;
  for (const GroupCode& g : groups_) {
    end += g.size;
    size = g.size;
  }
  if (end <= count_) return {};
  return {size, uint32_t(size - (end - count_)), 0};
}

bool SplitChunkReader::find(VertexChoice& choice, const ProgressiveMesh* mesh, uint32_t upto,
                            std::vector<uint32_t>& vs) {
  RangeState st = conn_dec_->state();
  Prob* m = models_->choice;
  const int r = choice.scan(mesh, upto, [&](uint32_t w, uint32_t ctx) {
    const uint32_t b = st.bit(m[ctx]);
    if (!st.ok) return -1;  // past the end: a valid stream never gets here
    if (b) vs.push_back(w);
    return int(b);
  });
  conn_dec_->set_state(st);
  return r == 1 && conn_dec_->ok;
}

bool SplitChunkReader::wedge_count(uint32_t context, uint32_t& count) {
  return decode_small(*conn_dec_, models_->wedge_count[context], count);
}

bool SplitChunkReader::wedge_rank(uint32_t context, uint32_t& rank) {
  RangeState st = conn_dec_->state();
  const uint32_t nonzero = st.bit(models_->rank_zero[context]);
  conn_dec_->set_state(st);
  if (!conn_dec_->ok) return false;
  if (!nonzero) return rank = 0, true;
  uint32_t rest;
  if (!decode_small(*conn_dec_, models_->wedge_rank[context], rest) || rest == 0xFFFFFFFFu)
    return false;
  rank = rest + 1;
  return true;
}

bool SplitChunkReader::residuals(const uint32_t context[3], const uint32_t mix[3],
                                 int32_t residual[3]) {
  for (int a = 0; a < 3; ++a) {
    uint32_t z;
    if (!decode_symbol(*geo_dec_, models_->residual[a][context[a]], models_->mix(a, mix[a]), z) ||
        !geo_dec_->ok)
      return false;
    residual[a] = zigzag_decode(z);
  }
  return true;
}

bool SplitChunkReader::speed_residuals(const uint32_t context[3], int32_t residual[3]) {
  for (int a = 0; a < 3; ++a) {
    uint32_t z;
    if (!decode_symbol(*geo_dec_, models_->residual[a][context[a]], z) || !geo_dec_->ok)
      return false;
    residual[a] = zigzag_decode(z);
  }
  return true;
}

}  // namespace pmz
