// SPDX-License-Identifier: MIT
// Plain indexed triangle mesh shared by the encoder's stages (flat arrays, no OpenMesh).
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace pmz {

// A corner without a value for an attribute (e.g. an OBJ face without `vt` in a file with
// texture coordinates) reads as zeros.
constexpr uint32_t kNoAttribute = 0xFFFFFFFFu;

// Material metadata as the file states it (OBJ's MTL, glTF materials): carried, not interpreted.
struct Material {
  std::string name;
  std::string base_color_texture;      // texture file name or URI (MTL map_Kd, glTF baseColor)
  std::string normal_texture;          // MTL norm / map_Bump, glTF normalTexture
  float base_color[4] = {1, 1, 1, 1};  // MTL Kd (+ d), glTF baseColorFactor
  bool operator==(const Material&) const = default;
};

// Per-corner attributes as wedges (Hoppe's progressive meshes): a wedge is one combination of
// attribute values at one position vertex; a vertex on a texture seam or normal crease has
// several wedges, and the corners around it each name theirs. Positions stay per vertex, so
// the geometry (IndexedMesh::positions / indices) is the same with or without attributes.
struct MeshAttributes {
  std::vector<uint32_t> corner_wedges;   // wedge per corner (3 per face), or empty
  std::vector<uint32_t> wedge_vertices;  // position vertex of each wedge
  // Per set (TEXCOORD_n): u, v per wedge, v up the image as in OBJ and PLY (glTF's v, which runs
  // down, is flipped on reading and on writing).
  std::vector<std::vector<float>> texcoords;
  std::vector<float> normals;            // xyz per wedge, or empty
  std::vector<float> colors;             // color_components per wedge (0..1), or empty
  uint32_t color_components = 0;         // 0, 3 (RGB) or 4 (RGBA)
  std::vector<uint32_t> face_materials;  // material id per face, or empty
  std::vector<Material> materials;
  std::string material_library;  // OBJ mtllib file name as written in the file
  uint32_t wedge_count() const { return uint32_t(wedge_vertices.size()); }
  bool has_wedges() const { return !texcoords.empty() || !normals.empty() || !colors.empty(); }
  bool empty() const { return !has_wedges() && face_materials.empty() && materials.empty(); }
  // "2 texture coordinate sets, normals, RGBA colours, 3 materials" (empty when none).
  std::string describe() const;
};

struct IndexedMesh {
  std::vector<float> positions;    // xyz per vertex
  std::vector<uint32_t> indices;   // three per counter-clockwise triangle
  MeshAttributes attributes = {};  // optional; the encoder uses positions and indices only
  uint32_t vertex_count() const { return uint32_t(positions.size() / 3); }
  uint32_t face_count() const { return uint32_t(indices.size() / 3); }
};

// Attributes as a file states them: each one a pool of values and, per corner, an index into
// it (OBJ indexes each attribute on its own; per-vertex values in PLY or glTF use the corner's
// vertex id) or kNoAttribute. Values are checked to be finite; indices to be in range.
struct SoupAttributes {
  std::vector<std::vector<float>> texcoords;  // per set: u, v per entry
  std::vector<std::vector<uint32_t>> corner_texcoords;
  std::vector<float> normals;  // xyz per entry
  std::vector<uint32_t> corner_normals;
  std::vector<float> colors;  // color_components per entry
  uint32_t color_components = 0;
  std::vector<uint32_t> corner_colors;
  std::vector<uint32_t> face_materials;  // per face, or empty
  std::vector<Material> materials;
  std::string material_library;
};

// Faces exactly as a file states them (any corner count, repeated corners allowed), with
// indices already checked to be in range and coordinates checked to be finite.
struct PolygonSoup {
  std::vector<float> positions;        // xyz per vertex
  std::vector<uint32_t> corners;       // vertex ids of all faces, concatenated
  std::vector<uint32_t> face_offsets;  // face f: corners[face_offsets[f] .. face_offsets[f+1])
  SoupAttributes attributes = {};
  uint64_t welded_vertices = 0;  // glTF / PLY vertices merged with an equal position (seams)
  uint32_t vertex_count() const { return uint32_t(positions.size() / 3); }
  uint32_t face_count() const {
    return face_offsets.empty() ? 0 : uint32_t(face_offsets.size() - 1);
  }
};

// What repair_mesh changed; everything that is not plain triangulation is reported.
struct MeshRepairStats {
  uint64_t input_faces = 0;               // faces in the file (polygons count once)
  uint64_t polygons_triangulated = 0;     // input faces with more than three corners
  uint64_t triangles_from_polygons = 0;   // the triangles those became
  uint64_t welded_vertices = 0;           // PolygonSoup::welded_vertices
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
// Attributes follow their corners: each output corner keeps its input corner's values, and the
// corners of one output vertex with equal values share a wedge.
void repair_mesh(const PolygonSoup& soup, IndexedMesh& out, MeshRepairStats& stats);
// The same, consuming the soup: its arrays are freed as soon as the repair no longer reads them
// and its positions become the mesh's, so the repair holds less at its peak. `soup` is left
// empty.
void repair_mesh(PolygonSoup&& soup, IndexedMesh& out, MeshRepairStats& stats);

// Parses OBJ/OFF (ascii, binary)/PLY (ascii, binary)/STL (ascii, binary)/glTF (.gltf, .glb) by
// extension into a soup. Returns false with a one-line message naming the problem:
// missing/unreadable/empty file, unknown format, malformed or truncated data, NaN/Inf
// coordinates or attributes (naming the vertex), out-of-range indices (naming the face), no
// faces. STL corners with bitwise-equal positions are welded, and so are glTF vertices and PLY
// vertices with attributes (their files split vertices at seams; pmz keeps seams as wedges).
// OBJ, OFF, PLY and STL files are parsed as they are read, a window of the file at a time
// (pmz/mesh_stream.hpp): reading holds the soup, not the file's bytes.
bool read_polygon_soup(const std::string& path, PolygonSoup& out, std::string& error);
// The same from bytes in memory; `path` names the format (extension) and the messages. Files a
// format refers to (OBJ's MTL, glTF's external buffers) are looked up beside `path`.
bool parse_polygon_soup(const std::string& path, std::string_view data, PolygonSoup& out,
                        std::string& error);

// read_polygon_soup + repair_mesh. This overload returns the statistics for the caller to print.
bool read_mesh(const std::string& path, IndexedMesh& out, MeshRepairStats& stats,
               std::string& error);
// Same, printing the repair summary (if any) on stderr so nothing is changed silently.
bool read_mesh(const std::string& path, IndexedMesh& out, std::string& error);

// Writes by extension (.obj .off .ply .stl .glb) exactly what is in the mesh (no OpenMesh, so
// any IndexedMesh round-trips through OBJ/OFF/PLY; STL has no shared vertices, so it cannot keep
// isolated vertices or split copies apart). Attributes: OBJ writes vt/vn per wedge, usemtl and
// an MTL beside it (colours per vertex: the first wedge's); PLY and .glb write one vertex per
// wedge (glTF: one primitive per material); OFF and STL have none. Atomic, as every pmz tool
// writes: a temporary file beside the target, renamed when complete (through a symlink: the
// link keeps pointing at the updated file; a device or FIFO is written directly; "-" is
// stdout); on any error (missing directory, disk full) the temporary is removed and the error
// reads "path: cannot write: reason".
bool write_mesh(const std::string& path, const IndexedMesh& mesh, std::string& error);

// Receives a writer's bytes in order, a buffer's worth at a time; false stops the writing.
using MeshSink = std::function<bool(const void* data, size_t size)>;
// The same bytes as write_mesh, in `format` (obj, off, ply, stl, glb), handed to `sink` instead
// of a file: for outputs that are not plain files (stdout, pipes, devices; the tools' safe
// output). OBJ materials get no MTL here; with `mtl_name` the OBJ names it in its mtllib line
// (the caller writes it, e.g. with write_material_library). `name` names the output in
// messages; a refused write gives "name: write failed" (the sink knows why).
bool write_mesh_to(const std::string& name, const std::string& format, const IndexedMesh& mesh,
                   const MeshSink& sink, std::string& error, const std::string& mtl_name = "");
// An MTL file of these materials (Kd, d, map_Kd, norm), atomic like write_mesh.
bool write_material_library(const std::string& path, const std::vector<Material>& materials,
                            std::string& error);
// The same bytes handed to `sink` (the tools' safe output); `name` names it in messages.
bool write_material_library_to(const std::string& name, const std::vector<Material>& materials,
                               const MeshSink& sink, std::string& error);

}  // namespace pmz
