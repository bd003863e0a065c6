// SPDX-License-Identifier: MIT
// Attribute error at corresponding surface points: a sample on ORIGINAL, the closest point on
// OTHER, the attributes interpolated at both compared (texture space, normal angle, colour).
#include "compare_attributes.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "sampling.hpp"

namespace pmz {

namespace {

constexpr uint32_t kBlockFaces = 2048;
constexpr double kDegreesPerRadian =
    57.295779513082321;  // fixed blocks reduced in order: any thread count agrees

using sampling::triangle_area;
using sampling::uniform01;

double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Barycentric coordinates of the point of triangle (a, b, c) closest to p (Ericson, Real-Time
// Collision Detection 5.1.5); a degenerate triangle gives its first corner.
void closest_barycentric(const double p[3], const float* fa, const float* fb, const float* fc,
                         double w[3]) {
  double ab[3], ac[3], ap[3], bp[3], cp[3];
  for (int k = 0; k < 3; ++k)
    ab[k] = double(fb[k]) - fa[k], ac[k] = double(fc[k]) - fa[k], ap[k] = p[k] - fa[k],
    bp[k] = p[k] - fb[k], cp[k] = p[k] - fc[k];
  auto set = [&](double a, double b, double c) { w[0] = a, w[1] = b, w[2] = c; };
  const double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
  if (d1 <= 0 && d2 <= 0) return set(1, 0, 0);
  const double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
  if (d3 >= 0 && d4 <= d3) return set(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double t = d1 - d3 != 0 ? d1 / (d1 - d3) : 0;
    return set(1 - t, t, 0);
  }
  const double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
  if (d6 >= 0 && d5 <= d6) return set(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 - d6 != 0 ? d2 / (d2 - d6) : 0;
    return set(1 - t, 0, t);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double den = (d4 - d3) + (d5 - d6);
    const double t = den != 0 ? (d4 - d3) / den : 0;
    return set(0, 1 - t, t);
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) return set(1, 0, 0);
  set(va / sum, vb / sum, vc / sum);
}

// One attribute of one mesh: `components` values per wedge, interpolated over a face.
struct Field {
  const std::vector<float>* values = nullptr;
  uint32_t stride = 0, components = 0;
  const float* at(const IndexedMesh& m, size_t corner) const {
    return values->data() + size_t(m.attributes.corner_wedges[corner]) * stride;
  }
  void interpolate(const IndexedMesh& m, uint32_t f, const double w[3], double* out) const {
    for (uint32_t i = 0; i < components; ++i) out[i] = 0;
    for (int k = 0; k < 3; ++k) {
      const float* v = at(m, size_t(f) * 3 + k);
      for (uint32_t i = 0; i < components; ++i) out[i] += w[k] * v[i];
    }
  }
  bool same(const IndexedMesh& m, size_t c, size_t d) const {
    const float *a = at(m, c), *b = at(m, d);
    for (uint32_t i = 0; i < components; ++i)
      if (!(a[i] == b[i])) return false;
    return true;
  }
};

double distance(const double* a, const double* b, uint32_t components) {
  double d2 = 0;
  for (uint32_t i = 0; i < components; ++i) d2 += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(d2);
}

// Vertices grouped by position value (a format that splits seam vertices into copies gives
// the same groups): position_of[v], and the number of positions.
uint32_t group_positions(const IndexedMesh& m, std::vector<uint32_t>& position_of) {
  const uint32_t nv = m.vertex_count();
  auto key = [&](uint32_t v) {
    std::array<uint32_t, 3> bits;
    for (int k = 0; k < 3; ++k) {
      const float x = m.positions[size_t(v) * 3 + k] + 0.0f;  // -0 as +0
      std::memcpy(&bits[k], &x, 4);
    }
    return bits;
  };
  std::vector<uint32_t> order(nv);
  for (uint32_t v = 0; v < nv; ++v) order[v] = v;
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
  position_of.assign(nv, 0);
  uint32_t positions = 0;
  for (uint32_t i = 0; i < nv; ++i) {
    if (i > 0 && key(order[i]) != key(order[i - 1])) ++positions;
    position_of[order[i]] = positions;
  }
  return nv ? positions + 1 : 0;
}

// Texture charts: faces joined across edges whose two ends agree in position and in texture
// coordinates, numbered from 0 in the order of their first faces.
std::vector<uint32_t> texture_charts(const IndexedMesh& m, const Field& uv,
                                     const std::vector<uint32_t>& position_of) {
  const uint32_t faces = m.face_count();
  std::vector<uint32_t> parent(faces);
  for (uint32_t f = 0; f < faces; ++f) parent[f] = f;
  auto find = [&](uint32_t f) {
    while (parent[f] != f) f = parent[f] = parent[parent[f]];
    return f;
  };
  struct Edge {
    uint64_t key;     // the two positions, lower first
    uint32_t lo, hi;  // the face's corners at the lower and the higher position
  };
  std::vector<Edge> edges;
  edges.reserve(m.indices.size());
  for (uint32_t c = 0; c < m.indices.size(); ++c) {
    uint32_t lo = c, hi = c / 3 * 3 + (c % 3 + 1) % 3;
    uint64_t a = position_of[m.indices[lo]], b = position_of[m.indices[hi]];
    if (a == b) continue;
    if (a > b) std::swap(a, b), std::swap(lo, hi);
    edges.push_back({a << 32 | b, lo, hi});
  }
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
    return x.key < y.key || (x.key == y.key && x.lo < y.lo);
  });
  constexpr size_t kFan = 16;  // faces of a non-manifold edge: each against the next 16 on it
  for (size_t i = 0, j; i < edges.size(); i = j) {
    for (j = i + 1; j < edges.size() && edges[j].key == edges[i].key;) ++j;
    for (size_t x = i; x < j; ++x)
      for (size_t y = x + 1; y < std::min(j, x + 1 + kFan); ++y)
        if (uv.same(m, edges[x].lo, edges[y].lo) && uv.same(m, edges[x].hi, edges[y].hi))
          parent[find(edges[x].lo / 3)] = find(edges[y].lo / 3);
  }
  std::vector<uint32_t> chart(faces), id(faces, UINT32_MAX);
  uint32_t charts = 0;
  for (uint32_t f = 0; f < faces; ++f) {
    const uint32_t r = find(f);
    if (id[r] == UINT32_MAX) id[r] = charts++;
    chart[f] = id[r];
  }
  return chart;
}

// For each face of OTHER, the chart of ORIGINAL it stands for: every chart of OTHER takes the
// ORIGINAL chart under most of its area (by the closest ORIGINAL face to each face's centroid).
std::vector<uint32_t> chart_labels(const IndexedMesh& other, const std::vector<uint32_t>& charts,
                                   const std::vector<uint32_t>& original_charts,
                                   const TriangleBvh& to_original, unsigned threads) {
  const uint32_t faces = other.face_count();
  std::vector<uint32_t> under(faces);
  const float* pos = other.positions.data();
  const uint32_t* idx = other.indices.data();
  sampling::for_each_block(
      (faces + kBlockFaces - 1) / kBlockFaces, threads, [&](uint64_t block, uint32_t& hint) {
        const uint32_t end = uint32_t(std::min<uint64_t>(faces, (block + 1) * kBlockFaces));
        for (uint32_t f = uint32_t(block * kBlockFaces); f < end; ++f) {
          double c[3] = {0, 0, 0};
          for (int k = 0; k < 3; ++k)
            for (int i = 0; i < 3; ++i) c[i] += pos[size_t(idx[f * 3 + k]) * 3 + i] / 3.0;
          to_original.closest_distance2(c, hint);
          under[f] = original_charts[to_original.face_of(hint)];
        }
      });
  std::vector<std::pair<uint64_t, double>> votes(faces);  // (chart << 32 | chart under, area)
  for (uint32_t f = 0; f < faces; ++f)
    votes[f] = {uint64_t(charts[f]) << 32 | under[f],
                triangle_area(pos + size_t(idx[f * 3]) * 3, pos + size_t(idx[f * 3 + 1]) * 3,
                              pos + size_t(idx[f * 3 + 2]) * 3)};
  std::sort(votes.begin(), votes.end());
  std::vector<uint32_t> best(faces ? *std::max_element(charts.begin(), charts.end()) + 1 : 0);
  std::vector<double> best_area(best.size(), -1);
  for (size_t i = 0, j; i < votes.size(); i = j) {
    double area = 0;
    for (j = i; j < votes.size() && votes[j].first == votes[i].first; ++j) area += votes[j].second;
    const uint32_t chart = uint32_t(votes[i].first >> 32);
    if (area > best_area[chart]) best_area[chart] = area, best[chart] = uint32_t(votes[i].first);
  }
  std::vector<uint32_t> labels(faces);
  for (uint32_t f = 0; f < faces; ++f) labels[f] = best[charts[f]];
  return labels;
}

// The texture seams of a mesh: at a seam one position carries several texture coordinates
// (one per chart meeting there).
struct Seams {
  std::vector<uint32_t> position_of;  // vertex -> position
  std::vector<uint32_t> first;        // position -> its corners: corners[first[p], first[p + 1])
  std::vector<uint32_t> corners;
  std::vector<uint8_t> face_on_seam;  // a corner of the face is on a seam

