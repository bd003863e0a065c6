// The collapse engine: half-edge collapses u -> v in order of the metric's cost, each vertex
// keyed in a binary heap by its cheapest outgoing collapse, recomputing only the neighbourhood
// a collapse touches (spec/algorithm.md).
#include "pmz/simplify.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "halfedge.hpp"
#include "metric.hpp"

namespace pmz {

namespace {

using namespace detail;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// A collapse may turn a surviving face by at most ~78 degrees (cos 0.2) ...
constexpr float kFoldCos = 0.2f;
// ... and may not make a needle (quality 4*sqrt(3)*area / sum of squared edges, 1 for an
// equilateral triangle) below this unless the face was already that bad.
constexpr float kMinQuality = 0.05f;
constexpr float kInfinity = std::numeric_limits<float>::infinity();

struct Candidate {
  float cost;
  uint32_t target;
};

class Engine {
 public:
  HalfEdgeMesh m;
  Features feat;
  std::vector<Quadric> quad;
  Metric metric = Metric::multifeature;
  MetricParams params;
  double inv_unit4 = 1, unit = 1;
  SimplifyStats stats;
  bool stats_enabled = false;
  uint64_t faces = 0;
  std::vector<HalfEdgeCollapse>* record = nullptr;

  bool init(const IndexedMesh& input, const SimplifyOptions& options, std::string& error);
  void run(const SimplifyOptions& options);

 private:
  // Binary min-heap of vertices keyed by their cheapest collapse.
  std::vector<uint32_t> heap, heap_pos;
  std::vector<float> key;
  std::vector<uint32_t> target;
  // Scratch: a stamp per vertex for set membership, and buffers reused across collapses.
  std::vector<uint32_t> mark;
  uint32_t mark_id = 0;
  std::vector<uint32_t> ring1, ring2, corners;
  std::vector<Candidate> candidates;

  float cost(uint32_t u, uint32_t x, uint32_t h) const;
  bool find_edge(uint32_t u, uint32_t v, uint32_t& ha, uint32_t& hb) const;
  bool legal(uint32_t u, uint32_t v, uint32_t ha, uint32_t hb);
  Candidate best_candidate(uint32_t u);
  Candidate best_legal_candidate(uint32_t u);
  void set_key(uint32_t v, Candidate c);
  void perform(uint32_t u, uint32_t v, uint32_t ha, uint32_t hb, float c);
  void fix_out(uint32_t w, uint32_t candidate);
  void update_after(uint32_t v);
  bool final_boundary_collapse();

