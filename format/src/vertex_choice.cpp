// SPDX-License-Identifier: MIT
#include "pmz/vertex_choice.hpp"

#include <algorithm>

#include "pmz/progressive_mesh.hpp"

namespace pmz {

// The per-vertex arrays worked on (this object's, or attach()'s owner's), under the members'
// names.
#define PMZ_CHOICE_ARRAYS                  \
  VertexChoice& choice_arrays_ = shared(); \
  auto& degree_ = choice_arrays_.degree_;  \
  auto& sums_ = choice_arrays_.sums_;      \
  auto& key_ = choice_arrays_.key_;        \
  auto& mark_ = choice_arrays_.mark_;      \
  (void)degree_, (void)sums_, (void)key_, (void)mark_

namespace {
inline uint64_t l1(int64_t x, int64_t y, int64_t z) {
  return uint64_t(x < 0 ? -x : x) + uint64_t(y < 0 ? -y : y) + uint64_t(z < 0 ? -z : z);
}
}  // namespace

[[gnu::cold]] void VertexChoice::reset(ProgressiveMesh& base, const int32_t* coords,
                                       uint32_t position_bits, bool umbrella) {
  shift_ = umbrella_shift(position_bits);
  umbrella_ = umbrella;
  degree_.assign(base.vertex_count(), 0);
  sums_.assign(base.vertex_count(), RingSums{{0, 0, 0}, 0});
  key_.assign(base.vertex_count(), 0);
  for (uint32_t w = 0; w < base.vertex_count(); ++w) {
    if (base.gather_ring(w)) {
      degree_[w] = uint32_t(base.ring().size());
      RingSums& s = sums_[w];
      for (uint32_t x : umbrella ? base.ring() : std::span<const uint32_t>()) {
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
  cells_ = false;
  cell_.clear();
  bits_.clear();
  top_.clear();
  size_bitmap((size_t(base.vertex_count()) + 63) / 64);
}

void VertexChoice::start_group(bool near) {
  PMZ_CHOICE_ARRAYS;
  const size_t words = (degree_.size() + 63) / 64;       // every noted vertex is below the count
  if (near && bits_.size() < words) size_bitmap(words);  // writer only: the decoder reserve()d
  near_.swap(noted_);
  noted_.clear();
  if (!near) {
    near_.clear();
    return;
  }
  // A bitmap of the noted vertices and a summary of its nonzero words, then the set bits in
  // index order, clearing both on the way: work in the noted count and the summary's n / 4096
  // words (sorting them costs a mispredicted branch per comparison; no allocation: at most
  // near_.size() distinct).
  uint64_t* const bits = bits_.data();
  uint64_t* const top = top_.data();
  for (uint32_t w : near_) {
    bits[w >> 6] |= uint64_t(1) << (w & 63);
    top[w >> 12] |= uint64_t(1) << ((w >> 6) & 63);
  }
  near_.clear();
  for (size_t t = 0, e = top_.size(); t < e; ++t) {
    for (uint64_t y = top[t]; y; y &= y - 1) {
      const size_t i = t * 64 + uint32_t(__builtin_ctzll(y));
      uint64_t x = bits[i];
      bits[i] = 0;
      do {
        near_.push_back(uint32_t(i * 64 + uint32_t(__builtin_ctzll(x))));
        x &= x - 1;
      } while (x);
    }
    top[t] = 0;
  }
}

void VertexChoice::exclude(const ProgressiveMesh& mesh, uint32_t w) {
  PMZ_CHOICE_ARRAYS;
  mark_[w] = excluded_;
  mesh.for_each_fan_face(w, [&](uint32_t a, uint32_t b) { mark_[a] = mark_[b] = excluded_; });
}

bool VertexChoice::independent(const ProgressiveMesh& mesh, std::span<const uint32_t> vs) {
  PMZ_CHOICE_ARRAYS;
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
template <class V>
void make_room(V& b, size_t extra) {
  if (b.capacity() - b.size() < extra) b.reserve(std::max(b.size() + extra, 2 * b.capacity()));
}
}  // namespace

// u's entries, within the capacity reserve() made (no reallocation code: the decoder's library
// has a size budget); attached, at u in the owner's arrays (sized by it).
void VertexChoice::push_vertex(uint32_t u, uint32_t degree) {
  PMZ_CHOICE_ARRAYS;
  if (owner_) {
    degree_[u] = degree;
    mark_[u] = 0;
    key_[u] = 0;
    sums_[u] = RingSums{{0, 0, 0}, 0};
    return;
  }
  if (degree_.size() == degree_.capacity() || mark_.capacity() == mark_.size() ||
      key_.size() == key_.capacity() || sums_.size() == sums_.capacity())
    __builtin_unreachable();
  degree_.push_back(degree);
  mark_.push_back(0);
  key_.push_back(0);
  sums_.push_back(RingSums{{0, 0, 0}, 0});
}

PMZ_SMALL_IN_WASM void VertexChoice::grow(size_t k) {
  make_room(noted_, k + 2);
  if (!owner_) {
    make_room(degree_, 1);
    make_room(mark_, 1);
    make_room(sums_, 1);
    make_room(key_, 1);
  }
  make_room(cell_, 1);
  // start_group's bitmap for the vertex count after this split (it must not allocate then: the
  // group's state has begun to change).
  const size_t words = (shared().degree_.size() + 64) / 64;
  if (bits_.size() < words) {
    make_room(bits_, 1);
    make_room(top_, 1);
    size_bitmap(words);
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
  PMZ_CHOICE_ARRAYS;
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

// The speed level's keys (class 0): those of the vertices whose degree changed. Out of line:
// the default level's applied() stays as it was.
[[gnu::noinline]] void VertexChoice::degree_keys(const ProgressiveMesh& pm, bool has_left,
                                                 bool has_right) {
  const std::span<const uint32_t> ur = pm.u_ring();
  const uint32_t r = uint32_t(ur.size());
  update_key(ur[0]);
  update_key(pm.vertex_count() - 1);
  if (has_left) update_key(ur[1]);
  if (has_right) update_key(ur[r - 1]);
}

void VertexChoice::applied(const ProgressiveMesh& pm, const int32_t* coords, bool has_left,
                           bool has_right) {
  PMZ_CHOICE_ARRAYS;
  const std::span<const uint32_t> ring = pm.ring(), ur = pm.u_ring();
  const uint32_t v = ur[0], u = pm.vertex_count() - 1, r = uint32_t(ur.size());
  reserve(ring.size());  // (the decoder did, before the split)
  degree_[v] = uint32_t(ring.size()) + 2 + (has_left ? 1 : 0) + (has_right ? 1 : 0) - r;
  push_vertex(u, r);
  if (has_left) ++degree_[ur[1]];
  if (has_right) ++degree_[ur[r - 1]];
  if (umbrella_)
    umbrella(pm, coords, has_left, has_right);
  else
    degree_keys(pm, has_left, has_right);
  // Exclusion (the scan's caller applies the split when its closed one-ring starts to count).
  const uint32_t excluded = excluded_;
  mark_[v] = excluded;
  for (uint32_t w : ring) mark_[w] = excluded;
  noted_.insert(noted_.end(), ring.begin(), ring.end());
  noted_.push_back(v);
  noted_.push_back(u);
  if (cells_) cell_.push_back(u);
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

}  // namespace pmz
