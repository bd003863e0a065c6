// SPDX-License-Identifier: MIT
#include "mesh_mirror.hpp"

#include <algorithm>
#include <cstring>

namespace pmzview {
namespace {

constexpr float kStatic = -1e30f;  // morph start far in the past: the vertex sits at its position

// Smoothstep of the geomorph's progress; the vertex shader computes the same.
float morph_weight(float now, float start, float seconds) {
  if (seconds <= 0) return 1;
  float t = std::clamp((now - start) / seconds, 0.0f, 1.0f);
  return t * t * (3 - 2 * t);
}

}  // namespace

void MeshMirror::clear_dirty() {
  dirty_all = false;
  dirty_vertex_begin = UINT32_MAX;
  dirty_wedge_begin = UINT32_MAX;
  dirty_normals.clear();
  dirty_faces.clear();
}

void DirtyBits::take_runs(uint32_t count, uint32_t gap, std::vector<Run>& runs) {
  runs.clear();
  const size_t end_word = std::min(words.size(), (size_t(count) + 63) / 64);
  for (size_t w = 0; w < end_word; ++w) {
    for (uint64_t bits = words[w]; bits; bits &= bits - 1) {
      uint32_t id = uint32_t(w * 64 + size_t(__builtin_ctzll(bits)));
      if (id >= count) break;
      if (!runs.empty() && id <= runs.back().end + gap)
        runs.back().end = id + 1;
      else
        runs.push_back({id, id + 1});
    }
  }
  clear();
}

MeshFrame frame_of(const pmz::Decoder& decoder) {
  MeshFrame f;
  const pmz::MeshChanges& changes = decoder.changes();
  const pmz::StreamInfo& info = decoder.info();
  f.vertex_count = decoder.vertex_count();
  f.face_count = decoder.face_count();
  f.positions = decoder.positions();
  f.indices = decoder.indices();
  f.split_parents = decoder.split_parents();
  f.full_vertices = info.full_vertices;
  f.full_faces = info.full_faces;
  f.all = changes.all;
  f.vertex_begin = changes.vertex_begin;
  f.face_begin = changes.face_begin;
  f.modified_faces = changes.modified_faces.data();
  f.modified_face_count = changes.modified_faces.size();
  f.wedge_begin = changes.wedge_begin;
  f.wedge_count = decoder.wedge_count();
  if (f.wedge_count) {
    f.wedge_vertices = decoder.wedge_vertices();
    f.wedge_indices = decoder.wedge_indices();
    f.texcoords = decoder.texcoord_set_count() ? decoder.texcoords(0) : nullptr;
    f.normals = decoder.normals();
    f.colors = decoder.colors();
    f.color_components = decoder.color_components();
    f.face_materials = decoder.face_materials();
  }
  return f;
}

void MeshMirror::sync(pmz::Decoder& decoder, float now, float morph_seconds) {
  sync(frame_of(decoder), now, morph_seconds);
  decoder.clear_changes();
}

void MeshMirror::copy_wedges(const MeshFrame& frame, uint32_t begin, uint32_t end) {
  const uint32_t nv = frame.vertex_count;
  for (uint32_t w = begin; w < end; ++w) {
    const uint32_t v = frame.wedge_vertices[w];
    wedge_vertices[w] = v < nv ? v : 0;  // never index past the vertex buffers
  }
  if (has_texcoords)
    std::memcpy(&texcoords[2 * size_t(begin)], &frame.texcoords[2 * size_t(begin)],
                sizeof(float) * 2 * size_t(end - begin));
  if (has_normals)
    std::memcpy(&wedge_normals[3 * size_t(begin)], &frame.normals[3 * size_t(begin)],
                sizeof(float) * 3 * size_t(end - begin));
  if (has_colors) {
    const uint32_t k = frame.color_components;
    for (uint32_t w = begin; w < end; ++w)
      for (uint32_t i = 0; i < 4; ++i)
        colors[4 * size_t(w) + i] = i < k ? frame.colors[k * size_t(w) + i] : 1.0f;
  }
}

void MeshMirror::sync(const MeshFrame& frame, float now, float morph_seconds) {
  const uint32_t nv = frame.vertex_count, nf = frame.face_count;
  const float* src_positions = frame.positions;
  const uint32_t* src_indices = frame.indices;
  const uint32_t* parents = frame.split_parents;
  if (nf == 0 || !src_positions || !src_indices) {
    vertex_count = face_count = wedge_count = 0;
    return;
  }
  const bool frame_wedges = frame.wedge_count > 0 && frame.wedge_vertices && frame.wedge_indices;
  const uint32_t nw = frame_wedges ? frame.wedge_count : 0;

  auto face_normal = [&](uint32_t f, float out[3]) {
    const uint32_t* t = &indices[3 * size_t(f)];
    const float* a = &positions[3 * size_t(t[0])];
    const float* b = &positions[3 * size_t(t[1])];
    const float* c = &positions[3 * size_t(t[2])];
    float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    // Unnormalized: the length is twice the area, which weights the vertex sums.
    out[0] = e1[1] * e2[2] - e1[2] * e2[1];
    out[1] = e1[2] * e2[0] - e1[0] * e2[2];
    out[2] = e1[0] * e2[1] - e1[1] * e2[0];
  };
  auto add_face = [&](uint32_t f, float sign) {
    const float* n = &face_normals[3 * size_t(f)];
    for (int k = 0; k < 3; ++k) {
      uint32_t v = indices[3 * size_t(f) + k];
      for (int i = 0; i < 3; ++i) normals[3 * size_t(v) + i] += sign * n[i];
      dirty_normals.mark(v);
    }
  };
  auto copy_face = [&](uint32_t f) {
    const uint32_t* t = &src_indices[3 * size_t(f)];
    bool valid = t[0] < nv && t[1] < nv && t[2] < nv;  // never index past the buffers
    for (int k = 0; k < 3; ++k) indices[3 * size_t(f) + k] = valid ? t[k] : 0;
    face_normal(f, &face_normals[3 * size_t(f)]);
    if (has_wedges) {
      const uint32_t* w = &frame.wedge_indices[3 * size_t(f)];
      valid = w[0] < nw && w[1] < nw && w[2] < nw;
      for (int k = 0; k < 3; ++k) wedge_indices[3 * size_t(f) + k] = valid ? w[k] : 0;
    }
    if (has_face_materials) face_materials[f] = frame.face_materials[f];
  };

  if (frame.all || vertex_count == 0 || has_wedges != frame_wedges) {
    // Room for the finest level up front: no reallocation (and copy) while refining.
    const size_t full_vertices =
        std::max<size_t>(nv, size_t(std::min<uint64_t>(frame.full_vertices, 1u << 27)));
    const size_t full_faces =
        std::max<size_t>(nf, size_t(std::min<uint64_t>(frame.full_faces, 1u << 28)));
    const size_t full_wedges =
        std::max<size_t>(nw, size_t(std::min<uint64_t>(frame.full_wedges, 1u << 28)));
    for (auto* v : {&positions, &morph_from, &normals}) v->reserve(3 * full_vertices);
    morph_start.reserve(full_vertices);
    indices.reserve(3 * full_faces);
    face_normals.reserve(3 * full_faces);
    has_wedges = frame_wedges;
    has_texcoords = has_wedges && frame.texcoords;
    has_normals = has_wedges && frame.normals;
    has_colors =
        has_wedges && frame.colors && (frame.color_components == 3 || frame.color_components == 4);
    has_face_materials = frame.face_materials != nullptr;
    wedge_count = nw;
    wedge_vertices.reserve(full_wedges);
    wedge_vertices.resize(nw);
    if (has_wedges) wedge_indices.reserve(3 * full_faces);
    wedge_indices.resize(has_wedges ? 3 * size_t(nf) : 0);
    if (has_face_materials) face_materials.reserve(full_faces);
    face_materials.resize(has_face_materials ? nf : 0);
    if (has_texcoords) texcoords.reserve(2 * full_wedges);
    texcoords.resize(has_texcoords ? 2 * size_t(nw) : 0);
    if (has_normals) wedge_normals.reserve(3 * full_wedges);
    wedge_normals.resize(has_normals ? 3 * size_t(nw) : 0);
    if (has_colors) colors.reserve(4 * full_wedges);
    colors.resize(has_colors ? 4 * size_t(nw) : 0);
    copy_wedges(frame, 0, nw);
    positions.assign(src_positions, src_positions + 3 * size_t(nv));
    morph_from = positions;
    morph_start.assign(nv, kStatic);
    normals.assign(3 * size_t(nv), 0.0f);
    indices.resize(3 * size_t(nf));
    face_normals.resize(3 * size_t(nf));
    vertex_count = nv;
    face_count = nf;
    for (uint32_t f = 0; f < nf; ++f) copy_face(f);
    for (uint32_t f = 0; f < nf; ++f) add_face(f, 1);
    clear_dirty();
    dirty_all = true;
    return;
  }

  const uint32_t vertex_begin = std::min({frame.vertex_begin, vertex_count, nv});
  const uint32_t face_begin = std::min({frame.face_begin, face_count, nf});
  const uint32_t old_faces = face_count;
  // Rewritten faces below face_begin, each once: a repeat would subtract its normal twice.
  std::vector<uint32_t>& modified = modified_;
  modified.clear();
  for (size_t i = 0; i < frame.modified_face_count; ++i) {
    const uint32_t f = frame.modified_faces[i];
    if (f >= face_begin ||
        (f >> 6 < seen_faces_.words.size() && (seen_faces_.words[f >> 6] >> (f & 63) & 1)))
      continue;
    seen_faces_.mark(f);
    modified.push_back(f);
  }
  for (uint32_t f : modified) seen_faces_.words[f >> 6] = 0;

  // 1. Take the old faces' contributions out of their old vertices.
  for (uint32_t f : modified) add_face(f, -1);
  for (uint32_t f = face_begin; f < old_faces; ++f) add_face(f, -1);

  // 2. New and rewritten vertices. All their faces are among the changed ones (a vertex
  // split only touches faces it reports), so their normal sums restart from zero.
  positions.resize(3 * size_t(nv));
  morph_from.resize(3 * size_t(nv));
  morph_start.resize(nv);
  normals.resize(3 * size_t(nv));
  std::memcpy(&positions[3 * size_t(vertex_begin)], &src_positions[3 * size_t(vertex_begin)],
              sizeof(float) * 3 * size_t(nv - vertex_begin));
  for (uint32_t v = vertex_begin; v < nv; ++v) {
    uint32_t parent = parents ? parents[v] : UINT32_MAX;
    float* from = &morph_from[3 * size_t(v)];
    if (parent < v) {
      // Start where the parent is drawn right now, even if it is still morphing itself.
      float w = morph_weight(now, morph_start[parent], morph_seconds);
      for (int i = 0; i < 3; ++i)
        from[i] = morph_from[3 * size_t(parent) + i] +
                  w * (positions[3 * size_t(parent) + i] - morph_from[3 * size_t(parent) + i]);
      morph_start[v] = now;
      last_morph_start = now;
    } else {
      std::memcpy(from, &positions[3 * size_t(v)], sizeof(float) * 3);
      morph_start[v] = kStatic;
    }
    for (int i = 0; i < 3; ++i) normals[3 * size_t(v) + i] = 0;
  }
  vertex_count = nv;
  dirty_vertex_begin = std::min(dirty_vertex_begin, vertex_begin);

  // 3. New and rewritten wedges: their values are copied as they are.
  if (has_wedges) {
    const uint32_t wedge_begin = std::min({frame.wedge_begin, wedge_count, nw});
    wedge_vertices.resize(nw);
    texcoords.resize(has_texcoords ? 2 * size_t(nw) : 0);
    wedge_normals.resize(has_normals ? 3 * size_t(nw) : 0);
    colors.resize(has_colors ? 4 * size_t(nw) : 0);
    copy_wedges(frame, wedge_begin, nw);
    wedge_count = nw;
    dirty_wedge_begin = std::min(dirty_wedge_begin, wedge_begin);
  }

  // 4. The new faces' contributions.
  indices.resize(3 * size_t(nf));
  face_normals.resize(3 * size_t(nf));
  wedge_indices.resize(has_wedges ? 3 * size_t(nf) : 0);
  face_materials.resize(has_face_materials ? nf : 0);
  face_count = nf;
  for (uint32_t f : modified) {
    if (f >= nf) continue;
    copy_face(f);
    add_face(f, 1);
    dirty_faces.mark(f);
  }
  for (uint32_t f = face_begin; f < nf; ++f) {
    copy_face(f);
    add_face(f, 1);
    dirty_faces.mark(f);
  }
}

}  // namespace pmzview
