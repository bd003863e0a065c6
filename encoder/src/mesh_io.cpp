// Mesh input/output through OpenMesh, into and out of the flat IndexedMesh.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "pmz/mesh.hpp"

namespace pmz {

namespace {
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;
}

bool read_mesh(const std::string& path, IndexedMesh& out, std::string& error) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    error = path + ": no such file";
    return false;
  }
  OmMesh m;
  OpenMesh::IO::Options opt;
  if (!OpenMesh::IO::read_mesh(m, path, opt)) {
    error = path + ": cannot read mesh (unknown format or unreadable file)";
    return false;
  }
  if (m.n_faces() == 0) {
    error = path + ": mesh has no faces";
    return false;
  }
  out.positions.resize(m.n_vertices() * 3);
  for (auto v : m.vertices()) {
    const auto& p = m.point(v);
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(p[k])) {
        error = path + ": vertex " + std::to_string(v.idx()) + " has a NaN or infinite coordinate";
        return false;
      }
      out.positions[size_t(v.idx()) * 3 + k] = p[k];
    }
  }
  out.indices.clear();
  out.indices.reserve(m.n_faces() * 3);
  for (auto f : m.faces())
    for (auto v : m.fv_range(f)) out.indices.push_back(uint32_t(v.idx()));
  return true;
}

bool write_mesh(const std::string& path, const IndexedMesh& mesh, std::string& error) {
  OmMesh m;
  for (uint32_t i = 0; i < mesh.vertex_count(); ++i)
    m.add_vertex(OmMesh::Point(mesh.positions[i * 3], mesh.positions[i * 3 + 1], mesh.positions[i * 3 + 2]));
  for (uint32_t f = 0; f < mesh.face_count(); ++f)
    m.add_face(OmMesh::VertexHandle(int(mesh.indices[f * 3])), OmMesh::VertexHandle(int(mesh.indices[f * 3 + 1])),
               OmMesh::VertexHandle(int(mesh.indices[f * 3 + 2])));
  std::filesystem::path p(path);
  // Hidden temporary beside the target (same filesystem, so rename is atomic); it keeps the
  // extension because OpenMesh picks the writer by it.
  std::string name = ".";
  name.append(p.filename().string()).append(".tmp").append(p.extension().string());
  std::string tmp = (p.parent_path() / name).string();
  if (!OpenMesh::IO::write_mesh(m, tmp)) {
    std::remove(tmp.c_str());
    error = path + ": cannot write mesh";
    return false;
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    error = path + ": " + ec.message();
    return false;
  }
  return true;
}

}  // namespace pmz
