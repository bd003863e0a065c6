// SPDX-License-Identifier: MIT
#include "pmz/base_codec.hpp"

#include <memory>
#include <string>
#include <unordered_map>

#include "pmz/coding.hpp"
#include "pmz/progressive_mesh.hpp"
#include "pmz/range_coder.hpp"
#include "pmz/wasm_hints.hpp"

namespace pmz {

namespace {

constexpr uint32_t kNone = 0xFFFFFFFFu;
// Counts a stream of S bytes can hold (spec/format.md section 12): a face costs at least two
// adaptive decisions, a vertex at least 12 (four length decisions per residual), and S bytes decode
// at most 755.8 (S + 1) of them (the decoder reads up to 4 zero bytes past the end, spec/format.md
// section 11.2): bounds are per (S + 1).
constexpr uint64_t kFacesPerByte = 384, kVerticesPerByte = 64;
// Open-edge list scans (spec/format.md section 7): at most this much per half-edge, plus slack.
constexpr uint64_t kWorkPerHalfEdge = 16, kWorkSlack = uint64_t(1) << 22;

inline uint64_t edge_key(uint32_t a, uint32_t b) { return uint64_t(a) << 32 | b; }

struct BaseModels {
  Prob face = kProbInit;  // a gate has a face beyond it
  Prob is_new[5];         // 0: a component's first face; 1 + [left] + 2 [right]
  Prob is_left[2];        // by [right]
  Prob is_right = kProbInit;
  UIntModel other;           // an earlier vertex: vertices - 1 - id
  UIntModel residual[2][3];  // [0] parallelogram, [1] from the previous vertex; per axis
  BaseModels() {
    for (Prob& p : is_new) p = kProbInit;
    for (Prob& p : is_left) p = kProbInit;
  }
};

// The traversal state: faces so far (half-edge h = corner h runs from faces[h] to
// faces[next(h)]) and the open half-edges (coded, twin not coded, not declared a boundary) in
// per-vertex lists by source and by target, most recent first. Gates are processed first in,
// first out.
class Front {
 public:
  std::vector<uint32_t> faces;
  uint64_t work = 0;  // list entries scanned

  void reset(uint32_t n, uint32_t fn) {
    faces.clear();
    faces.reserve(size_t(fn) * 3);
    state_.clear();
    state_.reserve(size_t(fn) * 3);
    for (auto* v : {&out_next_, &out_prev_, &in_next_, &in_prev_}) {
      v->clear();
      v->reserve(size_t(fn) * 3);
    }
    out_head_.assign(n, kNone);
    in_head_.assign(n, kNone);
    gates_.clear();
    gates_.reserve(size_t(fn) * 3);
    gate_at_ = 0;
  }
  uint32_t face_count() const { return uint32_t(faces.size() / 3); }
  uint32_t from(uint32_t h) const { return faces[h]; }
  uint32_t to(uint32_t h) const { return faces[next_corner(h)]; }
  uint32_t third(uint32_t h) const { return faces[prev_corner(h)]; }
  // Appends face (x, y, z) (distinct vertices below n): each half-edge is glued to its open
  // twin, if any, or becomes open and a gate.
  void add_face(uint32_t x, uint32_t y, uint32_t z) {
    const uint32_t h0 = uint32_t(faces.size());
    faces.insert(faces.end(), {x, y, z});
    for (auto* v : {&out_next_, &out_prev_, &in_next_, &in_prev_}) v->insert(v->end(), 3, kNone);
    state_.insert(state_.end(), 3, kOpen);
    for (uint32_t h = h0; h < h0 + 3; ++h) {
      const uint32_t twin = find_open(to(h), from(h));
      if (twin != kNone) {
        unlink(twin);
        state_[twin] = state_[h] = kGlued;
      } else {
        link(h);
        gates_.push_back(h);
      }
    }
  }
  // The next gate still open, if any.
  bool pop_gate(uint32_t& h) {
    while (gate_at_ < gates_.size()) {
      h = gates_[gate_at_++];
      if (state_[h] == kOpen) return true;
    }
    return false;
  }
  void boundary(uint32_t h) {
    unlink(h);
    state_[h] = kBoundary;
  }
  // Front neighbours of gate a -> b: the source of the latest open half-edge into a, the
  // target of the latest open half-edge out of b.
  uint32_t left(uint32_t h) const {
    const uint32_t e = in_head_[from(h)];
    return e == kNone ? kNone : from(e);
  }
  uint32_t right(uint32_t h) const {
    const uint32_t e = out_head_[to(h)];
    return e == kNone ? kNone : to(e);
  }

