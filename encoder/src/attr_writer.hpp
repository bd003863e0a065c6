// SPDX-License-Identifier: MIT
// Internal: the writer's side of attribute wedges (spec/format.md section 14). Replays the
// collapse sequence with the collapse rule (fine to coarse) to know every level's wedges, then,
// as the writer replays the decoder's splits (coarse to fine), codes each assigned corner's
// wedge in the decoder's order with the decoder's own state (pmz/attribute_codec.hpp).
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "attr_collapse.hpp"
#include "pmz/attribute_codec.hpp"
#include "pmz/writer.hpp"

namespace pmz {

class AttributeWriter {
 public:
  // False with a message on attributes it cannot write. `used`: the collapses the splits
  // invert (the base is the mesh after them); input_of: decoded vertex id -> input id.
  bool init(const CollapseSequence& seq, size_t used, const WriteOptions& opt,
            const std::vector<uint32_t>& input_of, std::string& error);
  const AttributeHeader& header() const { return state_.head; }
  // The base mesh's ATTR payload (pm: the base mesh as the decoder builds it).
  void encode_base(const ProgressiveMesh& pm, const int32_t* coords, std::vector<uint8_t>& payload);
  // Right after the split inverting collapse `collapse` was applied to pm (u's coordinates in
  // coords): its materials and corner wedges into the current chunk's stream.
  void encode_split(const ProgressiveMesh& pm, const int32_t* coords, uint32_t collapse, bool has_l,
                    bool has_r);
  // The ATTR payload of the splits since the last call.
  void finish_chunk(std::vector<uint8_t>& payload);
  // After the last split: the decoded wedges and materials are the input's, corner by corner.
  bool check_full(const ProgressiveMesh& pm, std::string& error) const;
  uint32_t wedge_count() const { return state_.wedge_count; }
  // Streams in nodes (spec/format.md section 15.4): the models the first node left, and a
  // later node's start from them.
  const AttributeModels& models() const { return models_; }
  void restart_models(const AttributeModels& first) { models_ = first; }

 private:
  using Face = std::array<uint32_t, 3>;
  // The input wedge and material of decoded face f's corner k, looked up in `fan` (input face
  // slots and corners).
  bool lookup(const ProgressiveMesh& pm, const CollapseFan& fan, uint32_t f, uint32_t k,
              uint32_t& wedge, uint32_t& material) const;
  // The decoded id of an input wedge; a new one (numbered after fresh_count others of the same
  // split) gets fresh = its values.
  uint32_t decoded_id(uint32_t input_wedge, uint32_t& fresh_count, const int32_t*& fresh);
  const IndexedMesh* mesh_ = nullptr;
  const std::vector<uint32_t>* input_of_ = nullptr;
  AttributeState state_;
  AttributeModels models_;
  std::vector<int32_t> values_;          // quantized, stride per input wedge
  std::vector<uint32_t> decoded_wedge_;  // input wedge -> decoded id (or kNoCorner)
  std::vector<CollapseFan> fans_;        // per collapse: u's faces before it
  std::vector<uint32_t> final_wedge_;    // replay's corner wedges after all collapses
  std::vector<uint32_t> final_corner_;   // and its corner vertices
  std::map<Face, uint32_t> final_face_;  // canonical face (input ids) -> input face slot
  std::vector<uint8_t> chunk_;
  std::unique_ptr<RangeEncoder> rc_;
  std::vector<uint32_t> corners_, wedges_;
  std::vector<const int32_t*> fresh_;
};

}  // namespace pmz
