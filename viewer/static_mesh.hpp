// SPDX-License-Identifier: MIT
// A mesh file (OBJ, PLY, glTF, OFF, STL) shown as it is, through the same mirror and renderer
// as a stream: one frame that reports everything.
#pragma once
#include <pmz/mesh.hpp>
#include <string>
#include <vector>

#include "materials.hpp"
#include "mesh_mirror.hpp"

namespace pmzview {

// True when SOURCE names a mesh file by its extension (not a .pmz, URL or stdin).
bool is_mesh_file(const std::string& source);

struct StaticMesh {
  pmz::IndexedMesh mesh;
  std::vector<uint32_t> identity;    // wedges for a mesh with materials but no wedge attributes
  std::string texture_directory;     // where its material's texture names are relative to
  bool texcoord_origin_top = false;  // glTF: v = 0 is the image's top row

  MeshFrame frame() const;
};

// Reads with meshio (repairs reported on stderr). False with a one-line error.
bool load_static_mesh(const std::string& path, StaticMesh& out, std::string& error);

std::vector<ViewMaterial> view_materials(const std::vector<pmz::Material>& materials);

// The folder part of a path ("" for a bare file name).
std::string directory_of(const std::string& path);

}  // namespace pmzview
