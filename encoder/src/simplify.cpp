// SPDX-License-Identifier: MIT
// The collapse engine: half-edge collapses u -> v in order of the metric's cost, each vertex
// keyed in a binary heap by its cheapest outgoing collapse, recomputing only the neighbourhood
// a collapse touches (spec/algorithm.md).
#include "pmz/simplify.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <queue>
#include <thread>
#include <type_traits>

#include "attr_collapse.hpp"
#include "attr_simplify.hpp"
#include "cluster_grid.hpp"
#include "halfedge.hpp"
#include "metric.hpp"
#include "parallel.hpp"
#include "pmz/format.hpp"
#include "survivors.hpp"

namespace pmz {

namespace {

using namespace detail;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// A collapse may turn a surviving face by at most ~78 degrees (cos 0.2) ...
constexpr float kFoldCos = 0.2f;
// ... and may not make a needle (quality 4*sqrt(3)*area / sum of squared edges, 1 for an
// equilateral triangle) below this unless the face was already that bad or stays in its plane
// (normal turned by less than ~0.26 degrees: the thin strips of CAD surfaces are their own
// shape, and forbidding them kept exact collapses out of reach, spec/algorithm.md section 3).
constexpr float kMinQuality = 0.05f;
constexpr float kPlaneCos = 0.99999f;
constexpr float kInfinity = std::numeric_limits<float>::infinity();

// Squared distances from points to the triangle (a, b, c) (Ericson, Real-Time Collision
// Detection 5.1.5: the closest point by the Voronoi region of x). The guard measures several
// points against each triangle: what depends on the triangle alone is computed once.
struct DistanceTriangle {
  const float *a, *b, *c;
  float ab[3], ac[3];
  DistanceTriangle(const float* a_, const float* b_, const float* c_) : a(a_), b(b_), c(c_) {
    sub(b, a, ab), sub(c, a, ac);
  }
  static void sub(const float* p, const float* q, float* r) {
    r[0] = p[0] - q[0], r[1] = p[1] - q[1], r[2] = p[2] - q[2];
  }
  static float dot(const float* p, const float* q) {
    return p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
  }
  float squared_distance(const float* x) const {
    float ap[3], bp[3], cp[3];
    sub(x, a, ap);
    auto to = [&](const float* base, const float* dir, float t) {
      float d[3] = {base[0] + t * dir[0] - x[0], base[1] + t * dir[1] - x[1],
                    base[2] + t * dir[2] - x[2]};
      return dot(d, d);
    };
    const float d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return dot(ap, ap);
    sub(x, b, bp);
    const float d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return dot(bp, bp);
    const float vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return to(a, ab, d1 / (d1 - d3));
    sub(x, c, cp);
    const float d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return dot(cp, cp);
    const float vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return to(a, ac, d2 / (d2 - d6));
    const float va = d3 * d6 - d5 * d4;
    if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
      float bc[3];
      sub(c, b, bc);
      return to(b, bc, (d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    const float denom = va + vb + vc;
    if (!(denom > 0)) {  // degenerate triangle: the nearest of its edges
      float bc[3];
      sub(c, b, bc);
      auto segment = [&](const float* base, const float* dir) {
        const float len = dot(dir, dir);
        float d[3];
        sub(x, base, d);
        const float t = len > 0 ? std::clamp(dot(d, dir) / len, 0.f, 1.f) : 0.f;
        return to(base, dir, t);
      };
      return std::min({segment(a, ab), segment(a, ac), segment(b, bc)});
    }
    const float v = vb / denom, w = vc / denom;
    const float d[3] = {a[0] + ab[0] * v + ac[0] * w - x[0], a[1] + ab[1] * v + ac[1] * w - x[1],
                        a[2] + ab[2] * v + ac[2] * w - x[2]};
    return dot(d, d);
  }
};

// Min-heap of vertices keyed by their cheapest collapse: 4-ary with the keys inline, so a sift
// walks one array (the heap dominated the profile when keys were a separate array).
class VertexHeap {
 public:
  void reset(uint32_t vertex_count) {
    entries.clear();
    pos.assign(vertex_count, kNone);
  }
  bool empty() const { return entries.empty(); }
  // Trades the per-vertex index with another empty heap's (a lane borrowing an idle engine's).
  void swap_index(VertexHeap& o) { pos.swap(o.pos); }
  // Empties the heap in time of its size (a lane's heap serves many cells).
  void clear() {
    for (const Entry& e : entries) pos[e.v] = kNone;
    entries.clear();
  }
  uint32_t top() const { return entries[0].v; }
  bool contains(uint32_t v) const { return pos[v] != kNone; }
  void prefetch(uint32_t v) const { __builtin_prefetch(&pos[v]); }
  void prefetch_entry(uint32_t v) const {
    if (pos[v] != kNone) __builtin_prefetch(&entries[pos[v]]);
  }
  float key(uint32_t v) const { return entries[pos[v]].key; }
  void push_unordered(uint32_t v, float key) {
    pos[v] = uint32_t(entries.size());
    entries.push_back({key, v});
  }
  void build() {
    for (uint32_t i = uint32_t(entries.size()) / 4 + 1; i-- > 0;)
      if (i < entries.size()) sift_down(i);
  }
  void set(uint32_t v, float key) {
    if (pos[v] == kNone) {
      push_unordered(v, key);
      sift_up(pos[v]);
      return;
    }
    Entry& e = entries[pos[v]];
    const float old = e.key;
    e.key = key;
    if (key == old) return;  // a sift would not move it
    if (key < old)
      sift_up(pos[v]);
    else
      sift_down(pos[v]);
  }
  void remove(uint32_t v) {
    const uint32_t i = pos[v];
    if (i == kNone) return;
    const float old = entries[i].key;
    const Entry last = entries.back();
    entries.pop_back();
    pos[v] = kNone;
    if (i == entries.size()) return;
    entries[i] = last;
    pos[last.v] = i;
    if (last.key < old)
      sift_up(i);
    else
      sift_down(i);
  }

 private:
  struct Entry {
    float key;
    uint32_t v;
  };
  std::vector<Entry> entries;
  std::vector<uint32_t> pos;

  void place(uint32_t i, const Entry& e) {
    entries[i] = e;
    pos[e.v] = i;
  }
  void sift_up(uint32_t i) {
    const Entry e = entries[i];
    while (i > 0) {
      const uint32_t parent = (i - 1) / 4;
      if (!(e.key < entries[parent].key)) break;
      place(i, entries[parent]);
      i = parent;
    }
    place(i, e);
  }
  void sift_down(uint32_t i) {
    const Entry e = entries[i];
    const uint32_t n = uint32_t(entries.size());
    for (;;) {
      const uint32_t first = 4 * i + 1;
      if (first >= n) break;
      uint32_t best = first;
      for (uint32_t c = first + 1; c < first + 4 && c < n; ++c)
        if (entries[c].key < entries[best].key) best = c;
      if (!(entries[best].key < e.key)) break;
      place(i, entries[best]);
      i = best;
    }
    place(i, e);
  }
};

struct Candidate {
  float cost;
  uint32_t target;
};

// The Hausdorff guard (Metric::guarded, spec/algorithm.md section 6): per vertex kWitnesses
// original points its region must stay near (those found farthest from the surface so far; at
// the start the vertex itself), and the largest bound of the collapses performed so far.
// One witness forgot the points it displaced, and the surface later drifted from them.
constexpr int kWitnesses = 4;
constexpr int kBoundPoints = 1 + 2 * kWitnesses;  // p_u, witnesses of u and of v

// What the threads simplifying the cells of one level share: the mesh and every term kept per
// vertex, face or half-edge. A cell's collapses write only vertices of the cell and faces whose
// corners are all in it, and its keys read only those (Engine::run_cell).
struct EngineData {
  HalfEdgeMesh m;
  Features feat;
  std::vector<Quadric> quad, accumulated;
  std::vector<double> self_error;
  std::vector<float> witness;
  AttributeField attr;
  std::vector<uint32_t> target;
  std::vector<uint8_t> stale;
  std::vector<uint64_t> cell;
  // Between the levels of a hierarchical simplification: each queued vertex's key (the heaps
  // are per cell), whether a vertex has all its neighbours in its cell at this level, and per
  // vertex the worst guard bound of the cells it was in.
  std::vector<float> key;
  std::vector<uint8_t> inner;
  std::vector<float> region_bound;

  // What an array's elements are kept per (a vertex, a half-edge slot, a face, an attribute
  // wedge) and which ids its values are (none, vertex ids, half-edge slots or wedges).
  enum class Per : uint8_t { vertex, slot, face, wedge };
  enum class Ids : uint8_t { none, vertex, slot, wedge };
  // f(array, per, ids) for every array above: what a cell's collapses can change (a cell run
  // apart hands over the elements it changed: CellResult), and what a cell's region holds of
  // them (CellRegion).
  template <class F>
  void for_each_array(F&& f) {
    constexpr Per V = Per::vertex;
    constexpr Ids N = Ids::none;
    f(m.pos, V, N), f(m.vert, Per::slot, Ids::vertex), f(m.twin, Per::slot, Ids::slot);
    f(m.out, V, Ids::slot), f(feat.face, Per::face, N), f(feat.vertex, V, N), f(quad, V, N);
    f(accumulated, V, N), f(self_error, V, N), f(witness, V, N),
        f(attr.wedge, Per::slot, Ids::wedge);
    f(attr.material, Per::face, N), f(attr.values, Per::wedge, N), f(target, V, Ids::vertex);
    f(stale, V, N), f(cell, V, N), f(key, V, N), f(inner, V, N), f(region_bound, V, N);
  }
};

// What one thread of the engine owns: its heap, the count of faces it simplifies, its record
// and scratch buffers.
struct Pending {
  uint32_t x, h;
  float length_ratio;
  double error;
};
struct EngineLane {
  VertexHeap heap;
  // Scratch: a stamp per vertex for set membership, and buffers reused across collapses.
  std::vector<uint32_t> mark;
  uint32_t mark_id = 0;
  // The stamp perform() gives the vertices whose fan the collapse changed (besides v).
  uint32_t fan_changed = 0;
  std::vector<uint32_t> ring1, ring2, corners, walk, pair = {0, 0};
  std::vector<Candidate> candidates;
  std::vector<Pending> pending;
  std::vector<std::pair<uint32_t, uint32_t>> moved;  // AttributeField::collapse's
  // guard_bound's choice of the witnesses v keeps if the collapse is performed.
  float next_witness[3 * kWitnesses];
  double worst_bound = 0;
  SimplifyStats stats;
  uint64_t faces = 0;
  std::vector<HalfEdgeCollapse>* record = nullptr;
};

// The engine's settings, read-only during a run.
struct EngineSettings {
  Metric metric = Metric::multifeature;
  MetricParams params;
  bool guard = false;
  double inv_unit4 = 1, unit = 1;
  bool stats_enabled = false;
  // Hierarchical simplification: while `cells` is set, a collapse u -> v is legal only when u,
  // v and every neighbour of both have one cell[] (encoder/src/cluster_grid.hpp says why).
  bool cells = false;
  uint64_t max_collapses = UINT64_MAX;  // run() stops after this many (detail::queued_collapses)
  bool keyed = false;                   // the heap holds the keys of an earlier run
};

class Engine : public EngineSettings, public EngineLane {
  std::shared_ptr<EngineData> data_ = std::make_shared<EngineData>();
  Engine* lender_ = nullptr;  // whose heap index and marks this lane holds (Borrow)

 public:
  Engine() = default;
  // A copy has its own data.
  Engine(const Engine& o)
      : EngineSettings(o), EngineLane(o), data_(std::make_shared<EngineData>(*o.data_)) {}
  Engine& operator=(const Engine&) = delete;
  // The first rule of the engine's state that a cell's run (run_cell on `members`, the cell's
  // live vertices) relies on and the state breaks, nullptr when it keeps them all: a cell's
  // region read from bytes (CellRegion::read, which has checked the ids and the half-edges'
  // pairing) is held to them.
  const char* broken_cell_invariant(const std::vector<uint32_t>& members) const;
  // A lane of `o` for one thread of a cell level: o's data and settings, its own heap and
  // scratch.
  struct Lane {};
  Engine(const Engine& o, Lane) : EngineSettings(o), data_(o.data_) {
    cells = keyed = true;
    heap.reset(m.vertex_count());
    mark.assign(m.vertex_count(), 0);
  }
  // A lane working on `o`'s own heap index and marks while o is idle, its heap empty (the cell
  // levels' first lane: two arrays of 4 bytes a vertex less at the encode's peak), until
  // give_back(); the marks' stamps go on from o's, so o's later stamps stay new.
  struct Borrow {};
  Engine(Engine& o, Borrow) : EngineSettings(o), data_(o.data_), lender_(&o) {
    cells = keyed = true;
    heap.swap_index(o.heap);
    mark.swap(o.mark);
    mark_id = o.mark_id;
  }
  ~Engine() { give_back(); }
  void give_back() {
    if (!lender_) return;
    lender_->heap.swap_index(heap);
    lender_->mark.swap(mark);
    lender_->mark_id = mark_id;
    lender_ = nullptr;
  }

  // Frees the engine's arrays and its own heap and marks; nothing may use it afterwards.
  void release() {
    data_.reset();
    heap = VertexHeap();
    std::vector<uint32_t>().swap(mark);
  }

  EngineData* data() { return data_.get(); }
  HalfEdgeMesh& m = data_->m;
  Features& feat = data_->feat;
  // The quadric a cost evaluates: QSlim's accumulated one (qem), or the current mesh's plus
  // quadric_memory times the accumulated one, kept in `accumulated` (multifeature).
  std::vector<Quadric>& quad = data_->quad;
  std::vector<Quadric>& accumulated = data_->accumulated;
  std::vector<double>& self_error = data_->self_error;  // Q_v(p_v) / L^4, cached: half of
                                                        // every cost evaluation
  std::vector<float>& witness = data_->witness;         // kWitnesses points (x, y, z) per vertex
  AttributeField& attr = data_->attr;  // seams and the attribute term (inactive without attributes)
  std::vector<uint64_t>& cell = data_->cell;
  std::vector<float>& key = data_->key;
  std::vector<uint8_t>& inner = data_->inner;
  std::vector<float>& region_bound = data_->region_bound;

  bool init(const IndexedMesh& input, const SimplifyOptions& options, std::string& error);
  void run(const SimplifyOptions& options);
  // The keys of every vertex from scratch, kNone where a vertex has no collapse.
  void initial_keys(std::vector<Candidate>& initial);
  // Collapses until the faces drop to goal (0: no goal) or the heap runs out.
  void collapse_until(uint64_t goal, const SimplifyOptions& options);
  // Keys afresh the vertices of a cell (its live vertices, ascending) inside it that a border
  // held back, into key[].
  void key_cell(const uint32_t* vertices, size_t count);
  // One cell of a level, on a lane: `vertices` (the cell's live vertices, ascending) keyed
  // from key[], collapsed until its `cell_faces` drop to `goal` or the cheapest collapse costs
  // more than options.max_cost, their keys written back.
  void run_cell(const uint32_t* vertices, size_t count, uint64_t cell_faces, uint64_t goal,
                const SimplifyOptions& options);
  // The queued keys of key[] into the heap (after the cell levels, for the whole mesh).
  void load_keys();
  bool queued_key(uint32_t v) const { return stale[v] & kQueued; }
  void set_queued(uint32_t v, Candidate c) {
    target[v] = c.target, key[v] = c.cost, stale[v] |= kQueued;
  }
  // After a cell level: every live vertex with a neighbour in another cell gets its T (none
  // under QEM, which keeps no face and vertex terms) and key recomputed when next needed.
  void hold_borders() {
    const uint8_t flags = metric == Metric::qem ? kCellHeld : kTorsionStale | kCellHeld;
    for (uint32_t v = 0; v < m.vertex_count(); ++v)
      if (m.out[v] != kNone && !inner[v]) stale[v] |= flags;
  }
  void add_counts(const SimplifyStats& s) {
    stats.cost_evaluations += s.cost_evaluations, stats.legality_checks += s.legality_checks;
    stats.guard_checks += s.guard_checks, stats.guard_deferrals += s.guard_deferrals;
  }
  // The queue now, each key beside its collapse's cost from scratch (detail::queued_collapses);
  // input: the mesh init() was given, collapses: those performed (engine ids).
  void queued(const IndexedMesh& input, const std::vector<HalfEdgeCollapse>& collapses,
              std::vector<QueuedCollapse>& out) const;
  // The cost of u -> v as the heap would key it now; NaN if (u, v) is not an edge.
  float edge_cost(uint32_t u, uint32_t v) const {
    float c = std::numeric_limits<float>::quiet_NaN();
    for_each_neighbour(m, u, [&](uint32_t x, uint32_t h) {
      if (x == v) c = cost(u, x, h);
    });
    return c;
  }

 private:
  std::vector<uint32_t>& target = data_->target;
  // Per vertex: T(v) is stale (recomputed when next needed); the key is stale (recomputed when
  // it reaches the top of the heap); Q(v) is still the input's (multifeature: the first
  // recomputation from the current mesh changes its bits even where the faces did not change).
  // kBoundary: the vertex is on the boundary. Collapses never change that for the vertices
  // they keep (an edge becomes a boundary edge only between two boundary vertices, and the
  // link condition keeps holes open), so it is set once.
  // kGuardDeferred: the key is the guard's penalised cost of the collapse to target (set when
  // the collapse was held back; any recomputation of the key clears it).
  // kCellHeld: a collapse out of the vertex was illegal only for the cells (hierarchical
  // simplification): its key is keyed afresh when the next level starts.
  enum : uint8_t {
    kTorsionStale = 1,
    kKeyStale = 2,
    kInputQuadric = 4,
    kBoundary = 8,
    kGuardDeferred = 16,
    kCellHeld = 32,
    kQueued = 64  // between the levels: the vertex has a key in key[] and target[]
  };
  std::vector<uint8_t>& stale = data_->stale;
  uint32_t new_mark() {
    if (++mark_id == 0) std::fill(mark.begin(), mark.end(), 0), mark_id = 1;
    return mark_id;
  }
  // The engine's time is mostly cache misses on the neighbourhood a collapse lands on: the
  // prefetches start the loads of what the next steps read, so that they overlap.
  static void prefetch_quadric(const std::vector<Quadric>& q, uint32_t v) {
    if (q.empty()) return;
    __builtin_prefetch(&q[v]);  // 80 bytes at a multiple of 16: two cache lines
    __builtin_prefetch(reinterpret_cast<const char*>(&q[v]) + sizeof(Quadric) - 1);
  }

  // What every collapse out of u shares, read once per vertex: evaluating its costs from it
  // does the same arithmetic as evaluating each from scratch.
  struct Origin {
    Quadric q;
    double factor;   // c0 + C_norm(u)
    double torsion;  // T(u)
  };
  Origin origin(uint32_t u) const {
    if (metric == Metric::qem) return {quad[u], 0, 0};
    return {quad[u], double(params.quadric_floor) + feat.c_norm(u), double(feat.torsion(u))};
  }
  // Cost of u -> x in two parts: the quadric error, then the factor that weights it.
  double quadric_error(const Origin& o, uint32_t x) const {
    return std::max(0.0, o.q.error(m.p(x)) * inv_unit4 + self_error[x]);
  }
  float weighted(const Origin& o, double e, float length_ratio) const;
  float geometric_cost(const Origin& o, uint32_t x, uint32_t h) const {
    return weighted(o, quadric_error(o, x),
                    metric == Metric::qem ? 0.f : edge_length_ratio(m, feat, h));
  }
  float cost(const Origin& o, uint32_t x, uint32_t h) const {
    const float c = geometric_cost(o, x, h);
    return attr.active ? c + attribute_cost(x, h) : c;
  }
  // Whether a candidate of geometric cost c can still beat best: the attribute term is never
  // negative, so once c alone is not cheaper it is not evaluated (most of the attribute-aware
  // run's time); the same choice as comparing the full costs.
  static bool may_beat(float c, const Candidate& best) {
    return best.target == kNone || c < best.cost;
  }
  // The attribute term of the collapse towards x along h (outgoing u->x, or for the last
  // neighbour of a boundary vertex the incoming boundary half-edge x->u).
  float attribute_cost(uint32_t x, uint32_t h) const {
    if (m.vert[h] == x) return attr.cost(m, m.dest(h), x, kNone, h);
    return attr.cost(m, m.vert[h], x, h, m.twin[h]);
  }
  float cost(uint32_t u, uint32_t x, uint32_t h) const { return cost(origin(u), x, h); }
  bool find_edge(uint32_t u, uint32_t v, uint32_t& ha, uint32_t& hb) const;
  bool legal(uint32_t u, uint32_t v, uint32_t ha, uint32_t hb);
  Candidate best_candidate(uint32_t u) {
    if (m.out[u] == kNone) return {kInfinity, kNone};
    if (stale[u] & kTorsionStale) return scan_with_torsion(u);
    return scan(u, stats.cost_evaluations);
  }
  // scan() for a vertex whose T is stale: T and the costs in one walk round u.
  Candidate scan_with_torsion(uint32_t u);
  // The cheapest direction out of u by cost alone (T(u) up to date); counts its evaluations.
  Candidate scan(uint32_t u, uint64_t& evaluations) const;
  void refresh_torsion(uint32_t u) {
    if (stale[u] & kTorsionStale) feat.update_torsion(m, u), stale[u] &= uint8_t(~kTorsionStale);
  }
  Candidate best_legal_candidate(uint32_t u);
  void set_key(uint32_t v, Candidate c);
  // The guard's bound of u -> v: the largest distance from u's position and the witnesses of u
  // and v to the faces v will have after the collapse; the farthest of these points in
  // next_witness, which keep_witnesses(v) makes v's after the collapse.
  float guard_bound(uint32_t u, uint32_t v, uint32_t ha, uint32_t hb);
  void prefetch_witnesses(uint32_t v) const {  // 48 bytes: one or two cache lines
    const float* w = &witness[size_t(v) * 3 * kWitnesses];
    __builtin_prefetch(w);
    __builtin_prefetch(w + 3 * kWitnesses - 1);
  }
  void keep_witnesses(uint32_t v) {
    std::copy(next_witness, next_witness + 3 * kWitnesses, &witness[size_t(v) * 3 * kWitnesses]);
  }
  // The guard's cost of a collapse of cost c and bound b: c while b stays within guard_slack
  // times the worst bound so far, c * (b / (guard_slack * worst))^2 beyond, the factor at most
  // guard_penalty_cap.
  float guarded(float c, float bound) const {
    const double scale = double(params.guard_slack) * worst_bound;
    if (!(scale > 0) || !(bound > scale)) return c;
    const double excess = double(bound) / scale;
    return float(double(c) * std::min(double(params.guard_penalty_cap), excess * excess));
  }
  void perform(uint32_t u, uint32_t v, uint32_t ha, uint32_t hb, float c);
  void fix_out(uint32_t w, uint32_t candidate);
  void update_after(uint32_t u, uint32_t v);
  bool final_boundary_collapse();
};

const char* Engine::broken_cell_invariant(const std::vector<uint32_t>& members) const {
  // A collapse rewrites the corners of u's faces and links the outer twins of the two it
  // deletes: a face with a repeated corner would leave v a face of two corners.
  // The attribute field reads the values of the wedge of every corner it moves or prices.
  for (uint32_t f = 0; f < m.face_count(); ++f) {
    const uint32_t* c = &m.vert[HalfEdgeMesh::half_edge(f, 0)];
    if (c[0] == kNone) continue;
    if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0]) return "a face repeats a corner";
    const uint32_t* w = attr.active ? &attr.wedge[HalfEdgeMesh::half_edge(f, 0)] : nullptr;
    if (w && (w[0] == kNone || w[1] == kNone || w[2] == kNone))
      return "a corner without an attribute wedge";
  }
  const uint32_t n = m.vertex_count();
  for (uint32_t v = 0; v < n; ++v)
    if (stale[v] >= 2 * kQueued || inner[v] > 1) return "a vertex's flags are out of range";
  // A stale T(v) or key is recomputed from the face and vertex terms, which only the
  // multifeature metric keeps.
  if (feat.face.empty() || feat.vertex.empty())
    for (uint32_t v = 0; v < n; ++v)
      if (stale[v] & (kTorsionStale | kKeyStale))
        return "a vertex's torsion or key is flagged stale without its terms";
  // A collapse is legal only with u, v and all their neighbours in u's cell, so the vertices
  // it touches are the cell's exactly when no other vertex has the cell's key.
  std::vector<uint8_t> in_cell(n, 0);
  for (uint32_t v : members) in_cell[v] = 1;
  for (uint32_t v = 0; v < n && !members.empty(); ++v)
    if ((cell[v] == cell[members[0]]) != bool(in_cell[v]))
      return "a vertex's cell is not the cell of its vertices";
  // Each vertex of the cell: its faces are one fan, swept by the walk from out[v] (the
  // boundary half-edge when it has one, and then flagged kBoundary: fix_out keeps it so), and
  // it meets every neighbour once. (The walk ends: twins pair up, so a rotation never comes back
  // to a half-edge but the first.)
  std::vector<uint32_t> leaving(n, 0), seen(n, kNone);
  for (uint32_t h = 0; h < m.slot_count(); ++h)
    if (m.vert[h] != kNone) ++leaving[m.vert[h]];
  for (uint32_t v : members) {
    uint32_t swept = 0;
    bool twice = false;
    for_each_neighbour(m, v, [&](uint32_t w, uint32_t h) {
      swept += m.vert[h] == v;
      twice |= seen[w] == v;
      seen[w] = v;
    });
    if (swept == 0 || swept != leaving[v] || twice)
      return "the faces round a vertex of the cell are not one fan";
    if (((stale[v] & kBoundary) != 0) != m.is_boundary(v))
      return "a vertex of the cell is flagged on the boundary against its faces";
    // run_cell queues v with its key and target; the collapse reads the target.
    if (inner[v] && (stale[v] & kQueued) && target[v] >= n)
      return "a queued vertex without a target";
  }
  return nullptr;
}

void Engine::set_key(uint32_t v, Candidate c) {
  stale[v] &= uint8_t(~kGuardDeferred);
  if (c.target == kNone) {
    heap.remove(v);
    return;
  }
  target[v] = c.target;
  heap.set(v, c.cost);
}

float Engine::guard_bound(uint32_t u, uint32_t v, uint32_t ha, uint32_t hb) {
  ++stats.guard_checks;
  const uint32_t fa = ha != kNone ? HalfEdgeMesh::face(ha) : kNone,
                 fb = hb != kNone ? HalfEdgeMesh::face(hb) : kNone;
  const float* points[kBoundPoints];
  points[0] = m.p(u);
  for (int i = 0; i < kWitnesses; ++i) {
    points[1 + i] = &witness[(size_t(u) * kWitnesses + i) * 3];
    points[1 + kWitnesses + i] = &witness[(size_t(v) * kWitnesses + i) * 3];
  }
  // The distances of the distinct points only: the same point gives the same distance, and
  // most vertices carry few distinct points (at the start the nine are two: p_u and p_v).
  int first_equal[kBoundPoints], distinct[kBoundPoints], distinct_count = 0;
  for (int i = 0; i < kBoundPoints; ++i) {
    first_equal[i] = i;
    for (int j = 0; j < distinct_count; ++j)
      if (std::equal(points[i], points[i] + 3, points[distinct[j]])) {
        first_equal[i] = distinct[j];
        break;
      }
    if (first_equal[i] == i) distinct[distinct_count++] = i;
  }
  float nearest[kBoundPoints];
  std::fill(nearest, nearest + kBoundPoints, kInfinity);
  const float* pv = m.p(v);
  auto fan = [&](uint32_t centre) {
    for_each_outgoing(m, centre, [&](uint32_t h) {
      if (HalfEdgeMesh::face(h) == fa || HalfEdgeMesh::face(h) == fb) return;
      const DistanceTriangle t(pv, m.p(m.dest(h)), m.p(m.vert[HalfEdgeMesh::prev(h)]));
      for (int k = 0; k < distinct_count; ++k) {
        const int i = distinct[k];
        nearest[i] = std::min(nearest[i], t.squared_distance(points[i]));
      }
    });
  };
  fan(u);
  fan(v);
  for (int i = 0; i < kBoundPoints; ++i) nearest[i] = nearest[first_equal[i]];
  // The kWitnesses farthest distinct points, ties in the order above (deterministic); when fewer
  // are distinct (at the start every witness of a vertex is the vertex), the farthest repeats.
  int order[kBoundPoints];
  for (int i = 0; i < kBoundPoints; ++i) order[i] = i;
  std::stable_sort(order, order + kBoundPoints,
                   [&](int a, int b) { return nearest[a] > nearest[b]; });
  int kept = 0;
  for (int j = 0; j < kBoundPoints && kept < kWitnesses; ++j) {
    const float* p = points[order[j]];
    bool seen = false;
    for (int i = 0; i < kept && !seen; ++i) seen = std::equal(p, p + 3, &next_witness[i * 3]);
    if (!seen) std::copy(p, p + 3, &next_witness[3 * kept++]);
  }
  for (int i = kept; i < kWitnesses; ++i)
    std::copy(next_witness, next_witness + 3, &next_witness[i * 3]);
  return nearest[order[0]] < kInfinity ? std::sqrt(nearest[order[0]]) : 0.f;
}

// Cost of u -> x (o = origin(u)) from its quadric error e and the length ratio of the edge.
inline float Engine::weighted(const Origin& o, double e, float length_ratio) const {
  if (metric == Metric::qem) return float(e);
  // CA and CB both weight the quadric error (spec/algorithm.md section 2): a collapse that
  // moves no surface is free whatever the normals and torsion around it.
  const double torsion = double(params.torsion_weight) * length_ratio * o.torsion * unit;
  return float(e * (o.factor + torsion));
}

Candidate Engine::scan_with_torsion(uint32_t u) {
  const bool boundary = m.is_boundary(u);
  Origin o = origin(u);
  Features::TorsionSum t;
  pending.clear();
  for_each_neighbour(m, u, [&](uint32_t x, uint32_t h) {
    t.add(feat, u, x, h);
    if (boundary && m.twin[h] != kNone) return;  // interior directions are never legal for u
    pending.push_back({x, h, edge_length_ratio(m, feat, h), quadric_error(o, x)});
  });
  feat.vertex[u].torsion = t.value();
  stale[u] &= uint8_t(~kTorsionStale);
  o.torsion = double(feat.torsion(u));
  Candidate best{kInfinity, kNone};
  for (const Pending& p : pending) {
    ++stats.cost_evaluations;
    float c = weighted(o, p.error, p.length_ratio);
    if (!may_beat(c, best)) continue;
    if (attr.active) c += attribute_cost(p.x, p.h);
    if (c < best.cost || best.target == kNone) best = {c, p.x};
  }
  return best;
}

bool Engine::find_edge(uint32_t u, uint32_t v, uint32_t& ha, uint32_t& hb) const {
  ha = hb = kNone;
  for_each_outgoing(m, u, [&](uint32_t h) {
    if (m.dest(h) == v) ha = h;
    const uint32_t p = HalfEdgeMesh::prev(h);
    if (m.vert[p] == v) hb = p;
  });
  return ha != kNone || hb != kNone;
}

bool Engine::legal(uint32_t u, uint32_t v, uint32_t ha, uint32_t hb) {
  ++stats.legality_checks;
  const bool boundary_edge = ha == kNone || hb == kNone;
  // A boundary vertex moves only along its boundary (keeps the boundary's shape and count).
  if (m.is_boundary(u) && !boundary_edge) return false;
  if (boundary_edge) {
    // The last triangle of a disc stays.
    const uint32_t h = ha != kNone ? ha : hb;
    if (m.twin[HalfEdgeMesh::next(h)] == kNone && m.twin[HalfEdgeMesh::prev(h)] == kNone)
      return false;
  }
  // Seams and material boundaries: along them or not at all (spec/algorithm.md section 7).
  if (attr.active && !attr.allowed(m, u, v)) return false;
  const uint64_t home = cells ? cell[u] : 0;
  if (cells && cell[v] != home) {
    stale[u] |= kCellHeld;
    return false;
  }
  const uint32_t vl = ha != kNone ? m.vert[HalfEdgeMesh::prev(ha)] : kNone;
  const uint32_t vr = hb != kNone ? m.vert[HalfEdgeMesh::prev(hb)] : kNone;
  // Link condition: u and v share no neighbour but the wedge vertices (else the collapse
  // pinches the surface or closes a handle or a 3-edge hole).
  new_mark();
  uint32_t valence_u = 0, valence_v = 0;
  bool foreign = false;  // a neighbour in another cell
  for_each_neighbour(m, u, [&](uint32_t w, uint32_t) {
    mark[w] = mark_id, ++valence_u;
    foreign |= cells && cell[w] != home;
  });
  bool shared = false;
  for_each_neighbour(m, v, [&](uint32_t w, uint32_t) {
    ++valence_v;
    shared |= mark[w] == mark_id && w != vl && w != vr;
    foreign |= cells && cell[w] != home;
  });
  if (shared) return false;
  if (foreign) {
    stale[u] |= kCellHeld;
    return false;
  }
  if (!boundary_edge && valence_u == 3 && valence_v == 3) return false;  // a tetrahedron stays
  // Two faces on the same three vertices (a closed two-face component) stay: the collapse would
  // delete both, each the other's outer twin, and leave v without a face.
  if (!boundary_edge && vl == vr) return false;
  // Geometry of the faces that survive around u, with u moved onto v.
  const uint32_t fa = ha != kNone ? HalfEdgeMesh::face(ha) : kNone,
                 fb = hb != kNone ? HalfEdgeMesh::face(hb) : kNone;
  const float* pu = m.p(u);
  const float* pv = m.p(v);
  bool ok = true;
  for_each_outgoing(m, u, [&](uint32_t h) {
    if (!ok || HalfEdgeMesh::face(h) == fa || HalfEdgeMesh::face(h) == fb) return;
    const float* pb = m.p(m.dest(h));
    const float* pc = m.p(m.vert[HalfEdgeMesh::prev(h)]);
    auto normal = [&](const float* a, float n[3]) {
      const float e1[3] = {pb[0] - a[0], pb[1] - a[1], pb[2] - a[2]};
      const float e2[3] = {pc[0] - a[0], pc[1] - a[1], pc[2] - a[2]};
      n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2],
      n[2] = e1[0] * e2[1] - e1[1] * e2[0];
      return e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2] + e2[0] * e2[0] + e2[1] * e2[1] +
             e2[2] * e2[2];
    };
    float n_old[3], n_new[3];
    const float l_old = normal(pu, n_old), l_new = normal(pv, n_new);
    const float a_old = std::sqrt(n_old[0] * n_old[0] + n_old[1] * n_old[1] + n_old[2] * n_old[2]);
    const float a_new = std::sqrt(n_new[0] * n_new[0] + n_new[1] * n_new[1] + n_new[2] * n_new[2]);
    if (!(a_new > 0)) {
      ok = false;
      return;
    }
    const float turn = n_old[0] * n_new[0] + n_old[1] * n_new[1] + n_old[2] * n_new[2];
    if (turn < kFoldCos * a_old * a_new) {
      ok = false;
      return;
    }
    const float bc = (pb[0] - pc[0]) * (pb[0] - pc[0]) + (pb[1] - pc[1]) * (pb[1] - pc[1]) +
                     (pb[2] - pc[2]) * (pb[2] - pc[2]);
    const float q_old = 3.4641016f * a_old / (l_old + bc),
                q_new = 3.4641016f * a_new / (l_new + bc);
    if (q_new < kMinQuality && q_new < q_old && turn < kPlaneCos * a_old * a_new) ok = false;
  });
  return ok;
}

