// SPDX-License-Identifier: MIT
// bench-subdivide IN OUT LEVELS: LEVELS uniform Loop subdivisions (OpenMesh's LoopT), used
// to make the corpus's ~1M-face mesh. LEVELS 0 only converts (e.g. OFF to PLY for Draco).
// OpenMesh wants MeshIO (bench_openmesh.hpp) before the tools: keep this order.
// clang-format off
#include "bench_openmesh.hpp"
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>
// clang-format on

using Mesh = pmz_bench::OmMesh;

int main(int argc, char** argv) {
  return pmz_bench::openmesh_main("bench-subdivide", argc, argv,
                                  [](Mesh& mesh, unsigned long long levels) {
                                    if (levels > 0) {
                                      OpenMesh::Subdivider::Uniform::LoopT<Mesh> loop;
                                      loop.attach(mesh);
                                      loop(size_t(levels));
                                      loop.detach();
                                    }
                                    return std::string();
                                  });
}
