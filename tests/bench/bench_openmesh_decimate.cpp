// bench-openmesh-decimate IN OUT FACES: OpenMesh's Decimater (ModQuadric + ModNormalFlipping,
// both at their defaults) with decimate_to_faces(0, FACES), the classic half-edge QEM peer.
#include "bench_openmesh.hpp"  // first: OpenMesh wants MeshIO before the tools
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

#include "bench_common.hpp"

using Mesh = pmz_bench::OmMesh;

int main(int argc, char** argv) {
  const char* tool = "bench-openmesh-decimate";
  if (argc != 4) return pmz_bench::fail(tool, "usage: bench-openmesh-decimate IN OUT FACES");
  const unsigned long long target_faces = pmz_bench::parse_count(tool, argv[3]);
  Mesh mesh;
  if (!OpenMesh::IO::read_mesh(mesh, argv[1])) return pmz_bench::fail(tool, std::string(argv[1]) + ": cannot read mesh");
  const unsigned long long faces_in = mesh.n_faces();

  pmz_bench::Stopwatch clock;
  mesh.request_face_normals();
  mesh.update_face_normals();
  OpenMesh::Decimater::DecimaterT<Mesh> decimater(mesh);
  OpenMesh::Decimater::ModQuadricT<Mesh>::Handle quadric;
  OpenMesh::Decimater::ModNormalFlippingT<Mesh>::Handle normal_flipping;
  decimater.add(quadric);
  decimater.add(normal_flipping);
  if (!decimater.initialize()) return pmz_bench::fail(tool, "decimater did not initialize");
  decimater.decimate_to_faces(0, size_t(target_faces));
  mesh.garbage_collection();
  const double seconds = clock.seconds();

  const pmz::IndexedMesh out = pmz_bench::to_indexed(mesh);
  std::string error;
  if (!pmz::write_mesh(argv[2], out, error)) return pmz_bench::fail(tool, error);
  pmz_bench::report(seconds, faces_in, out.face_count());
  return 0;
}