  void build(const IndexedMesh& m, const Field& uv) {
    const uint32_t positions = group_positions(m, position_of);
    first.assign(size_t(positions) + 1, 0);
    for (uint32_t v : m.indices) ++first[position_of[v] + 1];
    for (uint32_t p = 0; p < positions; ++p) first[p + 1] += first[p];
    corners.resize(m.indices.size());
    std::vector<uint32_t> next(first.begin(), first.end() - 1);
    for (uint32_t c = 0; c < m.indices.size(); ++c) corners[next[position_of[m.indices[c]]]++] = c;
    face_on_seam.assign(m.face_count(), 0);
    for (uint32_t p = 0; p < positions; ++p) {
      bool seam = false;
      for (uint32_t i = first[p] + 1; i < first[p + 1] && !seam; ++i)
        seam = !uv.same(m, corners[first[p]], corners[i]);
      for (uint32_t i = first[p]; i < first[p + 1] && seam; ++i) face_on_seam[corners[i] / 3] = 1;
    }
  }

  // The smallest texture error at sample p (texture coordinates `want`) over the faces across
  // a seam from face g (another chart's coordinates at one of g's corners), each at its point
  // closest to p; `best` when none is smaller.
  double across(const IndexedMesh& m, const Field& uv, uint32_t g, const double p[3],
                const double* want, double best) const {
    if (!face_on_seam[g]) return best;
    const float* pos = m.positions.data();
    const uint32_t* idx = m.indices.data();
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t c = g * 3 + k, at = position_of[idx[c]];
      for (uint32_t i = first[at]; i < first[at + 1]; ++i) {
        const uint32_t h = corners[i] / 3;
        if (h == g || uv.same(m, c, corners[i])) continue;
        double w[3], v[4];
        closest_barycentric(p, pos + size_t(idx[h * 3]) * 3, pos + size_t(idx[h * 3 + 1]) * 3,
                            pos + size_t(idx[h * 3 + 2]) * 3, w);
        uv.interpolate(m, h, w, v);
        best = std::min(best, distance(want, v, uv.components));
      }
    }
    return best;
  }
};

