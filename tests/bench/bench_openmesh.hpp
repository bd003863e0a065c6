// OpenMesh side of the harness programs: the triangle mesh type and its conversion to the
// flat IndexedMesh that pmz::write_mesh writes (atomically).
#pragma once
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include "pmz/mesh.hpp"

namespace pmz_bench {

using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;

inline pmz::IndexedMesh to_indexed(const OmMesh& mesh) {
  pmz::IndexedMesh out;
  out.positions.reserve(mesh.n_vertices() * 3);
  for (auto v : mesh.vertices())
    for (int k = 0; k < 3; ++k) out.positions.push_back(mesh.point(v)[k]);
  out.indices.reserve(mesh.n_faces() * 3);
  for (auto f : mesh.faces())
    for (auto v : mesh.fv_range(f)) out.indices.push_back(uint32_t(v.idx()));
  return out;
}

}  // namespace pmz_bench