// The cheapest direction by cost alone; legality is checked when it reaches the top of the heap.
Candidate Engine::scan(uint32_t u, uint64_t& evaluations) const {
  Candidate best{kInfinity, kNone};
  const bool boundary = m.is_boundary(u);
  const Origin o = origin(u);
  for_each_neighbour(m, u, [&](uint32_t x, uint32_t h) {
    if (boundary && m.twin[h] != kNone) return;  // interior directions are never legal for u
    ++evaluations;
    float c = geometric_cost(o, x, h);
    if (!may_beat(c, best)) return;
    if (attr.active) c += attribute_cost(x, h);
    if (c < best.cost || best.target == kNone) best = {c, x};
  });
  return best;
}

Candidate Engine::best_legal_candidate(uint32_t u) {
  candidates.clear();
  if (m.out[u] == kNone) return {kInfinity, kNone};
  refresh_torsion(u);
  const bool boundary = m.is_boundary(u);
  const Origin o = origin(u);
  for_each_neighbour(m, u, [&](uint32_t x, uint32_t h) {
    if (boundary && m.twin[h] != kNone) return;
    ++stats.cost_evaluations;
    candidates.push_back({cost(o, x, h), x});
  });
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
  for (const Candidate& c : candidates) {
    uint32_t ha, hb;
    if (find_edge(u, c.target, ha, hb) && legal(u, c.target, ha, hb)) return c;
  }
  return {kInfinity, kNone};
}