  void heap_up(uint32_t i);
  void heap_down(uint32_t i);
  void heap_remove(uint32_t v);
  bool less(uint32_t a, uint32_t b) const { return key[heap[a]] < key[heap[b]]; }
  void heap_swap(uint32_t a, uint32_t b) {
    std::swap(heap[a], heap[b]);
    heap_pos[heap[a]] = a;
    heap_pos[heap[b]] = b;
  }
};

void Engine::heap_up(uint32_t i) {
  while (i > 0) {
    uint32_t parent = (i - 1) / 2;
    if (!less(i, parent)) break;
    heap_swap(i, parent);
    i = parent;
  }
}

void Engine::heap_down(uint32_t i) {
  const uint32_t n = uint32_t(heap.size());
  for (;;) {
    uint32_t l = 2 * i + 1, r = l + 1, smallest = i;
    if (l < n && less(l, smallest)) smallest = l;
    if (r < n && less(r, smallest)) smallest = r;
    if (smallest == i) return;
    heap_swap(i, smallest);
    i = smallest;
  }
}

void Engine::heap_remove(uint32_t v) {
  const uint32_t i = heap_pos[v];
  if (i == kNone) return;
  const uint32_t last = uint32_t(heap.size()) - 1;
  if (i != last) heap_swap(i, last);
  heap.pop_back();
  heap_pos[v] = kNone;
  if (i < heap.size()) {
    const uint32_t moved = heap[i];
    heap_up(i);
    heap_down(heap_pos[moved]);
  }
}

void Engine::set_key(uint32_t v, Candidate c) {
  if (c.target == kNone) {
    heap_remove(v);
    return;
  }
  key[v] = c.cost;
  target[v] = c.target;
  if (heap_pos[v] == kNone) {
    heap_pos[v] = uint32_t(heap.size());
    heap.push_back(v);
    heap_up(heap_pos[v]);
  } else {
    heap_up(heap_pos[v]);
    heap_down(heap_pos[v]);
  }
}

// Cost of u -> x, h a half-edge of the edge (u, x).
float Engine::cost(uint32_t u, uint32_t x, uint32_t h) const {
  const float* px = m.p(x);
  const double e = std::max(0.0, (quad[u].error(px) + quad[x].error(px)) * inv_unit4);
  if (metric == Metric::qem) return float(e);
  const double ca = (params.quadric_floor + feat.c_norm[u]) * e;
  const double cb = params.torsion_weight * edge_length_ratio(m, h) * feat.torsion[u] * unit;
  return float(ca + cb);
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
    if (m.twin[HalfEdgeMesh::next(h)] == kNone && m.twin[HalfEdgeMesh::prev(h)] == kNone) return false;
  }
  const uint32_t vl = ha != kNone ? m.vert[HalfEdgeMesh::prev(ha)] : kNone;
  const uint32_t vr = hb != kNone ? m.vert[HalfEdgeMesh::prev(hb)] : kNone;
  // Link condition: u and v share no neighbour but the wedge vertices (else the collapse
  // pinches the surface or closes a handle or a 3-edge hole).
  if (++mark_id == 0) std::fill(mark.begin(), mark.end(), 0), mark_id = 1;
  uint32_t valence_u = 0, valence_v = 0;
  for_each_neighbour(m, u, [&](uint32_t w, uint32_t) { mark[w] = mark_id, ++valence_u; });
  bool shared = false;
  for_each_neighbour(m, v, [&](uint32_t w, uint32_t) {
    ++valence_v;
    shared |= mark[w] == mark_id && w != vl && w != vr;
  });
  if (shared) return false;
  if (!boundary_edge && valence_u == 3 && valence_v == 3) return false;  // a tetrahedron stays
  // Geometry of the faces that survive around u, with u moved onto v.
  const uint32_t fa = ha != kNone ? ha / 3 : kNone, fb = hb != kNone ? hb / 3 : kNone;
  const float* pu = m.p(u);
  const float* pv = m.p(v);
  bool ok = true;
  for_each_outgoing(m, u, [&](uint32_t h) {
    if (!ok || h / 3 == fa || h / 3 == fb) return;
    const float* pb = m.p(m.dest(h));
    const float* pc = m.p(m.vert[HalfEdgeMesh::prev(h)]);
    auto normal = [&](const float* a, float n[3]) {
      const float e1[3] = {pb[0] - a[0], pb[1] - a[1], pb[2] - a[2]};
      const float e2[3] = {pc[0] - a[0], pc[1] - a[1], pc[2] - a[2]};
      n[0] = e1[1] * e2[2] - e1[2] * e2[1], n[1] = e1[2] * e2[0] - e1[0] * e2[2], n[2] = e1[0] * e2[1] - e1[1] * e2[0];
      return e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2] + e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2];
    };
    float n_old[3], n_new[3];
    const float l_old = normal(pu, n_old), l_new = normal(pv, n_new);
    const float a_old = std::sqrt(n_old[0] * n_old[0] + n_old[1] * n_old[1] + n_old[2] * n_old[2]);
    const float a_new = std::sqrt(n_new[0] * n_new[0] + n_new[1] * n_new[1] + n_new[2] * n_new[2]);
    if (!(a_new > 0)) {
      ok = false;
      return;
    }
    if (n_old[0] * n_new[0] + n_old[1] * n_new[1] + n_old[2] * n_new[2] < kFoldCos * a_old * a_new) {
      ok = false;
      return;
    }
    const float bc = (pb[0] - pc[0]) * (pb[0] - pc[0]) + (pb[1] - pc[1]) * (pb[1] - pc[1]) + (pb[2] - pc[2]) * (pb[2] - pc[2]);
    const float q_old = 3.4641016f * a_old / (l_old + bc), q_new = 3.4641016f * a_new / (l_new + bc);
    if (q_new < kMinQuality && q_new < q_old) ok = false;
  });
  return ok;
}

// The cheapest direction by cost alone; legality is checked when it reaches the top of the heap.
Candidate Engine::best_candidate(uint32_t u) {
  Candidate best{kInfinity, kNone};
  if (m.out[u] == kNone) return best;
  const bool boundary = m.is_boundary(u);
  for_each_neighbour(m, u, [&](uint32_t x, uint32_t h) {
    if (boundary && m.twin[h] != kNone) return;  // interior directions are never legal for u
    ++stats.cost_evaluations;
    const float c = cost(u, x, h);
    if (c < best.cost || best.target == kNone) best = {c, x};
  });
  return best;
}

