// SPDX-License-Identifier: MIT
// Attribute wedges in the .pmz format (spec/format.md section 14; format 12.0): the HEAD
// fields, the per-corner wedge state writer and decoder keep in step, and the coding of a
// corner's wedge reference and a new wedge's values (ATTR chunks). Writer and decoder share it.
//
// A file with attributes (HEAD flag kFlagAttributes) follows BASE with an ATTR chunk coding the
// base mesh's wedges, and each SPLT chunk with an ATTR chunk coding, per split, the wedges of
// the corners the split creates or rewrites (split_corners()) and the new faces' materials.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "pmz/format.hpp"
#include "pmz/huge_pages.hpp"
#include "pmz/progressive_mesh.hpp"
#include "pmz/range_coder.hpp"

namespace pmz {

inline constexpr uint32_t kFlagAttributes = 1;  // HEAD flags bit 0
inline constexpr uint8_t kChunkAttributes = 5;
inline constexpr uint32_t kMaxTexcoordSets = 8, kMaxAttributeBits = 24, kMaxMaterials = 1u << 16;
inline constexpr uint32_t kMaxMaterialString = 4096;
inline constexpr uint32_t kPendingWedge = 0xFFFFFFFEu;  // a corner whose wedge is being coded

// The collapse rule (encoder/src/attr_collapse.hpp, spec/format.md section 14.5): how many leading
// sector corners (u's wedges, in order from L's side) take v's wedge in L; the rest take v's
// wedge in R. The decoder undoes a split with it.
inline uint32_t collapse_left_arc(std::span<const uint32_t> sector_u_wedges, uint32_t u_wedge_l,
                                  bool has_l, bool has_r) {
  if (!has_l) return 0;
  if (!has_r) return uint32_t(sector_u_wedges.size());
  uint32_t n = 0;
  while (n < sector_u_wedges.size() && sector_u_wedges[n] == u_wedge_l) ++n;
  return n;
}

struct FileMaterial {
  std::string name, base_color_texture, normal_texture;
  float base_color[4] = {1, 1, 1, 1};
};

// HEAD's attribute fields (present when flags has kFlagAttributes). bits 0 = lossless.
struct AttributeHeader {
  uint32_t texcoord_sets = 0, texcoord_bits = 12;
  float texcoord_min[kMaxTexcoordSets][2] = {}, texcoord_max[kMaxTexcoordSets][2] = {};
  bool normals = false;
  uint32_t normal_bits = 10;  // octahedral, per component
  uint32_t color_components = 0, color_bits = 8;
  std::vector<FileMaterial> materials;
  std::string material_library;
  uint32_t base_wedges = 0, full_wedges = 0;
  bool has_wedges() const { return texcoord_sets || normals || color_components; }
  // Integer components per wedge: 2 per texcoord set, 2 (octahedral) or 3 (lossless) for the
  // normal, then the colour's.
  uint32_t normal_components() const { return normals ? (normal_bits ? 2 : 3) : 0; }
  uint32_t stride() const { return 2 * texcoord_sets + normal_components() + color_components; }
};

void write_attribute_header(std::vector<uint8_t>& out, const AttributeHeader& a);
// False with a message when a field is malformed or out of range.
bool read_attribute_header(ByteReader& r, AttributeHeader& a, std::string& error);

// Quantization of each attribute (spec/format.md section 14.2), both directions.
struct AttributeQuantizer {
  Quantizer texcoord[kMaxTexcoordSets];
  uint32_t normal_bits = 0, color_bits = 0;
  void init(const AttributeHeader& a);
  void quantize_normal(const float n[3], int32_t* q) const;
  void dequantize_normal(const int32_t* q, float n[3]) const;
  int32_t quantize_color(float c) const;
  float dequantize_color(int32_t q) const;
};

// What the ATTR symbols cost, in bits, per kind (for analysis: pmz-info), summed into bits[]
// while decoding when bits is set (null, the default: a test per symbol). A symbol's cost is
// how far it narrowed the range decoder's interval: 8 bits per byte taken in, plus log2 of the
// range before over the range after (its -log2 p, with the coder's rounding). A chunk's costs
// add up to its bytes but for the coder's start and end. The values of a new a-wedge count as
// their kinds, the face materials as kMaterials, and every other symbol (the reference, escape
// and simple symbols of spec/format.md sections 14.3 and 14.5: which a-wedge each corner
// takes) as kWedges. The WebAssembly decoder leaves the counting out (its size budget).
struct AttributeCost {
  enum Kind { kTexcoords, kNormals, kColors, kMaterials, kWedges, kKinds };
  double* bits = nullptr;  // kKinds sums (the decoder's caller's: pmz::AttributeBits)
  const uint8_t* at;       // the decoder's state after the last symbol counted
  uint32_t range;
#if defined(__wasm__)
  static constexpr bool kCounts = false;
#else
  static constexpr bool kCounts = true;
#endif
  bool counting() const { return kCounts && bits; }
  // Where decoding resumes (a chunk's start, or its next split), rc the decoder's state.
  void resume(const RangeState& rc) {
    if (kCounts) at = rc.p, range = rc.range;
  }
  // The bits since the last symbol counted (or resume()) to k, when counting.
  void charge(const RangeState& rc, Kind k) {
    if (counting()) [[unlikely]]
      add(rc, k);
  }
  void add(const RangeState& rc, Kind k);  // out of line: the call sites stay small
};

// Context models of the ATTR streams, created once per file (carried across chunks).
struct AttributeModels {
  AttributeCost cost;  // symbol costs, counted only when cost.bits is set (first: the shortest
                       // address at the decoder's call sites)
  SmallModel reference[2][3];    // [u corner][candidates]
  UIntModel escape;              // an existing wedge that is no candidate: wedges - 1 - id
  UIntModel texcoord[2];         // [component], without a face-map prediction
  UIntModel texcoord_fan[8][9];  // [face maps' spread context][u: 0; v: class of u's residual]
  UIntModel normal[3];           // lossless normals [component]
  UIntModel normal_fan[8][9];    // octahedral [neighbours' spread][0, or class of the first's]
  UIntModel color[4];
  SmallModel material[4];  // [candidates]
  UIntModel material_escape;
  Prob simple[2] = {kProbInit, kProbInit};  // a split's "simple" bit [the previous split's]
  uint32_t last_simple = 0;
  int32_t normal_score = 0;  // > 0: new normals take the neighbour's prediction (14.3)
};

// The attribute state writer and decoder keep: per corner its wedge, per wedge its vertex and
// integer values (stride() per wedge), per face its material (empty without materials).
// (BigVector: read at random like the mesh's buffers, huge pages where available)
struct AttributeState {
  AttributeHeader head;
  uint32_t stride = 0;
  BigVector<uint32_t> corner_wedge;
  BigVector<uint32_t> wedge_vertex;
  BigVector<int32_t> values;
  BigVector<uint32_t> face_material;
  uint32_t wedge_count = 0;  // wedges in use (the arrays may hold more: undone splits' wedges)
  void init(const AttributeHeader& a) {
    head = a;
    stride = a.stride();
  }
  bool has_materials() const { return !head.materials.empty(); }
};

// The corners a split assigns wedges to, in coding order (spec/format.md section 14.5), right after
// ProgressiveMesh::split_gathered() or resplit(): L's v and vl corners, R's v and vr corners,
// then u's corners in L, in the sector faces in order, in R.
void split_corners(const ProgressiveMesh& pm, bool has_l, bool has_r, std::vector<uint32_t>& out);

// A base corner's wedge (the corner is pending in s.corner_wedge): the writer codes `wedge` (an
// existing wedge id, or s.wedge_count for a new wedge with values `fresh`), the decoder reads
// it. coords: the mesh's integer positions (3 per vertex).
void encode_corner_wedge(RangeEncoder& rc, AttributeModels& m, const ProgressiveMesh& pm,
                         const int32_t* coords, AttributeState& s, uint32_t c, uint32_t wedge,
                         const int32_t* fresh);
bool decode_corner_wedge(RangeState& rc, AttributeModels& m, const ProgressiveMesh& pm,
                         const int32_t* coords, AttributeState& s, uint32_t c);
// A split's wedges (spec/format.md section 14.5): `corners` from split_corners(), all pending; u
// the new vertex. The writer gives per corner the wedge id it gets (existing, or s.wedge_count + k
// for the k-th new one, numbered in order) and, at a new wedge's first corner, its values.
void encode_split_wedges(RangeEncoder& rc, AttributeModels& m, const ProgressiveMesh& pm,
                         const int32_t* coords, AttributeState& s,
                         std::span<const uint32_t> corners, uint32_t u, const uint32_t* wedges,
                         const int32_t* const* fresh);
// False on a malformed stream or reference (s then holds part of the split's assignments).
bool decode_split_wedges(RangeState& rc, AttributeModels& m, const ProgressiveMesh& pm,
                         const int32_t* coords, AttributeState& s,
                         std::span<const uint32_t> corners, uint32_t u);
// A face's material (its entry pending in s.face_material), when there are two or more.
void encode_face_material(RangeEncoder& rc, AttributeModels& m, const ProgressiveMesh& pm,
                          AttributeState& s, uint32_t f, uint32_t material);
bool decode_face_material(RangeState& rc, AttributeModels& m, const ProgressiveMesh& pm,
                          AttributeState& s, uint32_t f);

}  // namespace pmz