// Makes out[w] a live outgoing half-edge, the boundary one if w is on the boundary.
void Engine::fix_out(uint32_t w, uint32_t candidate) {
  uint32_t h = m.out[w];
  if (h == kNone || !m.face_alive(HalfEdgeMesh::face(h))) h = candidate;
  if (h == kNone) {
    m.out[w] = kNone;
    return;
  }
  // An interior vertex may keep any live out-edge (the walk below would go round its whole fan
  // back to h); a boundary vertex needs the one without a twin.
  const uint32_t start = h;
  if (stale[w] & kBoundary) {
    for (uint32_t t = m.twin[h]; t != kNone; t = m.twin[h]) {
      h = HalfEdgeMesh::next(t);
      if (h == start) break;
    }
  }
  m.out[w] = h;
}

void Engine::perform(uint32_t u, uint32_t v, uint32_t ha, uint32_t hb, float c) {
  const uint32_t vl = ha != kNone ? m.vert[HalfEdgeMesh::prev(ha)] : kNone;
  const uint32_t vr = hb != kNone ? m.vert[HalfEdgeMesh::prev(hb)] : kNone;
  record->push_back({u, v, vl, vr, c});
  if (attr.active) attr.collapse(m, u, ha, hb, moved, !cells);
  if (metric == Metric::qem) {
    quad[v].add(quad[u]);
    self_error[v] = quad[v].error(m.p(v)) * inv_unit4;
  } else if (!accumulated.empty()) {
    accumulated[v].add(accumulated[u]);  // quad[v] is recomputed in update_after
  }
  const uint32_t fa = ha != kNone ? HalfEdgeMesh::face(ha) : kNone,
                 fb = hb != kNone ? HalfEdgeMesh::face(hb) : kNone;
  corners.clear();
  for_each_outgoing(m, u, [&](uint32_t h) {
    if (HalfEdgeMesh::face(h) != fa && HalfEdgeMesh::face(h) != fb) corners.push_back(h);
  });
  // The faces that change are u's surviving ones (u becomes v) and fa, fb (deleted): their
  // other corners are the vertices whose fan changed, besides v.
  fan_changed = new_mark();
  for (uint32_t h : corners)
    m.vert[h] = v,
    mark[m.vert[HalfEdgeMesh::next(h)]] = mark[m.vert[HalfEdgeMesh::prev(h)]] = fan_changed;
  if (vl != kNone) mark[vl] = fan_changed;
  if (vr != kNone) mark[vr] = fan_changed;
  // The two outer edges of each deleted face become one edge: link their outer twins.
  auto link = [&](uint32_t a, uint32_t b) {
    if (a != kNone) m.twin[a] = b;
    if (b != kNone) m.twin[b] = a;
  };
  uint32_t vl_v = kNone, v_vl = kNone, vr_v = kNone, v_vr = kNone;
  if (ha != kNone) {
    vl_v = m.twin[HalfEdgeMesh::next(ha)];
    v_vl = m.twin[HalfEdgeMesh::prev(ha)];
    link(vl_v, v_vl);
  }
  if (hb != kNone) {
    vr_v = m.twin[HalfEdgeMesh::next(hb)];
    v_vr = m.twin[HalfEdgeMesh::prev(hb)];
    link(vr_v, v_vr);
  }
  for (uint32_t f : {fa, fb}) {
    if (f == kNone) continue;
    for (uint32_t k = 0; k < 3; ++k)
      m.vert[HalfEdgeMesh::half_edge(f, k)] = kNone, m.twin[HalfEdgeMesh::half_edge(f, k)] = kNone;
    --faces;
  }
  m.out[u] = kNone;
  heap.remove(u);
  // The vertex now at the top is most often the next one taken; its target and flags are read
  // first thing then, and would be misses: start them while the 1-ring is updated.
  if (!heap.empty()) {
    const uint32_t next = heap.top();
    __builtin_prefetch(&target[next]);
    __builtin_prefetch(&stale[next]);
    __builtin_prefetch(&m.out[next]);
  }
  fix_out(v, v_vl != kNone ? v_vl : v_vr != kNone ? v_vr : corners.empty() ? kNone : corners[0]);
  if (vl != kNone)
    fix_out(vl, vl_v != kNone ? vl_v : v_vl != kNone ? HalfEdgeMesh::next(v_vl) : kNone);
  if (vr != kNone)
    fix_out(vr, vr_v != kNone ? vr_v : v_vr != kNone ? HalfEdgeMesh::next(v_vr) : kNone);
}

