// glTF 2.0 input (.gltf, .glb) and .glb output for mesh_io.cpp, through Debian's tinygltf.
#pragma once
#include <string>
#include <string_view>

#include "pmz/mesh.hpp"

namespace pmz {

// The triangles of every mesh the default scene draws (node transforms applied; all meshes
// when the file has no scene), with POSITION, NORMAL, TEXCOORD_n, COLOR_0 and the material
// per face (one id per glTF material). Vertices with equal positions are welded.
bool read_gltf(const std::string& path, std::string_view data, PolygonSoup& out,
               std::string& error);

// The mesh as a binary glTF: one vertex per wedge (one per vertex without attributes), one
// primitive per material. Normals are written normalised and colours clamped to [0, 1], as
// glTF requires; texture file names become image URIs.
// Merges vertices with bitwise-equal positions (mesh_io.cpp); attribute indices are kept.
void weld_vertices(PolygonSoup& soup);

bool write_glb(const IndexedMesh& mesh, std::string& bytes, std::string& error);

}  // namespace pmz
