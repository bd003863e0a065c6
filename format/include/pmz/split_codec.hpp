// Coding of one SPLT chunk: groups of vertex splits into seven range-coded streams with
// adaptive context models (spec/format.md, "SPLT"). Writer and decoder share this code.
//
// Groups and gaps (which vertices split) are decoded when the chunk arrives. Wedge and residual
// symbols use contexts from the mesh the decoder already has (v's ring, u's ring and the
// prediction), so they are decoded split by split as each split is first applied.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "pmz/geometry.hpp"
#include "pmz/range_coder.hpp"

namespace pmz {

class ProgressiveMesh;

inline constexpr uint32_t kGapContexts = 33, kWedgeContexts = 18;

// One split's symbols and the contexts they are coded with (the writer computes the contexts
// by replaying the decoder's mesh).
struct SplitSymbols {
  uint32_t v;                    // vertex that splits
  uint32_t wedge_context;        // wedge_context(k, closed) of v's ring
  uint32_t wedge_count, wedge_rank;
  uint32_t rank_context;         // 1 closed, 0 open
  uint32_t residual_context[3];  // PositionPrediction::context, per slot
  int32_t residual[3];           // position residual per slot (two tangent axes, the normal axis)
};

// Context models, created once per file and carried from SPLT chunk to chunk (a chunk needs
// the mesh of the chunks before it anyway). Groups and gaps models advance as chunks arrive,
// the others as splits are first applied: both in stream order.
struct SplitModels {
  UIntModel groups;
  UIntModel gaps[kGapContexts];
  UIntModel wedge_count[kWedgeContexts];
  UIntModel wedge_rank[2];
  UIntModel residual[3][kResidualContexts];
};

// Appends the SPLT payload for the given groups (sizes sum to count); vertices_before: the
// vertex count before the chunk; models: the file's models (updated). stream_bytes[k] receives
// the coded size of stream k (optional).
void encode_split_chunk(const std::vector<uint32_t>& group_sizes, const SplitSymbols* splits, size_t count,
                        uint64_t vertices_before, SplitModels& models, std::vector<uint8_t>& payload,
                        uint64_t* stream_bytes = nullptr);

// Decoder side of one SPLT chunk. open() copies the payload, decodes groups and gaps (every v
// must be below the vertex count at the start of its group: vertices_before + splits of
// earlier groups; at most max_splits) and validates them before appending anything to vs.
// models (the file's, see SplitModels) must outlive the reader.
// Then wedge() and residuals() return the symbols of the splits in order, with the contexts
// the caller computes from its mesh; false when a stream is malformed or exhausted.
class SplitChunkReader {
 public:
  bool open(const uint8_t* p, size_t size, uint64_t vertices_before, uint64_t max_splits, SplitModels& models,
            std::vector<uint32_t>& vs, std::string& error);
  bool wedge(uint32_t k, bool closed, uint32_t& count, uint32_t& rank);
  bool residuals(const uint32_t context[3], int32_t residual[3]);
  uint64_t split_count() const { return count_; }

 private:
  std::vector<uint8_t> bytes_;
  SplitModels* models_ = nullptr;
  std::unique_ptr<RangeDecoder> count_dec_, rank_dec_, res_dec_[3];
  uint64_t count_ = 0;
};

// Coded stream sizes of a SPLT payload without decoding it (for pmz-info).
bool split_chunk_stream_sizes(const uint8_t* p, size_t size, uint64_t& count, uint64_t stream_bytes[7]);

// ---- Mesh-dependent symbols (spec/format.md, sections 4 and 5) ----

__extension__ typedef unsigned __int128 WedgeScore;  // exact squared lengths (GCC/Clang)
__extension__ typedef __int128 WedgeScoreSigned;

// Reusable buffers for the wedge scores (no allocation per split once grown).
struct WedgeScratch {
  std::vector<int64_t> q;           // prefix sums of the ring offsets from v, 3 per entry
  std::vector<uint64_t> score64;    // per candidate, when narrow (the same values, in 64 bits)
  std::vector<WedgeScore> score;    // per candidate, otherwise
  std::vector<uint32_t> order;
  bool narrow = true;
};

// wedge_count context: ring size (clamped to 8) and whether the fan is closed; wedge_rank
// uses only the latter (measured: more rank contexts learn too slowly on small meshes).
inline uint32_t wedge_context(uint32_t k, bool closed) { return 2 * (k < 8 ? k : 8) + (closed ? 1 : 0); }

// Writer: the wedge (canonical ranks, kNoRank for a boundary side) of the ring gathered last in
// pm as symbols (interior count, rank among the candidates of that count). False if the ranks
// are not a valid wedge.
bool wedge_symbols(const int32_t* coords, uint32_t v, const ProgressiveMesh& pm, uint32_t rank_l,
                   uint32_t rank_r, uint32_t& count, uint32_t& rank, WedgeScratch& s);
// Decoder: symbols back to ranks; false if count or rank is out of range for the ring.
bool wedge_ranks(const int32_t* coords, uint32_t v, const ProgressiveMesh& pm, uint32_t count, uint32_t rank,
                 uint32_t& rank_l, uint32_t& rank_r, WedgeScratch& s);

}  // namespace pmz
