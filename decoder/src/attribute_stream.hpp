// SPDX-License-Identifier: MIT
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
  // `assigned` (the new faces' materials, then per corner of split_corners() the corner and its
  // wedge: re-applying and undoing the split need no walk).
  BigVector<uint32_t> wedge_end;
  BigVector<uint64_t> assign_begin{0};
  BigVector<uint32_t> assigned;
  std::vector<uint32_t> corners, saved, sector_wedges;  // scratch
  // Float values per wedge (the public arrays), filled as wedges are first decoded.
  BigVector<float> texcoords[kMaxTexcoordSets], normals, colors, wedge_positions;

  // HEAD's attribute fields (after the fixed ones). False with a message.
  bool head(const uint8_t* p, size_t n, uint64_t full_faces, std::string& error);
  // The base ATTR chunk (pm: the base mesh; positions 3 floats per vertex).
  bool base(const uint8_t* p, size_t n, const ProgressiveMesh& pm, const int32_t* coords,
            const float* positions, std::string& error);
  // An ATTR chunk after a SPLT chunk: queued for its splits.
  void chunk(const uint8_t* p, size_t n) { lazy.push_back(std::make_unique<RangeDecoder>(p, n)); }
  // Room for the first `splits` of the stream's `total` splits (faces: the mesh's faces after
  // them), from HEAD's counts, before refining: every buffer grows once rather than doubling
  // (copies and page faults) split by split. reserve_split() stays the guarantee.
  void reserve(size_t faces, uint64_t splits, uint64_t total);
  // Room for `wedges` wedges in every per-wedge buffer (they grow together).
  void reserve_wedges(size_t wedges);
  // Before a split's first application (faces: the mesh's now, ring: v's ring size): allocates
  // what first_apply() may need, so that it cannot fail to allocate after the mesh changed.
  void reserve_split(uint32_t faces, uint32_t ring);
  // First application of split i (== wedge_end.size()), right after pm.split_gathered() and u's
  // position: decodes its wedges from lazy.front(). False (state as before the split; the caller
  // then undoes the mesh split) on a malformed stream or a wedge reference out of range.
  bool first_apply(const ProgressiveMesh& pm, const int32_t* coords, const float* positions,
                   bool has_l, bool has_r);
  // After the decoder finished the first applications of a chunk: its ATTR decoder goes too.
  void chunk_done() { lazy.pop_front(); }
  // Split i applied again (ProgressiveMesh::resplit): its assignments from first_apply.
  void reapply(const ProgressiveMesh& pm, uint64_t i, bool has_l, bool has_r);
  // Split i undone (after ProgressiveMesh::undo_resplit): the sector corners take v's wedges
  // by the collapse rule, the new faces' entries go.
  void undo(const ProgressiveMesh& pm, uint64_t i, bool has_l, bool has_r);

  // Float arrays for the wedges decoded since the last call.
  void new_wedges(const float* positions);
};

}  // namespace pmz