// Texture error at corresponding points that respects charts: the smallest |delta uv| over the
// closest face of OTHER and the closest face of OTHER's part of the sample's own chart, each
// with the faces across a seam at its corners (Seams::across). The second lookup matters where
// two charts lie within a position step of each other: sheets that touch or cross.
struct TextureLookup {
  Seams seams;
  std::vector<uint32_t> chart;     // ORIGINAL face -> its chart
  std::vector<uint32_t> label;     // OTHER face -> the ORIGINAL chart it stands for
  std::vector<uint8_t> has_faces;  // ORIGINAL chart -> some OTHER face stands for it

  void build(const IndexedMesh& original, const IndexedMesh& other, const Field& uv_original,
             const Field& uv_other, const TriangleBvh& to_original, unsigned threads) {
    seams.build(other, uv_other);
    std::vector<uint32_t> position_of;
    group_positions(original, position_of);
    chart = texture_charts(original, uv_original, position_of);
    label = chart_labels(other, texture_charts(other, uv_other, seams.position_of), chart,
                         to_original, threads);
    has_faces.assign(chart.empty() ? 0 : *std::max_element(chart.begin(), chart.end()) + 1, 0);
    for (uint32_t c : label) has_faces[c] = 1;
  }

  // |delta uv| at sample p of ORIGINAL face f (texture coordinates want), whose closest face of
  // OTHER is g at barycentric w; chart_hint: the search hint of the chart-bound lookup.
  double error(const IndexedMesh& other, const TriangleBvh& to_other, const Field& uv, uint32_t f,
               uint32_t g, const double p[3], const double w[3], const double* want,
               uint32_t& chart_hint) const {
    double v[4], bw[3];
    uv.interpolate(other, g, w, v);
    double e = seams.across(other, uv, g, p, want, distance(want, v, uv.components));
    const uint32_t c = chart[f];
    if (e > 0 && label[g] != c && has_faces[c] &&
        to_other.closest_distance2(p, chart_hint, label.data(), c) <
            std::numeric_limits<double>::infinity()) {
      const float* t = to_other.triangle(chart_hint);
      closest_barycentric(p, t, t + 3, t + 6, bw);
      const uint32_t h = to_other.face_of(chart_hint);
      uv.interpolate(other, h, bw, v);
      e = seams.across(other, uv, h, p, want, std::min(e, distance(want, v, uv.components)));
    }
    return e;
  }
};

