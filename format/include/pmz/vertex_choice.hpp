// SPDX-License-Identifier: MIT
// Which vertices split (spec/format.md sections 9.1 and 9.2): the vertex choice state the writer
// and the decoder keep in step (degrees, umbrella sums, the near list, exclusion), the choice
// contexts, and the scan over a group's candidates. The chunk codec (split_chunk.hpp) codes the
// choice bits this scan asks for.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "pmz/progressive_mesh.hpp"
#include "pmz/range_coder.hpp"

namespace pmz {

class ProgressiveMesh;

// Vertex choice contexts (spec/format.md section 9.2): density x near x degree x umbrella
// class.
inline constexpr uint32_t kChoiceDensities = 21, kChoiceDegrees = 9, kChoiceShapes = 3;
inline constexpr uint32_t kChoiceKeys =
    kChoiceDegrees * kChoiceShapes;  // per vertex: degree x class
inline constexpr uint32_t kChoiceContexts = kChoiceDensities * 2 * kChoiceKeys;

// bitlen(floor(D / m)) for m >= 1 without dividing (a division per vertex choice bit costs more
// than the bit): the quotient has bitlen(D) - bitlen(m) bits or one more, one more exactly when
// D >= m 2^(bitlen(D) - bitlen(m)), i.e. floor(D / 2^t) >= m.
inline uint32_t bitlen_quotient(uint64_t D, uint64_t m) {
  if (D < m) return 0;
  const uint32_t t = uint32_t(__builtin_clzll(m) - __builtin_clzll(D));
  return t + ((D >> t) >= m ? 1u : 0u);
}

// Initial probability of a 0 (scaled to 32768) of the choice models of expected-gap class d
// (spec/format.md section 9.2 and Appendix A): a 1 has probability about 1 / (1.5 * 2^(d - 1))
// there. Models with d >= 1 start at count kPriorCount (primed_model, spec/format.md section 11.1).
inline uint32_t choice_prior(uint32_t d) {
  return d == 0 ? kProbInit : std::min(32768u - 131072u / (3u << d), 31744u);
}

// The umbrella sums of a vertex w (spec/format.md section 9.1): over w's ring as the degree rule
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

// Exclusion lag (spec/format.md section 9.2): a group's j-th split excludes its closed one-ring
// from the group's candidates once kChoiceLag more splits of the group are found, so the decoder
// can find the group's vertices kChoiceLag + 1 splits ahead of the split it applies (for the
// fan prefetching) and take each ring from that split's own ring walk.
inline constexpr uint32_t kChoiceLag = 8;

// Which vertices split (spec/format.md sections 9.1 and 9.2): the state the writer and the decoder
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
  // umbrella false (the speed level, spec/format.md section 9.10): no sums, every class 0.
  void reset(ProgressiveMesh& base, const int32_t* coords, uint32_t position_bits,
             bool umbrella = true);
  // Starts a group: the neighbourhood noted since the last call becomes the near list (if
  // `near`: a decoder knows the group's flag and skips building a list it does not use).
  void start_group(bool near = true);
  // Then the group's scan: `size` splits, the first of them split number first_split of the
  // file (0-based, in stream order); limit: the vertex count at the group's start.
  void begin_scan(bool near, uint32_t limit, uint32_t size) {
    near_scan_ = near;
    n_ = near ? near_.size() : cells_ ? cell_.size() : limit;
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
    const uint32_t* const list = near_scan_ ? near_.data() : cell_.data();
    const uint32_t* const mark = shared().mark_.data();  // exclude() writes marks, never resizes
    const uint32_t excluded = excluded_;
    const bool near = near_scan_, listed = near_scan_ || cells_;
    const uint8_t* const key = shared().key_.data();
    uint64_t i = i_;
    uint32_t found = found_;
    // The density class d = bitlen_quotient(n - at, size_ - found) changes only once n - at
    // falls below lo = (size_ - found) 2^(d - 1), or when a split is found: recomputed then, not
    // per candidate. base: the context without the vertex's key.
    uint64_t lo = UINT64_MAX;
    uint32_t base = 0;
    int result = 1;
    while (found < upto) {
      if (i >= n) {
        result = 0;
        break;
      }
      const uint64_t at = i++;
      const uint32_t w = listed ? list[at] : uint32_t(at);
      if (mark[w] == excluded) continue;
      if (n - at < lo) {
        const uint64_t m = size_ - found;
        const uint32_t d = bitlen_quotient(n - at, m);
        lo = d ? m << (d - 1) : 0;
        base = context_base(d, near);
      }
      const int r = f(w, base + key[w]);
      if (r < 0) {
        result = -1;
        break;
      }
      if (r) {
        lo = UINT64_MAX;  // size_ - found changes
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
  // A node of a stream with a node table starts (spec/format.md section 15.4): its groups' `near`
  // lists come from its own splits only, and the other groups scan `cell` (the vertices of its
  // cell, ascending) and the vertices its splits add, instead of every vertex.
  void begin_node(std::vector<uint32_t>&& cell) {
    cells_ = true;
    cell_ = std::move(cell);
    noted_.clear();
  }
  // The node that holds every vertex (a level without cells): scans as without a node table.
  void begin_whole_node() {
    cells_ = false;
    cell_.clear();
    noted_.clear();
  }
  // Writer: whether every vertex of vs is in the near list (vs ascending).
  bool covers(std::span<const uint32_t> vs) const;
  // Writer: whether no vertex of vs is in the closed one-ring (in mesh) of another.
  bool independent(const ProgressiveMesh& mesh, std::span<const uint32_t> vs);
  // Decoder, before a split with a ring of k vertices: room so that applied() and the next
  // start_group() do not allocate. (Inline: once per split, it rarely needs to grow anything.)
  void reserve(size_t k) {
    const VertexChoice& o = shared();
    if (noted_.capacity() - noted_.size() < k + 2 ||
        (!owner_ && (degree_.capacity() == degree_.size() || mark_.capacity() == mark_.size() ||
                     sums_.capacity() == sums_.size() || key_.capacity() == key_.size())) ||
        bits_.size() * 64 <= o.degree_.size() || cell_.capacity() == cell_.size())
      grow(k);
  }
  // Parallel decoding: this object scans and applies the splits of one node (its own near list,
  // cell, scan and exclusion epochs) on owner's per-vertex arrays (degrees, sums, keys, marks),
  // sized beforehand for every vertex it adds. Marks are compared only within a node's cell,
  // but must never meet an older value: this object takes epochs from `epochs` on, one per
  // group, and the caller gives each node room for one per split (see epochs_used()).
  void attach(VertexChoice& owner, uint32_t epochs) {
    owner_ = &owner;
    shift_ = owner.shift_;
    umbrella_ = owner.umbrella_;
    epoch_ = excluded_ = epochs;
    bits_.clear();
    top_.clear();
    size_bitmap(owner.degree_.size() / 64 + 2);
  }
  // The owner before attaching workers: a fresh epoch range of n values for them (the marks are
  // cleared first if it would wrap), returned as its first value; the owner's own epochs go on
  // after it.
  uint32_t take_epochs(uint64_t n) {
    if (uint64_t(epoch_) + n + 2 > UINT32_MAX) {
      std::fill(mark_.begin(), mark_.end(), 0);
      epoch_ = 0;
    }
    const uint32_t first = epoch_;
    epoch_ += uint32_t(n);
    return first;
  }
  // The per-vertex arrays for n vertices (value-initialized; the owner, before attaching
  // workers that add vertices up to n).
  void resize_vertices(size_t n) {
    degree_.resize(n);
    mark_.resize(n);
    key_.resize(n);
    sums_.resize(n);
  }
  // Decoder: room for n vertices in the per-vertex arrays at once (refine() knows how many it
  // may add): growing them by doubling one vertex at a time copied them and faulted their
  // pages in twice.
  void reserve_vertices(size_t n) {
    degree_.reserve(n);
    mark_.reserve(n);
    key_.reserve(n);
    sums_.reserve(n);
    bits_.reserve(n / 64 + 2);
    top_.reserve(n / 4096 + 2);
  }
  // After pm.split_gathered() (its ring and u_ring still those of the split), once u's
  // coordinates are known: coords holds 3 per vertex, u's included.
  void applied(const ProgressiveMesh& pm, const int32_t* coords, bool has_left, bool has_right);
  uint32_t degree(uint32_t w) const { return shared().degree_[w]; }
  const RingSums& sums(uint32_t w) const { return shared().sums_[w]; }
  const uint8_t* sums_bytes() const {
    return reinterpret_cast<const uint8_t*>(shared().sums_.data());
  }                                                                              // (prefetching)
  uint32_t shape(uint32_t w) const { return shared().key_[w] % kChoiceShapes; }  // umbrella class
  const uint32_t* degrees() const {
    return shared().degree_.data();
  }  // per vertex (the wedge score's end weights)

 private:
  // A candidate w's context is context_base(d, near) + key_[w]: ((min(d, 20) * 2 + near) * 9 +
  // min(degree, 8)) * 3 + umbrella class, d = bitlen(expected gap); the last two as key_[w].
  static uint32_t context_base(uint32_t d, bool near) {
    return ((d < kChoiceDensities ? d : kChoiceDensities - 1) * 2 + (near ? 1 : 0)) * kChoiceKeys;
  }
  int64_t coord(const int32_t* coords, uint32_t w, int a) const {
    return coords[size_t(w) * 3 + a] >> shift_;
  }
  static uint8_t key_of(const RingSums& s, uint32_t deg) {
    return uint8_t((deg < kChoiceDegrees ? deg : kChoiceDegrees - 1) * kChoiceShapes +
                   umbrella_class(s));
  }
  void push_vertex(uint32_t u, uint32_t degree);
  void umbrella(const ProgressiveMesh& pm, const int32_t* coords, bool has_left, bool has_right);
  template <bool kShift>
  void umbrella_sums(const ProgressiveMesh& pm, const int32_t* coords, bool has_left,
                     bool has_right);
  void degree_keys(const ProgressiveMesh& pm, bool has_left, bool has_right);
  void update_key(uint32_t w) {
    VertexChoice& o = shared();
    const uint32_t deg = o.degree_[w];
    o.key_[w] = umbrella_
                    ? key_of(o.sums_[w], deg)
                    : uint8_t((deg < kChoiceDegrees ? deg : kChoiceDegrees - 1) * kChoiceShapes);
  }
  // A fresh mark value (all of mark_ differs from it).
  uint32_t next_epoch() {
    if (++epoch_ == 0) {  // (never attached: attach() leaves room)
      std::fill(mark_.begin(), mark_.end(), 0);
      epoch_ = 1;
    }
    return epoch_;
  }
  void exclude(const ProgressiveMesh& mesh, uint32_t w);
  VertexChoice* owner_ = nullptr;  // attach()'s, or null: the per-vertex arrays are this object's
  VertexChoice& shared() { return owner_ ? *owner_ : *this; }
  const VertexChoice& shared() const { return owner_ ? *owner_ : *this; }
  void grow(size_t k);  // reserve()'s work  // w's closed one-ring in mesh
  BigVector<uint32_t> degree_;
  std::vector<uint32_t> near_, noted_;
  BigVector<RingSums> sums_;  // per vertex
  BigVector<uint8_t> key_;    // per vertex: min(degree, 8) * 3 + umbrella class
  uint32_t shift_ = 0;        // umbrella_shift
  bool umbrella_ = true;      // umbrella sums kept (else every class is 0)
  // start_group's bitmap of the noted vertices, and of its nonzero words (all 0 between calls).
  std::vector<uint64_t> bits_, top_;
  void size_bitmap(size_t words) {
    bits_.resize(words);
    top_.resize((words + 63) / 64);
  }
  // Per vertex: epoch_ when in the near list being built (start_group), excluded_ when
  // excluded from the group being scanned, another value of epoch_ in independent().
  BigVector<uint32_t> mark_;
  uint32_t epoch_ = 0, excluded_ = 0;
  // The scan: near or all vertices, candidates n_, next candidate i_, the group's size and
  // splits found; with a mesh, the vertices found.
  bool near_scan_ = false;
  bool cells_ = false;          // within a node of a cell: candidates from cell_
  std::vector<uint32_t> cell_;  // its cell's vertices, then the vertices its splits added
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

}  // namespace pmz
