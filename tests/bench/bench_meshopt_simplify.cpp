// SPDX-License-Identifier: MIT
// bench-meshopt-simplify IN OUT FACES: meshoptimizer's meshopt_simplify to FACES triangles.
// target_error = 1.0 (100% of the extent) so the error bound never stops it before the face
// target: the comparison is at equal face counts. Positions are used as read (shared
// vertices, as meshopt_simplify needs).
#include <meshoptimizer.h>

#include <vector>

#include "bench_common.hpp"
#include "pmz/mesh.hpp"

int main(int argc, char** argv) {
  const char* tool = "bench-meshopt-simplify";
  if (argc != 4) return pmz_bench::fail(tool, "usage: bench-meshopt-simplify IN OUT FACES");
  const unsigned long long target_faces = pmz_bench::parse_count(tool, argv[3]);
  pmz::IndexedMesh mesh;
  std::string error;
  if (!pmz::read_mesh(argv[1], mesh, error)) return pmz_bench::fail(tool, error);

  pmz_bench::Stopwatch clock;
  std::vector<unsigned int> simplified(mesh.indices.size());
  float result_error = 0;
  size_t count = meshopt_simplify(simplified.data(), mesh.indices.data(), mesh.indices.size(),
                                  mesh.positions.data(), mesh.vertex_count(), sizeof(float) * 3,
                                  size_t(target_faces) * 3, 1.0f, 0, &result_error);
  simplified.resize(count);
  const double seconds = clock.seconds();

  // Compact to the vertices still referenced.
  pmz::IndexedMesh out;
  std::vector<unsigned int> remap(mesh.vertex_count(), ~0u);
  for (unsigned int& i : simplified) {
    if (remap[i] == ~0u) {
      remap[i] = out.vertex_count();
      out.positions.insert(out.positions.end(), &mesh.positions[size_t(i) * 3],
                           &mesh.positions[size_t(i) * 3 + 3]);
    }
    i = remap[i];
  }
  out.indices = std::move(simplified);
  if (out.indices.empty()) return pmz_bench::fail(tool, "simplified to an empty mesh");
  if (!pmz::write_mesh(argv[2], out, error)) return pmz_bench::fail(tool, error);
  pmz_bench::report(seconds, mesh.face_count(), out.face_count());
  return 0;
}