enum Kind { kTexcoord, kNormal, kColor, kKinds };

struct Partial {
  double sum[kKinds] = {}, sum2[kKinds] = {}, max[kKinds] = {};
  uint64_t n[kKinds] = {};
};

}  // namespace

void compare_attributes(const IndexedMesh& original, const IndexedMesh& other,
                        const TriangleBvh& to_other, const TriangleBvh* to_original,
                        uint64_t face_samples, uint64_t seed, unsigned threads,
                        AttributeErrors& out) {
  out = AttributeErrors();
  const MeshAttributes &a = original.attributes, &b = other.attributes;
  if (a.corner_wedges.size() != original.indices.size() ||
      b.corner_wedges.size() != other.indices.size() || original.indices.empty())
    return;
  // Inconsistent arrays (a caller's, not a reader's: those are checked) are not read past.
  auto in_range = [](const MeshAttributes& m) {
    return std::all_of(m.corner_wedges.begin(), m.corner_wedges.end(),
                       [&](uint32_t w) { return w < m.wedge_count(); });
  };
  if (!in_range(a) || !in_range(b)) return;
  // Each kind measured when both meshes have one value per wedge.
  Field fa[kKinds], fb[kKinds];
  auto pick = [](const MeshAttributes& m, Kind kind, Field& f) {
    const std::vector<float>* v = nullptr;
    uint32_t stride = 0;
    if (kind == kTexcoord && !m.texcoords.empty()) v = &m.texcoords[0], stride = 2;
    if (kind == kNormal && !m.normals.empty()) v = &m.normals, stride = 3;
    if (kind == kColor && !m.colors.empty()) v = &m.colors, stride = m.color_components;
    if (v && stride && v->size() >= size_t(m.wedge_count()) * stride) f = {v, stride, stride};
  };
  bool any = false;
  for (int k = 0; k < kKinds; ++k) {
    pick(a, Kind(k), fa[k]);
    pick(b, Kind(k), fb[k]);
    if (!fa[k].values || !fb[k].values) {
      fa[k].values = nullptr;
      continue;
    }
    fa[k].components = fb[k].components = std::min(fa[k].components, fb[k].components);
    any = true;
  }
  if (!any) return;
  TextureLookup texture;
  if (fa[kTexcoord].values) {
    TriangleBvh built;
    if (!to_original)
      built.build(original.positions.data(), original.indices.data(), original.face_count());
    texture.build(original, other, fa[kTexcoord], fb[kTexcoord], to_original ? *to_original : built,
                  threads);
  }

  const float* pos = original.positions.data();
  const uint32_t* idx = original.indices.data();
  const uint32_t faces = original.face_count();
  double total_area = 0;
  for (uint32_t f = 0; f < faces; ++f)
    total_area += triangle_area(pos + size_t(idx[f * 3]) * 3, pos + size_t(idx[f * 3 + 1]) * 3,
                                pos + size_t(idx[f * 3 + 2]) * 3);
  const double density = total_area > 0 ? double(face_samples) / total_area : 0;
  const uint64_t blocks = (faces + kBlockFaces - 1) / kBlockFaces;
  std::vector<Partial> partials(blocks);
  sampling::for_each_block(blocks, threads, [&](uint64_t block, uint32_t& hint) {
    Partial acc;
    uint32_t chart_hint = 0xFFFFFFFFu;
    const uint32_t end = uint32_t(std::min<uint64_t>(faces, (block + 1) * kBlockFaces));
    for (uint32_t f = uint32_t(block * kBlockFaces); f < end; ++f) {
      uint64_t rng = seed ^ (uint64_t(f) * 0xD1B54A32D192ED03ull);
      const float* pa = pos + size_t(idx[f * 3]) * 3;
      const float* pb = pos + size_t(idx[f * 3 + 1]) * 3;
      const float* pc = pos + size_t(idx[f * 3 + 2]) * 3;
      const uint64_t n = uint64_t(triangle_area(pa, pb, pc) * density + uniform01(rng));
      for (uint64_t s = 0; s < n; ++s) {
        double w[3];
        sampling::uniform_barycentric(rng, w);
        double p[3];
        for (int k = 0; k < 3; ++k) p[k] = w[0] * pa[k] + w[1] * pb[k] + w[2] * pc[k];
        to_other.closest_distance2(p, hint);
        const float* t = to_other.triangle(hint);
        double wo[3];
        closest_barycentric(p, t, t + 3, t + 6, wo);
        const uint32_t g = to_other.face_of(hint);
        for (int k = 0; k < kKinds; ++k) {
          if (!fa[k].values) continue;
          double va[4], vb[4];
          fa[k].interpolate(original, f, w, va);
          fb[k].interpolate(other, g, wo, vb);
          double e;
          if (k == kTexcoord) {
            e = texture.error(other, to_other, fb[k], f, g, p, wo, va, chart_hint);
          } else if (k == kNormal) {
            const double la = std::sqrt(dot3(va, va)), lb = std::sqrt(dot3(vb, vb));
            if (!(la > 0) || !(lb > 0)) continue;
            e = std::acos(std::clamp(dot3(va, vb) / (la * lb), -1.0, 1.0)) * kDegreesPerRadian;
          } else {
            e = distance(va, vb, fa[k].components);
          }
          acc.sum[k] += e, acc.sum2[k] += e * e, acc.max[k] = std::max(acc.max[k], e), ++acc.n[k];
        }
      }
    }
    partials[block] = acc;
  });
  AttributeErrorStats* stats[kKinds] = {&out.texcoord, &out.normal, &out.color};
  for (int k = 0; k < kKinds; ++k) {
    double sum = 0, sum2 = 0, max = 0;
    uint64_t n = 0;
    for (const Partial& p : partials)
      sum += p.sum[k], sum2 += p.sum2[k], max = std::max(max, p.max[k]), n += p.n[k];
    if (n == 0) continue;
    *stats[k] = {max, sum / double(n), std::sqrt(sum2 / double(n)), n};
  }
}

}  // namespace pmz