Candidate Engine::best_legal_candidate(uint32_t u) {
  candidates.clear();
  if (m.out[u] == kNone) return {kInfinity, kNone};
  const bool boundary = m.is_boundary(u);
  for_each_neighbour(m, u, [&](uint32_t x, uint32_t h) {
    if (boundary && m.twin[h] != kNone) return;
    ++stats.cost_evaluations;
    candidates.push_back({cost(u, x, h), x});
  });
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
  for (const Candidate& c : candidates) {
    uint32_t ha, hb;
    if (find_edge(u, c.target, ha, hb) && legal(u, c.target, ha, hb)) return c;
  }
  return {kInfinity, kNone};
}

// Makes out[w] a live outgoing half-edge, the boundary one if w is on the boundary.
void Engine::fix_out(uint32_t w, uint32_t candidate) {
  uint32_t h = m.out[w];
  if (h == kNone || !m.face_alive(h / 3)) h = candidate;
  if (h == kNone) {
    m.out[w] = kNone;
    return;
  }
  const uint32_t start = h;
  for (uint32_t t = m.twin[h]; t != kNone; t = m.twin[h]) {
    h = HalfEdgeMesh::next(t);
    if (h == start) break;
  }
  m.out[w] = h;
}

void Engine::perform(uint32_t u, uint32_t v, uint32_t ha, uint32_t hb, float c) {
  const uint32_t vl = ha != kNone ? m.vert[HalfEdgeMesh::prev(ha)] : kNone;
  const uint32_t vr = hb != kNone ? m.vert[HalfEdgeMesh::prev(hb)] : kNone;
  record->push_back({u, v, vl, vr, c});
  quad[v].add(quad[u]);
  const uint32_t fa = ha != kNone ? ha / 3 : kNone, fb = hb != kNone ? hb / 3 : kNone;
  corners.clear();
  for_each_outgoing(m, u, [&](uint32_t h) {
    if (h / 3 != fa && h / 3 != fb) corners.push_back(h);
  });
  for (uint32_t h : corners) m.vert[h] = v;
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
    for (uint32_t h = 3 * f; h < 3 * f + 3; ++h) m.vert[h] = kNone, m.twin[h] = kNone;
    --faces;
  }
  m.out[u] = kNone;
  heap_remove(u);
  fix_out(v, v_vl != kNone ? v_vl : v_vr != kNone ? v_vr : corners.empty() ? kNone : corners[0]);
  if (vl != kNone) fix_out(vl, vl_v != kNone ? vl_v : v_vl != kNone ? HalfEdgeMesh::next(v_vl) : kNone);
  if (vr != kNone) fix_out(vr, vr_v != kNone ? vr_v : v_vr != kNone ? HalfEdgeMesh::next(v_vr) : kNone);
}

// Recomputes the cached terms and the keys a collapse onto v changed: faces around v, normal
// terms on its 1-ring, torsion on its 2-ring (B changed on the 1-ring).
void Engine::update_after(uint32_t v) {
  const auto t0 = stats_enabled ? Clock::now() : Clock::time_point{};
  if (++mark_id == 0) std::fill(mark.begin(), mark.end(), 0), mark_id = 1;
  ring1.clear();
  ring1.push_back(v);
  mark[v] = mark_id;
  for_each_neighbour(m, v, [&](uint32_t w, uint32_t) { ring1.push_back(w), mark[w] = mark_id; });
  std::vector<uint32_t>* update = &ring1;
  if (metric == Metric::multifeature) {
    for_each_outgoing(m, v, [&](uint32_t h) { feat.update_face(m, h / 3); });
    for (uint32_t w : ring1) feat.update_normal_terms(m, w);
    ring2 = ring1;
    for (uint32_t w : ring1)
      for_each_neighbour(m, w, [&](uint32_t x, uint32_t) {
        if (mark[x] != mark_id) ring2.push_back(x), mark[x] = mark_id;
      });
    for (uint32_t w : ring2) feat.update_torsion(m, w);
    update = &ring2;
  }
  const auto t1 = stats_enabled ? Clock::now() : Clock::time_point{};
  for (uint32_t w : *update) set_key(w, best_candidate(w));
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
  perform(best_u, best.target, ha, hb, best.cost);
  return true;
}

bool Engine::init(const IndexedMesh& input, const SimplifyOptions& options, std::string& error) {
  if (!build_halfedge(input, m, error)) return false;
  metric = options.metric;
  params = options.params;
  stats_enabled = options.stats != nullptr;
  const uint32_t n = m.vertex_count();
  unit = mean_edge_length(m);
  if (!(unit > 0)) unit = 1;
  inv_unit4 = 1.0 / (unit * unit * unit * unit);
  initial_quadrics(m, params.boundary_weight, quad);
  feat.epsilon = params.epsilon;
  if (metric == Metric::multifeature) feat.compute_all(m);
  faces = m.face_count();
  mark.assign(n, 0);
  key.assign(n, kInfinity);
  target.assign(n, kNone);
  heap_pos.assign(n, kNone);
  return true;
}