// Recomputes what a collapse onto v changed. Faces around v and the normal terms (n, C_norm,
// B) of its 1-ring are recomputed now, and the keys of the 1-ring. T changes on the 2-ring (B
// changed on the 1-ring): it is marked stale and recomputed when next used, and the keys of
// the outer ring are marked stale and recomputed when they reach the top of the heap.
// Under QEM only the edges to v changed cost: a 1-ring vertex whose best target was neither u
// nor v only compares its old best with the edge to v.
void Engine::update_after(uint32_t u, uint32_t v) {
  const auto t0 = stats_enabled ? Clock::now() : Clock::time_point{};
  ring1.clear();
  ring1.push_back(v);
  for_each_neighbour(m, v, [&](uint32_t w, uint32_t) { ring1.push_back(w); });
  for (uint32_t w : ring1) {
    prefetch_quadric(quad, w);
    prefetch_quadric(accumulated, w);  // the recomputed vertices' current Q reads it
    __builtin_prefetch(&self_error[w]);
    __builtin_prefetch(&m.out[w]);
    __builtin_prefetch(&target[w]);
    heap.prefetch(w);
    if (metric == Metric::multifeature) __builtin_prefetch(&feat.vertex[w]);
  }
  if (metric == Metric::multifeature) {
    for (uint32_t w : ring1)
      if (const uint32_t h = m.out[w]; h != kNone) {
        __builtin_prefetch(&feat.face[HalfEdgeMesh::face(h)]);
        prefetch_face_links(m, h);
      }
    // Flags the 2-ring without a visited set (setting a flag twice is harmless); the 1-ring,
    // flagged too, gets its key recomputed below. (Flagging only next to a changed B or Q is
    // not exact: a stale key is re-read without legality, so a vertex keyed by its best legal
    // collapse goes back to its cheapest key, and the heap operations would differ.) The walks
    // go first and interleaved: they load every face the steps below read, overlapping the misses.
    // The flags are set after the walks, their loads started with the others'.
    ring2.clear();
    for_each_neighbour_interleaved(
        m, ring1, walk,
        [&](uint32_t x) {
          ring2.push_back(x);
          __builtin_prefetch(&stale[x]);
          // The 1-ring's keys read B (torsion), p and Q(p) of its neighbours.
          __builtin_prefetch(&feat.vertex[x]);
          __builtin_prefetch(m.p(x));
          __builtin_prefetch(&self_error[x]);
        },
        [&](uint32_t f) { __builtin_prefetch(&feat.face[f]); });
    for_each_outgoing(m, v, [&](uint32_t h) { feat.update_face(m, HalfEdgeMesh::face(h)); });
    // In a cell level another cell's vertices are not this thread's: run_cell_levels flags
    // every vertex with a neighbour in another cell when the level ends.
    if (cells) {
      for (uint32_t x : ring2)
        if (cell[x] == cell[v]) stale[x] |= kTorsionStale | kKeyStale;
    } else {
      for (uint32_t x : ring2) stale[x] |= kTorsionStale | kKeyStale;
    }
    for (uint32_t w : ring1) {
      // A vertex whose fan did not change reads bit for bit the same faces: same terms.
      if (w != v && mark[w] != fan_changed && !(stale[w] & kInputQuadric)) continue;
      stale[w] &= uint8_t(~kInputQuadric);
      feat.update_normal_terms(m, w);
      // Q of the current mesh (not accumulated): only the 1-ring's faces changed.
      current_quadric(m, feat, w, params.boundary_weight, quad[w]);
      if (!accumulated.empty())
        for (int i = 0; i < 10; ++i)
          quad[w].a[i] += double(params.quadric_memory) * accumulated[w].a[i];
      self_error[w] = quad[w].error(m.p(w)) * inv_unit4;
    }
  }
  const auto t1 = stats_enabled ? Clock::now() : Clock::time_point{};
  for (uint32_t w : ring1) heap.prefetch_entry(w);
  if (metric == Metric::multifeature) {
    for (uint32_t w : ring1)
      if (!cells || inner[w]) stale[w] &= uint8_t(~kKeyStale), set_key(w, best_candidate(w));
  } else {
    set_key(v, best_candidate(v));
    for_each_neighbour(m, v, [&](uint32_t w, uint32_t h) {
      if (cells && !inner[w]) return;
      const uint32_t t = target[w];
      if (!heap.contains(w) || t == u || t == v || t == kNone) {
        set_key(w, best_candidate(w));
      } else if (!(m.twin[h] != kNone &&
                   m.is_boundary(w))) {  // boundary vertices move along the boundary
        ++stats.cost_evaluations;
        const float c = cost(w, v, h);
        if (c < heap.key(w)) set_key(w, {c, v});
      }
    });
  }
  if (stats_enabled) {
    stats.update_terms += std::chrono::duration<double>(t1 - t0).count();
    stats.update_costs += seconds_since(t1);
  }
}

// With one face left to remove and only interior (two-face) collapses on top, take the
// cheapest legal boundary collapse instead so the face count comes out exact.
bool Engine::final_boundary_collapse() {
  Candidate best{kInfinity, kNone};
  uint32_t best_u = kNone;
  for (uint32_t u = 0; u < m.vertex_count(); ++u) {
    if (m.out[u] == kNone || !m.is_boundary(u)) continue;
    refresh_torsion(u);
    for_each_neighbour(m, u, [&](uint32_t x, uint32_t h) {
      if (m.twin[h] != kNone) return;
      const float c = cost(u, x, h);
      if (best_u != kNone && !(c < best.cost)) return;
      uint32_t ha, hb;
      if (find_edge(u, x, ha, hb) && legal(u, x, ha, hb)) best = {c, x}, best_u = u;
    });
  }
  if (best_u == kNone) return false;
  uint32_t ha, hb;
  find_edge(best_u, best.target, ha, hb);
  const float bound = guard ? guard_bound(best_u, best.target, ha, hb) : 0.f;
  perform(best_u, best.target, ha, hb, best.cost);
  if (guard) {
    worst_bound = std::max(worst_bound, double(bound));
    keep_witnesses(best.target);
  }
  return true;
}

bool Engine::init(const IndexedMesh& input, const SimplifyOptions& options, std::string& error) {
  if (!build_halfedge(input, m, error)) return false;
  guard = options.metric == Metric::guarded;
  metric = guard ? Metric::multifeature : options.metric;
  params = options.params;
  stats_enabled = options.stats != nullptr;
  const uint32_t n = m.vertex_count();
  unit = mean_edge_length(m);
  if (!(unit > 0)) unit = 1;
  inv_unit4 = 1.0 / (unit * unit * unit * unit);
  attr.init(m, input.attributes.corner_wedges, input.attributes.face_materials, input.attributes,
            options.attributes, params.attribute_weight, unit);
  initial_quadrics(m, params.boundary_weight, quad);
  feat.epsilon = params.epsilon;
  if (metric == Metric::multifeature) feat.compute_all(m);
  self_error.resize(n);
  if (metric == Metric::multifeature && params.quadric_memory > 0) {
    // At the start the current mesh's quadric is the accumulated one.
    accumulated = quad;
    for (Quadric& q : quad)
      for (double& a : q.a) a *= 1.0 + double(params.quadric_memory);
  }
  parallel_halves(n, [&](uint32_t begin, uint32_t end) {
    for (uint32_t v = begin; v < end; ++v) self_error[v] = quad[v].error(m.p(v)) * inv_unit4;
  });
  stale.assign(n, metric == Metric::multifeature ? kInputQuadric : 0);
  for (uint32_t v = 0; v < n; ++v)
    if (m.out[v] != kNone && m.is_boundary(v)) stale[v] |= kBoundary;
  if (guard) {
    witness.resize(size_t(n) * 3 * kWitnesses);
    for (uint32_t v = 0; v < n; ++v)
      for (int i = 0; i < kWitnesses; ++i)
        std::copy(m.p(v), m.p(v) + 3, &witness[(size_t(v) * kWitnesses + i) * 3]);
  }
  faces = m.face_count();
  mark.assign(n, 0);
  target.assign(n, kNone);
  heap.reset(n);
  return true;
}

void Engine::run(const SimplifyOptions& options) {
  auto t0 = Clock::now();
  const uint32_t n = m.vertex_count();
  if (keyed) {
    // A later run (the next level of a hierarchical simplification): the vertices whose best
    // collapse the last level's cells held back are keyed afresh; the other keys stand.
    for (uint32_t v = 0; v < n; ++v)
      if (stale[v] & kCellHeld) {
        stale[v] &= uint8_t(~kCellHeld);
        set_key(v, best_candidate(v));
      }
  } else {
    // The initial keys, pushed in vertex order.
    std::vector<Candidate> initial;
    initial_keys(initial);
    for (uint32_t v = 0; v < n; ++v) {
      if (initial[v].target == kNone) continue;
      target[v] = initial[v].target;
      heap.push_unordered(v, initial[v].cost);
    }
    heap.build();
    keyed = true;
  }
  stats.initial_costs = seconds_since(t0);
  t0 = Clock::now();
  collapse_until(options.target_faces, options);
  stats.collapse = seconds_since(t0) - stats.update_terms - stats.update_costs;
  stats.guard_worst_bound = worst_bound;
}

void Engine::initial_keys(std::vector<Candidate>& initial) {
  // On two threads: T is not stale at the start, nothing else is written.
  const uint32_t n = m.vertex_count();
  initial.resize(n);
  uint64_t evaluations[2] = {0, 0};
  parallel_halves(n, [&](uint32_t begin, uint32_t end) {
    for (uint32_t v = begin; v < end; ++v)
      initial[v] =
          m.out[v] == kNone ? Candidate{kInfinity, kNone} : scan(v, evaluations[begin != 0]);
  });
  stats.cost_evaluations += evaluations[0] + evaluations[1];
}

void Engine::collapse_until(uint64_t goal, const SimplifyOptions& options) {
  const uint64_t start_faces = faces;
  const uint64_t progress_step = std::max<uint64_t>(1, start_faces / 200);
  uint64_t next_progress = progress_step;
  while (!heap.empty()) {
    if ((goal && faces <= goal) || record->size() >= max_collapses) break;
    const uint32_t u = heap.top(), v = target[u];
    if (stale[u] & kKeyStale) {
      stale[u] &= uint8_t(~kKeyStale);
      // Its neighbourhood is cold: start the loads of the fan and of what the scan reads.
      pair.resize(1), pair[0] = u;
      prefetch_fans(m, pair, walk, [&](uint32_t x) {
        __builtin_prefetch(&feat.vertex[x]);
        __builtin_prefetch(m.p(x));
        __builtin_prefetch(&self_error[x]);
      });
      set_key(u, best_candidate(u));
      continue;
    }
    const float c = heap.key(u);
    if (options.max_cost >= 0 && c > options.max_cost) break;
    // The legality check walks the fans of u and v; v's position and the quadrics are needed
    // after. A prefetch walk over both fans, each from both ends, first loads their faces (and
    // the positions the geometry checks read) four misses at a time instead of one.
    __builtin_prefetch(m.p(v));
    prefetch_quadric(quad, u);
    prefetch_quadric(quad, v);
    prefetch_quadric(accumulated, u);
    prefetch_quadric(accumulated, v);
    if (guard) prefetch_witnesses(u), prefetch_witnesses(v);
    pair.resize(2), pair[0] = u, pair[1] = v;
    prefetch_fans(m, pair, walk, [&](uint32_t x) { __builtin_prefetch(m.p(x)); });
    uint32_t ha, hb;
    if (!find_edge(u, v, ha, hb) || !legal(u, v, ha, hb)) {
      set_key(u, best_legal_candidate(u));
      continue;
    }
    const uint64_t removes = (ha != kNone) + (hb != kNone);
    if (goal && faces - removes < goal) {
      if (!cells) final_boundary_collapse();  // a cell's goal need not be met exactly
      break;
    }
    float bound = 0;
    if (guard) {
      // Hold back a collapse whose bound exceeds the worst so far (times the slack): its cost
      // is raised by the square of the excess and it goes back into the heap, once; a collapse
      // that moves no surface (cost 0) is never held back.
      bound = guard_bound(u, v, ha, hb);
      if (const float g = guarded(c, bound); !(stale[u] & kGuardDeferred) && g > c) {
        ++stats.guard_deferrals;
        heap.set(u, g);
        stale[u] |= kGuardDeferred;
        continue;
      }
      stale[u] &= uint8_t(~kGuardDeferred);
    }
    perform(u, v, ha, hb, c);
    if (guard) {
      worst_bound = std::max(worst_bound, double(bound));
      keep_witnesses(v);
    }
    update_after(u, v);
    if (options.progress && start_faces - faces >= next_progress) {
      next_progress += progress_step;
      const double span = double(start_faces - std::min(goal, start_faces));
      options.progress(span > 0 ? std::min(1.0, double(start_faces - faces) / span) : 1.0);
    }
  }
}

