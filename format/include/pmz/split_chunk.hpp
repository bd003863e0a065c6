// SPDX-License-Identifier: MIT
// Coding of one SPLT chunk: groups of vertex splits into two range-coded streams with adaptive
// context models (spec/format.md sections 8 and 9): connectivity (groups, vertex choice, wedges)
// and geometry (position residuals). Writer and decoder share this code.
//
// Groups (sizes and near flags) are decoded when the chunk arrives. Which vertices split (the
// choice stream), wedge and residual symbols use contexts from the mesh the decoder already has
// (vertex degrees and the previous group's neighbourhood, v's ring, u's ring and the
// prediction), so they are decoded as the splits are first applied: a group's vertices when
// its first split is, the other symbols split by split.
//
// The symbols' contexts come from the vertex choice (vertex_choice.hpp), the fan wedges
// (fan_wedge.hpp) and the position prediction (geometry.hpp).
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "pmz/fan_wedge.hpp"
#include "pmz/format.hpp"
#include "pmz/geometry.hpp"
#include "pmz/range_coder.hpp"
#include "pmz/vertex_choice.hpp"

namespace pmz {

class ProgressiveMesh;

// One split's symbols and the contexts they are coded with (the writer computes the contexts
// by replaying the decoder's mesh).
struct SplitSymbols {
  uint32_t v;              // vertex that splits (coded by the group's choice bits)
  uint32_t wedge_context;  // wedge_context(k, closed) of v's ring
  uint32_t wedge_count, wedge_rank;
  uint32_t rank_context;         // rank_context(closed, confident)
  uint32_t residual_context[3];  // PositionPrediction::context, per slot
  int32_t residual[3];           // position residual per slot (two tangent axes, the normal axis)
  uint32_t mix_context[3];       // PositionPrediction::mix, per slot (the residuals' second models)
};

// Context models, created once per file and carried from SPLT chunk to chunk (a chunk needs
// the mesh of the chunks before it anyway). The groups models advance as chunks arrive, the
// others as splits are first applied: both in stream order.
struct SplitModels {
  UIntModel groups;
  Prob near = kProbInit;
  Prob choice[kChoiceContexts];  // initialised from the expected gap (choice_prior)
  SplitModels();
  SmallModel wedge_count[kWedgeContexts];
  Prob rank_zero[kRankContexts] = {kProbInit, kProbInit, kProbInit, kProbInit};  // rank > 0
  SmallModel wedge_rank[kRankContexts];  // rank - 1 when rank > 0
  UIntModel residual[3][kResidualContexts];
  // The second model of each residual bit (spec/format.md section 9.6): tangent slots by
  // PositionPrediction::mix (kMixTangentContexts), the normal slot likewise (kMixNormalContexts).
  UIntModel mix_tangent[2][kMixTangentContexts];
  UIntModel mix_normal[kMixNormalContexts];
  // The speed level (spec/format.md section 9.10): each residual with its residual model alone.
  bool speed = false;
  // A node after the first of a stream in nodes (spec/format.md section 15.4) starts its
  // split symbols from the models the first node left (`first`); its group table's models
  // (groups, near: decoded as its chunks arrive) are its own.
  void inherit(const SplitModels& first) {
    const UIntModel own_groups = groups;
    const Prob own_near = near;
    *this = first;
    groups = own_groups;
    near = own_near;
  }
  UIntModel& mix(int slot, uint32_t context) {
    return slot < 2 ? mix_tangent[slot][context] : mix_normal[context];
  }
};

// A group of the chunk: its size and whether its vertices are chosen among the previous
// group's neighbourhood (near) or among all vertices.
struct GroupCode {
  uint32_t size;
  bool near;
};

// The split symbol schedule (spec/format.md section 9.3), defined here once for the writer
// (encode_split_chunk), the decoder (Decoder::Impl::apply) and SplitChunkReader::group_symbols:
// a group's choice bits are read until its first scan_at_group_start() vertices are found, and
// after its split j (0-based) is first applied until scan_after_split(j) are (1-based counts,
// capped by the group's size).
inline constexpr uint32_t scan_at_group_start() { return kChoiceLag + 1; }
inline constexpr uint32_t scan_after_split(uint32_t j) { return j + 2 + kChoiceLag; }

// A group that a chunk's end cuts (spec/format.md section 8): it continues in the next chunk.
// size: the group's split count (0: no group is cut); done: its splits in the chunks before the
// next; found (writer): its vertices whose choice bits the chunks before hold.
struct OpenGroup {
  uint32_t size = 0, done = 0, found = 0;
};

// Appends the SPLT payload for the given groups (sizes sum to count) and choice bits (the
// concatenation of choice_bits() of the groups), every symbol in the order the decoder reads it;
// models: the file's models (updated). stream_bytes[k] receives the coded size of stream k
// (optional); symbol_bits[kind] (optional, SymbolKind) has the code length of the chunk's
// symbols of each kind added (RangeEncoder::position differences; the writer's accounting,
// pmz-encode --symbol-stats). open (optional): in, the group the chunk before cut (its splits
// first, its remaining choice bits first in `choice`); out, the group this chunk cuts (the
// last of `groups` when count ends inside it). choice_used (optional): the choice bits coded
// (the rest belong to the group cut).
void encode_split_chunk(const std::vector<GroupCode>& groups, const std::vector<uint32_t>& choice,
                        const SplitSymbols* splits, size_t count, SplitModels& models,
                        std::vector<uint8_t>& payload, uint64_t* stream_bytes = nullptr,
                        double* symbol_bits = nullptr, OpenGroup* open = nullptr,
                        size_t* choice_used = nullptr);

// Decoder side of one SPLT chunk. open() copies the payload, decodes the groups (sizes summing
// to the split count, at most max_splits) and validates them. models (the file's, see
// SplitModels) must outlive the reader. Then, in stream order and in the decoder's schedule
// (spec/format.md section 9.3: the choice, wedge_count and wedge_rank calls read one stream):
// begin_group() and find() the vertices of each group, wedge_count(), wedge_rank() and residuals()
// the symbols of each split, with the contexts the caller computes from its mesh; false when a
// stream is malformed or exhausted, or a group's candidates run out.
class SplitChunkReader {
 public:
  // Once per chunk: cold (optimized for size; the decoder library has a size budget).
  // carried: the group the chunk before cut (its open_group()); max_splits also bounds the
  // splits of a group this chunk cuts.
  [[gnu::cold]] bool open(const uint8_t* p, size_t size, uint64_t max_splits, SplitModels& models,
                          std::string& error, const OpenGroup& carried = {});
  // The group this chunk cuts (size 0: none), for the next chunk's open().
  OpenGroup open_group() const;
  // Whether the chunk's first splits continue a group the chunk before cut (its scan goes on,
  // from this chunk's stream once the chunk before is done: no begin_group() for it).
  bool continues() const { return carried_; }
  // The vertex choice, group by group. group_end(): the chunk's splits up to the end of the
  // group begun last (0 before the first). begin_group() starts the next group (after every
  // split of the one before was applied; choice.start_group() is called), limit the vertex
  // count; false if there is none. find() then continues the group's scan (VertexChoice::scan, mesh
  // as there) until `upto` of its vertices are found, appending the new ones to vs; false if the
  // choice stream is malformed or exhausted, or the candidates ran out.
  uint64_t group_end() const { return group_end_; }
  bool begin_group(VertexChoice& choice, uint32_t limit);
  bool find(VertexChoice& choice, const ProgressiveMesh* mesh, uint32_t upto,
            std::vector<uint32_t>& vs);
  // Tests, fuzzing: the next group with every symbol in the decoder's schedule (its vertices
  // kChoiceLag + 1 ahead of the split being read, exclusion from the rings in mesh, the mesh at
  // the group's start); contexts(s) sets the contexts in s (s.v known) before its symbols are
  // read. Appends the group's splits to out; false where a decoder would refuse (the splits
  // before that point appended). found (optional) receives the group's vertices found.
  template <class F>
  bool group_symbols(VertexChoice& choice, const ProgressiveMesh& mesh,
                     std::vector<SplitSymbols>& out, F&& contexts,
                     std::vector<uint32_t>* found = nullptr);
  // The wedge symbols, each when its context is known: count (wedge_context of v's ring), then
  // rank (rank_context, from the scores).
  bool wedge_count(uint32_t context, uint32_t& count);
  bool wedge_rank(uint32_t context, uint32_t& rank);
  // context, mix: PositionPrediction's per slot.
  bool residuals(const uint32_t context[3], const uint32_t mix[3], int32_t residual[3]);
  // The speed level's: one model per residual (SplitModels::speed).
  bool speed_residuals(const uint32_t context[3], int32_t residual[3]);
  uint64_t split_count() const { return count_; }
  size_t largest_group() const { return largest_; }
  // The models the symbols after the groups are decoded with from now on (a node's, made as its
  // first application starts: its groups were decoded with another object's group models).
  void set_models(SplitModels& models) { models_ = &models; }

