// SPDX-License-Identifier: MIT
// bench-openmesh-decimate IN OUT FACES: OpenMesh's Decimater (ModQuadric + ModNormalFlipping,
// both at their defaults) with decimate_to_faces(0, FACES), the classic half-edge QEM peer.
// OpenMesh wants MeshIO (bench_openmesh.hpp) before the tools: keep this order.
// clang-format off
#include "bench_openmesh.hpp"
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
// clang-format on

using Mesh = pmz_bench::OmMesh;

int main(int argc, char** argv) {
  return pmz_bench::openmesh_main(
      "bench-openmesh-decimate", argc, argv, [](Mesh& mesh, unsigned long long faces) {
        mesh.request_face_normals();
        mesh.update_face_normals();
        OpenMesh::Decimater::DecimaterT<Mesh> decimater(mesh);
        OpenMesh::Decimater::ModQuadricT<Mesh>::Handle quadric;
        OpenMesh::Decimater::ModNormalFlippingT<Mesh>::Handle normal_flipping;
        decimater.add(quadric);
        decimater.add(normal_flipping);
        if (!decimater.initialize()) return std::string("decimater did not initialize");
        decimater.decimate_to_faces(0, size_t(faces));
        mesh.garbage_collection();
        return std::string();
      });
}