void Engine::key_cell(const uint32_t* vertices, size_t count) {
  for (size_t i = 0; i < count; ++i) {
    const uint32_t v = vertices[i];
    if (!inner[v] || !(stale[v] & kCellHeld)) continue;
    stale[v] &= uint8_t(~(kCellHeld | kGuardDeferred | kQueued));
    const Candidate c = best_candidate(v);
    if (c.target != kNone) set_queued(v, c);
  }
}

void Engine::run_cell(const uint32_t* vertices, size_t count, uint64_t cell_faces, uint64_t goal,
                      const SimplifyOptions& options) {
  // The cell's heap: its vertices with every neighbour in the cell (no other can be u or v of
  // a collapse confined to it). The guard's worst bound starts at the worst of the cells of the
  // levels below that its vertices were in.
  faces = cell_faces;
  worst_bound = 0;
  for (size_t i = 0; i < count; ++i) {
    const uint32_t v = vertices[i];
    if (guard) worst_bound = std::max(worst_bound, double(region_bound[v]));
    if (inner[v] && (stale[v] & kQueued)) heap.push_unordered(v, key[v]);
  }
  heap.build();
  collapse_until(goal, options);
  for (size_t i = 0; i < count; ++i) {
    const uint32_t v = vertices[i];
    if (guard) region_bound[v] = float(worst_bound);
    if (!inner[v]) continue;
    if (heap.contains(v))
      key[v] = heap.key(v), stale[v] |= kQueued;
    else
      stale[v] &= uint8_t(~kQueued);
  }
  heap.clear();
}

void Engine::load_keys() {
  for (uint32_t v = 0; v < m.vertex_count(); ++v) {
    if (guard && v < region_bound.size())
      worst_bound = std::max(worst_bound, double(region_bound[v]));
    if (!(stale[v] & kQueued)) continue;
    stale[v] &= uint8_t(~kQueued);
    heap.push_unordered(v, key[v]);
  }
  heap.build();
  keyed = true;
}

void Engine::queued(const IndexedMesh& input, const std::vector<HalfEdgeCollapse>& collapses,
                    std::vector<QueuedCollapse>& out) const {
  // A copy whose every cached term is rebuilt from the current mesh: the input's quadrics summed
  // over each vertex's merged vertices (the accumulated quadric), the face and vertex terms with
  // torsion, the current quadric and its self error.
  Engine fresh = *this;
  HalfEdgeMesh start;
  std::string error;
  build_halfedge(input, start, error);
  std::vector<Quadric> initial, merged(m.vertex_count());
  initial_quadrics(start, params.boundary_weight, initial);
  CollapseSequence performed;
  performed.mesh = input;
  performed.collapses = collapses;
  const std::vector<uint32_t> survivor = collapse_survivors(performed, collapses.size());
  for (uint32_t x = 0; x < m.vertex_count(); ++x) merged[survivor[x]].add(initial[x]);
  if (metric == Metric::multifeature) fresh.feat.compute_all(m);
  for (uint32_t v = 0; v < m.vertex_count(); ++v) {
    if (m.out[v] == kNone) continue;
    if (metric == Metric::qem) {
      fresh.quad[v] = merged[v];
    } else {
      current_quadric(m, fresh.feat, v, params.boundary_weight, fresh.quad[v]);
      for (int i = 0; i < 10; ++i)
        fresh.quad[v].a[i] += double(params.quadric_memory) * merged[v].a[i];
    }
    fresh.self_error[v] = fresh.quad[v].error(m.p(v)) * inv_unit4;
  }
  // And the cost from the engine's own terms, T first brought up to date where it is flagged
  // stale, as it would be before a key is computed.
  Engine now = *this;
  out.clear();
  for (uint32_t u = 0; u < m.vertex_count(); ++u) {
    if (!heap.contains(u)) continue;
    now.refresh_torsion(u);
    out.push_back({u, target[u], heap.key(u), now.edge_cost(u, target[u]),
                   fresh.edge_cost(u, target[u]), (stale[u] & kKeyStale) != 0,
                   (stale[u] & kGuardDeferred) != 0});
  }
}

// Renumbers vertices along a Morton curve and faces by their first vertex, so that neighbours
// sit close in every per-vertex array (subdivided or scrambled input otherwise misses the cache
// on almost every neighbour access). order[new id] = input id.
void reorder_for_locality(const IndexedMesh& in, IndexedMesh& out, std::vector<uint32_t>& order) {
  const uint32_t n = in.vertex_count();
  float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (uint32_t v = 0; v < n; ++v)
    for (int k = 0; k < 3; ++k) {
      const float c = in.positions[size_t(v) * 3 + k];
      lo[k] = v == 0 ? c : std::min(lo[k], c);
      hi[k] = v == 0 ? c : std::max(hi[k], c);
    }
  const float extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-30f});
  auto spread = [](uint64_t x) {  // 10 bits -> every third of 30
    x &= 0x3ff;
    x = (x | (x << 16)) & 0x30000ff;
    x = (x | (x << 8)) & 0x300f00f;
    x = (x | (x << 4)) & 0x30c30c3;
    return (x | (x << 2)) & 0x9249249;
  };
  std::vector<std::pair<uint32_t, uint32_t>> keyed(n);
  for (uint32_t v = 0; v < n; ++v) {
    uint64_t code = 0;
    for (int k = 0; k < 3; ++k)
      code |= spread(uint64_t((in.positions[size_t(v) * 3 + k] - lo[k]) / extent * 1023.f)) << k;
    keyed[v] = {uint32_t(code), v};
  }
  std::sort(keyed.begin(), keyed.end());
  order.resize(n);
  std::vector<uint32_t> new_id(n);
  out.positions.resize(in.positions.size());
  for (uint32_t i = 0; i < n; ++i) {
    order[i] = keyed[i].second;
    new_id[order[i]] = i;
    for (int k = 0; k < 3; ++k)
      out.positions[size_t(i) * 3 + k] = in.positions[size_t(order[i]) * 3 + k];
  }
  // Faces bucketed by their smallest new vertex id (counting sort), winding kept.
  const uint32_t faces = in.face_count();
  std::vector<uint32_t> start(size_t(n) + 1, 0);
  auto first = [&](uint32_t f) {
    const uint32_t* t = &in.indices[size_t(f) * 3];
    const uint32_t a = t[0] < n ? new_id[t[0]] : 0, b = t[1] < n ? new_id[t[1]] : 0,
                   c = t[2] < n ? new_id[t[2]] : 0;
    return std::min({a, b, c});
  };
  for (uint32_t f = 0; f < faces; ++f) ++start[first(f) + 1];
  for (uint32_t v = 0; v < n; ++v) start[v + 1] += start[v];
  out.indices.resize(in.indices.size());
  // The attributes follow: corners and face materials with their faces, wedges renumbered.
  const MeshAttributes& a = in.attributes;
  const bool corner_wedges = a.corner_wedges.size() == in.indices.size();
  const bool materials = a.face_materials.size() == faces;
  if (!a.empty()) {
    out.attributes = a;
    for (uint32_t& v : out.attributes.wedge_vertices) v = v < n ? new_id[v] : v;
  }
  for (uint32_t f = 0; f < faces; ++f) {
    const uint32_t slot = start[first(f)]++;
    for (int k = 0; k < 3; ++k) {
      out.indices[size_t(slot) * 3 + k] = new_id[in.indices[size_t(f) * 3 + k]];
      if (corner_wedges)
        out.attributes.corner_wedges[size_t(slot) * 3 + k] = a.corner_wedges[size_t(f) * 3 + k];
    }
    if (materials) out.attributes.face_materials[slot] = a.face_materials[f];
  }
}

// The collapses of a level's cells into one sequence, each cell's in its order, the next always
// the cheapest of the cells' next ones (ties to the lower cell): the collapses of different
// cells commute, and a prefix of the level is then about what one heap over the mesh would
// have collapsed first (mesh_after, and a decoder that stops inside a level).
void merge_by_cost(const std::vector<std::vector<HalfEdgeCollapse>>& records,
                   std::vector<HalfEdgeCollapse>& out) {
  using Next = std::pair<float, uint32_t>;  // the cell's next cost, the cell
  std::priority_queue<Next, std::vector<Next>, std::greater<>> next;
  std::vector<size_t> taken(records.size(), 0);
  for (uint32_t c = 0; c < records.size(); ++c)
    if (!records[c].empty()) next.push({records[c][0].cost, c});
  while (!next.empty()) {
    const uint32_t c = next.top().second;
    next.pop();
    out.push_back(records[c][taken[c]++]);
    if (taken[c] < records[c].size()) next.push({records[c][taken[c]].cost, c});
  }
}

// v's bytes appended to out (the cell results and regions: host byte order).
template <class T>
void put(std::vector<uint8_t>& out, const T& v) {
  static_assert(std::is_trivially_copyable_v<T>);
  const auto* b = reinterpret_cast<const uint8_t*>(&v);
  out.insert(out.end(), b, b + sizeof v);
}

// Whether the numbers of an engine term (a float, a double, a quadric or a record of floats:
// FaceTerms, VertexTerms) are finite; with `infinite`, infinity passes too.
template <class T>
bool finite_term(const T& x, bool infinite = false) {
  if constexpr (std::is_floating_point_v<T>) {
    return infinite ? !std::isnan(x) : std::isfinite(x);
  } else if constexpr (std::is_same_v<T, Quadric>) {
    return std::all_of(std::begin(x.a), std::end(x.a), [](double a) { return finite_term(a); });
  } else {
    float f[sizeof(T) / sizeof(float)];
    static_assert(sizeof f == sizeof(T));
    std::memcpy(f, &x, sizeof f);
    return std::all_of(std::begin(f), std::end(f),
                       [&](float a) { return finite_term(a, infinite); });
  }
}

// A cell's region (CellRegion) numbers its vertices, faces and attribute wedges apart, ascending
// in the whole mesh's numbers: vertex i of the region is vertices[i] of the mesh, face j is
// faces[j], wedge k is wedges[k].
struct RegionIds {
  std::vector<uint32_t> vertices, faces, wedges;
  std::vector<uint64_t> sizes;  // the whole mesh's size of each array (for_each_array's order)

  uint32_t vertex(uint32_t x) const { return vertices[x]; }
  uint32_t slot(uint32_t h) const { return faces[h >> 2] * 4 + (h & 3); }
  uint32_t id(EngineData::Ids ids, uint32_t x) const {
    if (x == kNone) return x;
    return ids == EngineData::Ids::vertex ? vertex(x)
           : ids == EngineData::Ids::slot ? slot(x)
                                          : wedges[x];
  }
  size_t units(EngineData::Per per) const {
    return per == EngineData::Per::vertex ? vertices.size()
           : per == EngineData::Per::slot ? faces.size() * 4
           : per == EngineData::Per::face ? faces.size()
                                          : wedges.size();
  }
  // The mesh's index of element i of an array of `size` elements of the region.
  uint64_t element(EngineData::Per per, size_t size, uint64_t i) const {
    const uint64_t k = size / units(per), unit = i / k;
    const uint64_t g = per == EngineData::Per::vertex ? vertices[unit]
                       : per == EngineData::Per::slot ? slot(uint32_t(unit))
                       : per == EngineData::Per::face ? faces[unit]
                                                      : wedges[unit];
    return g * k + i % k;
  }
};

// A cell of the first level simplified apart (simplify_cell): its collapses, the faces they
// removed, and every element of the engine's arrays they changed (the cells of a level write
// disjoint elements), as bytes: "PMZCELL1", the cell and the level's cell count (u32), removed
// faces (u64), the collapses (u64 count, then u, v, vl, vr, cost), then per array of
// EngineData::for_each_array its size and changed count (u64) and each change (u32 index, the
// element). Host byte order: the tasks of one plan run on machines of one kind.
class CellResult {
 public:
  static constexpr char kMagic[8] = {'P', 'M', 'Z', 'C', 'E', 'L', 'L', '1'};

