// SPDX-License-Identifier: MIT
// The node table of a stream in independently decodable parts (spec/format.md section 15): the
// levels' grids of cells over the file's integer coordinates and, per node (one cell of one
// level with its vertex splits), what a decoder needs to schedule it, to place its vertices and
// faces, to fetch its bytes and to judge whether a view needs it. Shared by writer and decoder.
#pragma once
#include <climits>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace pmz {

inline constexpr uint8_t kChunkNodes = 6;
inline constexpr uint32_t kFlagNodes = 2;       // HEAD flags bit 1: a NODE chunk follows BASE
inline constexpr uint32_t kMaxNodeLevels = 32;  // levels of a node table

// A level's grid: cubes of `side` file units, cell index floor((c - origin) / side) per axis.
// side 0: one cell holding every vertex (the whole mesh).
struct NodeGrid {
  int64_t side = 0;
  int64_t origin[3] = {0, 0, 0};
  // The cell index of coordinate c on axis a (side > 0).
  int64_t index(int32_t c, int a) const {
    const int64_t d = int64_t(c) - origin[a];
    return d >= 0 ? d / side : -((-d + side - 1) / side);
  }
};

// The coordinate box of a cell, to test vertices against without a division per axis.
struct CellBox {
  int64_t lo[3] = {INT64_MIN, INT64_MIN, INT64_MIN}, hi[3] = {INT64_MAX, INT64_MAX, INT64_MAX};
  CellBox() = default;
  CellBox(const NodeGrid& g, const int64_t cell[3]) {
    if (g.side == 0) return;
    for (int a = 0; a < 3; ++a) {
      lo[a] = g.origin[a] + cell[a] * g.side;
      hi[a] = lo[a] + g.side - 1;
    }
  }
  bool contains(const int32_t c[3]) const {
    return c[0] >= lo[0] && c[0] <= hi[0] && c[1] >= lo[1] && c[1] <= hi[1] && c[2] >= lo[2] &&
           c[2] <= hi[2];
  }
};

struct NodeEntry {
  uint32_t level = 0;
  int64_t cell[3] = {0, 0, 0};  // 0 on a level whose side is 0
  uint64_t splits = 0;          // vertex splits (>= 1)
  uint64_t faces = 0;           // faces its splits add
  uint64_t wedges = 0;          // attribute wedges its splits add (streams with attributes)
  uint64_t bytes = 0;           // its chunks (SPLT, and ATTR with attributes), headers included
  float center[3] = {0, 0, 0};  // a sphere holding the vertices its splits move or add
  float radius = 0;
  float error =
      0;  // geometric error its splits remove, in model units (spec/format.md section 15.2)
  // Its normal cone (format 13.1, spec/format.md section 15.5): the faces around the vertices
  // its splits add have normals within asin(cone_cutoff / 127) of the axis cone_axis (not unit).
  // A zero axis or a cutoff above 127: no cone (kNoCone, what a writer writes).
  int8_t cone_axis[3] = {0, 0, 0};
  uint8_t cone_cutoff = kNoCone;
  static constexpr uint8_t kNoCone = 255;
  bool has_cone() const {
    return cone_cutoff <= 127 && (cone_axis[0] | cone_axis[1] | cone_axis[2]) != 0;
  }
};

struct NodeTable {
  bool attributes = false;       // the stream's (HEAD flag bit 0): nodes state their wedges
  bool cones = false;            // format 13.1: a cone per node after the last node's error
  std::vector<NodeGrid> levels;  // finest first; only the last may have side 0
  std::vector<NodeEntry> nodes;  // in file order
};

// Appends the NODE payload (spec/format.md section 15.1).
void write_node_table(std::vector<uint8_t>& out, const NodeTable& t);

// Parses and checks a NODE payload against HEAD's counts (spec/format.md section 15.1): false with
// a one-line reason for a malformed or inconsistent table (a node before one of its parents, a cell
// twice, split counts that do not sum to total_splits, ...). max_nodes bounds the node count.
// cones: the stream's HEAD minor version is 1 or more, so the cones follow the nodes (15.5).
bool read_node_table(const uint8_t* p, size_t size, uint64_t total_splits, uint64_t max_nodes,
                     bool attributes, bool cones, NodeTable& t, std::string& error);

// The nodes of coarser levels whose cells overlap node k's (its parents, spec/format.md
// section 15.3), in ascending order; `index` as made by NodeIndex.
class NodeIndex {
 public:
  explicit NodeIndex(const NodeTable& t);
  // The node of cell `cell` on `level`, or -1.
  int64_t find(uint32_t level, const int64_t cell[3]) const;
  std::vector<uint32_t> parents(uint32_t k) const;

 private:
  struct Key {
    int64_t level, cell[3];
    uint32_t node;
  };
  static bool less(const Key& a, const Key& b);  // by (level, cell, node)
  const NodeTable& t_;
  std::vector<Key> sorted_;  // by (level, cell)
};

// The candidates of a node (spec/format.md section 15.4): the vertices below `count` whose
// coordinates lie in its cell, ascending. Binned once per level (the nodes of a level follow one
// another in file order): build() puts every vertex in the bin of its level's node, if any; take()
// hands node k's bin over (k < the table's node count).
class CellBins {
 public:
  void build(const NodeTable& t, uint32_t level, const int32_t* coords, uint32_t count);
  std::vector<uint32_t> take(uint32_t node);
  std::span<const uint32_t> bin(uint32_t node) const { return bins_[node]; }

 private:
  std::vector<std::vector<uint32_t>> bins_;  // per node of the table
};

}  // namespace pmz
