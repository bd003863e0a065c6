// Coding of one SPLT chunk: groups of vertex splits into two range-coded streams with adaptive
// context models (spec/format.md, sections 8 and 9): connectivity (groups, vertex choice, wedges)
// and geometry (position residuals). Writer and decoder share this code.
//
// Groups (sizes and near flags) are decoded when the chunk arrives. Which vertices split (the
// choice stream), wedge and residual symbols use contexts from the mesh the decoder already has
// (vertex degrees and the previous group's neighbourhood, v's ring, u's ring and the
// prediction), so they are decoded as the splits are first applied: a group's vertices when
// its first split is, the other symbols split by split.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "pmz/format.hpp"
#include "pmz/geometry.hpp"
#include "pmz/progressive_mesh.hpp"
#include "pmz/range_coder.hpp"

namespace pmz {

class ProgressiveMesh;

inline constexpr uint32_t kWedgeContexts = 18, kRankContexts = 4;
// Vertex choice contexts (spec section 9.2): density x near x degree x umbrella
// class.
inline constexpr uint32_t kChoiceDensities = 21, kChoiceDegrees = 9, kChoiceShapes = 3;
inline constexpr uint32_t kChoiceKeys =
    kChoiceDegrees * kChoiceShapes;  // per vertex: degree x class
inline constexpr uint32_t kChoiceContexts = kChoiceDensities * 2 * kChoiceKeys;

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
  // The second model of each residual bit (spec section 9.6): tangent slots by
  // PositionPrediction::mix (kMixTangentContexts), the normal slot likewise (kMixNormalContexts).
  UIntModel mix_tangent[2][kMixTangentContexts];
  UIntModel mix_normal[kMixNormalContexts];
  UIntModel& mix(int slot, uint32_t context) {
    return slot < 2 ? mix_tangent[slot][context] : mix_normal[context];
  }
};

// bitlen(floor(D / m)) for m >= 1 without dividing (a division per vertex choice bit costs more
// than the bit): the quotient has bitlen(D) - bitlen(m) bits or one more, one more exactly when
// D >= m 2^(bitlen(D) - bitlen(m)), i.e. floor(D / 2^t) >= m.
inline uint32_t bitlen_quotient(uint64_t D, uint64_t m) {
  if (D < m) return 0;
  const uint32_t t = uint32_t(__builtin_clzll(m) - __builtin_clzll(D));
  return t + ((D >> t) >= m ? 1u : 0u);
}

// Initial probability of a 0 (scaled to 32768) of the choice models of expected-gap class d
// (spec section 9.2 and Appendix A): a 1 has probability about 1 / (1.5 * 2^(d - 1)) there. Models
// with d >= 1 start at count kPriorCount (primed_model, spec section 11.1).
inline uint32_t choice_prior(uint32_t d) {
  return d == 0 ? kProbInit : std::min(32768u - 131072u / (3u << d), 31744u);
}

// A group of the chunk: its size and whether its vertices are chosen among the previous
// group's neighbourhood (near) or among all vertices.
struct GroupCode {
  uint32_t size;
  bool near;
};

// The umbrella sums of a vertex w (spec section 9.1): over w's ring as the degree rule
// counts it, with c' = c >> umbrella_shift (per axis) and the spokes e = c'[x] - c'[w], the sum
// D of the spokes per axis and the sum L of their lengths |e_x| + |e_y| + |e_z|, modulo 2^32
// (D two's complement).
struct alignas(16) RingSums {  // (FanPrefetcher::kSumBytes)
  uint32_t d[3];
  uint32_t l;
};
static_assert(sizeof(RingSums) == FanPrefetcher::kSumBytes);
// Coordinates of up to 16 bits are summed as they are; wider ones (and lossless float patterns,
// 32 bits) lose their low bits: spokes below 2^16 per axis keep the sums exact (no wrap) up to
// degree 2^14.
inline uint32_t umbrella_shift(uint32_t position_bits) {
  return position_bits == 0 ? 16 : position_bits > 16 ? position_bits - 16 : 0;
}
// The umbrella class of a vertex with sums s: 0 when 64 |D|^2 < L^2 (the ring's centroid offset
// |D| / n below 1/8 of the mean spoke length L / n, |D| Euclidean, L in the L1 norm), else 1 when
// 16 |D|^2 < L^2, else 2 (also when L = 0). Exact in 64 bits: |D|^2 < 3 * 2^62, so |D|^2 <
// ceil(L^2 / 64) = (L^2 + 63) >> 6 is the comparison, without overflow.
inline uint32_t umbrella_class(const RingSums& s) {
  const int64_t x = int32_t(s.d[0]), y = int32_t(s.d[1]), z = int32_t(s.d[2]);
  // Each square fits int64 (<= 2^62), their sum only uint64: summed unsigned (no signed overflow).
  const uint64_t d2 = uint64_t(x * x) + uint64_t(y * y) + uint64_t(z * z), l2 = uint64_t(s.l) * s.l;
  return d2 < ((l2 + 63) >> 6) ? 0 : d2 < ((l2 + 15) >> 4) ? 1 : 2;
}

