// SPDX-License-Identifier: MIT
// Experimental: the node graph of a hierarchical simplification (SimplifyOptions::clusters), the
// plan of a stream whose parts decode independently.
//
// A node is one cell of one level with the collapses made in it. Its vertex splits (the
// collapses inverted) read and write only vertices and faces of its cell, so a node can be
// decoded as soon as every node of a coarser level whose cell overlaps its own has been: its
// parents. Nodes of one level never depend on each other.
#pragma once
#include <cstdint>
#include <vector>

#include "pmz/simplify.hpp"

namespace pmz {

struct ClusterNode {
  uint32_t level = 0;           // index into CollapseSequence::levels (the last: the whole mesh)
  int64_t cell[3] = {0, 0, 0};  // the cell's indices in the level's grid (0 at the last level)
  // The nodes of coarser levels whose cells overlap this one's (all of them, not only the
  // nearest level's: a region without collapses at the next level leaves no node there).
  std::vector<uint32_t> parents;
  uint64_t first = 0, count = 0;  // its collapses: ClusterPlan::collapses[first, first + count)
  float max_cost = 0;             // the largest metric value of its collapses
  float center[3] = {0, 0, 0};    // a sphere holding the vertices of its collapses
  float radius = 0;
};

struct ClusterPlan {
  // Decode order: coarser levels first, within a level by max_cost, largest first; every
  // node's parents come before it.
  std::vector<ClusterNode> nodes;
  // Indices into CollapseSequence::collapses, node by node in the order of `nodes`, each node's
  // in the order they were made.
  std::vector<uint64_t> collapses;
};

// The plan of a sequence simplify() made with clusters (position_bits: the writer's, as
// SimplifyOptions::clusters.position_bits). A sequence without levels gives one node.
ClusterPlan plan_clusters(const CollapseSequence& seq, uint32_t position_bits);

// The same collapses in node order, for a writer that writes vertex splits in the reverse
// of the collapse order: the last node's collapses first, the first node's last, each node's
// in the order made. Collapses of different cells commute, so the sequence leaves the same base
// mesh and every prefix of its inverse is a valid mesh.
CollapseSequence node_ordered(const CollapseSequence& seq, const ClusterPlan& plan);

// Parallel decoding figures of a plan, counting one unit of work per split: the longest chain
// of dependent work (the critical path) and the time of a greedy schedule on `workers` that
// starts ready nodes in plan order.
struct ClusterSchedule {
  uint64_t total = 0, critical_path = 0, makespan = 0;
};
ClusterSchedule schedule_clusters(const ClusterPlan& plan, uint32_t workers);

}  // namespace pmz
