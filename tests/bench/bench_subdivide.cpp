// bench-subdivide IN OUT LEVELS: LEVELS uniform Loop subdivisions (OpenMesh's LoopT), used
// to make the corpus's ~1M-face mesh. LEVELS 0 only converts (e.g. OFF to PLY for Draco).
#include "bench_openmesh.hpp"  // first: OpenMesh wants MeshIO before the tools
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>

#include "bench_common.hpp"

using Mesh = pmz_bench::OmMesh;

int main(int argc, char** argv) {
  const char* tool = "bench-subdivide";
  if (argc != 4) return pmz_bench::fail(tool, "usage: bench-subdivide IN OUT LEVELS");
  const unsigned long long levels = pmz_bench::parse_count(tool, argv[3]);
  Mesh mesh;
  if (!OpenMesh::IO::read_mesh(mesh, argv[1])) return pmz_bench::fail(tool, std::string(argv[1]) + ": cannot read mesh");
  const unsigned long long faces_in = mesh.n_faces();
  pmz_bench::Stopwatch clock;
  if (levels > 0) {
    OpenMesh::Subdivider::Uniform::LoopT<Mesh> loop;
    loop.attach(mesh);
    loop(size_t(levels));
    loop.detach();
  }
  const double seconds = clock.seconds();
  const pmz::IndexedMesh out = pmz_bench::to_indexed(mesh);
  std::string error;
  if (!pmz::write_mesh(argv[2], out, error)) return pmz_bench::fail(tool, error);
  pmz_bench::report(seconds, faces_in, out.face_count());
  return 0;
}
