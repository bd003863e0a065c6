// Plain indexed triangle mesh shared by the encoder's stages (flat arrays, no OpenMesh).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace pmz {

struct IndexedMesh {
  std::vector<float> positions;   // xyz per vertex
  std::vector<uint32_t> indices;  // three per counter-clockwise triangle
  uint32_t vertex_count() const { return uint32_t(positions.size() / 3); }
  uint32_t face_count() const { return uint32_t(indices.size() / 3); }
};

// Reads OBJ/OFF/PLY/STL through OpenMesh, triangulating polygons. Rejects (returns false with
// a one-line message naming the problem) empty files, unknown formats, NaN/Inf coordinates
// and out-of-range indices. Non-manifold input is repaired without losing a face (non-manifold
// vertices are split), documented in spec/algorithm.md.
bool read_mesh(const std::string& path, IndexedMesh& out, std::string& error);
// Writes by extension (.obj .off .ply .stl), atomically (temporary file + rename).
bool write_mesh(const std::string& path, const IndexedMesh& mesh, std::string& error);

}  // namespace pmz