  // The state of `data` before the cell runs.
  void snapshot(EngineData& data) {
    before_.clear();
    data.for_each_array([&](const auto& a, auto...) {
      const auto* p = reinterpret_cast<const uint8_t*>(a.data());
      before_.emplace_back(p, p + a.size() * sizeof(a[0]));
    });
  }
  // The result of cell `cell` of `cells` after it ran (snapshot() before). With `region`, `data`
  // holds a cell's region (CellRegion) and the result is written in the whole mesh's numbers.
  void write(EngineData& data, uint32_t cell, uint32_t cells, uint64_t removed,
             const std::vector<HalfEdgeCollapse>& record, std::vector<uint8_t>& out,
             const RegionIds* region = nullptr) const {
    auto vertex = [&](uint32_t x) { return region && x != kNone ? region->vertex(x) : x; };
    out.assign(kMagic, kMagic + 8);
    put(out, cell), put(out, cells), put(out, removed), put(out, uint64_t(record.size()));
    for (const HalfEdgeCollapse& c : record)
      put(out, vertex(c.u)), put(out, vertex(c.v)), put(out, vertex(c.vl)), put(out, vertex(c.vr)),
          put(out, c.cost);
    size_t k = 0;
    data.for_each_array([&](const auto& a, EngineData::Per per, EngineData::Ids ids) {
      using T = std::decay_t<decltype(a[0])>;
      static_assert(std::is_trivially_copyable_v<T>);
      const uint8_t* was = before_[k].data();
      std::vector<uint32_t> changed;
      for (uint32_t i = 0; i < a.size(); ++i)
        if (std::memcmp(&a[i], was + size_t(i) * sizeof(T), sizeof(T)) != 0) changed.push_back(i);
      put(out, region ? region->sizes[k] : uint64_t(a.size())), put(out, uint64_t(changed.size()));
      ++k;
      for (uint32_t i : changed) {
        if (!region) {
          put(out, i), put(out, a[i]);
          continue;
        }
        put(out, uint32_t(region->element(per, a.size(), i)));
        if constexpr (std::is_same_v<T, uint32_t>)
          put(out, ids == EngineData::Ids::none ? a[i] : region->id(ids, a[i]));
        else
          put(out, a[i]);
      }
    });
  }
  // Reads a result of cell `cell` of `cells` into `data`, `record` and `removed`; false with
  // `error` when it is not one that fits them.
  static bool read(const std::vector<uint8_t>& bytes, uint32_t cell, uint32_t cells,
                   EngineData& data, std::vector<HalfEdgeCollapse>& record, uint64_t& removed,
                   std::string& error) {
    const uint8_t *p = bytes.data(), *end = p + bytes.size();
    auto get = [&](auto& v) {
      if (size_t(end - p) < sizeof v) return false;
      std::memcpy(&v, p, sizeof v), p += sizeof v;
      return true;
    };
    uint32_t c = 0, n = 0;
    uint64_t count = 0;
    if (bytes.size() < 8 || std::memcmp(p, kMagic, 8) != 0)
      return error = "not a cell result", false;
    p += 8;
    if (!get(c) || !get(n) || !get(removed) || !get(count)) return error = "cut short", false;
    if (c != cell || n != cells)
      return error = "the result of cell " + std::to_string(c) + " of " + std::to_string(n) +
                     ", not of cell " + std::to_string(cell) + " of " + std::to_string(cells),
             false;
    if (count > uint64_t(end - p) / 20) return error = "cut short", false;
    record.resize(count);
    for (HalfEdgeCollapse& r : record) get(r.u), get(r.v), get(r.vl), get(r.vr), get(r.cost);
    bool ok = true;
    data.for_each_array([&](auto& a, auto...) {
      uint64_t size = 0, changed = 0;
      if (!ok || !get(size) || !get(changed) || size != a.size()) return void(ok = false);
      for (uint64_t j = 0; j < changed && ok; ++j) {
        uint32_t i = 0;
        ok = get(i) && i < a.size() && get(a[i]);
      }
    });
    if (!ok || p != end) return error = "does not fit the mesh (made from another plan?)", false;
    return true;
  }

 private:
  std::vector<std::vector<uint8_t>> before_;
};

// A first-level cell as a task that reads nothing else (simplify_cell_region): the engine's
// terms for the cell's vertices, their neighbours and the faces around both, numbered apart
// (RegionIds), with the settings and the level's threshold and goal. A cell's collapses read and
// write only its own vertices' faces and the vertices of those faces, so the region holds what
// its run needs and one ring more; an id that leads out of the region is kept as kOutside, and a
// run that changes such an element fails instead of handing over a wrong result. As bytes:
// "PMZREGN1", the cell and the level's cell count (u32), the cell's faces and its goal (u64),
// the threshold (f64), the settings, the region's vertex and face numbers in the mesh and the
// cell's live vertices in the region (each a u32 count and u32s), then per array of
// EngineData::for_each_array its size in the mesh and in the region (u64) and the region's
// elements. Host byte order, as CellResult.
class CellRegion {
 public:
  static constexpr char kMagic[8] = {'P', 'M', 'Z', 'R', 'E', 'G', 'N', '1'};
  static constexpr uint32_t kOutside = 0xFFFFFFFEu;

  uint32_t cell = 0, cells = 0;
  uint64_t cell_faces = 0, goal = 0;
  double max_cost = -1;
  RegionIds ids;
  std::vector<uint32_t> members;  // the cell's live vertices, ascending (region numbers)

  // Per vertex, face and attribute wedge of the mesh: its number in the region being written
  // (kNone outside it).
  struct Scratch {
    std::vector<uint32_t> vertex_local, face_local, wedge_local;
    uint64_t wedges = 0;  // of the mesh
    explicit Scratch(Engine& engine)
        : vertex_local(engine.m.vertex_count(), kNone), face_local(engine.m.face_count(), kNone) {
      for (uint32_t w : engine.attr.wedge)
        if (w != kNone) wedges = std::max<uint64_t>(wedges, uint64_t(w) + 1);
      wedge_local.assign(wedges, kNone);
    }
  };

  // The region of the cell whose live vertices are members[0, count) (ascending), from the
  // engine at the start of the first level's cells.
  static void write(Engine& engine, const uint32_t* members, size_t count, uint32_t cell,
                    uint32_t cells, uint64_t cell_faces, uint64_t goal, double max_cost,
                    Scratch& scratch, std::vector<uint8_t>& out) {
    const HalfEdgeMesh& m = engine.m;
    const AttributeField& attr = engine.attr;
    std::vector<uint32_t>& vertex_local = scratch.vertex_local;
    std::vector<uint32_t>& face_local = scratch.face_local;
    std::vector<uint32_t>& wedge_local = scratch.wedge_local;
    std::vector<uint32_t> verts(members, members + count), faces;
    for (uint32_t v : verts) vertex_local[v] = kOutside;
    for (size_t i = 0; i < count; ++i)
      for_each_neighbour(m, members[i], [&](uint32_t w, uint32_t) {
        if (vertex_local[w] == kNone) vertex_local[w] = kOutside, verts.push_back(w);
      });
    for (size_t i = 0, near = verts.size(); i < near; ++i)
      for_each_outgoing(m, verts[i], [&](uint32_t h) {
        const uint32_t f = HalfEdgeMesh::face(h);
        if (face_local[f] == kNone) face_local[f] = 0, faces.push_back(f);
      });
    for (uint32_t f : faces)
      for (uint32_t k = 0; k < 3; ++k)
        if (const uint32_t w = m.vert[HalfEdgeMesh::half_edge(f, k)]; vertex_local[w] == kNone)
          vertex_local[w] = kOutside, verts.push_back(w);
    std::vector<uint32_t> wedges;  // those of the region's corners
    if (!attr.wedge.empty())
      for (uint32_t f : faces)
        for (uint32_t k = 0; k < 3; ++k)
          if (const uint32_t w = attr.wedge[HalfEdgeMesh::half_edge(f, k)];
              w != kNone && wedge_local[w] == kNone)
            wedge_local[w] = kOutside, wedges.push_back(w);
    std::sort(verts.begin(), verts.end());
    std::sort(faces.begin(), faces.end());
    std::sort(wedges.begin(), wedges.end());
    for (uint32_t i = 0; i < verts.size(); ++i) vertex_local[verts[i]] = i;
    for (uint32_t j = 0; j < faces.size(); ++j) face_local[faces[j]] = j;
    for (uint32_t k = 0; k < wedges.size(); ++k) wedge_local[wedges[k]] = k;
    auto local = [&](EngineData::Ids kind, uint32_t x) {
      if (x == kNone) return x;
      if (kind != EngineData::Ids::slot) {
        const uint32_t i = (kind == EngineData::Ids::vertex ? vertex_local : wedge_local)[x];
        return i == kNone ? kOutside : i;
      }
      const uint32_t f = face_local[HalfEdgeMesh::face(x)];
      return f == kNone ? kOutside : f * 4 + HalfEdgeMesh::corner(x);
    };
    out.assign(kMagic, kMagic + 8);
    put(out, cell), put(out, cells), put(out, cell_faces), put(out, goal), put(out, max_cost);
    put(out, uint8_t(engine.metric)), put(out, uint8_t(engine.guard));
    const MetricParams& p = engine.params;
    for (float f :
         {p.epsilon, p.quadric_floor, p.torsion_weight, p.boundary_weight, p.quadric_memory,
          p.guard_slack, p.guard_penalty_cap, p.attribute_weight, engine.feat.epsilon})
      put(out, f);
    put(out, engine.unit), put(out, engine.inv_unit4);
    put(out, uint8_t(attr.active)), put(out, uint8_t(attr.cost_term));
    put(out, uint8_t(attr.priced)), put(out, attr.dims), put(out, attr.scale);
    put(out, attr.seam_scale);
    put_list(out, verts), put_list(out, faces), put_list(out, wedges);
    put(out, uint32_t(count));
    for (size_t i = 0; i < count; ++i) put(out, vertex_local[members[i]]);
    RegionIds region;
    region.vertices = std::move(verts), region.faces = std::move(faces);
    region.wedges = std::move(wedges);
    const uint64_t mesh_units[4] = {m.vertex_count(), m.slot_count(), m.face_count(),
                                    scratch.wedges};
    engine.data()->for_each_array([&](const auto& a, EngineData::Per per, EngineData::Ids kind) {
      const uint64_t units = mesh_units[int(per)];
      const uint64_t k = units ? a.size() / units : 0, n = region.units(per);
      put(out, uint64_t(a.size())), put(out, k * n);
      for (uint64_t i = 0; i < n * k; ++i) {
        const auto& e = a[region.element(per, n * k, i)];
        if constexpr (std::is_same_v<std::decay_t<decltype(e)>, uint32_t>)
          put(out, kind == EngineData::Ids::none ? e : local(kind, e));
        else
          put(out, e);
      }
    });
    for (uint32_t v : region.vertices) vertex_local[v] = kNone;
    for (uint32_t f : region.faces) face_local[f] = kNone;
    for (uint32_t w : region.wedges) wedge_local[w] = kNone;
  }