 private:
  SplitModels* models_ = nullptr;
  std::vector<GroupCode> groups_;
  size_t next_group_ = 0, largest_ = 0;
  uint64_t group_end_ = 0;
  uint32_t group_size_ = 0;  // of the group begun last (or continued)
  bool carried_ = false;
  uint64_t carry_ = 0;               // the carried group's splits in this chunk and after
  uint32_t group_size_carried_ = 0;  // its size
  static uint32_t vertex_count(
      const ProgressiveMesh& mesh);                   // (ProgressiveMesh is incomplete here)
  std::unique_ptr<RangeDecoder> conn_dec_, geo_dec_;  // connectivity and geometry streams
  uint64_t count_ = 0;
};

template <class F>
bool SplitChunkReader::group_symbols(VertexChoice& choice, const ProgressiveMesh& mesh,
                                     std::vector<SplitSymbols>& out, F&& contexts,
                                     std::vector<uint32_t>* found) {
  if (!begin_group(choice, vertex_count(mesh))) return false;
  const uint32_t size = group_size_;
  std::vector<uint32_t> local;
  std::vector<uint32_t>& vs = found ? *found : local;
  vs.clear();
  bool more = find(choice, &mesh, scan_at_group_start(), vs);
  for (uint32_t j = 0; j < size; ++j) {
    if (j >= vs.size()) return false;
    SplitSymbols s{vs[j], 0, 0, 0, 0, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    contexts(s);
    if (!wedge_count(s.wedge_context, s.wedge_count) || !wedge_rank(s.rank_context, s.wedge_rank))
      return false;
    if (more) more = find(choice, &mesh, scan_after_split(j), vs);
    if (!(models_->speed ? speed_residuals(s.residual_context, s.residual)
                         : residuals(s.residual_context, s.mix_context, s.residual)))
      return false;
    out.push_back(s);
  }
  return more;
}

// Coded stream sizes of a SPLT payload without decoding it (for pmz-info).
bool split_chunk_stream_sizes(const uint8_t* p, size_t size, uint64_t& count,
                              uint64_t stream_bytes[kSplitStreamCount]);

}  // namespace pmz
