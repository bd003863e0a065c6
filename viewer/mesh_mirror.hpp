// The render thread's copy of the decoder's mesh, plus what the GPU needs beyond it:
// geomorph start positions/times and smooth vertex normals. sync() folds in only what the
// decoder reports as changed and records which ranges the GPU buffers must re-upload.
#pragma once
#include <pmz/decoder.hpp>

#include <cstdint>
#include <vector>

namespace pmzview {

struct MeshMirror {
  uint32_t vertex_count = 0, face_count = 0;
  std::vector<float> positions;    // xyz per vertex
  std::vector<float> morph_from;   // xyz: where the vertex's geomorph starts
  std::vector<float> morph_start;  // seconds: when it starts (far past = not morphing)
  std::vector<float> normals;      // xyz: sum of the area-weighted normals of its faces
  std::vector<uint32_t> indices;   // three per face
  std::vector<float> face_normals; // xyz per face: exactly what was added to its vertices

  // Upload work since the last take: everything, or vertices [vertex_begin, vertex_count)
  // (positions and morph data), vertices whose normal changed, and rewritten faces.
  bool dirty_all = false;
  uint32_t dirty_vertex_begin = UINT32_MAX;
  std::vector<uint32_t> dirty_normals;  // vertex ids, may repeat
  std::vector<uint32_t> dirty_faces;    // face ids below face_count, may repeat
  double last_morph_start = -1e30;

  // Call with the decoder locked. Consumes and clears the decoder's changes. `now` is the
  // geomorph clock; new vertices morph from their parent's current on-screen position.
  void sync(pmz::Decoder& decoder, float now, float morph_seconds);
  void clear_dirty();
};

// Sorted runs [begin, end) covering ids; ids at most `gap` apart share a run, so a scattered
// set becomes a few buffer uploads instead of one per element. Sorts/uniques ids in place.
struct Run {
  uint32_t begin, end;
};
void coalesce(std::vector<uint32_t>& ids, uint32_t gap, std::vector<Run>& runs);

}  // namespace pmzview
