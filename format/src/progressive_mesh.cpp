#include "pmz/progressive_mesh.hpp"

#include <algorithm>

namespace pmz {

namespace {
inline uint32_t next_corner(uint32_t c) { return c % 3 == 2 ? c - 2 : c + 1; }
inline uint32_t prev_corner(uint32_t c) { return c % 3 == 0 ? c + 2 : c - 1; }
}  // namespace

bool ProgressiveMesh::build(uint32_t n, const uint32_t* indices, size_t faces, std::string& error) {
  corner_vertex.assign(indices, indices + faces * 3);
  opposite.assign(faces * 3, kNoCorner);
  vertex_corner.assign(n, kNoCorner);
  // Directed edge (from, to) of corner c is the edge opposite c: next(c) -> prev(c).
  std::vector<uint64_t> edges(faces * 3);
  for (uint32_t c = 0; c < faces * 3; ++c) {
    uint32_t a = corner_vertex[c];
    if (a >= n) return error = "face index out of range", false;
    uint32_t f = c - c % 3;
    if (corner_vertex[f] == corner_vertex[f + 1] || corner_vertex[f] == corner_vertex[f + 2] ||
        corner_vertex[f + 1] == corner_vertex[f + 2])
      return error = "degenerate face", false;
    vertex_corner[a] = c;
  }
  std::vector<uint32_t> order(faces * 3);
  for (uint32_t c = 0; c < faces * 3; ++c) {
    edges[c] = uint64_t(corner_vertex[next_corner(c)]) << 32 | corner_vertex[prev_corner(c)];
    order[c] = c;
  }
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return edges[a] < edges[b]; });
  for (size_t i = 1; i < order.size(); ++i)
    if (edges[order[i]] == edges[order[i - 1]]) return error = "non-manifold edge", false;
  for (uint32_t c = 0; c < faces * 3; ++c) {
    uint64_t twin = edges[c] << 32 | edges[c] >> 32;
    auto it = std::lower_bound(order.begin(), order.end(), twin,
                               [&](uint32_t x, uint64_t key) { return edges[x] < key; });
    if (it != order.end() && edges[*it] == twin) opposite[c] = *it;
  }
  return true;
}

bool ProgressiveMesh::gather_fan(uint32_t v) {
  fan_.clear();
  ring_.clear();
  start_ = 0;
  closed_ = false;
  const uint32_t c0 = vertex_corner[v];
  if (c0 == kNoCorner) return false;
  const uint32_t* opp = opposite.data();
  const uint32_t* cv = corner_vertex.data();
  const size_t cap = corner_vertex.size();
  // Counter-clockwise: the next face shares edge (v, prev vertex), opposite next(c). Collect
  // the ring on the way and remember where the smallest neighbour is (closed fans start there).
  uint32_t c = c0, best = 0xFFFFFFFFu;
  do {
    const uint32_t n = next_corner(c), w = cv[n];
    if (w < best) {
      best = w;
      start_ = uint32_t(fan_.size());
    }
    fan_.push_back(c);
    ring_.push_back(w);
    const uint32_t o = opp[n];
    if (o == kNoCorner) break;
    c = next_corner(o);
    if (c == c0) {
      closed_ = true;
      return true;
    }
  } while (fan_.size() <= cap);
  // Open fan: walk clockwise from c0 to the boundary and put those faces first.
  start_ = 0;
  back_.clear();
  c = c0;
  for (;;) {
    const uint32_t o = opp[prev_corner(c)];
    if (o == kNoCorner || back_.size() > cap) break;
    c = prev_corner(o);
    back_.push_back(c);
  }
  if (!back_.empty()) {
    fan_.insert(fan_.begin(), back_.rbegin(), back_.rend());
    ring_.clear();
    for (uint32_t f : fan_) ring_.push_back(cv[next_corner(f)]);
  }
  ring_.push_back(cv[prev_corner(fan_.back())]);
  return true;
}

bool ProgressiveMesh::gather_ring(uint32_t v) {
  if (v >= vertex_count()) {
    fan_.clear();
    ring_.clear();
    return false;
  }
  return gather_fan(v);
}

uint32_t ProgressiveMesh::rank_of(uint32_t w) const {
  const uint32_t k = uint32_t(ring_.size());
  for (uint32_t i = 0; i < k; ++i)
    if (ring_[i] == w) return (i + k - start_) % k;
  return kNoRank;
}

