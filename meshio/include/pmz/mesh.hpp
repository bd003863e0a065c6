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

// Faces exactly as a file states them (any corner count, repeated corners allowed), with
// indices already checked to be in range and coordinates checked to be finite.
struct PolygonSoup {
  std::vector<float> positions;        // xyz per vertex
  std::vector<uint32_t> corners;       // vertex ids of all faces, concatenated
  std::vector<uint32_t> face_offsets;  // face f: corners[face_offsets[f] .. face_offsets[f+1])
  uint32_t vertex_count() const { return uint32_t(positions.size() / 3); }
  uint32_t face_count() const {
    return face_offsets.empty() ? 0 : uint32_t(face_offsets.size() - 1);
  }
};

// What repair_mesh changed; everything that is not plain triangulation is reported.
struct MeshRepairStats {
  uint64_t input_faces = 0;               // faces in the file (polygons count once)
  uint64_t polygons_triangulated = 0;     // input faces with more than three corners
  uint64_t degenerate_faces_dropped = 0;  // fewer than three distinct corners: not representable
  uint64_t repeated_corners_removed = 0;  // faces that kept >= 3 distinct corners after cleaning
  uint64_t duplicate_faces = 0;           // same three vertices as an earlier triangle (kept)
  uint64_t nonmanifold_edges = 0;         // edges with 3+ faces or two faces in the same direction
  uint64_t nonmanifold_vertices = 0;      // input vertices split into several copies
  uint64_t vertices_added = 0;            // copies appended after the input vertices
  uint64_t isolated_vertices = 0;         // vertices no face uses (kept)
  // One line listing every repair (empty when the input needed none). Tools print it on stderr.
  std::string summary() const;
};

// Triangulates (ear clipping, fan beyond 64 corners) and makes the soup a manifold-with-boundary
// triangle mesh without losing a face: every undirected edge ends up with at most two faces of
// opposite orientation and every vertex with one fan of faces. Faces keep input order (a polygon
// of n corners becomes n-2 consecutive triangles) and their winding; vertices keep their input
// ids, and the copies made to cut non-manifold edges and split non-manifold vertices are
// appended after them. Only faces with fewer than three distinct corners are dropped (counted).
void repair_mesh(const PolygonSoup& soup, IndexedMesh& out, MeshRepairStats& stats);

// Parses OBJ/OFF/PLY (ascii, binary)/STL (ascii, binary) by extension into a soup. Returns false
// with a one-line message naming the problem: missing/unreadable/empty file, unknown format,
// malformed or truncated data, NaN/Inf coordinates (naming the vertex), out-of-range indices
// (naming the face), no faces. STL corners with bitwise-equal positions are welded.
bool read_polygon_soup(const std::string& path, PolygonSoup& out, std::string& error);

// read_polygon_soup + repair_mesh. This overload returns the statistics for the caller to print.
bool read_mesh(const std::string& path, IndexedMesh& out, MeshRepairStats& stats,
               std::string& error);
// Same, printing the repair summary (if any) on stderr so nothing is changed silently.
bool read_mesh(const std::string& path, IndexedMesh& out, std::string& error);

// Writes by extension (.obj .off .ply .stl) exactly what is in the mesh (no OpenMesh, so any
// IndexedMesh round-trips through OBJ/OFF/PLY; STL has no shared vertices, so it cannot keep
// isolated vertices or split copies apart). Atomic: a temporary file beside the target, renamed
// when complete; on any error (missing directory, disk full) the temporary is removed.
bool write_mesh(const std::string& path, const IndexedMesh& mesh, std::string& error);

}  // namespace pmz