  // Reads a region into `engine` (a fresh one); false with `error` on bytes that are not one
  // the engine can run on. Every id is checked to lie in the region, every number to be finite
  // and the half-edges to pair up, so that no walk leaves the arrays or goes round for ever;
  // then the rules of the engine's state that the cell's run relies on
  // (Engine::broken_cell_invariant).
  bool read(const std::vector<uint8_t>& bytes, Engine& engine, std::string& error) {
    const uint8_t *p = bytes.data(), *end = p + bytes.size();
    bool ok = true;
    auto get = [&](auto& v) {
      if (!ok || size_t(end - p) < sizeof v) return void(ok = false);
      std::memcpy(&v, p, sizeof v), p += sizeof v;
    };
    auto get_list = [&](std::vector<uint32_t>& list, uint64_t below) {
      uint32_t n = 0;
      get(n);
      if (!ok || n > size_t(end - p) / 4) return void(ok = false);
      list.resize(n);
      for (uint32_t i = 0; i < n && ok; ++i) {
        get(list[i]);
        ok = list[i] < below && (i == 0 || list[i - 1] < list[i]);
      }
    };
    if (bytes.size() < 8 || std::memcmp(p, kMagic, 8) != 0)
      return error = "not a cell region", false;
    p += 8;
    uint8_t metric = 0, guard = 0;
    bool finite = true;  // every number of the settings, then of the terms
    MetricParams& q = engine.params;
    get(cell), get(cells), get(cell_faces), get(goal), get(max_cost), get(metric), get(guard);
    for (float* f :
         {&q.epsilon, &q.quadric_floor, &q.torsion_weight, &q.boundary_weight, &q.quadric_memory,
          &q.guard_slack, &q.guard_penalty_cap, &q.attribute_weight, &engine.feat.epsilon})
      get(*f), finite = finite && finite_term(*f);
    get(engine.unit), get(engine.inv_unit4);
    AttributeField& attr = engine.attr;
    uint8_t active = 0, cost_term = 0, priced = 0;
    get(active), get(cost_term), get(priced), get(attr.dims), get(attr.scale), get(attr.seam_scale);
    if (!ok) return error = "cut short", false;
    for (double x : {engine.unit, engine.inv_unit4, attr.scale, attr.seam_scale})
      finite = finite && finite_term(x);
    if (metric > uint8_t(Metric::guarded) || guard > 1 || cell >= cells || std::isnan(max_cost) ||
        !finite || active > 1 || cost_term > 1 || priced > 1 || attr.dims > 64 ||
        (cost_term && attr.dims == 0))
      return error = "damaged (its settings)", false;
    engine.metric = Metric(metric), engine.guard = guard;
    attr.active = active, attr.cost_term = cost_term, attr.priced = priced;
    get_list(ids.vertices, kNone), get_list(ids.faces, kNone / 4), get_list(ids.wedges, kNone);
    get_list(members, kNone);
    const uint32_t nv = uint32_t(ids.vertices.size()), slots = uint32_t(ids.faces.size()) * 4;
    const uint32_t wedges = uint32_t(ids.wedges.size());
    for (uint32_t v : members) ok = ok && v < nv;
    if (!ok) return error = "damaged (its vertices and faces)", false;
    // Per array of for_each_array: elements per vertex, slot, face or wedge, and when it may be
    // empty (the attribute field's wedges must be there when it is active: it reads them).
    const bool multifeature = engine.metric == Metric::multifeature;
    const uint64_t per_unit[19] = {3, 1, 1,         1, 1, 1, 1, 1, 1, 3 * kWitnesses,
                                   1, 1, attr.dims, 1, 1, 1, 1, 1, 1};
    const bool may_be_empty[19] = {false,         false, false, false,        !multifeature,
                                   !multifeature, false, true,  false,        !engine.guard,
                                   !attr.active,  true,  false, false,        false,
                                   false,         false, false, !engine.guard};
    size_t k = 0;
    ids.sizes.clear();
    engine.data()->for_each_array([&](auto& a, EngineData::Per per, EngineData::Ids kind) {
      using T = std::decay_t<decltype(a[0])>;
      uint64_t size = 0, local = 0;
      get(size), get(local);
      const uint64_t want = per_unit[k] * ids.units(per);
      ok = ok && (local == want || (local == 0 && may_be_empty[k])) &&
           local <= size_t(end - p) / sizeof(T) && (local == 0) == (size == 0) && size < kNone;
      ++k;
      if (!ok) return;
      ids.sizes.push_back(size);
      a.resize(local);
      if (local) std::memcpy(a.data(), p, local * sizeof(T)), p += local * sizeof(T);
      if constexpr (std::is_same_v<T, uint32_t>) {
        if (kind == EngineData::Ids::none) return;
        const uint32_t below = kind == EngineData::Ids::vertex ? nv
                               : kind == EngineData::Ids::slot ? slots
                                                               : wedges;
        // Ids that may lead out of the region: twins, out-edges, targets, wedges.
        const bool may_leave = kind != EngineData::Ids::vertex || per == EngineData::Per::vertex;
        for (uint32_t i = 0; i < a.size() && ok; ++i) {
          uint32_t& x = a[i];
          if (x == kOutside && may_leave) outside_.push_back({k - 1, i}), x = kNone;
          ok = x == kNone || (x < below && (kind != EngineData::Ids::slot || (x & 3) != 3));
        }
      } else if constexpr (!std::is_integral_v<T>) {
        // Finite terms; a key may be infinity (the cost of a collapse the seam rule forbids).
        const bool keys = static_cast<const void*>(&a) == &engine.key;
        for (const T& x : a) finite = finite && finite_term(x, keys);
      }
    });
    if (!ok || p != end) return error = "damaged (its arrays)", false;
    if (!finite) return error = "damaged (a number that is not finite)", false;
    // A face is live (three corners) or deleted (none, no twins), its padding slot empty; a
    // live half-edge's twin runs the other way along the same edge of a live face; every
    // vertex's out-edge starts at it. Walks then stay on live faces and come round or stop.
    const HalfEdgeMesh& m = engine.m;
    for (uint32_t h = 0; h < slots && ok; ++h) {
      const uint32_t t = m.twin[h], first = m.vert[h & ~3u];
      if ((h & 3) == 3 || first == kNone) {
        ok = m.vert[h] == kNone && t == kNone;
        continue;
      }
      ok = m.vert[h] != kNone &&
           (t == kNone || (m.twin[t] == h && m.vert[t] == m.dest(h) && m.dest(t) == m.vert[h]));
    }
    for (uint32_t v = 0; v < nv && ok; ++v) ok = m.out[v] == kNone || m.vert[m.out[v]] == v;
    if (!ok) return error = "damaged (its half-edges do not pair up)", false;
    if (const char* broken = engine.broken_cell_invariant(members))
      return error = std::string("damaged (") + broken + ")", false;
    engine.stats_enabled = false;
    return true;
  }

  // Whether the run left every element that leads out of the region as it was.
  bool stayed_inside(EngineData& data) const {
    bool inside = true;
    size_t k = 0;
    data.for_each_array([&](const auto& a, auto...) {
      if constexpr (std::is_same_v<std::decay_t<decltype(a[0])>, uint32_t>)
        for (const auto& [array, i] : outside_) inside &= array != k || a[i] == kNone;
      ++k;
    });
    return inside;
  }

 private:
  static void put_list(std::vector<uint8_t>& out, const std::vector<uint32_t>& list) {
    put(out, uint32_t(list.size()));
    for (uint32_t x : list) put(out, x);
  }
  std::vector<std::pair<size_t, uint32_t>> outside_;  // (array, element): held kOutside
};

// What run_cell_levels does with the first level's cells: simplify them all here (run), only
// count them (count: `cells`), simplify cell `cell` alone and stop (one: `result`), hand each
// cell's region to `region` and stop (regions: `cells`), or take every cell's result from
// SimplifyOptions::clusters.first_level (when set, in mode run).
struct FirstLevel {
  enum Mode { run, count, one, regions } mode = run;
  uint32_t cell = 0, cells = 0;
  std::vector<uint8_t>* result = nullptr;
  const CellRegionSink* region = nullptr;
};