// Exclusion lag (spec section 9.2): a group's j-th split excludes its closed one-ring from
// the group's candidates once kChoiceLag more splits of the group are found, so the decoder
// can find the group's vertices kChoiceLag + 1 splits ahead of the split it applies (for the
// fan prefetching) and take each ring from that split's own ring walk.
inline constexpr uint32_t kChoiceLag = 8;

// The split symbol schedule (spec section 9.3), defined here once for the writer
// (encode_split_chunk), the decoder (Decoder::Impl::apply) and SplitChunkReader::group_symbols:
// a group's choice bits are read until its first scan_at_group_start() vertices are found, and
// after its split j (0-based) is first applied until scan_after_split(j) are (1-based counts,
// capped by the group's size).
inline constexpr uint32_t scan_at_group_start() { return kChoiceLag + 1; }
inline constexpr uint32_t scan_after_split(uint32_t j) { return j + 2 + kChoiceLag; }

// Which vertices split (spec/format.md, sections 9.1 and 9.2): the state the writer and the decoder
// keep in step, updated at every first application of a split, in stream order.
// - degree of every vertex: base vertices their ring size, then per split the rule of
//   applied() (the ring sizes on a manifold mesh);
// - umbrella sums (RingSums) of every vertex over the same rings, and from them and the degree
//   a context key per vertex: min(degree, 8) * 3 + umbrella class;
// - the neighbourhood of the splits since start_group(): v's ring before the split, v and u;
// - exclusion: per vertex, the first split of the current group whose closed one-ring holds it.
// A group's candidates, in order: near: the previous group's neighbourhood (ascending,
// distinct); otherwise every vertex below the vertex count at the group's start. One bit per
// candidate not excluded says whether it splits, until the group's splits are all found.
class VertexChoice {
 public:
  // Degrees and umbrella sums from the base rings (0 without a face); coords: 3 per vertex.
  void reset(ProgressiveMesh& base, const int32_t* coords, uint32_t position_bits);
  // Starts a group: the neighbourhood noted since the last call becomes the near list (if
  // `near`: a decoder knows the group's flag and skips building a list it does not use).
  void start_group(bool near = true);
  // Then the group's scan: `size` splits, the first of them split number first_split of the
  // file (0-based, in stream order); limit: the vertex count at the group's start.
  void begin_scan(bool near, uint32_t limit, uint32_t size) {
    near_scan_ = near;
    n_ = near ? near_.size() : limit;
    i_ = 0;
    size_ = size;
    found_ = 0;
    chosen_.clear();
    excluded_ = next_epoch();
  }
  uint32_t found() const { return found_; }  // splits of the group found so far
  // Continues the scan: calls f(w, context) per candidate not excluded, in order, until f
  // returned 1 (w splits) so often that `upto` (at most the group's size) splits are found.
  // 1 when they are, 0 if the candidates ran out first, -1 if f returned -1 (stop).
  // Exclusion: a candidate is skipped when it is in the closed one-ring of the group's split j
  // (0-based) with j <= found - 1 - kChoiceLag. With mesh (the mesh at the group's start:
  // writer, tests) that ring is taken from mesh once the scan gets there; without (decoder),
  // applied() notes it, and the caller applies split j right before it continues the scan to
  // j + 2 + kChoiceLag found (so every split noted is one whose ring counts, and no other).
  template <class F>
  int scan(const ProgressiveMesh* mesh, uint32_t upto, F&& f) {
    if (upto > size_) upto = size_;
    // The scan's state in locals (f's stores could alias the members), written back on exit.
    const uint64_t n = n_;
    const uint32_t* const list = near_.data();
    const uint32_t* const mark = mark_.data();  // exclude() writes marks, never resizes
    const uint32_t excluded = excluded_;
    const bool near = near_scan_;
    uint64_t i = i_;
    uint32_t found = found_;
    int result = 1;
    while (found < upto) {
      if (i >= n) {
        result = 0;
        break;
      }
      const uint64_t at = i++;
      const uint32_t w = near ? list[at] : uint32_t(at);
      if (mark[w] == excluded) continue;
      const int r = f(w, context(w, bitlen_quotient(n - at, size_ - found), near));
      if (r < 0) {
        result = -1;
        break;
      }
      if (r) {
        ++found;
        if (mesh) {
          i_ = i;
          found_ = found;
          chosen_.push_back(w);
          if (found > kChoiceLag) exclude(*mesh, chosen_[found - 1 - kChoiceLag]);
        }
      }
    }
    i_ = i;
    found_ = found;
    return result;
  }
  // Writer: whether every vertex of vs is in the near list (vs ascending).
  bool covers(std::span<const uint32_t> vs) const;
  // Writer: whether no vertex of vs is in the closed one-ring (in mesh) of another.
  bool independent(const ProgressiveMesh& mesh, std::span<const uint32_t> vs);
  // Decoder, before a split with a ring of k vertices: room so that applied() and the next
  // start_group() do not allocate. (Inline: once per split, it rarely needs to grow anything.)
  void reserve(size_t k) {
    if (noted_.capacity() - noted_.size() < k + 2 || degree_.capacity() == degree_.size() ||
        mark_.capacity() == mark_.size() || sums_.capacity() == sums_.size() ||
        key_.capacity() == key_.size() || bits_.size() * 64 <= degree_.size())
      grow(k);
  }
  // Decoder: room for n vertices in the per-vertex arrays at once (refine() knows how many it
  // may add): growing them by doubling one vertex at a time copied them and faulted their
  // pages in twice. f(vector) is called on each, for memory hints.
  template <class F>
  void reserve_vertices(size_t n, F&& f) {
    degree_.reserve(n);
    mark_.reserve(n);
    key_.reserve(n);
    sums_.reserve(n);
    bits_.reserve(n / 64 + 2);
    f(degree_), f(mark_), f(key_), f(sums_);
  }
  // After pm.split_gathered() (its ring and u_ring still those of the split), once u's
  // coordinates are known: coords holds 3 per vertex, u's included.
  void applied(const ProgressiveMesh& pm, const int32_t* coords, bool has_left, bool has_right);
  uint32_t degree(uint32_t w) const { return degree_[w]; }
  const RingSums& sums(uint32_t w) const { return sums_[w]; }
  const uint8_t* sums_bytes() const {
    return reinterpret_cast<const uint8_t*>(sums_.data());
  }                                                                     // (prefetching)
  uint32_t shape(uint32_t w) const { return key_[w] % kChoiceShapes; }  // umbrella class
  const uint32_t* degrees() const {
    return degree_.data();
  }  // per vertex (the wedge score's end weights)

