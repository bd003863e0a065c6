// SPDX-License-Identifier: MIT
#include "pmz/progressive_mesh.hpp"

#include <algorithm>
#include <cstring>

namespace pmz {

// The arrays worked on (this object's, or attach()'s owner's), under the members' names.
#define PMZ_MESH_ARRAYS                             \
  ProgressiveMesh& mesh_arrays_ = arrays();         \
  auto& corner_vertex = mesh_arrays_.corner_vertex; \
  auto& opposite = mesh_arrays_.opposite;           \
  auto& vertex_corner = mesh_arrays_.vertex_corner; \
  (void)corner_vertex, (void)opposite, (void)vertex_corner

PMZ_SMALL_IN_WASM void ProgressiveMesh::grow_scratch(size_t need) {
  size_t cap = std::max<size_t>(64, scratch_cap_);
  while (cap < need) cap *= 2;
  for (auto* b : {&fan_, &ring_, &u_ring_, &sector_, &sector_corner_}) b->resize(cap);
  scratch_cap_ = cap;
}

bool ProgressiveMesh::gather_fan(uint32_t v) {
  PMZ_MESH_ARRAYS;
  fan_n_ = ring_n_ = 0;
  start_ = 0;
  closed_ = false;
  const uint32_t c0 = vertex_corner[v];
  if (c0 == kNoCorner) return false;
  if (scratch_cap_ < 64) grow_scratch(64);
  const uint32_t* opp = opposite.data();
  const uint32_t* cv = corner_vertex.data();
  uint32_t* fan = fan_.data();
  uint32_t* ring = ring_.data();
  // Counter-clockwise: the next face shares edge (v, prev vertex), opposite next(c). The walk
  // tracks n = next(c) (then n' = next(next(opp[n])) = prev(opp[n])), collects the ring on the
  // way and remembers where the smallest neighbour is (closed fans start there).
  // fan_ stores n per face (the corner at v is prev(n); same face).
  const uint32_t n0 = next_corner(c0);
  uint32_t n = n0, best = 0xFFFFFFFFu, i = 0, start = 0;
  size_t room = scratch_cap_ - 2;
  for (;;) {
    const uint32_t w = cv[n], o = opp[n];
    if (i >= room) [[unlikely]] {
      if (i > corner_vertex.size())
        break;  // a corrupt cycle not through c0: cannot happen on a valid table
      grow_scratch(scratch_cap_ * 2);
      room = scratch_cap_ - 2;
      fan = fan_.data();
      ring = ring_.data();
    }
    start = w < best ? i : start;
    best = w < best ? w : best;
    fan[i] = n;
    ring[i] = w;
    ++i;
    if (o == kNoCorner) break;
    n = prev_corner(o);
    if (n == n0) {
      fan_n_ = ring_n_ = i;
      start_ = start;
      closed_ = true;
      return true;
    }
  }
  // Open fan: walk clockwise from c0 to the boundary and put those faces first.
  const size_t cap = corner_vertex.size();
  uint32_t back = 0, c = c0;
  for (;;) {
    const uint32_t o = opp[prev_corner(c)];
    if (o == kNoCorner || back > cap) break;
    c = prev_corner(o);
    ++back;
  }
  if (back) {
    if (i + back + 2 >= scratch_cap_) {
      grow_scratch(i + back + 2);
      fan = fan_.data();
      ring = ring_.data();
    }
    std::memmove(fan + back, fan, i * sizeof *fan);
    // c is now the boundary face's corner: walk counter-clockwise again to fill the front.
    for (uint32_t j = 0; j < back; ++j) {
      fan[j] = next_corner(c);
      c = next_corner(opp[fan[j]]);
    }
    i += back;
    for (uint32_t j = 0; j < i; ++j) ring[j] = cv[fan[j]];
  }
  ring[i] = cv[next_corner(fan[i - 1])];  // the far side of the last face
  fan_n_ = i;
  ring_n_ = i + 1;
  return true;
}

bool ProgressiveMesh::gather_ring(uint32_t v) {
  if (v >= vertex_count()) {
    fan_n_ = ring_n_ = 0;
    return false;
  }
  return gather_fan(v);
}

uint32_t ProgressiveMesh::rank_of(uint32_t w) const {
  const uint32_t k = ring_n_;
  for (uint32_t i = 0; i < k; ++i)
    if (ring_[i] == w) return (i + k - start_) % k;
  return kNoRank;
}

bool ProgressiveMesh::split_gathered(uint32_t v, uint32_t a, uint32_t b) {
  PMZ_MESH_ARRAYS;
  const uint32_t m = fan_n_, k = ring_n_;
  uint32_t s, count;
  if (closed_) {
    if (a >= k || b >= k || a == b) return false;
    s = a;
    count = b > a ? b - a : b + m - a;
  } else {
    if (a == kNoRank && b == kNoRank) return false;
    if ((a != kNoRank && a >= k) || (b != kNoRank && b >= k)) return false;
    if (a != kNoRank && b != kNoRank && a >= b) return false;
    s = a == kNoRank ? 0 : a;
    count = (b == kNoRank ? m : b) - s;
  }
  const bool has_l = a != kNoRank, has_r = b != kNoRank;
  const uint32_t u = vertex_count();
  const uint32_t* fan = fan_.data();
  const uint32_t* ring = ring_.data();
  auto walk_pos = [&](uint32_t rank) {  // canonical rank -> position in the walk (< 2k)
    uint32_t p = rank + start_;
    return p >= k ? p - k : p;
  };
  if (closed_) s = walk_pos(s);
  const uint32_t vl = has_l ? ring[walk_pos(a)] : kNoCorner;
  const uint32_t vr = has_r ? ring[walk_pos(b)] : kNoCorner;

  // Read every old link before writing any (see spec for the pairing).
  uint32_t* cv = corner_vertex.data();
  uint32_t* opp = opposite.data();
  uint32_t pl = kNoCorner, ql = kNoCorner, pr = kNoCorner, qr = kNoCorner;
  // With c the corner at v of a fan face and n = next(c) (what fan_ holds): prev(c) = next(n).
  if (has_l) {
    if (count) {
      pl = next_corner(fan[s]);
      ql = opp[pl];
    } else {
      ql = fan[m - 1];
    }
  }
  if (has_r) {
    if (count) {
      uint32_t e = s + count - 1;
      pr = fan[e >= m ? e - m : e];
      qr = opp[pr];
    } else {
      qr = next_corner(fan[0]);
    }
  }

  // u's ring: v, then ring[s .. s + count] (walk positions, wrapping for closed fans), and
  // the sector's corners become u.
  uint32_t* ur = u_ring_.data();
  uint32_t* sec = sector_.data();
  uint32_t* sc = sector_corner_.data();
  ur[0] = v;
  for (uint32_t i = 0, j = s; i <= count; ++i) {
    ur[i + 1] = ring[j];
    j = j + 1 == k ? 0 : j + 1;
  }
  for (uint32_t i = 0, j = s; i < count; ++i) {
    const uint32_t n = fan[j];
    cv[prev_corner(n)] = u;
    sec[i] = n / 3;
    sc[i] = n;
    j = j + 1 == m ? 0 : j + 1;
  }
  u_ring_n_ = count + 2;
  sector_n_ = count;
  hint_ = count ? fan[s] : has_r ? fan[0] : fan[m - 1];
  link_new_faces(v, vl, vr, pl, ql, pr, qr, has_l, has_r);
  return true;
}

void ProgressiveMesh::resplit(uint32_t v, uint32_t h, uint32_t count, bool has_l, bool has_r) {
  PMZ_MESH_ARRAYS;
  if (count > scratch_cap_) grow_scratch(count);
  // h = fan[s]: the sector's fan entries along the fan from there (the walk reads only
  // opposite, which the sector's rewrite does not change), then as from a list.
  uint32_t* sc = sector_corner_.data();
  for (uint32_t i = 0, n = h; i < count; ++i, n = prev_corner(opposite[n])) sc[i] = n;
  resplit_listed(v, sc, count, h, has_l, has_r);
}

void ProgressiveMesh::resplit_listed(uint32_t v, const uint32_t* sector, uint32_t count, uint32_t h,
                                     bool has_l, bool has_r) {
  PMZ_MESH_ARRAYS;
  if (count > scratch_cap_) grow_scratch(count);
  const uint32_t u = vertex_count();
  uint32_t* cv = corner_vertex.data();
  const uint32_t* opp = opposite.data();
  uint32_t* sec = sector_.data();
  uint32_t vl = kNoCorner, vr = kNoCorner, pl = kNoCorner, ql = kNoCorner, pr = kNoCorner,
           qr = kNoCorner;
  if (count) {  // the same reads as split_gathered(), from the sector's first and last faces
    h = sector[0];
    const uint32_t last = sector[count - 1];
    if (has_l) {
      pl = next_corner(h);
      ql = opp[pl];
      vl = cv[h];
    }
    if (has_r) {
      pr = last;
      qr = opp[last];
      vr = cv[next_corner(last)];
    }
    for (uint32_t i = 0; i < count; ++i) {
      const uint32_t n = sector[i];
      cv[prev_corner(n)] = u;
      sec[i] = n / 3;
    }
  } else if (has_r) {  // h = fan[0]
    qr = next_corner(h);
    vr = cv[h];
  } else {  // h = fan[m - 1]
    ql = h;
    vl = cv[next_corner(h)];
  }
  u_ring_n_ = 0;
  sector_n_ = count;
  hint_ = h;
  link_new_faces(v, vl, vr, pl, ql, pr, qr, has_l, has_r);
}

#if defined(__wasm__)
namespace {
// A new face: its corners' vertices (x, y, z) and opposite corners (ox, oy, oz), in the
// WebAssembly build with one out-of-line push_back call per array (smaller there).
[[gnu::noinline]] void append3(BigVector<uint32_t>& b, uint32_t x, uint32_t y, uint32_t z) {
  b.push_back(x);
  b.push_back(y);
  b.push_back(z);
}
}  // namespace
#endif

void ProgressiveMesh::link_new_faces(uint32_t v, uint32_t vl, uint32_t vr, uint32_t pl, uint32_t ql,
                                     uint32_t pr, uint32_t qr, bool has_l, bool has_r) {
  PMZ_MESH_ARRAYS;
  const uint32_t u = vertex_count(), F = face_count();
  uint32_t* opp = opposite.data();
  const uint32_t f0 = 3 * F, g0 = 3 * (F + (has_l ? 1 : 0));
  const uint32_t across = has_l && has_r;  // the two new faces share edge (u, v)
  if (has_l) {
    if (ql != kNoCorner) opp[ql] = f0;
    if (pl != kNoCorner) opp[pl] = f0 + 1;
  }
  if (has_r) {
    if (pr != kNoCorner) opp[pr] = g0;
    if (qr != kNoCorner) opp[qr] = g0 + 1;
  }
#if defined(__wasm__)
  // The WebAssembly build appends to its own arrays with push_back calls (smaller there); an
  // attached mesh (a node's worker) stores into the owner's, as natively.
  if (!owner_) {
    if (has_l) {
      append3(corner_vertex, u, v, vl);
      append3(opposite, ql, pl, across ? g0 + 2 : kNoCorner);
    }
    if (has_r) {
      append3(corner_vertex, v, u, vr);
      append3(opposite, pr, qr, across ? f0 + 2 : kNoCorner);
    }
  } else
#endif
  {
    // Natively both faces at once: one resize per buffer (the decoder reserved the capacity),
    // then plain stores. Six push_backs out of line cost about 112 instructions per split;
    // inlined, about 2 KB of the decoder library's size budget.
    const size_t at = size_t(F) * 3;
#if !defined(__wasm__)
    if (!owner_) {  // (attached: the owner's arrays hold the faces already)
      const size_t n = 3 * ((has_l ? 1 : 0) + (has_r ? 1 : 0));
      corner_vertex.resize(at + n);
      opposite.resize(at + n);
    }
#endif
    uint32_t* c = corner_vertex.data() + at;
    uint32_t* o = opposite.data() + at;
    if (has_l) {
      c[0] = u, c[1] = v, c[2] = vl;
      o[0] = ql, o[1] = pl, o[2] = across ? g0 + 2 : kNoCorner;
      c += 3, o += 3;
    }
    if (has_r) {
      c[0] = v, c[1] = u, c[2] = vr;
      o[0] = pr, o[1] = qr, o[2] = across ? f0 + 2 : kNoCorner;
    }
  }
  if (owner_) {
    vertex_corner[u] = has_l ? f0 : g0 + 1;
    ++vn_;
    fn_ += (has_l ? 1 : 0) + (has_r ? 1 : 0);
  } else {
    vertex_corner.push_back(has_l ? f0 : g0 + 1);
  }
  vertex_corner[v] = has_l ? f0 + 1 : g0;
}

PMZ_SMALL_IN_WASM void ProgressiveMesh::undo_split(uint32_t v, bool has_l, bool has_r) {
  PMZ_MESH_ARRAYS;
  const uint32_t u = vertex_count() - 1;
  const uint32_t limit = 3 * (face_count() - (has_l ? 1 : 0) - (has_r ? 1 : 0));
  gather_fan(u);
  sector_n_ = 0;
  for (uint32_t i = 0; i < fan_n_; ++i) {
    const uint32_t n = fan_[i];  // next of u's corner: same face
    if (n >= limit) continue;
    corner_vertex[prev_corner(n)] = v;
    sector_[sector_n_++] = n / 3;
  }
  unlink_new_faces(v, has_l, has_r);
}

PMZ_SMALL_IN_WASM void ProgressiveMesh::undo_resplit(uint32_t v, uint32_t h, uint32_t count,
                                                     bool has_l, bool has_r) {
  PMZ_MESH_ARRAYS;
  if (count > scratch_cap_) grow_scratch(count);
  // u's fan is [left face], the sector from h in order, [right face]: the order undo_split()
  // finds the sector in. The links inside the sector are those of before the split.
  uint32_t* cv = corner_vertex.data();
  const uint32_t* opp = opposite.data();
  uint32_t* sec = sector_.data();
  for (uint32_t i = 0, n = h; i < count; ++i, n = prev_corner(opp[n])) {
    cv[prev_corner(n)] = v;
    sec[i] = n / 3;
  }
  sector_n_ = count;
  unlink_new_faces(v, has_l, has_r);
}

PMZ_SMALL_IN_WASM void ProgressiveMesh::unlink_new_faces(uint32_t v, bool has_l, bool has_r) {
  PMZ_MESH_ARRAYS;
  const uint32_t nf = (has_l ? 1 : 0) + (has_r ? 1 : 0);
  const uint32_t limit = 3 * (face_count() - nf);
  const uint32_t f0 = limit, g0 = limit + (has_l ? 3 : 0);
  const uint32_t vl = has_l ? corner_vertex[f0 + 2] : kNoCorner;
  const uint32_t vr = has_r ? corner_vertex[g0 + 2] : kNoCorner;
  uint32_t links[4] = {kNoCorner, kNoCorner, kNoCorner, kNoCorner};
  if (has_l) {
    uint32_t p = opposite[f0 + 1], q = opposite[f0];
    if (p != kNoCorner) opposite[p] = q;
    if (q != kNoCorner) opposite[q] = p;
    links[0] = p;
    links[1] = q;
  }
  if (has_r) {
    uint32_t p = opposite[g0], q = opposite[g0 + 1];
    if (p != kNoCorner) opposite[p] = q;
    if (q != kNoCorner) opposite[q] = p;
    links[2] = p;
    links[3] = q;
  }
  if (owner_) {
    --vn_;
    fn_ -= nf;
  } else {
    corner_vertex.resize(limit);
    opposite.resize(limit);
    vertex_corner.pop_back();
  }
  // v, vl and vr may have pointed into the removed faces: repoint to a neighbouring face.
  for (uint32_t x : {v, vl, vr}) {
    if (x == kNoCorner || (vertex_corner[x] != kNoCorner && vertex_corner[x] < limit)) continue;
    vertex_corner[x] = kNoCorner;
    for (uint32_t l : links) {
      if (l == kNoCorner) continue;
      uint32_t f = l - l % 3;
      for (uint32_t c = f; c < f + 3; ++c)
        if (corner_vertex[c] == x) vertex_corner[x] = c;
    }
  }
}

}  // namespace pmz