 private:
  enum : uint8_t { kOpen, kGlued, kBoundary };
  uint32_t find_open(uint32_t a, uint32_t b) {
    for (uint32_t e = out_head_[a]; e != kNone; e = out_next_[e]) {
      ++work;
      if (to(e) == b) return e;
    }
    return kNone;
  }
  static void push(std::vector<uint32_t>& head, std::vector<uint32_t>& next,
                   std::vector<uint32_t>& prev, uint32_t key, uint32_t h) {
    next[h] = head[key];
    prev[h] = kNone;
    if (head[key] != kNone) prev[head[key]] = h;
    head[key] = h;
  }
  static void remove(std::vector<uint32_t>& head, std::vector<uint32_t>& next,
                     std::vector<uint32_t>& prev, uint32_t key, uint32_t h) {
    if (prev[h] != kNone)
      next[prev[h]] = next[h];
    else
      head[key] = next[h];
    if (next[h] != kNone) prev[next[h]] = prev[h];
  }
  void link(uint32_t h) {
    push(out_head_, out_next_, out_prev_, from(h), h);
    push(in_head_, in_next_, in_prev_, to(h), h);
  }
  void unlink(uint32_t h) {
    remove(out_head_, out_next_, out_prev_, from(h), h);
    remove(in_head_, in_next_, in_prev_, to(h), h);
  }
  std::vector<uint8_t> state_;
  std::vector<uint32_t> out_next_, out_prev_, in_next_, in_prev_, out_head_, in_head_, gates_;
  size_t gate_at_ = 0;
};

// Writer side: the mesh being coded, in its given ids.
struct Oracle {
  const int32_t* coords;
  const uint32_t* faces;
  std::unordered_map<uint64_t, uint32_t> edge;  // directed edge -> its half-edge
  std::vector<uint32_t> decoded;                // given id -> decoded id (kNone: not yet)
  std::vector<uint8_t> done;                    // per given face
  std::vector<uint32_t>* given_of;
  uint32_t next_seed = 0, next_isolated = 0;
};

struct EncodeIO {
  static constexpr bool kEncode = true;
  RangeEncoder rc;
  void bit(Prob& p, uint32_t& b) { rc.bit(p, b); }
  void direct(uint32_t& b) { rc.direct(b, 1); }
  bool uint(UIntModel& m, uint32_t& x) {
    encode_uint(rc, m, x);
    return true;
  }
  bool ok() const { return true; }
};

struct DecodeIO {
  static constexpr bool kEncode = false;
  RangeState s;
  void bit(Prob& p, uint32_t& b) { b = s.bit(p); }
  void direct(uint32_t& b) { b = s.direct(1); }
  bool uint(UIntModel& m, uint32_t& x) { return decode_uint(s, m, x); }
  bool ok() const { return s.ok; }
};

// The traversal (spec/format.md section 7), coding or decoding each value in turn: IO::kEncode
// takes the values from the oracle, otherwise from the stream.
template <class IO>
Status code_base(IO& io, uint32_t n, uint32_t fn, uint32_t midpoint, Oracle* oracle, BaseMesh& mesh,
                 std::string& error) {
  constexpr bool kEnc = IO::kEncode;
  io.direct(midpoint);
  auto models = std::make_unique<BaseModels>();
  BaseModels& m = *models;
  Front front;
  front.reset(n, fn);
  mesh.coords.assign(size_t(n) * 3, 0);
  uint32_t vertices = 0;
  const int32_t zero[3] = {0, 0, 0};
  auto last = [&]() -> const int32_t* {
    return vertices ? &mesh.coords[size_t(vertices - 1) * 3] : zero;
  };
  // A new vertex (writer: given id g) with its residuals from pred; kNone if none is left or a
  // residual is malformed.
  auto new_vertex = [&](uint32_t g, const int32_t* pred, UIntModel* res) -> uint32_t {
    if (vertices >= n) return kNone;
    const uint32_t c = vertices++;
    if constexpr (kEnc) {
      oracle->decoded[g] = c;
      oracle->given_of->push_back(g);
    }
    int32_t p[3] = {pred[0], pred[1], pred[2]};  // pred may point into coords
    for (int a = 0; a < 3; ++a) {
      uint32_t z = 0;
      if constexpr (kEnc)
        z = zigzag_encode(int32_t(uint32_t(oracle->coords[size_t(g) * 3 + a]) - uint32_t(p[a])));
      if (!io.uint(res[a], z)) return kNone;
      mesh.coords[size_t(c) * 3 + a] = int32_t(uint32_t(p[a]) + uint32_t(zigzag_decode(z)));
    }
    return c;
  };
  // The vertex symbol: new, the left or right front neighbour (when present), or an earlier one.
  auto vertex = [&](uint32_t g, uint32_t left, uint32_t right, uint32_t ctx, const int32_t* pred,
                    UIntModel* res) -> uint32_t {
    uint32_t c = 0, bit = 0;
    if constexpr (kEnc) c = oracle->decoded[g], bit = c == kNone;
    io.bit(m.is_new[ctx], bit);
    if (bit) return new_vertex(g, pred, res);
    if (left != kNone) {
      if constexpr (kEnc) bit = c == left;
      io.bit(m.is_left[right != kNone], bit);
      if (bit) return left;
    }
    if (right != kNone) {
      if constexpr (kEnc) bit = c == right;
      io.bit(m.is_right, bit);
      if (bit) return right;
    }
    uint32_t d = 0;
    if constexpr (kEnc) d = vertices - 1 - c;
    if (!io.uint(m.other, d) || d >= vertices) return kNone;
    return vertices - 1 - d;
  };
  const uint64_t work_limit = kWorkPerHalfEdge * 3 * uint64_t(fn) + kWorkSlack;
  while (front.face_count() < fn) {
    if (!io.ok()) return error = "BASE stream truncated", Status::corrupt;
    if (front.work > work_limit) return error = "BASE front too tangled", Status::limit_exceeded;
    uint32_t h;
    if (!front.pop_gate(h)) {  // a component's first face
      uint32_t g[3] = {0, 0, 0}, v[3];
      if constexpr (kEnc) {
        while (oracle->done[oracle->next_seed]) ++oracle->next_seed;
        oracle->done[oracle->next_seed] = 1;
        for (int k = 0; k < 3; ++k) g[k] = oracle->faces[size_t(oracle->next_seed) * 3 + k];
      }
      for (int k = 0; k < 3; ++k)
        if ((v[k] = vertex(g[k], kNone, kNone, 0, last(), m.residual[1])) == kNone)
          return error = "BASE vertex malformed", Status::corrupt;
      if (v[0] == v[1] || v[0] == v[2] || v[1] == v[2])
        return error = "BASE face repeats a vertex", Status::corrupt;
      front.add_face(v[0], v[1], v[2]);
      continue;
    }
    const uint32_t a = front.from(h), b = front.to(h), d = front.third(h);
    uint32_t has = 0, g = 0;
    if constexpr (kEnc) {
      const auto it = oracle->edge.find(edge_key(oracle->given_of->at(b), oracle->given_of->at(a)));
      if (it != oracle->edge.end()) {
        has = 1;
        if (oracle->done[it->second / 3]) return error = "BASE face coded twice", Status::corrupt;
        oracle->done[it->second / 3] = 1;
        g = oracle->faces[prev_corner(it->second)];
      }
    }
    io.bit(m.face, has);
    if (!has) {
      front.boundary(h);
      continue;
    }
    const uint32_t left = front.left(h), r = front.right(h), right = r == left ? kNone : r;
    int32_t pred[3];
    for (int k = 0; k < 3; ++k)
      pred[k] =
          midpoint
              ? int32_t(
                    (int64_t(mesh.coords[size_t(a) * 3 + k]) + mesh.coords[size_t(b) * 3 + k]) >> 1)
              : int32_t(uint32_t(mesh.coords[size_t(a) * 3 + k]) +
                        uint32_t(mesh.coords[size_t(b) * 3 + k]) -
                        uint32_t(mesh.coords[size_t(d) * 3 + k]));
    const uint32_t c =
        vertex(g, left, right, 1 + (left != kNone) + 2 * (right != kNone), pred, m.residual[0]);
    if (c == kNone) return error = "BASE vertex malformed", Status::corrupt;
    if (c == a || c == b) return error = "BASE face repeats a vertex", Status::corrupt;
    front.add_face(b, a, c);
  }
  while (vertices < n) {  // vertices without faces
    uint32_t g = 0;
    if constexpr (kEnc) {
      while (oracle->decoded[oracle->next_isolated] != kNone) ++oracle->next_isolated;
      g = oracle->next_isolated;
    }
    if (new_vertex(g, last(), m.residual[1]) == kNone)
      return error = "BASE vertex malformed", Status::corrupt;
  }
  if (!io.ok()) return error = "BASE stream truncated", Status::corrupt;
  mesh.faces = std::move(front.faces);
  return Status::ok;
}

}  // namespace

bool encode_base(const int32_t* coords, uint32_t n, const uint32_t* faces, uint32_t fn,
                 std::vector<uint8_t>& out, std::vector<uint32_t>& given_of, BaseMesh& decoded,
                 std::string& error) {
  Oracle oracle{coords,   faces, {}, std::vector<uint32_t>(n, kNone), std::vector<uint8_t>(fn, 0),
                &given_of};
  oracle.edge.reserve(size_t(fn) * 3);
  for (uint32_t h = 0; h < fn * 3; ++h) {
    const uint32_t a = faces[h], b = faces[next_corner(h)];
    if (a >= n || a == b)
      return error = "face " + PMZ_DECIMAL(h / 3) + " is out of range or degenerate", false;
    if (!oracle.edge.emplace(edge_key(a, b), h).second)
      return error = "directed edge " + PMZ_DECIMAL(a) + " -> " + PMZ_DECIMAL(b) + " used twice",
             false;
  }
  // Both predictors (the parallelogram, the gate's midpoint); the smaller stream is kept.
  std::vector<uint8_t> best;
  for (uint32_t midpoint = 0; midpoint < 2; ++midpoint) {
    given_of.clear();
    given_of.reserve(n);
    std::fill(oracle.decoded.begin(), oracle.decoded.end(), kNone);
    std::fill(oracle.done.begin(), oracle.done.end(), 0);
    oracle.next_seed = oracle.next_isolated = 0;
    std::vector<uint8_t> stream;
    EncodeIO io{RangeEncoder(stream)};
    if (code_base(io, n, fn, midpoint, &oracle, decoded, error) != Status::ok) return false;
    io.rc.finish();
    if (!midpoint || stream.size() < best.size()) best.swap(stream);
  }
  out.insert(out.end(), best.begin(), best.end());
  return true;
}

Status decode_base(const uint8_t* p, size_t size, uint32_t n, uint32_t fn, BaseMesh& out,
                   std::string& error) {
  if (fn > kFacesPerByte * (size + 1) || n > kVerticesPerByte * (size + 1)) {
    error = "BASE counts beyond what its " + PMZ_DECIMAL(size) + " bytes can hold";
    return Status::corrupt;
  }
  RangeDecoder dec(p, size);
  DecodeIO io{dec.state()};
  uint32_t midpoint = 0;  // read as the stream's first symbol
  return code_base(io, n, fn, midpoint, nullptr, out, error);
}

}  // namespace pmz