bool ProgressiveMesh::split_gathered(uint32_t v, uint32_t a, uint32_t b) {
  const uint32_t m = uint32_t(fan_.size()), k = uint32_t(ring_.size());
  uint32_t s, count;
  if (closed_) {
    if (a >= k || b >= k || a == b) return false;
    s = a;
    count = (b + m - a) % m;
  } else {
    if (a == kNoRank && b == kNoRank) return false;
    if ((a != kNoRank && a >= k) || (b != kNoRank && b >= k)) return false;
    if (a != kNoRank && b != kNoRank && a >= b) return false;
    s = a == kNoRank ? 0 : a;
    count = (b == kNoRank ? m : b) - s;
  }
  const bool has_l = a != kNoRank, has_r = b != kNoRank;
  const uint32_t u = vertex_count(), F = face_count();
  if (closed_) s = (s + start_) % m;  // canonical rank -> position in the walk
  const uint32_t vl = has_l ? ring_[(a + start_) % k] : kNoCorner;
  const uint32_t vr = has_r ? ring_[(b + start_) % k] : kNoCorner;

  // Read every old link before writing any (see spec for the pairing).
  uint32_t pl = kNoCorner, ql = kNoCorner, pr = kNoCorner, qr = kNoCorner;
  if (has_l) {
    if (count) {
      pl = prev_corner(fan_[s]);
      ql = opposite[pl];
    } else {
      ql = next_corner(fan_[m - 1]);
    }
  }
  if (has_r) {
    if (count) {
      pr = next_corner(fan_[(s + count - 1) % m]);
      qr = opposite[pr];
    } else {
      qr = prev_corner(fan_[0]);
    }
  }

  u_ring_.clear();
  u_ring_.push_back(v);
  sector_.clear();
  for (uint32_t i = 0, j = s; i <= count; ++i, j = j + 1 == k ? 0 : j + 1) u_ring_.push_back(ring_[j]);
  for (uint32_t i = 0, j = s % m; i < count; ++i, j = j + 1 == m ? 0 : j + 1) {
    uint32_t c = fan_[j];
    corner_vertex[c] = u;
    sector_.push_back(c / 3);
  }

  const uint32_t f0 = 3 * F, g0 = 3 * (F + (has_l ? 1 : 0));
  const size_t end = size_t(g0) + (has_r ? 3 : 0);
  corner_vertex.resize(end);
  opposite.resize(end);
  uint32_t* cv = corner_vertex.data();
  uint32_t* opp = opposite.data();
  if (has_l) {
    cv[f0] = u, cv[f0 + 1] = v, cv[f0 + 2] = vl;
    opp[f0] = ql, opp[f0 + 1] = pl, opp[f0 + 2] = kNoCorner;
    if (ql != kNoCorner) opp[ql] = f0;
    if (pl != kNoCorner) opp[pl] = f0 + 1;
  }
  if (has_r) {
    cv[g0] = v, cv[g0 + 1] = u, cv[g0 + 2] = vr;
    opp[g0] = pr, opp[g0 + 1] = qr, opp[g0 + 2] = kNoCorner;
    if (pr != kNoCorner) opp[pr] = g0;
    if (qr != kNoCorner) opp[qr] = g0 + 1;
  }
  if (has_l && has_r) {
    opposite[f0 + 2] = g0 + 2;
    opposite[g0 + 2] = f0 + 2;
  }
  vertex_corner.push_back(has_l ? f0 : g0 + 1);
  vertex_corner[v] = has_l ? f0 + 1 : g0;
  return true;
}

void ProgressiveMesh::undo_split(uint32_t v, bool has_l, bool has_r) {
  const uint32_t u = vertex_count() - 1;
  const uint32_t nf = (has_l ? 1 : 0) + (has_r ? 1 : 0);
  const uint32_t limit = 3 * (face_count() - nf);
  const uint32_t f0 = limit, g0 = limit + (has_l ? 3 : 0);
  const uint32_t vl = has_l ? corner_vertex[f0 + 2] : kNoCorner;
  const uint32_t vr = has_r ? corner_vertex[g0 + 2] : kNoCorner;

  sector_.clear();
  gather_fan(u);
  for (uint32_t c : fan_) {
    if (c >= limit) continue;
    corner_vertex[c] = v;
    sector_.push_back(c / 3);
  }
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
  corner_vertex.resize(limit);
  opposite.resize(limit);
  vertex_corner.pop_back();
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

