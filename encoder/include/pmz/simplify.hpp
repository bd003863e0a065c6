// SPDX-License-Identifier: MIT
// The collapse engine: the paper's multi-feature metric (or plain QEM) driving half-edge
// collapses u -> v in a priority queue, recorded as a replayable sequence.
//
// EXPERIMENTAL: the encoder API (this header and pmz/writer.hpp) may change in any release,
// without a major version; the stable parts of pmz are the decoder's API (pmz/decoder.hpp,
// pmz/pmz.h) and the .pmz format (spec/format.md).
//
// Errors: a function that can fail on its input returns false with one line in `error` (no
// newline, no program prefix) and leaves its output as it was; the only exception that can
// escape is std::bad_alloc. Nothing is printed.
// Threads: no global state. Calls on different data may run in different threads at once;
// simplify() runs part of its set-up on one extra thread of its own and calls
// SimplifyOptions::progress on the calling thread.
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

// One level of a hierarchical simplification (SimplifyOptions::clusters): a grid of cubes over
// the file's integer coordinates (spec/format.md section 5); the cell index on axis a is
// floor((c[a] - origin[a]) / side).
struct CellGrid {
  int64_t side = 0;  // > 0 for a grid; 0: one cell, the whole mesh
  int64_t origin[3] = {0, 0, 0};

  // The cell of integer coordinates c, the three indices packed 21 bits each (taken modulo
  // 2^21: grids are made with fewer cells than that per axis); 0 for every c when side is 0.
  uint64_t cell(const int32_t c[3]) const {
    if (side <= 0) return 0;
    uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const int64_t d = int64_t(c[a]) - origin[a];
      const int64_t i = d >= 0 ? d / side : -((-d + side - 1) / side);
      key = (key << 21) | (uint64_t(i) & 0x1FFFFF);
    }
    return key;
  }
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
  // Hierarchical simplification (experimental; the encoder side of a cluster format). With
  // vertices > 0 and a mesh of more than twice that many vertices, the engine runs in levels:
  // the first on a grid of cells of about `vertices` vertices each (encoder/src/cluster_grid.hpp),
  // each next on a wider grid (5/4 to twice the side) whose cells hold about `vertices` of the
  // vertices left and whose planes lie between the last one's, until a grid no longer cuts the
  // mesh or at most `vertices` are left; then one level on the whole mesh, as without clusters.
  // Within a level a collapse is legal only when u, v and every neighbour of both lie in one cell,
  // and each cell is simplified on its own (its own heap and guard bound; the result does not
  // depend on the other cells) until its cheapest collapse costs more than the level's threshold
  // (the cost_quantile of the keys of the vertices inside cells at the level's start; 1: none) or
  // its faces have dropped to phase_ratio of its faces at the level's start (or no legal
  // collapse is left in it). Cells are cut on the writer's integer coordinates:
  // position_bits must be the writer's (WriteOptions::position_bits).
  struct Clusters {
    uint32_t vertices = 0;  // 0: off
    uint32_t position_bits = 14;
    double phase_ratio = 0.25;
    double cost_quantile = 0.7;
    // Threads simplifying the cells of a level (0: one per core); the result is the same for
    // any count.
    uint32_t threads = 0;
    // The first level's cells simplified apart (simplify_cell, possibly in other processes):
    // when set, simplify() takes cell c's result from first_level(c, result, error) instead of
    // simplifying the cell itself, and fails with that error when it returns false.
    std::function<bool(uint32_t cell, std::vector<uint8_t>& result, std::string& error)>
        first_level;
  } clusters;
  // Progress callback (fraction done 0..1), called on simplify()'s thread during the run; may
  // be empty.
  std::function<void(double)> progress;
};

struct CollapseSequence {
  IndexedMesh mesh;  // the input as the engine saw it (after repair), full resolution
  std::vector<HalfEdgeCollapse> collapses;  // in the order performed
  std::vector<uint32_t> base_indices;       // faces left after all collapses, input vertex ids
  // With SimplifyOptions::clusters: the levels, finest first. Level i holds the collapses from
  // first_collapse up to the next level's, each inside one cell of its grid (u, v and their
  // neighbours at the time); the last level's grid has side 0 (the whole mesh). Empty without.
  struct Level {
    CellGrid grid;
    uint64_t first_collapse = 0;
  };
  std::vector<Level> levels;
};

// Runs the engine on `input`: finite positions; faces that are edge-manifold, consistently
// oriented and without a repeated vertex (what read_mesh and repair_mesh give); attributes, if
// any, consistent with the faces (a wedge per corner). Fills `out` (its mesh is a copy of
// input) and returns true, or returns false with a one-line message naming the offending face,
// edge or vertex and leaves `out` unchanged. `input` and `options` are not kept; the
// SimplifyOptions::stats object, when set, must outlive the call.
bool simplify(const IndexedMesh& input, const SimplifyOptions& options, CollapseSequence& out,
              std::string& error);

// The first cell level as tasks that can run apart, in other processes or on other machines.
// cell_tasks() counts its cells (0 when the mesh and options make no cell levels);
// simplify_cell() simplifies cell `cell` as simplify() would and gives, as opaque bytes, its
// collapses and the engine's terms they changed; simplify() with clusters.first_level handing it
// each cell's bytes then gives the same sequence as alone. All take the same input and options
// (clusters.threads aside). They fail as simplify() does, and simplify() also on a result that
// does not fit the mesh or the cell.
bool cell_tasks(const IndexedMesh& input, const SimplifyOptions& options, uint32_t& count,
                std::string& error);
bool simplify_cell(const IndexedMesh& input, const SimplifyOptions& options, uint32_t cell,
                   std::vector<uint8_t>& result, std::string& error);

// The first level's cells as tasks that need no more than their cell: cell_regions() hands
// sink(cell, region, error) each cell's region, the engine's terms of the cell's vertices, their
// neighbours and the faces around them (a sink returning false stops it with its error), and
// counts the cells; simplify_cell_region() simplifies cell `cell` from its region and gives the
// bytes simplify_cell() gives for it, holding the region only. Regions are bytes of this build of
// the library on machines of one kind; simplify_cell_region() fails with one line on bytes that
// are not one.
using CellRegionSink =
    std::function<bool(uint32_t cell, const std::vector<uint8_t>& region, std::string& error)>;
bool cell_regions(const IndexedMesh& input, const SimplifyOptions& options,
                  const CellRegionSink& sink, uint32_t& count, std::string& error);
bool simplify_cell_region(const std::vector<uint8_t>& region, uint32_t cell,
                          std::vector<uint8_t>& result, std::string& error);

// The mesh after the first k collapses (faces in input ids compacted to the vertices left), with
// its attributes when seq.mesh has them: the wedges the collapse rule leaves
// (encoder/src/attr_collapse.hpp), compacted in input order, and the surviving faces' materials.
// seq: as simplify() made it. k beyond seq.collapses.size() is taken as all of them. Never fails
// (but for std::bad_alloc).
IndexedMesh mesh_after(const CollapseSequence& seq, size_t k);

}  // namespace pmz
