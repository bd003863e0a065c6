// The collapse engine: the paper's multi-feature metric (or plain QEM) driving half-edge
// collapses u -> v in a priority queue, recorded as a replayable sequence.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "pmz/mesh.hpp"

namespace pmz {

inline constexpr uint32_t kNoVertex = 0xFFFFFFFFu;

// multifeature: the paper's metric alone. guarded (the default): the paper's metric plus the
// Hausdorff guard (spec/algorithm.md section 6), which holds back collapses that would carry an
// original vertex farther from the surface than the worst distance so far. qem: plain QSlim.
enum class Metric { multifeature, qem, guarded };

// How attribute wedges (texture coordinates, normals, colours) and materials steer the engine
// (spec/algorithm.md section 7). geometry_only: ignored, the collapses of a mesh without
// attributes. Both other modes add the attribute deviation of each collapse to its cost and
// keep material boundaries as discontinuity curves (a vertex moves along one or stays; their
// corners stay). seams (strict): texture and normal seams are such curves too. full (the
// default): a texture or normal seam is priced instead: a collapse across it, or one that moves
// its corner, costs the attribute jump it makes, so it happens only when every alternative
// costs more geometric error. A mesh without attributes is simplified the same way in every
// mode.
enum class AttributeMode { geometry_only, seams, full };

// One half-edge collapse u -> v (v keeps its position; u disappears), in *input* vertex ids.
// vl: third vertex of the face (u, v, vl) holding the directed edge u->v; vr: third vertex of
// the face (v, u, vr) holding v->u. One of them is kNoVertex when (u, v) is a boundary edge.
// Its inverse, the vertex split, re-creates u at positions[u] and the faces (u,v,vl), (v,u,vr).
struct HalfEdgeCollapse {
  uint32_t u, v, vl, vr;
  float cost;  // metric value when it was performed (non-decreasing only approximately)
};

// The multi-feature metric's free parameters (spec/algorithm.md says how the defaults were
// chosen). Cost of collapsing u -> v, with L the mean initial edge length:
//   (quadric_floor + C_norm(u) + torsion_weight * sigma(uv) * T(u) * L) * (Q_u + Q_v)(p_v) / L^4
// where Q is the quadric of the current mesh plus quadric_memory times the accumulated one.
struct MetricParams {
  float epsilon = 0.3f;          // eq. 2: faces with n.n_i <= epsilon add nothing to B
  float quadric_floor = 1.0f;    // c0: the quadric error is the floor, normal variation raises it
  float torsion_weight = 10.0f;  // w_T: weight of the torsion term in the quadric's factor
  float boundary_weight = 1.0f;  // boundary-plane quadrics (both metrics)
  float quadric_memory = 0.1f;   // weight of the accumulated (QSlim) quadric in Q
  // guarded: a collapse whose bound b exceeds guard_slack times the largest bound of the
  // collapses performed so far has its cost multiplied by (b / (guard_slack * that))^2, at
  // most by guard_penalty_cap: while that largest bound is still tiny (only near-zero-cost
  // collapses so far) the ratio says nothing, and uncapped keys would stay stale
  // (spec/algorithm.md section 6).
  float guard_slack = 0.8f;
  float guard_penalty_cap = 1000.0f;
  // seams, full: weight of the attribute deviation (in units where one edge's typical
  // change of an attribute, moved by one mean edge length, weighs like that much distance).
  float attribute_weight = 0.5f;
};

// Where the time went (seconds), filled when SimplifyOptions::stats is set.
struct SimplifyStats {
  double setup = 0, initial_costs = 0, collapse = 0, update_terms = 0, update_costs = 0, total = 0;
  uint64_t cost_evaluations = 0, legality_checks = 0;
  uint64_t guard_checks = 0, guard_deferrals = 0;  // guarded: bounds computed, collapses held back
  double guard_worst_bound = 0;  // guarded: the largest bound of the collapses performed
};

struct SimplifyOptions {
  Metric metric = Metric::guarded;
  AttributeMode attributes = AttributeMode::full;
  MetricParams params;
  SimplifyStats* stats = nullptr;
  uint64_t target_faces = 0;  // stop at this face count (0: as far as legal collapses go)
  double max_cost = -1;       // stop when the cheapest collapse costs more (<0: no limit)
  // Progress callback (fraction done 0..1); may be empty.
  std::function<void(double)> progress;
};

struct CollapseSequence {
  IndexedMesh mesh;  // the input as the engine saw it (after repair), full resolution
  std::vector<HalfEdgeCollapse> collapses;  // in the order performed
  std::vector<uint32_t> base_indices;       // faces left after all collapses, input vertex ids
};

// Runs the engine. Returns false with a one-line message on input it cannot handle.
bool simplify(const IndexedMesh& input, const SimplifyOptions& options, CollapseSequence& out,
              std::string& error);

// The mesh after the first k collapses (faces in input ids compacted to the vertices left), with
// its attributes when seq.mesh has them: the wedges the collapse rule leaves
// (encoder/src/attr_collapse.hpp), compacted in input order, and the surviving faces' materials.
IndexedMesh mesh_after(const CollapseSequence& seq, size_t k);

}  // namespace pmz