 private:
  // ((min(d, 20) * 2 + near) * 9 + min(degree, 8)) * 3 + umbrella class, d = bitlen(expected
  // gap); the last two as key_[w].
  uint32_t context(uint32_t w, uint32_t d, bool near) const {
    return ((d < kChoiceDensities ? d : kChoiceDensities - 1) * 2 + (near ? 1 : 0)) * kChoiceKeys +
           key_[w];
  }
  int64_t coord(const int32_t* coords, uint32_t w, int a) const {
    return coords[size_t(w) * 3 + a] >> shift_;
  }
  static uint8_t key_of(const RingSums& s, uint32_t deg) {
    return uint8_t((deg < kChoiceDegrees ? deg : kChoiceDegrees - 1) * kChoiceShapes +
                   umbrella_class(s));
  }
  void push_vertex(uint32_t degree);
  void umbrella(const ProgressiveMesh& pm, const int32_t* coords, bool has_left, bool has_right);
  template <bool kShift>
  void umbrella_sums(const ProgressiveMesh& pm, const int32_t* coords, bool has_left,
                     bool has_right);
  void update_key(uint32_t w) { key_[w] = key_of(sums_[w], degree_[w]); }
  // A fresh mark value (all of mark_ differs from it).
  uint32_t next_epoch() {
    if (++epoch_ == 0) {
      std::fill(mark_.begin(), mark_.end(), 0);
      epoch_ = 1;
    }
    return epoch_;
  }
  void exclude(const ProgressiveMesh& mesh, uint32_t w);
  void grow(size_t k);  // reserve()'s work  // w's closed one-ring in mesh
  std::vector<uint32_t> degree_, near_, noted_;
  std::vector<RingSums> sums_;  // per vertex
  std::vector<uint8_t> key_;    // per vertex: min(degree, 8) * 3 + umbrella class
  uint32_t shift_ = 0;          // umbrella_shift
  std::vector<uint64_t> bits_;  // start_group's bitmap of the noted vertices (all 0 between calls)
  // Per vertex: epoch_ when in the near list being built (start_group), excluded_ when
  // excluded from the group being scanned, another value of epoch_ in independent().
  std::vector<uint32_t> mark_;
  uint32_t epoch_ = 0, excluded_ = 0;
  // The scan: near or all vertices, candidates n_, next candidate i_, the group's size and
  // splits found; with a mesh, the vertices found.
  bool near_scan_ = false;
  uint64_t n_ = 0, i_ = 0;
  uint32_t size_ = 0, found_ = 0;
  std::vector<uint32_t> chosen_;
};

