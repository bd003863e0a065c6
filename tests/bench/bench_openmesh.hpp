// SPDX-License-Identifier: MIT
// OpenMesh side of the harness programs: the triangle mesh type, its conversion to the flat
// IndexedMesh that pmz::write_mesh writes (atomically), and their common main().
#pragma once
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include "bench_common.hpp"
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

// `tool IN OUT COUNT`: reads IN with OpenMesh, times run(mesh, COUNT) (which returns an error
// message, empty on success), writes OUT and prints the JSON report.
template <class Run>
int openmesh_main(const char* tool, int argc, char** argv, Run run) {
  if (argc != 4) return fail(tool, std::string("usage: ") + tool + " IN OUT COUNT");
  const unsigned long long count = parse_count(tool, argv[3]);
  OmMesh mesh;
  if (!OpenMesh::IO::read_mesh(mesh, argv[1]))
    return fail(tool, std::string(argv[1]) + ": cannot read mesh");
  const unsigned long long faces_in = mesh.n_faces();
  Stopwatch clock;
  const std::string run_error = run(mesh, count);
  const double seconds = clock.seconds();
  if (!run_error.empty()) return fail(tool, run_error);
  const pmz::IndexedMesh out = to_indexed(mesh);
  std::string error;
  if (!pmz::write_mesh(argv[2], out, error)) return fail(tool, error);
  report(seconds, faces_in, out.face_count());
  return 0;
}

}  // namespace pmz_bench