// The levels of a hierarchical simplification (SimplifyOptions::clusters), finest first. Each
// cell of a level is simplified on its own (Engine::run_cell), down to phase_ratio of its faces
// at the level's start: its collapses depend only on its faces and the ring of faces around
// its border, not on the other cells or on the order the cells run in, so the cells run on
// several threads and their collapses are merged by cost (merge_by_cost). `levels` gets each
// level's grid and first collapse. The caller runs the last level (the whole mesh), unless
// `first` stops after the first level's cells. False with `error` on a first-level result that
// does not fit (or that first_level could not give).
bool run_cell_levels(Engine& engine, const SimplifyOptions& options,
                     std::vector<CollapseSequence::Level>& levels, FirstLevel& first,
                     std::string& error) {
  const SimplifyOptions::Clusters& clusters = options.clusters;
  const uint32_t n = engine.m.vertex_count();
  // The writer's integer coordinates (the same bounding box and quantizer: writer.cpp).
  float lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = INFINITY, hi[a] = -INFINITY;
  for (uint32_t v = 0; v < n; ++v)
    for (int a = 0; a < 3; ++a)
      lo[a] = std::min(lo[a], engine.m.p(v)[a]), hi[a] = std::max(hi[a], engine.m.p(v)[a]);
  Quantizer quant;
  quant.init(clusters.position_bits, lo, hi);
  // Computed where needed rather than held: 12 bytes a vertex at the encode's peak.
  auto coords = [&](uint32_t v, int32_t c[3]) {
    for (int a = 0; a < 3; ++a) c[a] = quant.quantize(engine.m.p(v)[a], a);
  };
  detail::CoordBox box;
  box.vertices = n;
  for (int a = 0; a < 3; ++a)  // (quantizing does not reorder coordinates)
    box.lo[a] = quant.quantize(lo[a], a), box.hi[a] = quant.quantize(hi[a], a);
  double area = 0;  // of the surface, in integer units
  for (uint32_t f = 0; f < engine.m.face_count(); ++f) {
    int32_t c[3][3];
    for (int k = 0; k < 3; ++k) coords(engine.m.vert[HalfEdgeMesh::half_edge(f, k)], c[k]);
    area += detail::triangle_area(c[0], c[1], c[2]);
  }
  SimplifyOptions level = options;
  level.progress = nullptr;
  // Every vertex keyed once; from here keys wait in key[] between the cells' heaps.
  if (first.mode != FirstLevel::count) {
    std::vector<Candidate> initial;
    engine.initial_keys(initial);
    engine.key.assign(n, 0);
    for (uint32_t v = 0; v < n; ++v)
      if (initial[v].target != kNone) engine.set_queued(v, initial[v]);
  }
  engine.cells = true;
  engine.cell.resize(n);
  engine.inner.assign(n, 0);
  if (engine.guard) engine.region_bound.assign(n, 0.f);
  const uint32_t threads =
      clusters.threads ? clusters.threads : std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::unique_ptr<Engine>> lanes;
  std::vector<uint32_t> index, members;  // per vertex its cell's index; vertices by cell
  std::vector<uint64_t> keys, start, cell_faces, removed;
  std::vector<float> keys_inside;
  // f(lane) on `workers` lanes, one on this thread.
  auto on_lanes = [&](size_t workers, auto&& f) {
    if (lanes.empty()) lanes.push_back(std::make_unique<Engine>(engine, Engine::Borrow{}));
    while (lanes.size() < workers)
      lanes.push_back(std::make_unique<Engine>(engine, Engine::Lane{}));
    std::vector<std::thread> others;
    for (size_t t = 1; t < workers; ++t) others.emplace_back([&, t] { f(*lanes[t]); });
    f(*lanes[0]);
    for (std::thread& t : others) t.join();
  };
  // The vertices a level starts with (every vertex at the first level).
  auto live_vertices = [&] {
    uint64_t live = 0;
    for (uint32_t v = 0; v < n; ++v) live += engine.m.out[v] != kNone;
    return live;
  };
  // Cell levels while the grid cuts the mesh and more than a cell's vertices are left, at most
  // kMaxCellLevels of them (spec/format.md section 15.1: 32 levels with the root).
  constexpr size_t kMaxCellLevels = 31;
  uint64_t live = live_vertices();
  for (CellGrid grid = detail::cell_grid_for(box, area, clusters.vertices);
       levels.size() < kMaxCellLevels && detail::grid_cuts(grid, box);
       live = live_vertices(), grid = detail::next_cell_grid(grid, area, clusters.vertices, live)) {
    if (!levels.empty() && live <= clusters.vertices) break;
    levels.push_back({grid, engine.record->size()});
    // The level's cells (ascending keys), their live vertices and faces (a face counts in the
    // cell of its first corner: the faces a cell can remove have all their corners in it).
    // (Only where the cell changes from the vertex before: vertices are in Morton order, and a
    // key per vertex would be 8 bytes a vertex at the encode's peak.)
    keys.clear();
    for (uint32_t v = 0; v < n; ++v) {
      int32_t c[3];
      coords(v, c);
      engine.cell[v] = grid.cell(c);
      if (engine.m.out[v] != kNone && (keys.empty() || keys.back() != engine.cell[v]))
        keys.push_back(engine.cell[v]);
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    keys.shrink_to_fit();
    const size_t cells = keys.size();
    if (first.mode == FirstLevel::count) return first.cells = uint32_t(cells), true;
    start.assign(cells + 1, 0);
    index.resize(n);
    for (uint32_t v = 0; v < n; ++v) {
      if (engine.m.out[v] == kNone) continue;
      index[v] =
          uint32_t(std::lower_bound(keys.begin(), keys.end(), engine.cell[v]) - keys.begin());
      ++start[index[v] + 1];
    }
    for (size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
    members.resize(start[cells]);
    {
      std::vector<uint64_t> fill(start.begin(), start.end() - 1);
      for (uint32_t v = 0; v < n; ++v)
        if (engine.m.out[v] != kNone) members[fill[index[v]]++] = v;
    }
    cell_faces.assign(cells, 0);
    for (uint32_t f = 0; f < engine.m.face_count(); ++f)
      if (engine.m.face_alive(f)) ++cell_faces[index[engine.m.vert[HalfEdgeMesh::half_edge(f, 0)]]];
    std::vector<uint32_t>().swap(index);  // (not held while the cells run)
    parallel_halves(n, [&](uint32_t begin, uint32_t end) {
      for (uint32_t v = begin; v < end; ++v) {
        bool in = engine.m.out[v] != kNone;
        if (in)
          for_each_neighbour(engine.m, v,
                             [&](uint32_t w, uint32_t) { in &= engine.cell[w] == engine.cell[v]; });
        engine.inner[v] = in;
      }
    });
    // Each cell down to phase_ratio of its faces at most (or the share of them the target
    // leaves).
    double ratio = clusters.phase_ratio;
    if (options.target_faces)
      ratio = std::max(ratio, double(options.target_faces) / double(engine.faces));
    // The keys at the level's start: the vertices a border held back keyed afresh, then the
    // threshold (the cost quantile of the keys of the vertices inside cells).
    std::atomic<size_t> next{0};
    auto key_cells = [&](Engine& lane) {
      for (size_t c; (c = next.fetch_add(1)) < cells;)
        lane.key_cell(&members[start[c]], start[c + 1] - start[c]);
    };
    on_lanes(std::min<size_t>(threads, cells), key_cells);
    level.max_cost = options.max_cost;
    if (clusters.cost_quantile < 1) {
      keys_inside.clear();
      for (uint32_t v = 0; v < n; ++v)
        if (engine.inner[v] && engine.queued_key(v)) keys_inside.push_back(engine.key[v]);
      if (!keys_inside.empty()) {
        const size_t at = std::min(keys_inside.size() - 1,
                                   size_t(clusters.cost_quantile * double(keys_inside.size())));
        std::nth_element(keys_inside.begin(), keys_inside.begin() + at, keys_inside.end());
        const double threshold = keys_inside[at];
        level.max_cost = options.max_cost >= 0 ? std::min(options.max_cost, threshold) : threshold;
      }
      std::vector<float>().swap(keys_inside);  // (not held while the cells run)
    }
    std::vector<std::vector<HalfEdgeCollapse>> records(cells);
    removed.assign(cells, 0);
    auto run_cell = [&](Engine& lane, size_t c) {
      lane.record = &records[c];
      lane.run_cell(&members[start[c]], start[c + 1] - start[c], cell_faces[c],
                    uint64_t(double(cell_faces[c]) * ratio), level);
      removed[c] = cell_faces[c] - lane.faces;
    };
    const bool first_level = levels.size() == 1;
    if (first_level && first.mode == FirstLevel::regions) {
      CellRegion::Scratch scratch(engine);
      std::vector<uint8_t> bytes;
      first.cells = uint32_t(cells);
      for (uint32_t c = 0; c < cells; ++c) {
        CellRegion::write(engine, &members[start[c]], start[c + 1] - start[c], c, uint32_t(cells),
                          cell_faces[c], uint64_t(double(cell_faces[c]) * ratio), level.max_cost,
                          scratch, bytes);
        if (!(*first.region)(c, bytes, error)) return false;
      }
      return true;
    }
    if (first_level && first.mode == FirstLevel::one) {
      if (first.cell >= cells)
        return error = "there is no cell " + std::to_string(first.cell) + " (the first level has " +
                       std::to_string(cells) + ")",
               false;
      CellResult result;
      result.snapshot(*engine.data());
      Engine lane(engine, Engine::Lane{});
      run_cell(lane, first.cell);
      result.write(*engine.data(), first.cell, uint32_t(cells), removed[first.cell],
                   records[first.cell], *first.result);
      return true;
    }
    if (first_level && clusters.first_level) {
      std::vector<uint8_t> bytes;
      for (uint32_t c = 0; c < cells; ++c) {
        std::string why;
        if (!clusters.first_level(c, bytes, error)) return false;
        if (!CellResult::read(bytes, c, uint32_t(cells), *engine.data(), records[c], removed[c],
                              why))
          return error = "the result of cell " + std::to_string(c) + ": " + why, false;
      }
    } else {
      next = 0;
      on_lanes(std::min<size_t>(threads, cells), [&](Engine& lane) {
        for (size_t c; (c = next.fetch_add(1)) < cells;) run_cell(lane, c);
      });
    }
    merge_by_cost(records, *engine.record);
    uint64_t level_removed = 0;
    for (size_t c = 0; c < cells; ++c) level_removed += removed[c];
    engine.faces -= level_removed;
    if (engine.attr.active) engine.attr.remove_faces(level_removed);
    // The vertices next to another cell: their T may have changed with that cell's faces, and
    // their keys were left as they were: both are recomputed when next needed.
    engine.hold_borders();
    if (options.target_faces && engine.faces <= options.target_faces) break;
  }
  for (const std::unique_ptr<Engine>& lane : lanes) engine.add_counts(lane->stats);
  if (!lanes.empty()) lanes[0]->give_back();
  engine.cells = false;
  engine.load_keys();
  levels.push_back({CellGrid{}, engine.record->size()});
  return true;
}

// Checks the input, renumbers it for locality (local; order[engine id] = input id) and sets the
// engine up on it.
bool start_engine(const IndexedMesh& input, const SimplifyOptions& options, Engine& engine,
                  IndexedMesh& local, std::vector<uint32_t>& order, std::string& error) {
  // Indices out of range are refused by the half-edge build; check first so reordering can
  // index safely.
  const uint32_t vertex_count = input.vertex_count();
  for (uint32_t i : input.indices)
    if (i >= vertex_count) {
      error = "a face references vertex " + std::to_string(i) + ", out of range";
      return false;
    }
  if (input.indices.size() % 3 != 0) {
    error = "index count is not a multiple of three";
    return false;
  }
  reorder_for_locality(input, local, order);
  if (!engine.init(local, options, error)) {
    HalfEdgeMesh unordered;  // again in input numbering, so the message names input vertices
    build_halfedge(input, unordered, error);
    return false;
  }
  return true;
}

}  // namespace

namespace {

// simplify(), or with `first` in mode count or one, the first level's cells counted or one of
// them simplified (`out` then untouched).
bool simplify_levels(const IndexedMesh& input, const SimplifyOptions& options, FirstLevel& first,
                     CollapseSequence& out, std::string& error) {
  const auto t0 = Clock::now();
  std::vector<uint32_t> order;
  Engine engine;
  {
    IndexedMesh local;
    if (!start_engine(input, options, engine, local, order, error)) return false;
  }
  std::vector<HalfEdgeCollapse> collapses;
  std::vector<CollapseSequence::Level> levels;
  collapses.reserve(input.vertex_count());
  engine.record = &collapses;
  engine.stats.setup = seconds_since(t0);
  if (options.clusters.vertices > 0 &&
      engine.m.vertex_count() > 2 * uint64_t(options.clusters.vertices) &&
      !run_cell_levels(engine, options, levels, first, error))
    return false;
  if (first.mode != FirstLevel::run) return true;
  engine.run(options);
  out.collapses = std::move(collapses);
  out.levels = std::move(levels);
  auto input_id = [&](uint32_t v) { return v == kNone ? kNoVertex : order[v]; };
  for (HalfEdgeCollapse& c : out.collapses)
    c.u = input_id(c.u), c.v = input_id(c.v), c.vl = input_id(c.vl), c.vr = input_id(c.vr);
  out.base_indices.clear();
  out.base_indices.reserve(engine.faces * 3);
  for (uint32_t f = 0; f < engine.m.face_count(); ++f)
    if (engine.m.face_alive(f))
      for (int k = 0; k < 3; ++k)
        out.base_indices.push_back(order[engine.m.vert[HalfEdgeMesh::half_edge(f, k)]]);
  engine.stats.total = seconds_since(t0);
  if (options.stats) *options.stats = engine.stats;
  // The engine's arrays go before the input is copied: held with the copy, they made a second
  // peak as high as the cell levels'.
  engine.release();
  out.mesh = input;
  return true;
}

}  // namespace

bool simplify(const IndexedMesh& input, const SimplifyOptions& options, CollapseSequence& out,
              std::string& error) {
  FirstLevel first;
  return simplify_levels(input, options, first, out, error);
}

bool cell_tasks(const IndexedMesh& input, const SimplifyOptions& options, uint32_t& count,
                std::string& error) {
  FirstLevel first;
  first.mode = FirstLevel::count;
  CollapseSequence unused;
  if (!simplify_levels(input, options, first, unused, error)) return false;
  count = first.cells;
  return true;
}

bool cell_regions(const IndexedMesh& input, const SimplifyOptions& options,
                  const CellRegionSink& sink, uint32_t& count, std::string& error) {
  count = 0;
  FirstLevel first;
  first.mode = FirstLevel::regions;
  first.region = &sink;
  CollapseSequence unused;
  if (!simplify_levels(input, options, first, unused, error)) return false;
  count = first.cells;
  return true;
}

bool simplify_cell_region(const std::vector<uint8_t>& region, uint32_t cell,
                          std::vector<uint8_t>& result, std::string& error) {
  Engine engine;
  CellRegion r;
  if (!r.read(region, engine, error)) return false;
  if (r.cell != cell)
    return error = "the region of cell " + std::to_string(r.cell) + ", not of cell " +
                   std::to_string(cell),
           false;
  CellResult diff;
  diff.snapshot(*engine.data());
  std::vector<HalfEdgeCollapse> record;
  Engine lane(engine, Engine::Lane{});
  lane.record = &record;
  SimplifyOptions level;
  level.max_cost = r.max_cost;
  lane.run_cell(r.members.data(), r.members.size(), r.cell_faces, r.goal, level);
  if (!r.stayed_inside(*engine.data()))
    return error = "the cell's collapses reached beyond its region", false;
  diff.write(*engine.data(), r.cell, r.cells, r.cell_faces - lane.faces, record, result, &r.ids);
  return true;
}

bool simplify_cell(const IndexedMesh& input, const SimplifyOptions& options, uint32_t cell,
                   std::vector<uint8_t>& result, std::string& error) {
  FirstLevel first;
  first.mode = FirstLevel::one;
  first.cell = cell;
  std::vector<uint8_t> bytes;
  first.result = &bytes;
  CollapseSequence unused;
  if (!simplify_levels(input, options, first, unused, error)) return false;
  if (bytes.empty())
    return error = "there is no cell " + std::to_string(cell) + " (no cell levels)", false;
  result = std::move(bytes);
  return true;
}

namespace detail {

float initial_collapse_cost(const IndexedMesh& mesh, const SimplifyOptions& options, uint32_t u,
                            uint32_t v) {
  Engine engine;
  std::string error;
  if (!engine.init(mesh, options, error)) return std::numeric_limits<float>::quiet_NaN();
  return engine.edge_cost(u, v);
}

bool queued_collapses(const IndexedMesh& mesh, const SimplifyOptions& options, uint64_t k,
                      std::vector<QueuedCollapse>& out, std::string& error) {
  Engine engine;
  IndexedMesh local;
  std::vector<uint32_t> order;
  if (!start_engine(mesh, options, engine, local, order, error)) return false;
  std::vector<HalfEdgeCollapse> collapses;
  engine.record = &collapses;
  engine.max_collapses = k;
  engine.run(options);
  engine.queued(local, collapses, out);
  for (QueuedCollapse& q : out) q.u = order[q.u], q.v = order[q.v];
  return true;
}

}  // namespace detail

namespace {

// The faces alive in replay (input order) and their attributes: the wedges they name, in input
// order, and the faces' materials. remap: input vertex -> output vertex.
void attributes_after(const MeshAttributes& in, const CollapseReplay& replay,
                      const std::vector<uint32_t>& remap, IndexedMesh& out) {
  MeshAttributes& a = out.attributes;
  a.color_components = in.color_components;
  a.materials = in.materials;
  a.material_library = in.material_library;
  a.texcoords.resize(in.texcoords.size());
  std::vector<uint32_t> wedge_remap(replay.has_wedges() ? in.wedge_count() : 0, kNoVertex);
  for (uint32_t f = 0; f < replay.face_alive.size(); ++f) {
    if (!replay.face_alive[f]) continue;
    for (int k = 0; k < 3; ++k) out.indices.push_back(remap[replay.corner_vertex[f * 3 + k]]);
    if (!in.face_materials.empty()) a.face_materials.push_back(in.face_materials[f]);
    if (replay.has_wedges())
      for (int k = 0; k < 3; ++k) wedge_remap[replay.corner_wedge[f * 3 + k]] = 0;
  }
  for (uint32_t w = 0; w < wedge_remap.size(); ++w) {
    if (wedge_remap[w] == kNoVertex) continue;
    wedge_remap[w] = a.wedge_count();
    a.wedge_vertices.push_back(remap[in.wedge_vertices[w]]);
    for (size_t s = 0; s < in.texcoords.size(); ++s)
      a.texcoords[s].insert(a.texcoords[s].end(), &in.texcoords[s][size_t(w) * 2],
                            &in.texcoords[s][size_t(w) * 2 + 2]);
    if (!in.normals.empty())
      a.normals.insert(a.normals.end(), &in.normals[size_t(w) * 3], &in.normals[size_t(w) * 3 + 3]);
    const size_t cc = in.color_components;
    if (!in.colors.empty())
      a.colors.insert(a.colors.end(), &in.colors[w * cc], &in.colors[w * cc + cc]);
  }
  if (replay.has_wedges())
    for (uint32_t f = 0; f < replay.face_alive.size(); ++f)
      if (replay.face_alive[f])
        for (int k = 0; k < 3; ++k)
          a.corner_wedges.push_back(wedge_remap[replay.corner_wedge[f * 3 + k]]);
}

}  // namespace

IndexedMesh mesh_after(const CollapseSequence& seq, size_t k) {
  const uint32_t n = seq.mesh.vertex_count();
  k = std::min(k, seq.collapses.size());
  // Each input vertex's survivor (survivors.hpp); a face whose corners meet is one a collapse
  // deleted.
  const std::vector<uint32_t> survivor = collapse_survivors(seq, k);
  auto find = [&](uint32_t x) { return survivor[x]; };
  std::vector<uint32_t> remap(n, kNoVertex);
  IndexedMesh result;
  for (uint32_t i = 0; i < n; ++i) {
    if (find(i) != i) continue;
    remap[i] = result.vertex_count();
    result.positions.insert(result.positions.end(), &seq.mesh.positions[size_t(i) * 3],
                            &seq.mesh.positions[size_t(i) * 3 + 3]);
  }
  if (!seq.mesh.attributes.empty()) {
    // Attributes need the literal replay: the collapse rule depends on u's fan at the time.
    CollapseReplay replay(seq.mesh);
    bool replayed = true;
    for (size_t i = 0; i < k && replayed; ++i) replayed = replay.collapse(seq.collapses[i]);
    if (replayed) {
      attributes_after(seq.mesh.attributes, replay, remap, result);
      return result;
    }
  }
  for (size_t f = 0; f < seq.mesh.indices.size(); f += 3) {
    const uint32_t a = find(seq.mesh.indices[f]), b = find(seq.mesh.indices[f + 1]),
                   c = find(seq.mesh.indices[f + 2]);
    if (a == b || b == c || c == a) continue;
    result.indices.insert(result.indices.end(), {remap[a], remap[b], remap[c]});
  }
  return result;
}

}  // namespace pmz