// Writer: the choice bits of a group of vertices vs (ascending, all below limit) as
// (context << 1 | bit), after
// choice.start_group(), with exclusion from the rings in mesh (the mesh at the group's start);
// near: the flag it chose (near whenever the near list holds every vertex of the group). False
// if the group cannot be coded: a vertex of vs in the closed one-ring of another (the rings the
// decoder notes when it applies the splits would then differ from mesh's), or excluded.
bool choice_bits(VertexChoice& choice, const ProgressiveMesh& mesh, uint32_t limit,
                 std::span<const uint32_t> vs, std::vector<uint32_t>& bits, bool& near);

// Appends the SPLT payload for the given groups (sizes sum to count) and choice bits (the
// concatenation of choice_bits() of the groups), every symbol in the order the decoder reads it;
// models: the file's models (updated). stream_bytes[k] receives the coded size of stream k
// (optional); symbol_bits[kind] (optional, SymbolKind) has the code length of the chunk's
// symbols of each kind added (RangeEncoder::position differences; the writer's accounting,
// pmz-encode --symbol-stats).
void encode_split_chunk(const std::vector<GroupCode>& groups, const std::vector<uint32_t>& choice,
                        const SplitSymbols* splits, size_t count, SplitModels& models,
                        std::vector<uint8_t>& payload, uint64_t* stream_bytes = nullptr,
                        double* symbol_bits = nullptr);

// Decoder side of one SPLT chunk. open() copies the payload, decodes the groups (sizes summing
// to the split count, at most max_splits) and validates them. models (the file's, see
// SplitModels) must outlive the reader. Then, in stream order and in the decoder's schedule
// (spec section 9.3: the choice, wedge_count and wedge_rank calls read one stream): begin_group()
// and find() the vertices of each group, wedge_count(), wedge_rank() and residuals() the
// symbols of each split, with the contexts the caller computes from its mesh; false when a
// stream is malformed or exhausted, or a group's candidates run out.
class SplitChunkReader {
 public:
  // Once per chunk: cold (optimized for size; the decoder library has a size budget).
  [[gnu::cold]] bool open(const uint8_t* p, size_t size, uint64_t max_splits, SplitModels& models,
                          std::string& error);
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
  uint64_t split_count() const { return count_; }
  size_t largest_group() const { return largest_; }

 private:
  SplitModels* models_ = nullptr;
  std::vector<GroupCode> groups_;
  size_t next_group_ = 0, largest_ = 0;
  uint64_t group_end_ = 0;
  uint32_t group_size_ = 0;  // of the group begun last
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
    if (!residuals(s.residual_context, s.mix_context, s.residual)) return false;
    out.push_back(s);
  }
  return more;
}

// Coded stream sizes of a SPLT payload without decoding it (for pmz-info).
bool split_chunk_stream_sizes(const uint8_t* p, size_t size, uint64_t& count,
                              uint64_t stream_bytes[kSplitStreamCount]);

// ---- Mesh-dependent symbols (spec/format.md, sections 9.4 to 9.6) ----

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
  bool confident = true;  // their best score is over twice the second (spec section 9.4)
  uint32_t best = 0;      // the candidate at rank 0
  // Optional, set by the caller: a bound on |c[w] - c[v]| (per axis) over all vertex pairs, e.g.
  // the largest side of the coordinates' bounding box. When k (extent + 1) < 2^26 the scores
  // are computed in 64 bits without checking each ring offset. Unknown: UINT64_MAX.
  uint64_t extent = UINT64_MAX;
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
