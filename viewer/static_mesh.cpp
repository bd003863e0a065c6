// SPDX-License-Identifier: MIT
#include "static_mesh.hpp"

#include <algorithm>
#include <cctype>
#include <numeric>

#include "pmz/mesh_file_formats.hpp"

namespace pmzview {

bool is_mesh_file(const std::string& source) {
  const size_t dot = source.rfind('.');
  if (dot == std::string::npos || source.find("://") != std::string::npos) return false;
  std::string ext = source.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return pmz::mesh_format_readable(ext);
}

std::string directory_of(const std::string& path) {
  const size_t slash = path.rfind('/');
  return slash == std::string::npos ? "" : path.substr(0, slash + 1);
}

bool load_static_mesh(const std::string& path, StaticMesh& out, std::string& error) {
  if (!pmz::read_mesh(path, out.mesh, error)) return false;
  const pmz::MeshAttributes& a = out.mesh.attributes;
  out.texture_directory = directory_of(path);
  // OBJ texture names are relative to the MTL file, which may sit in a subfolder.
  if (!a.material_library.empty()) out.texture_directory += directory_of(a.material_library);
  std::string ext = path.substr(path.rfind('.') + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  out.texcoord_origin_top = ext == "gltf" || ext == "glb";
  if (!a.has_wedges() && !a.face_materials.empty()) {
    out.identity.resize(out.mesh.vertex_count());
    std::iota(out.identity.begin(), out.identity.end(), 0u);
  }
  return true;
}

MeshFrame StaticMesh::frame() const {
  MeshFrame f;
  const pmz::MeshAttributes& a = mesh.attributes;
  f.vertex_count = mesh.vertex_count();
  f.face_count = mesh.face_count();
  f.positions = mesh.positions.data();
  f.indices = mesh.indices.data();
  f.full_vertices = f.vertex_count;
  f.full_faces = f.face_count;
  f.all = true;
  if (a.has_wedges() && a.corner_wedges.size() == mesh.indices.size()) {
    f.wedge_count = a.wedge_count();
    f.wedge_vertices = a.wedge_vertices.data();
    f.wedge_indices = a.corner_wedges.data();
    if (!a.texcoords.empty()) f.texcoords = a.texcoords[0].data();
    if (!a.normals.empty()) f.normals = a.normals.data();
    if (!a.colors.empty()) {
      f.colors = a.colors.data();
      f.color_components = a.color_components;
    }
  } else if (!identity.empty()) {
    f.wedge_count = uint32_t(identity.size());
    f.wedge_vertices = identity.data();
    f.wedge_indices = mesh.indices.data();
  }
  f.full_wedges = f.wedge_count;
  if (f.wedge_count && a.face_materials.size() == mesh.face_count())
    f.face_materials = a.face_materials.data();
  return f;
}

std::vector<ViewMaterial> view_materials(const std::vector<pmz::Material>& materials) {
  std::vector<ViewMaterial> out(materials.size());
  for (size_t m = 0; m < materials.size(); ++m) {
    out[m].name = materials[m].name;
    std::copy(materials[m].base_color, materials[m].base_color + 4, out[m].base_color);
    out[m].texture = materials[m].base_color_texture;
  }
  return out;
}

}  // namespace pmzview
