// Internal: the decoder's attribute wedges (spec/format.md section 14). The ATTR chunks are
// decoded lazily like the SPLT symbols: a split's wedges when it is first applied; what it
// assigned is kept so re-applying it after coarsening reads no bytes, and undoing it follows
// the collapse rule. A file without attributes never gets here (one branch per split).
#pragma once
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "pmz/attribute_codec.hpp"

namespace pmz {

struct AttributeStream {
  AttributeState state;
  AttributeQuantizer quant;
  std::unique_ptr<AttributeModels> models;
  // One decoder per SPLT chunk whose splits are not all first-applied, oldest first (in step
  // with the decoder's chunk readers).
  std::deque<std::unique_ptr<RangeDecoder>> lazy;
  // Per first-applied split: the wedge count after it, and where its assignments start in
  // `assigned` (the new faces' materials, then the wedges of split_corners()).
  std::vector<uint32_t> wedge_end;
  std::vector<uint64_t> assign_begin{0};
  std::vector<uint32_t> assigned;
  std::vector<uint32_t> corners, saved;  // scratch
  // Float values per wedge (the public arrays), filled as wedges are first decoded.
  std::vector<float> texcoords[kMaxTexcoordSets], normals, colors, wedge_positions;

  // HEAD's attribute fields (after the fixed ones). False with a message.
  bool head(const uint8_t* p, size_t n, uint64_t full_faces, std::string& error);
  // The base ATTR chunk (pm: the base mesh; positions 3 floats per vertex).
  bool base(const uint8_t* p, size_t n, const ProgressiveMesh& pm, const int32_t* coords,
            const float* positions, std::string& error);
  // An ATTR chunk after a SPLT chunk: queued for its splits.
  void chunk(const uint8_t* p, size_t n) { lazy.push_back(std::make_unique<RangeDecoder>(p, n)); }
  // First application of split i (== wedge_end.size()), right after pm.split_gathered() and u's
  // position: decodes its wedges from lazy.front(). False (state as before the split; the caller
  // then undoes the mesh split) on a malformed stream or a wedge reference out of range.
  bool first_apply(const ProgressiveMesh& pm, const int32_t* coords, const float* positions,
                   bool has_l, bool has_r);
  // After the decoder finished the first applications of a chunk: its ATTR decoder goes too.
  void chunk_done() { lazy.pop_front(); }
  // Split i applied again (ProgressiveMesh::resplit): its assignments from first_apply.
  void reapply(const ProgressiveMesh& pm, uint64_t i, bool has_l, bool has_r);
  // Split i undone (after ProgressiveMesh::undo_resplit, v its vertex).
  void undo(const ProgressiveMesh& pm, uint64_t i, uint32_t v, bool has_l, bool has_r) {
    undo_split_wedges(pm, v, has_l, has_r, state, i ? wedge_end[i - 1] : state.head.base_wedges);
  }

 private:
  void new_wedges(const float* positions);  // float arrays for wedges decoded since last call
};

}  // namespace pmz
