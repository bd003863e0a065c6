// The render thread's copy of the decoder's mesh, plus what the GPU needs beyond it:
// geomorph start positions/times and smooth vertex normals. sync() folds in only what the
// decoder reports as changed and records which ranges the GPU buffers must re-upload.
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

struct MeshMirror {
  uint32_t vertex_count = 0, face_count = 0;
  std::vector<float> positions;     // xyz per vertex
  std::vector<float> morph_from;    // xyz: where the vertex's geomorph starts
  std::vector<float> morph_start;   // seconds: when it starts (far past = not morphing)
  std::vector<float> normals;       // xyz: sum of the area-weighted normals of its faces
  std::vector<uint32_t> indices;    // three per face
  std::vector<float> face_normals;  // xyz per face: exactly what was added to its vertices

  // Upload work since the renderer last took it: everything, or vertices [vertex_begin,
  // vertex_count) (positions and morph data), vertices whose normal changed, rewritten faces.
  bool dirty_all = false;
  uint32_t dirty_vertex_begin = UINT32_MAX;
  DirtyBits dirty_normals;  // by vertex
  DirtyBits dirty_faces;    // by face
  double last_morph_start = -1e30;

  // Call with the decoder locked. Consumes and clears the decoder's changes. `now` is the
  // geomorph clock; new vertices morph from their parent's current on-screen position.
  void sync(pmz::Decoder& decoder, float now, float morph_seconds);
  void clear_dirty();

 private:
  DirtyBits seen_faces_;  // dedups the decoder's modified-face list
  std::vector<uint32_t> modified_;
};

}  // namespace pmzview
