// SPDX-License-Identifier: MIT
// The render thread's copy of the decoder's mesh, plus what the GPU needs beyond it:
// geomorph start positions/times and smooth vertex normals. sync() folds in only what the
// decoder reports as changed and records which ranges the GPU buffers must re-upload.
// With attribute wedges the render vertex is the wedge: per-vertex data (positions, geomorph,
// smooth normals) stays per position vertex and each wedge names its vertex, so a wedge's
// values are uploaded once when it appears and never because its vertex's normal changed.
#pragma once
#include <algorithm>
#include <cstdint>
#include <pmz/decoder.hpp>
#include <vector>

namespace pmzview {

// A run [begin, end) of elements to upload.
struct Run {
  uint32_t begin, end;
};

// One bit per element: marking is O(1) and idempotent, and scanning yields sorted runs
// without sorting.
struct DirtyBits {
  std::vector<uint64_t> words;
  void mark(uint32_t i) {
    size_t w = i >> 6;
    if (w >= words.size()) words.resize(std::max(w + 1, 2 * words.size()), 0);
    words[w] |= uint64_t(1) << (i & 63);
  }
  // Sorted runs of the set bits below `count`; bits at most `gap` apart share a run, so a
  // scattered set becomes a few uploads instead of one per element. Clears every bit.
  void take_runs(uint32_t count, uint32_t gap, std::vector<Run>& runs);
  void clear() { std::fill(words.begin(), words.end(), 0); }
};

// The current mesh and what changed since the last sync, as pmz::Decoder reports it (or a
// mesh file shown as it is: everything, once). Pointers stay owned by the caller.
struct MeshFrame {
  uint32_t vertex_count = 0, face_count = 0;
  const float* positions = nullptr;         // xyz per vertex
  const uint32_t* indices = nullptr;        // three position vertices per face
  const uint32_t* split_parents = nullptr;  // per vertex (UINT32_MAX: none), or null
  uint64_t full_vertices = 0, full_faces = 0, full_wedges = 0;  // room to reserve up front

  // Change report (pmz::MeshChanges): everything, or vertices [vertex_begin, vertex_count),
  // wedges [wedge_begin, wedge_count) and faces [face_begin, face_count) new or rewritten,
  // plus rewritten faces below face_begin (may repeat).
  bool all = true;
  uint32_t vertex_begin = 0, face_begin = 0, wedge_begin = 0;
  const uint32_t* modified_faces = nullptr;
  size_t modified_face_count = 0;

  // Attribute wedges; wedge_count == 0: none (the render vertex is the position vertex).
  uint32_t wedge_count = 0;
  const uint32_t* wedge_vertices = nullptr;  // position vertex per wedge
  const uint32_t* wedge_indices = nullptr;   // three wedges per face
  const float* texcoords = nullptr;          // set 0: u, v per wedge, or null
  const float* normals = nullptr;            // xyz per wedge, or null
  const float* colors = nullptr;             // color_components (3 or 4) per wedge, or null
  uint32_t color_components = 0;
  const uint32_t* face_materials = nullptr;  // material id per face, or null
};

struct MeshMirror {
  uint32_t vertex_count = 0, face_count = 0;
  std::vector<float> positions;     // xyz per vertex
  std::vector<float> morph_from;    // xyz: where the vertex's geomorph starts
  std::vector<float> morph_start;   // seconds: when it starts (far past = not morphing)
  std::vector<float> normals;       // xyz: sum of the area-weighted normals of its faces
  std::vector<uint32_t> indices;    // three per face
  std::vector<float> face_normals;  // xyz per face: exactly what was added to its vertices

  // Attribute wedges (wedge_count > 0 or has_wedges): which attributes the stream has is
  // fixed by the first full sync.
  bool has_wedges = false, has_texcoords = false, has_normals = false, has_colors = false;
  bool has_face_materials = false;
  uint32_t wedge_count = 0;
  std::vector<uint32_t> wedge_vertices;  // position vertex per wedge
  std::vector<float> texcoords;          // u, v per wedge (set 0)
  std::vector<float> wedge_normals;      // decoded xyz per wedge
  std::vector<float> colors;             // rgba per wedge (alpha 1 for RGB)
  std::vector<uint32_t> wedge_indices;   // three per face
  std::vector<uint32_t> face_materials;  // per face

  // Upload work since the renderer last took it: everything, or vertices [vertex_begin,
  // vertex_count) (positions and morph data), wedges [wedge_begin, wedge_count), vertices
  // whose normal changed, rewritten faces (their indices, wedge indices and material).
  bool dirty_all = false;
  uint32_t dirty_vertex_begin = UINT32_MAX;
  uint32_t dirty_wedge_begin = UINT32_MAX;
  DirtyBits dirty_normals;  // by vertex
  DirtyBits dirty_faces;    // by face
  double last_morph_start = -1e30;

  // Call with the decoder locked. Consumes and clears the decoder's changes. `now` is the
  // geomorph clock; new vertices morph from their parent's current on-screen position.
  void sync(pmz::Decoder& decoder, float now, float morph_seconds);
  void sync(const MeshFrame& frame, float now, float morph_seconds);
  void clear_dirty();

 private:
  void copy_wedges(const MeshFrame& frame, uint32_t begin, uint32_t end);

  DirtyBits seen_faces_;  // dedups the decoder's modified-face list
  std::vector<uint32_t> modified_;
};

// The decoder's current mesh, change report and attribute wedges (texture coordinate set 0).
MeshFrame frame_of(const pmz::Decoder& decoder);

}  // namespace pmzview