void Engine::run(const SimplifyOptions& options) {
  auto t0 = Clock::now();
  const uint32_t n = m.vertex_count();
  heap.clear();
  for (uint32_t v = 0; v < n; ++v) {
    const Candidate c = best_candidate(v);
    if (c.target == kNone) continue;
    key[v] = c.cost, target[v] = c.target;
    heap_pos[v] = uint32_t(heap.size());
    heap.push_back(v);
  }
  for (uint32_t i = uint32_t(heap.size()) / 2; i-- > 0;) heap_down(i);
  stats.initial_costs = seconds_since(t0);
  t0 = Clock::now();

  const uint64_t start_faces = faces;
  const uint64_t goal = options.target_faces;
  const uint64_t progress_step = std::max<uint64_t>(1, start_faces / 200);
  uint64_t next_progress = progress_step;
  while (!heap.empty()) {
    if (goal && faces <= goal) break;
    const uint32_t u = heap[0], v = target[u];
    const float c = key[u];
    if (options.max_cost >= 0 && c > options.max_cost) break;
    uint32_t ha, hb;
    if (!find_edge(u, v, ha, hb) || !legal(u, v, ha, hb)) {
      set_key(u, best_legal_candidate(u));
      continue;
    }
    const uint64_t removes = (ha != kNone) + (hb != kNone);
    if (goal && faces - removes < goal) {
      final_boundary_collapse();
      break;
    }
    perform(u, v, ha, hb, c);
    update_after(v);
    if (options.progress && start_faces - faces >= next_progress) {
      next_progress += progress_step;
      const double span = double(start_faces - std::min(goal, start_faces));
      options.progress(span > 0 ? std::min(1.0, double(start_faces - faces) / span) : 1.0);
    }
  }
  stats.collapse = seconds_since(t0) - stats.update_terms - stats.update_costs;
}

}  // namespace

bool simplify(const IndexedMesh& input, const SimplifyOptions& options, CollapseSequence& out, std::string& error) {
  const auto t0 = Clock::now();
  Engine engine;
  if (!engine.init(input, options, error)) return false;
  out.mesh = input;
  out.collapses.clear();
  out.collapses.reserve(input.vertex_count());
  engine.record = &out.collapses;
  engine.stats.setup = seconds_since(t0);
  engine.run(options);
  out.base_indices.clear();
  out.base_indices.reserve(engine.faces * 3);
  for (uint32_t f = 0; f < engine.m.face_count(); ++f)
    if (engine.m.face_alive(f))
      for (int k = 0; k < 3; ++k) out.base_indices.push_back(engine.m.vert[3 * f + k]);
  engine.stats.total = seconds_since(t0);
  if (options.stats) *options.stats = engine.stats;
  return true;
}

IndexedMesh mesh_after(const CollapseSequence& seq, size_t k) {
  const uint32_t n = seq.mesh.vertex_count();
  k = std::min(k, seq.collapses.size());
  // Collapse i maps u to v; following the chain gives each input vertex's survivor. A face
  // whose corners meet is one a collapse deleted.
  std::vector<uint32_t> parent(n);
  for (uint32_t i = 0; i < n; ++i) parent[i] = i;
  for (size_t i = 0; i < k; ++i) parent[seq.collapses[i].u] = seq.collapses[i].v;
  auto find = [&](uint32_t x) {
    uint32_t root = x;
    while (parent[root] != root) root = parent[root];
    while (parent[x] != root) {
      const uint32_t next = parent[x];
      parent[x] = root;
      x = next;
    }
    return root;
  };
  std::vector<uint32_t> remap(n, kNoVertex);
  IndexedMesh result;
  for (uint32_t i = 0; i < n; ++i) {
    if (find(i) != i) continue;
    remap[i] = result.vertex_count();
    result.positions.insert(result.positions.end(), &seq.mesh.positions[size_t(i) * 3], &seq.mesh.positions[size_t(i) * 3 + 3]);
  }
  for (size_t f = 0; f < seq.mesh.indices.size(); f += 3) {
    const uint32_t a = find(seq.mesh.indices[f]), b = find(seq.mesh.indices[f + 1]), c = find(seq.mesh.indices[f + 2]);
    if (a == b || b == c || c == a) continue;
    result.indices.insert(result.indices.end(), {remap[a], remap[b], remap[c]});
  }
  return result;
}

}  // namespace pmz
