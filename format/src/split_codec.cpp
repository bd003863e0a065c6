#include "pmz/split_codec.hpp"

#include <algorithm>
#include <cstdlib>

#include "pmz/coding.hpp"
#include "pmz/format.hpp"
#include "pmz/progressive_mesh.hpp"

namespace pmz {

namespace {
inline uint64_t l1(int64_t x, int64_t y, int64_t z) {
  return uint64_t(x < 0 ? -x : x) + uint64_t(y < 0 ? -y : y) + uint64_t(z < 0 ? -z : z);
}
}  // namespace

[[gnu::cold]] void VertexChoice::reset(ProgressiveMesh& base, const int32_t* coords,
                                       uint32_t position_bits) {
  shift_ = umbrella_shift(position_bits);
  degree_.assign(base.vertex_count(), 0);
  sums_.assign(base.vertex_count(), RingSums{{0, 0, 0}, 0});
  key_.assign(base.vertex_count(), 0);
  for (uint32_t w = 0; w < base.vertex_count(); ++w) {
    if (base.gather_ring(w)) {
      degree_[w] = uint32_t(base.ring().size());
      RingSums& s = sums_[w];
      for (uint32_t x : base.ring()) {
        int64_t e[3];
        for (int a = 0; a < 3; ++a) {
          e[a] = coord(coords, x, a) - coord(coords, w, a);
          s.d[a] += uint32_t(e[a]);
        }
        s.l += uint32_t(l1(e[0], e[1], e[2]));
      }
    }
    update_key(w);
  }
  mark_.assign(base.vertex_count(), 0);
  epoch_ = 0;
  excluded_ = 0;
  near_.clear();
  noted_.clear();
  bits_.assign((size_t(base.vertex_count()) + 63) / 64, 0);
}

void VertexChoice::start_group(bool near) {
  const size_t n = degree_.size();  // the vertex count: every noted vertex is below it
  const size_t words = (n + 63) / 64;
  if (near && bits_.size() < words) bits_.resize(words);  // writer only: the decoder reserve()d
  near_.swap(noted_);
  noted_.clear();
  if (!near) {
    near_.clear();
    return;
  }
  if (near_.size() * 64 < n) {  // sparse: sort
    std::sort(near_.begin(), near_.end());
    near_.erase(std::unique(near_.begin(), near_.end()), near_.end());
    return;
  }
  // Dense: a bitmap of the noted vertices, then its set bits in index order, clearing it as it
  // goes (n / 64 words instead of a mark test per vertex; no allocation: at most near_.size()
  // distinct).
  uint64_t* bits = bits_.data();
  for (uint32_t w : near_) bits[w >> 6] |= uint64_t(1) << (w & 63);
  near_.clear();
  for (size_t i = 0; i < words; ++i) {
    uint64_t x = bits[i];
    if (!x) continue;
    bits[i] = 0;
    do {
      near_.push_back(uint32_t(i * 64 + uint32_t(__builtin_ctzll(x))));
      x &= x - 1;
    } while (x);
  }
}

void VertexChoice::exclude(const ProgressiveMesh& mesh, uint32_t w) {
  mark_[w] = excluded_;
  mesh.for_each_fan_face(w, [&](uint32_t a, uint32_t b) { mark_[a] = mark_[b] = excluded_; });
}

bool VertexChoice::independent(const ProgressiveMesh& mesh, std::span<const uint32_t> vs) {
  const uint32_t epoch = next_epoch();
  for (uint32_t v : vs) {
    if (mark_[v] == epoch) return false;
    mark_[v] = epoch;
  }
  bool ok = true;
  for (uint32_t v : vs)
    mesh.for_each_fan_face(
        v, [&](uint32_t a, uint32_t b) { ok = ok && mark_[a] != epoch && mark_[b] != epoch; });
  return ok;
}

bool VertexChoice::covers(std::span<const uint32_t> vs) const {
  auto it = near_.begin();
  for (uint32_t v : vs) {
    it = std::lower_bound(it, near_.end(), v);
    if (it == near_.end() || *it != v) return false;
  }
  return true;
}

namespace {
template <class T>
void make_room(std::vector<T>& b, size_t extra) {
  if (b.capacity() - b.size() < extra) b.reserve(std::max(b.size() + extra, 2 * b.capacity()));
}
}  // namespace

// u's entries, within the capacity reserve() made (no reallocation code: the decoder's library
// has a size budget).
void VertexChoice::push_vertex(uint32_t degree) {
  if (degree_.size() == degree_.capacity() || mark_.size() == mark_.capacity() ||
      key_.size() == key_.capacity() || sums_.size() == sums_.capacity())
    __builtin_unreachable();
  degree_.push_back(degree);
  mark_.push_back(0);
  key_.push_back(0);
  sums_.push_back(RingSums{{0, 0, 0}, 0});
}

void VertexChoice::grow(size_t k) {
  make_room(noted_, k + 2);
  make_room(degree_, 1);
  make_room(mark_, 1);
  make_room(sums_, 1);
  make_room(key_, 1);
  // start_group's bitmap for the vertex count after this split (it must not allocate then: the
  // group's state has begun to change).
  const size_t words = (degree_.size() + 64) / 64;
  if (bits_.size() < words) {
    make_room(bits_, 1);
    bits_.resize(words);
  }
}

// The umbrella sums of a split (see applied()). Positions of up to 16 bits (shift 0: the usual
// case) get their own copy without the shifts, which also frees a register in the ring loop.
void VertexChoice::umbrella(const ProgressiveMesh& pm, const int32_t* coords, bool has_left,
                            bool has_right) {
  if (shift_ == 0)
    umbrella_sums<false>(pm, coords, has_left, has_right);
  else
    umbrella_sums<true>(pm, coords, has_left, has_right);
}

template <bool kShift>
void VertexChoice::umbrella_sums(const ProgressiveMesh& pm, const int32_t* coords, bool has_left,
                                 bool has_right) {
  // From e = c'[x] - c'[v] per ring vertex x of u and du = c'[u] - c'[v], modulo 2^32: an
  // interior vertex's spoke -e to v becomes du - e; vl and vr gain the spoke du - e to u; v
  // loses the interior's spokes e and gains du; u's spokes are -du to v and e - du to each x.
  // (Locals: the stores could alias the members.)
  const std::span<const uint32_t> ur = pm.u_ring();
  const uint32_t v = ur[0], u = pm.vertex_count() - 1, r = uint32_t(ur.size());
  const uint32_t sh = kShift ? shift_ : 0;
  auto at = [&](uint32_t w, int a) -> int64_t {
    return kShift ? coords[size_t(w) * 3 + a] >> sh : coords[size_t(w) * 3 + a];
  };
  const uint32_t* const deg = degree_.data();
  RingSums* const sums = sums_.data();
  uint8_t* const key = key_.data();
  const int64_t vx = at(v, 0), vy = at(v, 1), vz = at(v, 2);
  const int64_t dx = at(u, 0) - vx, dy = at(u, 1) - vy, dz = at(u, 2) - vz;
  uint32_t ix = 0, iy = 0, iz = 0, il = 0;  // over the interior: sums of e and |e|
  uint32_t al = 0;                          // over all of u's ring vertices: sum of |e - du|
  const uint32_t lo = has_left ? 2 : 1, hi = has_right ? r - 1 : r;
  for (uint32_t i = lo; i < hi; ++i) {
    const uint32_t x = ur[i];
    const int64_t ex = at(x, 0) - vx, ey = at(x, 1) - vy, ez = at(x, 2) - vz;
    const uint32_t le = uint32_t(l1(ex, ey, ez)), lf = uint32_t(l1(ex - dx, ey - dy, ez - dz));
    ix += uint32_t(ex);
    iy += uint32_t(ey);
    iz += uint32_t(ez);
    il += le;
    al += lf;
    RingSums& sx = sums[x];
    sx.d[0] += uint32_t(dx);
    sx.d[1] += uint32_t(dy);
    sx.d[2] += uint32_t(dz);
    sx.l += lf - le;
    key[x] = key_of(sx, deg[x]);
  }
  uint32_t ax = ix, ay = iy, az = iz;  // sums of e over all of u's ring vertices
  uint32_t ends[2], n_ends = 0;        // vl, vr (a loop: the code once)
  if (has_left) ends[n_ends++] = ur[1];
  if (has_right) ends[n_ends++] = ur[r - 1];
  for (uint32_t j = 0; j < n_ends; ++j) {
    const uint32_t x = ends[j];
    const int64_t ex = at(x, 0) - vx, ey = at(x, 1) - vy, ez = at(x, 2) - vz;
    const uint32_t lf = uint32_t(l1(ex - dx, ey - dy, ez - dz));
    ax += uint32_t(ex);
    ay += uint32_t(ey);
    az += uint32_t(ez);
    al += lf;
    RingSums& sx = sums[x];
    sx.d[0] += uint32_t(dx - ex);
    sx.d[1] += uint32_t(dy - ey);
    sx.d[2] += uint32_t(dz - ez);
    sx.l += lf;
    key[x] = key_of(sx, deg[x]);
  }
  const uint32_t ldu = uint32_t(l1(dx, dy, dz));
  RingSums& sv = sums[v];
  sv.d[0] += uint32_t(dx) - ix;
  sv.d[1] += uint32_t(dy) - iy;
  sv.d[2] += uint32_t(dz) - iz;
  sv.l += ldu - il;
  key[v] = key_of(sv, deg[v]);
  RingSums& su = sums[u];
  su.d[0] = ax - r * uint32_t(dx);
  su.d[1] = ay - r * uint32_t(dy);
  su.d[2] = az - r * uint32_t(dz);
  su.l = al + ldu;
  key[u] = key_of(su, r);
}

void VertexChoice::applied(const ProgressiveMesh& pm, const int32_t* coords, bool has_left,
                           bool has_right) {
  const std::span<const uint32_t> ring = pm.ring(), ur = pm.u_ring();
  const uint32_t v = ur[0], u = pm.vertex_count() - 1, r = uint32_t(ur.size());
  reserve(ring.size());  // (the decoder did, before the split)
  degree_[v] = uint32_t(ring.size()) + 2 + (has_left ? 1 : 0) + (has_right ? 1 : 0) - r;
  push_vertex(r);
  if (has_left) ++degree_[ur[1]];
  if (has_right) ++degree_[ur[r - 1]];
  umbrella(pm, coords, has_left, has_right);
  // Exclusion (the scan's caller applies the split when its closed one-ring starts to count).
  const uint32_t excluded = excluded_;
  mark_[v] = excluded;
  for (uint32_t w : ring) mark_[w] = excluded;
  noted_.insert(noted_.end(), ring.begin(), ring.end());
  noted_.push_back(v);
  noted_.push_back(u);
}

bool choice_bits(VertexChoice& choice, const ProgressiveMesh& mesh, uint32_t limit,
                 std::span<const uint32_t> vs, std::vector<uint32_t>& bits, bool& near) {
  near = choice.covers(vs);
  if (!choice.independent(mesh, vs)) return false;
  choice.begin_scan(near, limit, uint32_t(vs.size()));
  size_t at = 0;
  const int r = choice.scan(&mesh, uint32_t(vs.size()), [&](uint32_t w, uint32_t ctx) {
    if (vs[at] < w) return -1;  // vs[at] was skipped: excluded
    const bool hit = vs[at] == w;
    at += hit;
    bits.push_back(ctx << 1 | (hit ? 1u : 0u));
    return hit ? 1 : 0;
  });
  return r == 1 && at == vs.size();
}

void encode_split_chunk(const std::vector<GroupCode>& groups, const std::vector<uint32_t>& choice,
                        const SplitSymbols* splits, size_t count, SplitModels& models,
                        std::vector<uint8_t>& payload, uint64_t* stream_bytes,
                        double* symbol_bits) {
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
    // Then each group in the decoder's order of reads (the schedule, spec section 9.3): its
    // choice bits up to its scan_at_group_start()-th vertex, then per split j the wedge symbols
    // and the choice bits up to the group's scan_after_split(j)-th vertex (those the decoder
    // finds once split j is applied); the residuals in their own stream.
    size_t bit = 0, at = 0;
    for (const GroupCode& g : groups) {
      uint32_t found = 0;
      auto choose = [&](uint32_t upto) {
        ca.to(kSymbolChoice);
        for (upto = std::min(upto, g.size); found < upto && bit < choice.size(); ++bit) {
          cn.bit(m->choice[choice[bit] >> 1], choice[bit] & 1);
          found += choice[bit] & 1;
        }
      };
      choose(scan_at_group_start());
      for (uint32_t j = 0; j < g.size && at < count; ++j) {
        const SplitSymbols& s = splits[at++];
        ca.to(kSymbolWedgeCount);
        encode_small(cn, m->wedge_count[s.wedge_context], s.wedge_count);
        ca.to(kSymbolWedgeRank);
        cn.bit(m->rank_zero[s.rank_context], s.wedge_rank > 0 ? 1 : 0);
        if (s.wedge_rank > 0) encode_small(cn, m->wedge_rank[s.rank_context], s.wedge_rank - 1);
        choose(scan_after_split(j));
        for (int a = 0; a < 3; ++a) {
          ga.to(kSymbolResidualT0 + a);
          encode_uint_mixed(ge, m->residual[a][s.residual_context[a]], m->mix(a, s.mix_context[a]),
                            zigzag_encode(s.residual[a]));
        }
      }
    }
    ca.to(-1);
    ga.to(-1);
    cn.finish();
    ge.finish();
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

bool SplitChunkReader::open(const uint8_t* p, size_t size, uint64_t max_splits, SplitModels& models,
                            std::string& error) {
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
  uint64_t groups = 0, done = 0;
  bool ok = true;
  for (int pass = 0; pass < 2 && ok; ++pass) {
    if (pass == 1) {
      m.groups = size_model;
      m.near = near_model;
      gr.set_state(start);
      groups_.clear();
      groups_.reserve(groups);
      groups = done = 0;
    }
    while (ok && done < count) {  // each group adds at least one split: at most count groups
      uint32_t g;
      ok = decode_uint(gr, m.groups, g) && uint64_t(g) + 1 <= count - done;
      if (!ok) break;
      RangeState st = gr.state();
      const bool near = st.bit(m.near) != 0;
      gr.set_state(st);
      if (pass == 1) groups_.push_back({g + 1, near});
      largest_ = std::max<size_t>(largest_, g + 1);
      done += g + 1;
      ++groups;
    }
    ok = ok && done == count && gr.ok;
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
[[gnu::noinline]] bool decode_small(RangeDecoder& rc, SmallModel& m, uint32_t& x) {
  RangeState st = rc.state();
  const bool ok = decode_small(st, m, x);
  rc.set_state(st);
  return ok && rc.ok;
}
}  // namespace

SplitModels::SplitModels() {
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

// ---- Wedge candidates (spec section 9.4) ----

namespace {

constexpr uint32_t kMaxScoredRing = 1u << 24;  // larger rings: all scores 0 (order by index)
constexpr uint32_t kTopSelect = 16;            // ranks below: insertion into the best rank + 1

// End weights (spec section 9.4): m = 4, 3, 2 for degree <= 4, 5, more, and r = 12 / m (a
// negative G is ordered by G / (m_a m_b)), by degree clamped to 7; a missing end as degree 7.
constexpr uint8_t kWeight[8][2] = {{4, 3}, {4, 3}, {4, 3}, {4, 3}, {4, 3}, {3, 4}, {2, 6}, {2, 6}};

// Whether every score of v's ring fits 64 bits: k (max|e| + 1) < 2^26 (spread: OR of |e| - (e <
// 0) per component, so every |e| <= spread + 1).
bool ring_narrow(const int32_t* coords, const ProgressiveMesh& pm, const int32_t* cv) {
  const std::span<const uint32_t> ring = pm.ring();
  uint64_t spread = 0;
  for (uint32_t w : ring) {
    const int32_t* cw = coords + size_t(w) * 3;
    const int64_t dx = int64_t(cw[0]) - cv[0], dy = int64_t(cw[1]) - cv[1],
                  dz = int64_t(cw[2]) - cv[2];
    spread |= uint64_t(dx ^ (dx >> 63)) | uint64_t(dy ^ (dy >> 63)) | uint64_t(dz ^ (dz >> 63));
  }
  return spread < (uint64_t(1) << 26) && (spread + 1) * ring.size() < (uint64_t(1) << 26);
}

// Scores of the candidates with `count` interior ring vertices, in integer type I (U its unsigned
// twin): 64 bits for a narrow ring (ring_narrow, or shown by s.extent: every |key| fits), 128
// otherwise (rare). Closed: candidate j has a = j, b = (j + count + 1) mod k. Open: interior
// starts at j (0 .. k - count), a = j - 1 (none for j = 0), b = j + count (none for k). One pass
// over the ring for the offsets e, |e|^2 and the weights per position (extended canonical order;
// a closed ring's wrapped positions copied, not recomputed), then one pass over the candidates
// with the interior's sums slid along (add the new end b, drop the first interior position),
// tracking the best two scores (s.confident) and the first best candidate (s.best, rank 0).
// G = |E|^2 + c (4 S - c T) with E = 2 * interior + both ends, S the interior's |e|^2, T = 2 or 4
// times the ends' |e|^2 (0 for a missing end); key = G m_a m_b when G >= 0, else G r_a r_b with
// r = 12 / m (spec section 9.4).
template <class I, class U>
void score_wedges(const int32_t* coords, const uint32_t* degree, const ProgressiveMesh& pm,
                  uint32_t count, const int32_t* cv, std::vector<I>& qbuf, std::vector<I>& score,
                  WedgeScratch& s) {
  const std::span<const uint32_t> ring = pm.ring();
  const uint32_t k = uint32_t(ring.size()), start = pm.ring_start();
  const bool closed = pm.ring_closed();
  const uint32_t n = closed ? k : k - count + 1;
  // Positions: closed 0 .. k + count (rank x mod k), open 0 .. k + 1 (rank x - 1; 0 and k + 1
  // missing: e = 0, weight as degree 7).
  const uint32_t len = closed ? k + count + 1 : k + 2;
  if (qbuf.size() < size_t(len) * 4) qbuf.resize(size_t(len) * 4);
  if (s.w.size() < size_t(len) * 2) s.w.resize(size_t(len) * 2);
  if (score.size() < n) score.resize(n);
  I* const q0 = qbuf.data();
  uint8_t* const w0 = s.w.data();
  I* q = q0;
  uint8_t* wm = w0;
  const int64_t cx = cv[0], cy = cv[1], cz = cv[2];
  auto put_vertex = [&](uint32_t w) {
    const int32_t* cw = coords + size_t(w) * 3;
    const int64_t dx = cw[0] - cx, dy = cw[1] - cy, dz = cw[2] - cz;
    q[0] = dx;
    q[1] = dy;
    q[2] = dz;
    q[3] = I(U(dx) * U(dx) + U(dy) * U(dy) + U(dz) * U(dz));
    q += 4;
    const uint32_t d = degree[w];
    const uint8_t* m = kWeight[d < 7 ? d : 7];
    wm[0] = m[0];
    wm[1] = m[1];
    wm += 2;
  };
  auto put_missing = [&] {
    q[0] = q[1] = q[2] = q[3] = 0;
    q += 4;
    wm[0] = kWeight[7][0];
    wm[1] = kWeight[7][1];
    wm += 2;
  };
  if (!closed) put_missing();
  for (uint32_t j = start; j < k; ++j) put_vertex(ring[j]);
  for (uint32_t j = 0; j < start; ++j) put_vertex(ring[j]);
  if (closed) {
    for (uint32_t i = 0; i <= count;
         ++i) {  // count + 1 < k: no overlap (a few positions: no memcpy call)
      q[4 * i] = q0[4 * i];
      q[4 * i + 1] = q0[4 * i + 1];
      q[4 * i + 2] = q0[4 * i + 2];
      q[4 * i + 3] = q0[4 * i + 3];
      wm[2 * i] = w0[2 * i];
      wm[2 * i + 1] = w0[2 * i + 1];
    }
  } else {
    put_missing();
  }
  // Candidate j: ends at positions j and j + count + 1, interior j + 1 .. j + count.
  I wx = 0, wy = 0, wz = 0, S = 0;
  for (const I* p = q0 + 4; p < q0 + size_t(count + 1) * 4; p += 4) {
    wx += p[0];
    wy += p[1];
    wz += p[2];
    S += p[3];
  }
  const I c = I(count);
  const size_t span = size_t(count + 1);
  I* const out = score.data();
  const I lowest = I(U(1) << (8 * sizeof(I) - 1));  // the type's minimum (C++20: modular)
  I best = lowest, second = lowest;
  uint32_t best_j = 0;
  for (uint32_t j = 0; j < n; ++j) {
    const I* a = q0 + size_t(j) * 4;
    const I* b = a + span * 4;
    const I ex = 2 * wx + a[0] + b[0], ey = 2 * wy + a[1] + b[1], ez = 2 * wz + a[2] + b[2];
    const I ends = a[3] + b[3];
    const I T = (closed || (j > 0 && j + count < k)) ? 2 * ends : 4 * ends;
    const I G = ex * ex + ey * ey + ez * ez + c * (4 * S - c * T);
    const uint8_t* ma = w0 + size_t(j) * 2;
    const uint8_t* mb = ma + span * 2;
    const I sc = G * I(G >= 0 ? ma[0] * mb[0] : ma[1] * mb[1]);
    out[j] = sc;
    if (sc > best) {
      second = best;
      best = sc;
      best_j = j;
    } else if (sc > second) {
      second = sc;
    }
    wx += b[0] - a[4];
    wy += b[1] - a[5];
    wz += b[2] - a[6];
    S += b[3] - a[7];
  }
  s.confident = n < 2 || second <= 0 || best - second > second;
  s.best = best_j;
  s.n = n;
}

// The two instantiations: 64-bit (every split of a real mesh) and 128-bit (cold, kept small).
void score_narrow(const int32_t* coords, const uint32_t* degree, const ProgressiveMesh& pm,
                  uint32_t count, const int32_t* cv, WedgeScratch& s) {
  score_wedges<int64_t, uint64_t>(coords, degree, pm, count, cv, s.q, s.score64, s);
}
[[gnu::cold]] void score_wide(const int32_t* coords, const uint32_t* degree,
                              const ProgressiveMesh& pm, uint32_t count, const int32_t* cv,
                              WedgeScratch& s) {
  score_wedges<WedgeScoreSigned, WedgeScore>(coords, degree, pm, count, cv, s.q128, s.score, s);
}

uint32_t wedge_candidates(const int32_t* coords, const uint32_t* degree, uint32_t v,
                          const ProgressiveMesh& pm, uint32_t count, WedgeScratch& s) {
  const uint32_t k = uint32_t(pm.ring().size());
  if (k > kMaxScoredRing) {
    const uint32_t n = pm.ring_closed() ? k : k - count + 1;
    s.narrow = true;
    s.score64.assign(n, 0);
    s.confident = true;
    s.best = 0;
    return s.n = n;
  }
  const int32_t* cv = coords + size_t(v) * 3;
  if ((s.extent < (uint64_t(1) << 26) && (s.extent + 1) * k < (uint64_t(1) << 26)) ||
      ring_narrow(coords, pm, cv)) {
    score_narrow(coords, degree, pm, count, cv, s);
    s.narrow = true;
  } else {
    score_wide(coords, degree, pm, count, cv, s);
    s.narrow = false;
  }
  return s.n;
}

// Candidate order: higher score first, ties by smaller j.
template <class Score>
inline bool better(const Score* score, uint32_t x, uint32_t y) {
  return score[x] > score[y] || (score[x] == score[y] && x < y);
}

// Number of candidates ordered before j.
template <class Score>
uint32_t rank_of(const Score* score, uint32_t n, uint32_t j) {
  uint32_t rank = 0;
  for (uint32_t i = 0; i < n; ++i) rank += better(score, i, j);
  return rank;
}

// The candidate at position rank (< n) of the order.
template <class Score>
uint32_t select(const Score* score, uint32_t n, uint32_t rank, std::vector<uint32_t>& order) {
  if (rank < kTopSelect) {
    // Keep the best rank + 1 candidates sorted while scanning j upwards; a later candidate
    // goes after equal scores, which is the tie-break by smaller j.
    uint32_t top[kTopSelect];
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; ++i) {
      if (m <= rank)
        ++m;
      else if (!(score[i] > score[top[rank]]))
        continue;
      uint32_t p = m - 1;
      for (; p > 0 && score[i] > score[top[p - 1]]; --p) top[p] = top[p - 1];
      top[p] = i;
    }
    return top[rank];
  }
  order.resize(n);
  for (uint32_t i = 0; i < n; ++i) order[i] = i;
  std::nth_element(order.begin(), order.begin() + rank, order.end(),
                   [&](uint32_t x, uint32_t y) { return better(score, x, y); });
  return order[rank];
}

inline uint32_t max_count(const ProgressiveMesh& pm) {
  const uint32_t k = uint32_t(pm.ring().size());
  return pm.ring_closed() ? k - 2 : k - 1;
}

}  // namespace

bool wedge_symbols(const int32_t* coords, const uint32_t* degree, uint32_t v,
                   const ProgressiveMesh& pm, uint32_t rank_l, uint32_t rank_r, uint32_t& count,
                   uint32_t& rank, WedgeScratch& s) {
  const uint32_t k = uint32_t(pm.ring().size());
  uint32_t j;
  if (pm.ring_closed()) {
    if (rank_l >= k || rank_r >= k || rank_l == rank_r) return false;
    count = (rank_r + k - rank_l) % k - 1;
    j = rank_l;
  } else {
    if ((rank_l == kNoRank && rank_r == kNoRank) || (rank_l != kNoRank && rank_l >= k) ||
        (rank_r != kNoRank && rank_r >= k) ||
        (rank_l != kNoRank && rank_r != kNoRank && rank_l >= rank_r))
      return false;
    j = rank_l == kNoRank ? 0 : rank_l + 1;
    count = (rank_r == kNoRank ? k : rank_r) - j;
  }
  const uint32_t n = wedge_candidates(coords, degree, v, pm, count, s);
  rank = s.narrow ? rank_of(s.score64.data(), n, j) : rank_of(s.score.data(), n, j);
  return true;
}

bool wedge_scores(const int32_t* coords, const uint32_t* degree, uint32_t v,
                  const ProgressiveMesh& pm, uint32_t count, WedgeScratch& s) {
  if (pm.ring().size() < 2 || count > max_count(pm)) return false;
  wedge_candidates(coords, degree, v, pm, count, s);
  return true;
}

bool wedge_ranks(const int32_t* coords, const uint32_t* degree, uint32_t v,
                 const ProgressiveMesh& pm, uint32_t count, uint32_t rank, uint32_t& rank_l,
                 uint32_t& rank_r, WedgeScratch& s) {
  return wedge_scores(coords, degree, v, pm, count, s) &&
         wedge_pick(pm, count, rank, rank_l, rank_r, s);
}

bool wedge_pick(const ProgressiveMesh& pm, uint32_t count, uint32_t rank, uint32_t& rank_l,
                uint32_t& rank_r, WedgeScratch& s) {
  const uint32_t k = uint32_t(pm.ring().size()), n = s.n;
  if (rank >= n) return false;
  const uint32_t j = rank == 0  ? s.best
                     : s.narrow ? select(s.score64.data(), n, rank, s.order)
                                : select(s.score.data(), n, rank, s.order);
  if (pm.ring_closed()) {
    rank_l = j;
    rank_r = (j + count + 1) % k;
  } else {
    rank_l = j == 0 ? kNoRank : j - 1;
    rank_r = j + count == k ? kNoRank : j + count;
  }
  return true;
}

}  // namespace pmz
