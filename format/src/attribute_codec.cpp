// SPDX-License-Identifier: MIT
#include "pmz/attribute_codec.hpp"

#include <algorithm>
#include <cmath>

#include "pmz/coding.hpp"
#include "pmz/wasm_hints.hpp"

namespace pmz {

namespace {

void put_string(std::vector<uint8_t>& out, const std::string& s) {
  put_varint(out, s.size());
  out.insert(out.end(), s.begin(), s.end());
}

bool read_string(ByteReader& r, std::string& s) {
  const uint64_t n = r.varint();
  if (!r.ok || n > kMaxMaterialString) return false;
  const uint8_t* p = r.bytes(size_t(n));
  if (!p) return false;
  s.assign(reinterpret_cast<const char*>(p), size_t(n));
  return true;
}

// One out-of-line copy of each symbol decoder for this file's few call sites (the decoder
// library has a size budget; the per-bit work stays inlined inside them).
[[gnu::noinline]] bool read_uint(RangeState& rc, UIntModel& m, uint32_t& x) {
  return decode_uint(rc, m, x);
}
[[gnu::noinline]] bool read_small(RangeState& rc, SmallModel& m, uint32_t& x) {
  return decode_small(rc, m, x);
}

// The kind of a wedge's value component i (spec/format.md section 14.2's order).
AttributeCost::Kind component_kind(const AttributeHeader& h, uint32_t i) {
  if (i < 2 * h.texcoord_sets) return AttributeCost::kTexcoords;
  return i < 2 * h.texcoord_sets + h.normal_components() ? AttributeCost::kNormals
                                                         : AttributeCost::kColors;
}

// Up to two candidate wedges of corner c (spec/format.md section 14.3): the wedges of c's vertex in
// the faces across c's two edges at that vertex (first the edge to next(c)), when assigned,
// distinct.
[[gnu::always_inline]] inline uint32_t candidates(const ProgressiveMesh& pm,
                                                  const AttributeState& s, uint32_t c,
                                                  uint32_t out[2]) {
  uint32_t n = 0;
  const uint32_t o1 = pm.opposite[prev_corner(c)], o2 = pm.opposite[next_corner(c)];
  const uint32_t across[2] = {o1 == kNoCorner ? kNoCorner : prev_corner(o1),
                              o2 == kNoCorner ? kNoCorner : next_corner(o2)};
  for (uint32_t a : across) {
    if (a == kNoCorner || a >= s.corner_wedge.size()) continue;
    const uint32_t w = s.corner_wedge[a];
    if (w >= s.wedge_count || (n == 1 && out[0] == w)) continue;
    out[n++] = w;
  }
  return n;
}

// Candidate 0 of corner c alone (kNoCorner when nc = 0): the simple rule's wedge.
[[gnu::always_inline]] inline uint32_t first_candidate(const ProgressiveMesh& pm,
                                                       const AttributeState& s, uint32_t c) {
  const uint32_t o1 = pm.opposite[prev_corner(c)];
  if (o1 != kNoCorner) {
    const uint32_t a = prev_corner(o1);
    if (a < s.corner_wedge.size() && s.corner_wedge[a] < s.wedge_count) return s.corner_wedge[a];
  }
  const uint32_t o2 = pm.opposite[next_corner(c)];
  if (o2 != kNoCorner) {
    const uint32_t a = next_corner(o2);
    if (a < s.corner_wedge.size() && s.corner_wedge[a] < s.wedge_count) return s.corner_wedge[a];
  }
  return kNoCorner;
}

// The assigned wedge at corner a (kNoCorner / pending: none).
uint32_t wedge_at(const AttributeState& s, uint32_t a) {
  return a < s.corner_wedge.size() && s.corner_wedge[a] < s.wedge_count ? s.corner_wedge[a]
                                                                        : kNoCorner;
}

// Octahedral quantization of the direction (x, y, z) (spec/format.md section 14.2), binary64
// throughout.
void octahedral(double x, double y, double z, uint32_t bits, int32_t* q) {
  const double l1 = std::fabs(x) + std::fabs(y) + std::fabs(z);
  if (!(l1 > 0))
    x = 0, y = 0, z = 1;
  else
    x /= l1, y /= l1, z /= l1;
  if (z < 0) {
    const double fx = (1 - std::fabs(y)) * (x < 0 ? -1 : 1),
                 fy = (1 - std::fabs(x)) * (y < 0 ? -1 : 1);
    x = fx, y = fy;
  }
  const double max_q = double((1u << bits) - 1);
  q[0] = int32_t(std::clamp(std::floor((x * 0.5 + 0.5) * max_q + 0.5), 0.0, max_q));
  q[1] = int32_t(std::clamp(std::floor((y * 0.5 + 0.5) * max_q + 0.5), 0.0, max_q));
}

// Which predictions a new wedge's values had, and how much its neighbourhood varies (they
// select the residual models).
struct PredictionKind {
  uint8_t face_map = 0;
  uint8_t texcoord_ctx = 0, normal_ctx = 0;
  bool scored = false;                 // both normal predictions exist: the choice learns
  int32_t neighbour[2], geometric[2];  // the two normal predictions (octahedral)
};

inline constexpr uint32_t kMaxChartFan = 16;

// x's corners in the faces around x (x = c's vertex) that c's chart reaches (spec/format.md
// section 14.3, "Chart fan"): c, then across x's edges toward next(c)'s side, then from c
// toward prev(c)'s side, crossing an edge only where its other vertex has the same assigned
// a-wedge in both faces (no seam or crease there); at most kMaxChartFan corners. With each
// corner, the assigned a-wedges at its next and previous corners (kNoCorner: none), gathered
// once for both predictions: the walk's check is the shared edge's wedge.
struct FanCorner {
  uint32_t corner, next_wedge, prev_wedge;
};

// Whether a walk around x crosses an edge whose other vertex has the a-wedges a and b in the
// edge's two faces: the same a-wedge (the chart fan), or equal normals at normals_at (the normal
// fan, spec/format.md section 14.3, "Normal prediction": it crosses texture seams).
bool crosses(const AttributeState& s, uint32_t a, uint32_t b, uint32_t normals_at) {
  if (a == kNoCorner || b == kNoCorner) return false;
  if (a == b) return true;
  if (normals_at == kNoCorner) return false;
  const int32_t *na = &s.values[size_t(a) * s.stride + normals_at],
                *nb = &s.values[size_t(b) * s.stride + normals_at];
  return na[0] == nb[0] && na[1] == nb[1];
}

// The chart fan (normals_at = kNoCorner, at most kMaxChartFan corners) or the normal fan (at
// most kMaxNormalFan). *closed: whether the walk came back to c (then the fan is all of x's
// faces, and a walk that crosses more edges, the normal fan, gives the same corners in the same
// order).
uint32_t walk_fan(const ProgressiveMesh& pm, const AttributeState& s, uint32_t c, FanCorner* out,
                  uint32_t max, uint32_t normals_at, bool* closed = nullptr) {
  uint32_t n = 0;
  out[n++] = {c, wedge_at(s, next_corner(c)), wedge_at(s, prev_corner(c))};
  for (uint32_t i = 0; n < max;) {  // out[i] is the last corner reached this way
    const uint32_t o = pm.opposite[prev_corner(out[i].corner)];
    if (o == kNoCorner) break;
    const uint32_t w = wedge_at(s, next_corner(o));
    if (!crosses(s, out[i].next_wedge, w, normals_at)) break;
    const uint32_t at = prev_corner(o);
    if (at == c) {  // the fan closed
      if (closed) *closed = true;
      return n;
    }
    out[n] = {at, wedge_at(s, next_corner(at)), w};
    i = n++;
  }
  for (uint32_t i = 0; n < max;) {
    const uint32_t o = pm.opposite[next_corner(out[i].corner)];
    if (o == kNoCorner) break;
    const uint32_t w = wedge_at(s, prev_corner(o));
    if (!crosses(s, out[i].prev_wedge, w, normals_at)) break;
    const uint32_t at = next_corner(o);
    out[n] = {at, w, wedge_at(s, prev_corner(at))};
    i = n++;
  }
  return n;
}

inline constexpr uint32_t kMaxNormalFan = 32;
// A closed chart fan is the normal fan (predict_normal() reuses it).
static_assert(kMaxChartFan <= kMaxNormalFan);
inline constexpr double kHalfPi = 1.5707963267948966;  // binary64 nearest pi / 2 (14.3)

// atan(t) for t >= 0 from +, -, *, / only, so that every decoder computes the same bits (a
// library's atan may differ in the last bit between platforms): a degree-11 odd polynomial on
// [0, 1] (error below 1e-5 rad), atan(t) = pi/2 - atan(1/t) above.
PMZ_SMALL double atan_nonnegative(double t) {
  const bool above = t > 1;
  const double x = above ? 1 / t : t, x2 = x * x;
  double p = -0.0117212;
  p = p * x2 + 0.05265332;
  p = p * x2 - 0.11643287;
  p = p * x2 + 0.19354346;
  p = p * x2 - 0.33262347;
  p = p * x2 + 0.99997726;
  p = p * x;
  return above ? kHalfPi - p : p;
}

// The normal predicted from positions (spec/format.md section 14.3, "Normal prediction"): the
// normal fan's face normals weighted by their angle at x (as most tools weight vertex normals),
// octahedral into p; p is left as it is when the sum is zero. Binary64, each operation rounded in
// the order written. fan / fan_n: c's chart fan, reused when it closed (closed).
PMZ_SMALL void predict_normal(const ProgressiveMesh& pm, const int32_t* coords,
                              const AttributeState& s, uint32_t c, const FanCorner* chart,
                              uint32_t fan_n, bool closed, int32_t* p) {
  FanCorner walked[kMaxNormalFan];
  const FanCorner* fan = chart;
  if (!closed)
    fan = walked, fan_n = walk_fan(pm, s, c, walked, kMaxNormalFan, 2 * s.head.texcoord_sets);
  const int32_t* px = coords + size_t(pm.corner_vertex[c]) * 3;
  double n[3] = {0, 0, 0};
  for (uint32_t i = 0; i < fan_n; ++i) {
    const int32_t* pa = coords + size_t(pm.corner_vertex[next_corner(fan[i].corner)]) * 3;
    const int32_t* pb = coords + size_t(pm.corner_vertex[prev_corner(fan[i].corner)]) * 3;
    double e[3], f[3];
    for (int j = 0; j < 3; ++j) {
      e[j] = double(pa[j]) - double(px[j]);
      f[j] = double(pb[j]) - double(px[j]);
    }
    const double m[3] = {e[1] * f[2] - e[2] * f[1], e[2] * f[0] - e[0] * f[2],
                         e[0] * f[1] - e[1] * f[0]};
    const double l = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    if (!(l > 0)) continue;
    const double d = e[0] * f[0] + e[1] * f[1] + e[2] * f[2];
    const double a = atan_nonnegative(d > 0 ? l / d : -d / l);  // the angle at x, below
    const double w = (d > 0 ? a : kHalfPi + a) / l;
    for (int j = 0; j < 3; ++j) n[j] = n[j] + m[j] * w;
  }
  if (n[0] == 0 && n[1] == 0 && n[2] == 0) return;
  octahedral(n[0], n[1], n[2], s.head.normal_bits, p);
}

uint8_t spread_context(uint32_t spread) { return uint8_t(1 + std::min(bit_length(spread), 6u)); }

// The prediction of a new wedge's values at corner c (spec/format.md section 14.3).
PredictionKind predict(const ProgressiveMesh& pm, const int32_t* coords, const AttributeState& s,
                       uint32_t c, const uint32_t* cand, uint32_t n, int32_t normal_score,
                       int32_t* pred) {
  const AttributeHeader& h = s.head;
  const uint32_t wa = wedge_at(s, next_corner(c)), wb = wedge_at(s, prev_corner(c));
  const uint32_t ref = n ? cand[0] : wa != kNoCorner ? wa : wb;
  for (uint32_t i = 0; i < s.stride; ++i)
    pred[i] = ref == kNoCorner ? 0 : s.values[size_t(ref) * s.stride + i];
  PredictionKind kind;
  FanCorner fan[kMaxChartFan];
  bool closed = false;
  const uint32_t fan_n = walk_fan(pm, s, c, fan, kMaxChartFan, kNoCorner, &closed);
  if (h.normals && h.normal_bits) {
    const uint32_t at = 2 * h.texcoord_sets;
    int32_t geo[2] = {pred[at], pred[at + 1]};
    predict_normal(pm, coords, s, c, fan, fan_n, closed, geo);
    if (ref != kNoCorner) {
      kind.scored = true;
      kind.neighbour[0] = pred[at], kind.neighbour[1] = pred[at + 1];
      kind.geometric[0] = geo[0], kind.geometric[1] = geo[1];
    }
    if (normal_score <= 0) pred[at] = geo[0], pred[at + 1] = geo[1];
    // How far the fan's neighbours' normals lie from the prediction (octahedral steps). In a
    // closed fan every previous a-wedge is another corner's next one: the next ones suffice.
    uint32_t spread = 0;
    bool any = false;
    for (uint32_t i = 0; i < fan_n; ++i)
      for (uint32_t w : {fan[i].next_wedge, closed ? kNoCorner : fan[i].prev_wedge}) {
        if (w == kNoCorner) continue;
        any = true;
        for (uint32_t k = 0; k < 2; ++k) {
          const int64_t d = int64_t(s.values[size_t(w) * s.stride + at + k]) - pred[at + k];
          spread = std::max(spread, uint32_t(std::min<int64_t>(d < 0 ? -d : d, 0xFFFFFFFF)));
        }
      }
    kind.normal_ctx = any ? spread_context(spread) : 0;
  }
  if (!h.texcoord_sets || !h.texcoord_bits) return kind;
  // The mean over the fan's faces of each face's map from positions to texture coordinates,
  // applied to x: x = a + s (b - a) + t perp(b - a) in both spaces, perp a quarter turn
  // counter-clockwise. Binary64, each operation rounded in this order (no fused multiply-add).
  double sum[kMaxTexcoordSets * 2] = {}, own[kMaxTexcoordSets * 2] = {}, lo[2] = {0, 0},
                                hi[2] = {0, 0};
  uint32_t maps = 0;
  bool own_map = false;  // c's own face gave a map
  const int32_t* px = coords + size_t(pm.corner_vertex[c]) * 3;
  for (uint32_t i = 0; i < fan_n; ++i) {
    const uint32_t k = fan[i].corner, ka = fan[i].next_wedge, kb = fan[i].prev_wedge;
    if (ka == kNoCorner || kb == kNoCorner) continue;
    const int32_t* pa = coords + size_t(pm.corner_vertex[next_corner(k)]) * 3;
    const int32_t* pb = coords + size_t(pm.corner_vertex[prev_corner(k)]) * 3;
    double e[3], d[3];
    for (int j = 0; j < 3; ++j) {
      e[j] = double(pb[j]) - double(pa[j]);
      d[j] = double(px[j]) - double(pa[j]);
    }
    const double ee = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
    if (!(ee > 0)) continue;
    const double along = (d[0] * e[0] + d[1] * e[1] + d[2] * e[2]) / ee;
    double hh = 0;
    for (int j = 0; j < 3; ++j) {
      const double r = d[j] - along * e[j];
      hh = hh + r * r;
    }
    const double across = std::sqrt(hh / ee);
    for (uint32_t t = 0; t < h.texcoord_sets; ++t) {
      const int32_t* A = &s.values[size_t(ka) * s.stride + 2 * t];
      const int32_t* B = &s.values[size_t(kb) * s.stride + 2 * t];
      const double du = double(B[0]) - double(A[0]), dv = double(B[1]) - double(A[1]);
      const double p[2] = {A[0] + along * du - across * dv, A[1] + along * dv + across * du};
      for (int j = 0; j < 2; ++j) {
        sum[2 * t + j] = sum[2 * t + j] + p[j];
        if (i == 0) own[2 * t + j] = p[j];
        if (t == 0 && (maps == 0 || p[j] < lo[j])) lo[j] = p[j];
        if (t == 0 && (maps == 0 || p[j] > hi[j])) hi[j] = p[j];
      }
    }
    own_map = own_map || i == 0;
    ++maps;
  }
  if (!maps) return kind;
  kind.face_map = 1;
  // How much the faces' maps disagree (set 0, texture steps).
  const double spread = std::min(std::max(hi[0] - lo[0], hi[1] - lo[1]), 1048576.0);
  kind.texcoord_ctx = maps == 1 ? 0 : spread_context(uint32_t(spread));
  // Maps that disagree by 128 steps or more: c's own face alone (a far face's map is off).
  const bool own_only = own_map && maps > 1 && spread >= 128;
  const double max_q = double((1u << h.texcoord_bits) - 1);
  for (uint32_t t = 0; t < 2 * h.texcoord_sets; ++t) {
    const double p = own_only ? own[t] : sum[t] / double(maps);
    pred[t] = int32_t(std::clamp(std::floor(p + 0.5), 0.0, max_q));
  }
  return kind;
}

// Which normal prediction the stream's next new a-wedges take (spec/format.md section 14.3):
// the score follows, with a decay of 1/16, how much closer the geometric prediction came than
// the neighbour's (in octahedral steps, each new a-wedge's share at most 64); the geometric one
// while the score is not positive.
PMZ_SMALL void score_normal(AttributeModels& m, const AttributeHeader& h,
                            const PredictionKind& kind, const int32_t* value) {
  if (!kind.scored) return;
  const uint32_t at = 2 * h.texcoord_sets;
  int64_t d = 0;
  for (int k = 0; k < 2; ++k) {
    const int64_t v = value[at + k];
    d += std::abs(v - kind.geometric[k]) - std::abs(v - kind.neighbour[k]);
  }
  m.normal_score = m.normal_score - m.normal_score / 16 + int32_t(std::clamp<int64_t>(d, -64, 64));
}

UIntModel& residual_model(AttributeModels& m, const AttributeHeader& h, uint32_t i,
                          PredictionKind kind, uint32_t prev) {
  // The second component of a pair (v, the octahedral second) by the class of the first's
  // residual (prev): the two are far from the prediction together.
  const uint32_t second = 1 + std::min(bit_length(prev), 7u);
  if (i < 2 * h.texcoord_sets)
    return kind.face_map ? m.texcoord_fan[kind.texcoord_ctx][i & 1 ? second : 0]
                         : m.texcoord[i & 1];
  i -= 2 * h.texcoord_sets;
  if (i < h.normal_components())
    return h.normal_bits ? m.normal_fan[kind.normal_ctx][i ? second : 0] : m.normal[i];
  return m.color[std::min(i - h.normal_components(), 3u)];
}

void push_wedge(AttributeState& s, uint32_t vertex, const int32_t* v) {
  const uint32_t w = s.wedge_count++;
  if (s.wedge_vertex.size() > w) {  // an undone split's wedge: overwritten (the same values)
    s.wedge_vertex[w] = vertex;
    std::copy(v, v + s.stride, s.values.begin() + std::ptrdiff_t(size_t(w) * s.stride));
    return;
  }
  s.wedge_vertex.push_back(vertex);
  s.values.insert(s.values.end(), v, v + s.stride);
}

uint32_t material_candidates(const ProgressiveMesh& pm, const AttributeState& s, uint32_t f,
                             uint32_t out[3]) {
  uint32_t n = 0;
  for (uint32_t k = 0; k < 3; ++k) {
    const uint32_t o = pm.opposite[f * 3 + k];
    if (o == kNoCorner || o / 3 >= s.face_material.size()) continue;
    const uint32_t mat = s.face_material[o / 3];
    if (mat >= s.head.materials.size() || std::find(out, out + n, mat) != out + n) continue;
    out[n++] = mat;
  }
  return n;
}

}  // namespace

void write_attribute_header(std::vector<uint8_t>& out, const AttributeHeader& a) {
  out.push_back(uint8_t(a.texcoord_sets));
  out.push_back(uint8_t(a.texcoord_bits));
  for (uint32_t t = 0; t < a.texcoord_sets; ++t) {
    put_f32le(out, a.texcoord_min[t][0]);
    put_f32le(out, a.texcoord_min[t][1]);
    put_f32le(out, a.texcoord_max[t][0]);
    put_f32le(out, a.texcoord_max[t][1]);
  }
  out.push_back(a.normals ? 1 : 0);
  out.push_back(uint8_t(a.normal_bits));
  out.push_back(uint8_t(a.color_components));
  out.push_back(uint8_t(a.color_bits));
  put_varint(out, a.base_wedges);
  put_varint(out, a.full_wedges);
  put_string(out, a.material_library);
  put_varint(out, a.materials.size());
  for (const FileMaterial& m : a.materials) {
    put_string(out, m.name);
    put_string(out, m.base_color_texture);
    put_string(out, m.normal_texture);
    for (float c : m.base_color) put_f32le(out, c);
  }
}

PMZ_SMALL bool read_attribute_header(ByteReader& r, AttributeHeader& a, std::string& error) {
  a.texcoord_sets = r.u8();
  a.texcoord_bits = r.u8();
  if (a.texcoord_sets > kMaxTexcoordSets || a.texcoord_bits > kMaxAttributeBits)
    return error = "texture coordinate sets or bits out of range", false;
  for (uint32_t t = 0; t < a.texcoord_sets; ++t) {
    for (float& x : a.texcoord_min[t]) x = r.f32le();
    for (float& x : a.texcoord_max[t]) x = r.f32le();
    for (int k = 0; k < 2; ++k)
      if (!std::isfinite(a.texcoord_min[t][k]) || !std::isfinite(a.texcoord_max[t][k]) ||
          a.texcoord_min[t][k] > a.texcoord_max[t][k])
        return error = "bad texture coordinate box", false;
  }
  const uint32_t normals = r.u8();
  a.normal_bits = r.u8();
  a.color_components = r.u8();
  a.color_bits = r.u8();
  if (normals > 1 || a.normal_bits == 1 || a.normal_bits > 16 ||
      (a.color_components != 0 && a.color_components != 3 && a.color_components != 4) ||
      a.color_bits > 16)
    return error = "normal or colour fields out of range", false;
  a.normals = normals == 1;
  const uint64_t base = r.varint(), full = r.varint();
  if (base > full || full > 0xFFFFFFF0u || (!a.has_wedges() && full != 0))
    return error = "attribute wedge counts out of range", false;
  a.base_wedges = uint32_t(base);
  a.full_wedges = uint32_t(full);
  if (!read_string(r, a.material_library)) return error = "material library name", false;
  const uint64_t materials = r.varint();
  if (!r.ok || materials > kMaxMaterials || materials > r.remaining() / 19)
    return error = "material count out of range", false;
  a.materials.resize(size_t(materials));
  for (FileMaterial& m : a.materials) {
    if (!read_string(r, m.name) || !read_string(r, m.base_color_texture) ||
        !read_string(r, m.normal_texture))
      return error = "material strings malformed", false;
    for (float& c : m.base_color) c = r.f32le();
  }
  if (!r.ok) return error = "attribute fields end early", false;
  return true;
}

void AttributeCost::add(const RangeState& rc, Kind k) {
  bits[k] += 8.0 * double(rc.p - at) + std::log2(double(range) / double(rc.range));
  resume(rc);
}

void AttributeQuantizer::init(const AttributeHeader& a) {
  for (uint32_t t = 0; t < a.texcoord_sets; ++t) {
    const float lo[3] = {a.texcoord_min[t][0], a.texcoord_min[t][1], 0},
                hi[3] = {a.texcoord_max[t][0], a.texcoord_max[t][1], 0};
    texcoord[t].init(a.texcoord_bits, lo, hi);
  }
  normal_bits = a.normal_bits;
  color_bits = a.color_bits;
}

// Octahedral: the unit vector projected onto |x| + |y| + |z| = 1, the lower half folded over
// the diagonals, each of x and y in [-1, 1] quantized to 0 .. 2^bits - 1.
void AttributeQuantizer::quantize_normal(const float n[3], int32_t* q) const {
  if (!normal_bits) {
    for (int k = 0; k < 3; ++k) q[k] = float_to_ordered(n[k]);
    return;
  }
  octahedral(n[0], n[1], n[2], normal_bits, q);
}

void AttributeQuantizer::dequantize_normal(const int32_t* q, float n[3]) const {
  if (!normal_bits) {
    for (int k = 0; k < 3; ++k) n[k] = ordered_to_float(q[k]);
    return;
  }
  const double max_q = double((1u << normal_bits) - 1);
  double x = double(q[0]) / max_q * 2 - 1, y = double(q[1]) / max_q * 2 - 1;
  double z = 1 - std::fabs(x) - std::fabs(y);
  if (z < 0) {
    const double fx = (1 - std::fabs(y)) * (x < 0 ? -1 : 1),
                 fy = (1 - std::fabs(x)) * (y < 0 ? -1 : 1);
    x = fx, y = fy;
  }
  const double len = std::sqrt(x * x + y * y + z * z);
  n[0] = float(x / len);
  n[1] = float(y / len);
  n[2] = float(z / len);
}

int32_t AttributeQuantizer::quantize_color(float c) const {
  if (!color_bits) return float_to_ordered(c);
  const double max_q = double((1u << color_bits) - 1);
  return int32_t(std::clamp(std::floor(double(c) * max_q + 0.5), 0.0, max_q));
}

float AttributeQuantizer::dequantize_color(int32_t q) const {
  if (!color_bits) return ordered_to_float(q);
  return float(double(q) / double((1u << color_bits) - 1));
}

void split_corners(const ProgressiveMesh& pm, bool has_l, bool has_r, std::vector<uint32_t>& out) {
  const std::span<const uint32_t> sector = pm.sector_faces();
  out.resize(sector.size() + 6);  // at most: the decoder reserved it before the split
  uint32_t* o = out.data();
  const uint32_t new_faces = (has_l ? 1u : 0u) + (has_r ? 1u : 0u);
  const uint32_t f0 = pm.face_count() - new_faces;
  const uint32_t fl = f0, fr = f0 + (has_l ? 1u : 0u);
  const uint32_t u = pm.vertex_count() - 1;
  if (has_l) *o++ = fl * 3 + 1, *o++ = fl * 3 + 2;  // L = (u, v, vl)
  if (has_r) *o++ = fr * 3 + 0, *o++ = fr * 3 + 2;  // R = (v, u, vr)
  if (has_l) *o++ = fl * 3;
  for (uint32_t f : sector) {  // u's corner in each sector face
    const uint32_t* cv = &pm.corner_vertex[f * 3];
    *o++ = f * 3 + (cv[0] == u ? 0 : cv[1] == u ? 1 : 2);
  }
  if (has_r) *o++ = fr * 3 + 1;
  out.resize(size_t(o - out.data()));
}

namespace {

// A new wedge's values (spec/format.md section 14.3, "New a-wedge"): the residuals from the
// prediction.
void encode_new_wedge(RangeEncoder& rc, AttributeModels& m, const ProgressiveMesh& pm,
                      const int32_t* coords, AttributeState& s, uint32_t c, const uint32_t* cand,
                      uint32_t n, const int32_t* fresh) {
  int32_t pred[kMaxTexcoordSets * 2 + 7];
  const PredictionKind kind = predict(pm, coords, s, c, cand, n, m.normal_score, pred);
  uint32_t prev = 0;
  for (uint32_t i = 0; i < s.stride; ++i) {
    const uint32_t z = zigzag_encode(int32_t(uint32_t(fresh[i]) - uint32_t(pred[i])));
    encode_uint(rc, residual_model(m, s.head, i, kind, prev), z);
    prev = z;
  }
  score_normal(m, s.head, kind, fresh);
  s.corner_wedge[c] = s.wedge_count;
  push_wedge(s, pm.corner_vertex[c], fresh);
}

PMZ_SMALL bool decode_new_wedge(RangeState& rc, AttributeModels& m, const ProgressiveMesh& pm,
                                const int32_t* coords, AttributeState& s, uint32_t c,
                                const uint32_t* cand, uint32_t n) {
  if (s.wedge_count >= s.head.full_wedges) return false;  // more wedges than HEAD announced
  int32_t pred[kMaxTexcoordSets * 2 + 7], value[kMaxTexcoordSets * 2 + 7];
  const PredictionKind kind = predict(pm, coords, s, c, cand, n, m.normal_score, pred);
  m.cost.charge(rc, AttributeCost::kWedges);  // the reference symbols before the values
  uint32_t z = 0;
  for (uint32_t i = 0; i < s.stride; ++i) {
    if (!read_uint(rc, residual_model(m, s.head, i, kind, z), z)) return false;
    if (m.cost.counting()) [[unlikely]]  // (the kind worked out only when counting)
      m.cost.add(rc, component_kind(s.head, i));
    value[i] = int32_t(uint32_t(pred[i]) + uint32_t(zigzag_decode(z)));
  }
  score_normal(m, s.head, kind, value);
  s.corner_wedge[c] = s.wedge_count;
  push_wedge(s, pm.corner_vertex[c], value);
  return rc.ok;
}

// A corner's reference symbol, then the new wedge or the escape (spec/format.md section 14.3).
void encode_reference(RangeEncoder& rc, AttributeModels& m, const ProgressiveMesh& pm,
                      const int32_t* coords, AttributeState& s, uint32_t c, bool u_corner,
                      uint32_t wedge, const int32_t* fresh) {
  uint32_t cand[2];
  const uint32_t n = candidates(pm, s, c, cand);
  SmallModel& ref = m.reference[u_corner ? 1 : 0][std::min(n, 2u)];
  if (wedge < s.wedge_count) {
    const uint32_t at = uint32_t(std::find(cand, cand + n, wedge) - cand);
    encode_small(rc, ref, at < n ? at : n + 1);
    if (at == n) encode_uint(rc, m.escape, s.wedge_count - 1 - wedge);
    s.corner_wedge[c] = wedge;
    return;
  }
  encode_small(rc, ref, n);
  encode_new_wedge(rc, m, pm, coords, s, c, cand, n, fresh);
}

bool decode_reference(RangeState& rc, AttributeModels& m, const ProgressiveMesh& pm,
                      const int32_t* coords, AttributeState& s, uint32_t c, bool u_corner) {
  uint32_t cand[2];
  const uint32_t n = candidates(pm, s, c, cand);
  uint32_t sym;
  if (!read_small(rc, m.reference[u_corner ? 1 : 0][std::min(n, 2u)], sym) || sym > n + 1)
    return false;
  if (sym < n) {
    s.corner_wedge[c] = cand[sym];
    return true;
  }
  if (sym == n + 1) {
    uint32_t back;
    if (!read_uint(rc, m.escape, back) || back >= s.wedge_count) return false;
    const uint32_t w = s.wedge_count - 1 - back;
    if (s.wedge_vertex[w] != pm.corner_vertex[c]) return false;  // another vertex's wedge
    s.corner_wedge[c] = w;
    return true;
  }
  return decode_new_wedge(rc, m, pm, coords, s, c, cand, n);
}

// Whether the "simple" rule (spec/format.md section 14.5: each corner takes its first candidate, a
// new wedge where it has none) gives the writer's wedges. Tried on s, which is then restored.
bool simple_rule_fits(const ProgressiveMesh& pm, AttributeState& s,
                      std::span<const uint32_t> corners, const uint32_t* wedges) {
  const uint32_t before = s.wedge_count;
  bool fits = true;
  for (size_t i = 0; i < corners.size() && fits; ++i) {
    uint32_t cand[2];
    const uint32_t n = candidates(pm, s, corners[i], cand);
    if (n)
      fits = wedges[i] == cand[0];
    else if ((fits = wedges[i] == s.wedge_count))
      ++s.wedge_count;  // the new wedge, assigned from here on
    s.corner_wedge[corners[i]] = wedges[i];
  }
  for (uint32_t c : corners) s.corner_wedge[c] = kPendingWedge;
  s.wedge_count = before;
  return fits;
}

}  // namespace

void encode_corner_wedge(RangeEncoder& rc, AttributeModels& m, const ProgressiveMesh& pm,
                         const int32_t* coords, AttributeState& s, uint32_t c, uint32_t wedge,
                         const int32_t* fresh) {
  encode_reference(rc, m, pm, coords, s, c, false, wedge, fresh);
}

bool decode_corner_wedge(RangeState& rc, AttributeModels& m, const ProgressiveMesh& pm,
                         const int32_t* coords, AttributeState& s, uint32_t c) {
  return decode_reference(rc, m, pm, coords, s, c, false);
}

void encode_split_wedges(RangeEncoder& rc, AttributeModels& m, const ProgressiveMesh& pm,
                         const int32_t* coords, AttributeState& s,
                         std::span<const uint32_t> corners, uint32_t u, const uint32_t* wedges,
                         const int32_t* const* fresh) {
  const uint32_t simple = simple_rule_fits(pm, s, corners, wedges) ? 1 : 0;
  rc.bit(m.simple[m.last_simple], simple);
  m.last_simple = simple;
  for (size_t i = 0; i < corners.size(); ++i) {
    const uint32_t c = corners[i];
    if (!simple) {
      encode_reference(rc, m, pm, coords, s, c, pm.corner_vertex[c] == u, wedges[i], fresh[i]);
      continue;
    }
    uint32_t cand[2];
    const uint32_t n = candidates(pm, s, c, cand);
    if (n)
      s.corner_wedge[c] = cand[0];
    else
      encode_new_wedge(rc, m, pm, coords, s, c, cand, n, fresh[i]);
  }
}

bool decode_split_wedges(RangeState& rc, AttributeModels& m, const ProgressiveMesh& pm,
                         const int32_t* coords, AttributeState& s,
                         std::span<const uint32_t> corners, uint32_t u) {
  const uint32_t simple = rc.bit(m.simple[m.last_simple]);
  m.last_simple = simple;
  for (size_t i = 0; i < corners.size(); ++i) {
    const uint32_t c = corners[i];
    if (!simple) {
      if (!decode_reference(rc, m, pm, coords, s, c, pm.corner_vertex[c] == u)) return false;
      continue;
    }
    const uint32_t w = first_candidate(pm, s, c);
    if (w != kNoCorner)
      s.corner_wedge[c] = w;
    else if (!decode_new_wedge(rc, m, pm, coords, s, c, nullptr, 0))
      return false;
  }
  m.cost.charge(rc, AttributeCost::kWedges);  // the reference symbols after the last values
  return rc.ok;
}

void encode_face_material(RangeEncoder& rc, AttributeModels& m, const ProgressiveMesh& pm,
                          AttributeState& s, uint32_t f, uint32_t material) {
  uint32_t cand[3];
  const uint32_t n = material_candidates(pm, s, f, cand);
  const uint32_t at = uint32_t(std::find(cand, cand + n, material) - cand);
  encode_small(rc, m.material[std::min(n, 3u)], at);
  if (at == n) encode_uint(rc, m.material_escape, material);
  s.face_material[f] = material;
}

bool decode_face_material(RangeState& rc, AttributeModels& m, const ProgressiveMesh& pm,
                          AttributeState& s, uint32_t f) {
  uint32_t cand[3], sym, material;
  const uint32_t n = material_candidates(pm, s, f, cand);
  if (!read_small(rc, m.material[std::min(n, 3u)], sym) || sym > n) return false;
  if (sym < n) {
    material = cand[sym];
  } else if (!read_uint(rc, m.material_escape, material) || material >= s.head.materials.size()) {
    return false;
  }
  m.cost.charge(rc, AttributeCost::kMaterials);
  s.face_material[f] = material;
  return true;
}

}  // namespace pmz
