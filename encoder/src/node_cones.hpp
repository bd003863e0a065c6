// SPDX-License-Identifier: MIT
// The nodes' normal cones (spec/format.md section 15.5), gathered while the writer replays its
// splits: a node's cone holds the normals of the faces around the vertices its splits add, at the
// decoded positions, both as the node leaves them and in the full mesh.
#pragma once
#include <cstdint>
#include <vector>

#include "pmz/format.hpp"
#include "pmz/node_table.hpp"
#include "pmz/progressive_mesh.hpp"

namespace pmz {

class NodeCones {
 public:
  // coords: every vertex's integer coordinates (decoded ids); quant: HEAD's quantizer
  // (spec/format.md section 5).
  NodeCones(const Quantizer& quant, const int32_t* coords) : quant_(quant), coords_(coords) {}
  // Right after the first application of the last split of the next node (in file order),
  // whose vertices are first .. end - 1 in m: their faces set its axis and its cutoff so far.
  void node_done(const ProgressiveMesh& m, uint32_t first, uint32_t end);
  // The full mesh m: every face with a corner among a node's vertices narrows that node's
  // cutoff; then each node of t (whose node_done calls these were, in order) gets its cone.
  void finish(const ProgressiveMesh& m, uint32_t base_vertices, NodeTable& t);

 private:
  // Face (a, b, c)'s unit normal at the decoded positions; false for a face without area.
  bool normal(uint32_t a, uint32_t b, uint32_t c, double n[3]) const;
  struct Cone {
    int8_t stored[3] = {0, 0, 0};  // the axis as stored; zero: no cone
    double axis[3] = {0, 0, 0};    // the same, unit
    double min_dot = 1;            // the smallest dot product of a normal with it
  };
  const Quantizer quant_;
  const int32_t* coords_;
  std::vector<Cone> cones_;      // per node in file order
  std::vector<double> normals_;  // scratch: a node's normals, three per face
};

}  // namespace pmz
