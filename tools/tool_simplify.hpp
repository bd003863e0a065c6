// SPDX-License-Identifier: MIT
// The simplifier's options, defined once for pmz-encode and pmz-simplify: the metric, how
// attributes steer it, and the metric's parameters (defaults: pmz::MetricParams), so both tools
// simplify alike for the same command line.
#pragma once
#include <CLI/CLI.hpp>
#include <string>

#include "pmz/simplify.hpp"

namespace pmz::tool {

// --cluster-vertices auto: cells of about 8,192 vertices for a mesh of at least 65,536
// vertices, the whole mesh at once below. Smaller cells let a view fetch less around what it
// shows and cost bytes (docs/benchmarks.md, "Nodes" and "Decoding for a view": against 16,384,
// a close-up of a 4.8M-face scan reads about two thirds of the bytes, for 1.5-2% more bytes;
// 4,096 costs 5%, past the 1.05x that a mesh in nodes may cost over one node).
inline constexpr uint32_t kAutoClusterVertices = 8192, kAutoClusterMeshVertices = 65536;

struct SimplifierCli {
  std::string metric = "guarded";
  std::string attributes = "full";
  MetricParams params;
  std::string cluster_vertices = "auto";
  uint32_t cell_threads = 0;

  // --metric, --attributes, --attribute-weight, then the parameters (--epsilon ...
  // --guard-slack), each --help line with its default.
  void add_to(CLI::App& app) {
    app.add_option("--metric", metric,
                   "guarded: the paper's multi-feature metric plus the Hausdorff guard "
                   "(spec/algorithm.md section 6); multifeature: the paper's metric alone; qem: "
                   "plain QEM (QSlim)")
        ->check(CLI::IsMember({"guarded", "multifeature", "qem"}))
        ->capture_default_str();
    app.add_option("--attributes", attributes,
                   "how texture coordinates, normals, colours and materials steer the "
                   "simplification (spec/algorithm.md section 7): full: attribute error added "
                   "to the cost, material boundaries kept as discontinuity curves, texture and "
                   "normal seams priced (crossed or their corners moved only where that costs "
                   "less than the geometric error of the alternatives); seams: strict, texture "
                   "and normal seams kept like material boundaries (moved along, never across; "
                   "their corners stay); geometry-only: ignored (the geometric metric alone). A "
                   "mesh without attributes simplifies the same in every mode")
        ->check(CLI::IsMember({"full", "seams", "geometry-only"}))
        ->capture_default_str();
    app.add_option("--attribute-weight", params.attribute_weight,
                   "full, seams: weight of the attribute error against the geometric cost")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    app.add_option("--epsilon", params.epsilon, "torsion threshold epsilon (eq. 2)")
        ->capture_default_str();
    app.add_option("--quadric-floor", params.quadric_floor,
                   "c0 in (c0 + C_norm + w_T * sigma * T) * Q")
        ->capture_default_str();
    app.add_option("--torsion-weight", params.torsion_weight,
                   "weight w_T of sigma * T in the quadric's factor")
        ->capture_default_str();
    app.add_option("--boundary-weight", params.boundary_weight, "weight of boundary quadrics")
        ->capture_default_str();
    app.add_option(
           "--quadric-memory", params.quadric_memory,
           "multifeature: weight of the accumulated (QSlim) quadric added to the current mesh's")
        ->capture_default_str();
    app.add_option("--guard-slack", params.guard_slack,
                   "guarded: collapses whose bound exceeds this times the worst bound so far are "
                   "penalised")
        ->capture_default_str();
    app.add_option("--cluster-vertices", cluster_vertices,
                   "simplify in cells of about this many vertices first, then in wider cells of "
                   "about as many of the vertices left, up to the whole mesh once that many are "
                   "left, and write the stream in nodes that decode "
                   "independently (spec/format.md section 15); 0: the whole mesh at once, one "
                   "node; auto: 8192 for meshes of at least 65536 vertices, else 0")
        ->check(CLI::IsMember({"auto"}) | CLI::Range(0u, 1u << 30))
        ->capture_default_str();
    app.add_option("--cell-threads", cell_threads,
                   "threads simplifying the cells of a level (0: one per core); the output is "
                   "the same for any count")
        ->check(CLI::Range(0u, 1024u))
        ->capture_default_str();
  }

  // The parsed values into the engine's options (metric, attribute mode, parameters, an explicit
  // cell size; apply_clusters() settles "auto" once the mesh is read).
  void apply(SimplifyOptions& options) const {
    options.metric = metric == "qem"            ? Metric::qem
                     : metric == "multifeature" ? Metric::multifeature
                                                : Metric::guarded;
    options.attributes = attributes == "geometry-only" ? AttributeMode::geometry_only
                         : attributes == "seams"       ? AttributeMode::seams
                                                       : AttributeMode::full;
    options.params = params;
    options.clusters.vertices =
        cluster_vertices == "auto" ? 0 : uint32_t(std::stoul(cluster_vertices));
    options.clusters.threads = cell_threads;
  }

  // The cell size for a mesh of `vertices` vertices (after apply()).
  void apply_clusters(SimplifyOptions& options, size_t vertices) const {
    if (cluster_vertices == "auto")
      options.clusters.vertices = vertices >= kAutoClusterMeshVertices ? kAutoClusterVertices : 0;
  }
};

}  // namespace pmz::tool
