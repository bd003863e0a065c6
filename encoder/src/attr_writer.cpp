// SPDX-License-Identifier: MIT
#include "attr_writer.hpp"

#include <algorithm>
#include <cmath>

namespace pmz {

namespace {

std::array<uint32_t, 3> canonical_face(const uint32_t* t) {
  if (t[1] < t[0] && t[1] < t[2]) return {t[1], t[2], t[0]};
  if (t[2] < t[0] && t[2] < t[1]) return {t[2], t[0], t[1]};
  return {t[0], t[1], t[2]};
}

}  // namespace

bool AttributeWriter::init(const CollapseSequence& seq, size_t used, const WriteOptions& opt,
                           const std::vector<uint32_t>& input_of, std::string& error) {
  const IndexedMesh& mesh = seq.mesh;
  const MeshAttributes& in = mesh.attributes;
  mesh_ = &mesh;
  input_of_ = &input_of;
  if (opt.texcoord_bits > kMaxAttributeBits || opt.color_bits > 16 || opt.normal_bits == 1 ||
      opt.normal_bits > 16)
    return error =
               "attribute bits out of range (texcoords 0..24, normals 0 or 2..16, colours "
               "0..16)",
           false;
  AttributeHeader h;
  h.texcoord_sets = uint32_t(in.texcoords.size());
  if (h.texcoord_sets > kMaxTexcoordSets)
    return error = "more than 8 texture coordinate sets", false;
  if (in.materials.size() > kMaxMaterials) return error = "more than 65536 materials", false;
  h.texcoord_bits = opt.texcoord_bits;
  h.normals = !in.normals.empty();
  h.normal_bits = opt.normal_bits;
  h.color_components = in.colors.empty() ? 0 : in.color_components;
  h.color_bits = opt.color_bits;
  const uint32_t wedges = in.wedge_count();
  if (h.has_wedges() && in.corner_wedges.size() != mesh.indices.size())
    return error = "attributes without a wedge per corner", false;
  for (uint32_t t = 0; t < h.texcoord_sets; ++t) {
    if (in.texcoords[t].size() != size_t(wedges) * 2) return error = "texcoord count", false;
    for (int k = 0; k < 2; ++k) {
      h.texcoord_min[t][k] = INFINITY;
      h.texcoord_max[t][k] = -INFINITY;
    }
    for (uint32_t w = 0; w < wedges; ++w)
      for (int k = 0; k < 2; ++k) {
        const float x = in.texcoords[t][size_t(w) * 2 + k];
        if (!std::isfinite(x)) return error = "non-finite texture coordinate", false;
        h.texcoord_min[t][k] = std::min(h.texcoord_min[t][k], x);
        h.texcoord_max[t][k] = std::max(h.texcoord_max[t][k], x);
      }
    if (wedges == 0)
      for (int k = 0; k < 2; ++k) h.texcoord_min[t][k] = h.texcoord_max[t][k] = 0;
  }
  for (const Material& m : in.materials) {
    FileMaterial fm;
    fm.name = m.name;
    fm.base_color_texture = m.base_color_texture;
    fm.normal_texture = m.normal_texture;
    std::copy(m.base_color, m.base_color + 4, fm.base_color);
    for (const std::string* s : {&fm.name, &fm.base_color_texture, &fm.normal_texture})
      if (s->size() > kMaxMaterialString) return error = "material string over 4096 bytes", false;
    h.materials.push_back(std::move(fm));
  }
  if (in.material_library.size() > kMaxMaterialString)
    return error = "material library name over 4096 bytes", false;
  h.material_library = in.material_library;
  if (!in.face_materials.empty() && in.face_materials.size() != mesh.face_count())
    return error = "face material count", false;
  for (uint32_t m : in.face_materials)
    if (m >= in.materials.size()) return error = "face material beyond the material table", false;
  state_.init(h);
  // Quantized values per input wedge.
  AttributeQuantizer q;
  q.init(h);
  const uint32_t stride = state_.stride;
  values_.assign(size_t(wedges) * stride, 0);
  for (uint32_t w = 0; w < wedges && h.has_wedges(); ++w) {
    int32_t* v = &values_[size_t(w) * stride];
    for (uint32_t t = 0; t < h.texcoord_sets; ++t)
      for (int k = 0; k < 2; ++k) *v++ = q.texcoord[t].quantize(in.texcoords[t][w * 2 + k], k);
    if (h.normals) {
      q.quantize_normal(&in.normals[size_t(w) * 3], v);
      v += h.normal_components();
    }
    for (uint32_t k = 0; k < h.color_components; ++k)
      *v++ = q.quantize_color(in.colors[size_t(w) * h.color_components + k]);
  }
  decoded_wedge_.assign(wedges, kNoCorner);
  // Fine to coarse with the collapse rule: u's fan before each collapse, and the base's wedges.
  CollapseReplay replay(mesh);
  fans_.resize(used);
  for (size_t i = 0; i < used; ++i)
    if (!replay.collapse(seq.collapses[i], &fans_[i]))
      return error = "collapse " + std::to_string(i) + " does not replay on the attributes", false;
  final_wedge_ = std::move(replay.corner_wedge);
  final_corner_ = std::move(replay.corner_vertex);
  for (uint32_t f = 0; f < replay.face_alive.size(); ++f)
    if (replay.face_alive[f]) final_face_[canonical_face(&final_corner_[f * 3])] = f;
  rc_ = std::make_unique<RangeEncoder>(chunk_);
  return true;
}

uint32_t AttributeWriter::decoded_id(uint32_t input_wedge, uint32_t& fresh_count,
                                     const int32_t*& fresh) {
  uint32_t& d = decoded_wedge_[input_wedge];
  fresh = nullptr;
  if (d == kNoCorner) {  // first corner of a new wedge: numbered in coding order
    d = state_.wedge_count + fresh_count++;
    fresh = &values_[size_t(input_wedge) * state_.stride];
  }
  return d;
}

void AttributeWriter::encode_base(const ProgressiveMesh& pm, const int32_t* coords,
                                  std::vector<uint8_t>& payload) {
  const AttributeHeader& h = state_.head;
  const uint32_t fn = pm.face_count();
  if (h.has_wedges()) state_.corner_wedge.assign(size_t(fn) * 3, kPendingWedge);
  if (!h.materials.empty()) state_.face_material.assign(fn, kPendingWedge);
  const std::vector<uint32_t>& input_of = *input_of_;
  const std::vector<uint32_t>& face_materials = mesh_->attributes.face_materials;
  for (uint32_t f = 0; f < fn; ++f) {
    const uint32_t t[3] = {input_of[pm.corner_vertex[f * 3]], input_of[pm.corner_vertex[f * 3 + 1]],
                           input_of[pm.corner_vertex[f * 3 + 2]]};
    const uint32_t slot = final_face_.at(canonical_face(t));
    if (h.materials.size() > 1)
      encode_face_material(*rc_, models_, pm, state_, f, face_materials[slot]);
    else if (!h.materials.empty())
      state_.face_material[f] = 0;
    if (!h.has_wedges()) continue;
    for (uint32_t k = 0; k < 3; ++k) {
      uint32_t j = 0;
      while (final_corner_[slot * 3 + j] != t[k]) ++j;
      uint32_t fresh_count = 0;
      const int32_t* fresh;
      const uint32_t d = decoded_id(final_wedge_[slot * 3 + j], fresh_count, fresh);
      encode_corner_wedge(*rc_, models_, pm, coords, state_, f * 3 + k, d, fresh);
    }
  }
  state_.head.base_wedges = state_.wedge_count;
  finish_chunk(payload);
}

bool AttributeWriter::lookup(const ProgressiveMesh& pm, const CollapseFan& fan, uint32_t f,
                             uint32_t k, uint32_t& wedge, uint32_t& material) const {
  const std::vector<uint32_t>& input_of = *input_of_;
  const uint32_t t[3] = {input_of[pm.corner_vertex[f * 3]], input_of[pm.corner_vertex[f * 3 + 1]],
                         input_of[pm.corner_vertex[f * 3 + 2]]};
  const auto want = canonical_face(t);
  for (size_t i = 0; i < fan.faces.size(); ++i) {
    if (canonical_face(&fan.corners[i * 3]) != want) continue;
    uint32_t j = 0;
    while (fan.corners[i * 3 + j] != t[k]) ++j;
    wedge = fan.wedges.empty() ? 0 : fan.wedges[i * 3 + j];
    material = mesh_->attributes.face_materials.empty()
                   ? 0
                   : mesh_->attributes.face_materials[fan.faces[i]];
    return true;
  }
  return false;
}

void AttributeWriter::encode_split(const ProgressiveMesh& pm, const int32_t* coords,
                                   uint32_t collapse, bool has_l, bool has_r) {
  const AttributeHeader& h = state_.head;
  const CollapseFan& fan = fans_[collapse];
  const uint32_t fn = pm.face_count(), f0 = fn - (has_l ? 1u : 0u) - (has_r ? 1u : 0u);
  uint32_t wedge = 0, material = 0;
  if (!h.materials.empty()) {
    state_.face_material.resize(fn, kPendingWedge);
    for (uint32_t f = f0; f < fn; ++f) {
      lookup(pm, fan, f, 0, wedge, material);
      if (h.materials.size() > 1)
        encode_face_material(*rc_, models_, pm, state_, f, material);
      else
        state_.face_material[f] = 0;
    }
  }
  if (!h.has_wedges()) return;
  split_corners(pm, has_l, has_r, corners_);
  state_.corner_wedge.resize(size_t(fn) * 3, kPendingWedge);
  for (uint32_t c : corners_) state_.corner_wedge[c] = kPendingWedge;
  wedges_.clear();
  fresh_.clear();
  uint32_t fresh_count = 0;
  for (uint32_t c : corners_) {
    lookup(pm, fan, c / 3, c % 3, wedge, material);
    const int32_t* fresh;
    wedges_.push_back(decoded_id(wedge, fresh_count, fresh));
    fresh_.push_back(fresh);
  }
  encode_split_wedges(*rc_, models_, pm, coords, state_, corners_, pm.vertex_count() - 1,
                      wedges_.data(), fresh_.data());
}

void AttributeWriter::finish_chunk(std::vector<uint8_t>& payload) {
  rc_->finish();
  payload = chunk_;
  chunk_.clear();
  rc_ = std::make_unique<RangeEncoder>(chunk_);
}

bool AttributeWriter::check_full(const ProgressiveMesh& pm, std::string& error) const {
  const IndexedMesh& mesh = *mesh_;
  const MeshAttributes& in = mesh.attributes;
  std::map<Face, uint32_t> input_face;
  for (uint32_t f = 0; f < mesh.face_count(); ++f)
    input_face[canonical_face(&mesh.indices[f * 3])] = f;
  std::vector<uint32_t> input_wedge(state_.wedge_count, kNoCorner);
  for (uint32_t w = 0; w < decoded_wedge_.size(); ++w)
    if (decoded_wedge_[w] != kNoCorner) input_wedge[decoded_wedge_[w]] = w;
  const std::vector<uint32_t>& input_of = *input_of_;
  for (uint32_t f = 0; f < pm.face_count(); ++f) {
    const uint32_t t[3] = {input_of[pm.corner_vertex[f * 3]], input_of[pm.corner_vertex[f * 3 + 1]],
                           input_of[pm.corner_vertex[f * 3 + 2]]};
    const uint32_t slot = input_face.at(canonical_face(t));
    if (!in.face_materials.empty() && state_.face_material[f] != in.face_materials[slot])
      return error = "internal: decoded face materials differ from the input", false;
    if (!state_.head.has_wedges()) continue;
    for (uint32_t k = 0; k < 3; ++k) {
      uint32_t j = 0;
      while (mesh.indices[slot * 3 + j] != t[k]) ++j;
      if (input_wedge[state_.corner_wedge[f * 3 + k]] != in.corner_wedges[slot * 3 + j])
        return error = "internal: decoded corner wedges differ from the input", false;
    }
  }
  return true;
}

}  // namespace pmz
