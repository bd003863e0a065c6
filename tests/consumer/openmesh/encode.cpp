// SPDX-License-Identifier: MIT
// The openmesh component: a TriMesh (an open, wavy strip with vertex normals and colours from
// OpenMesh, and two materials as face texture indices) encoded through pmz::openmesh::encode
// and written to argv[1].
#include <cmath>
#include <cstdio>
#include <pmz/openmesh.hpp>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  pmz::openmesh::TriMesh mesh;
  const int columns = 60, rows = 12;
  std::vector<OpenMesh::VertexHandle> v;
  for (int r = 0; r <= rows; ++r)
    for (int c = 0; c <= columns; ++c)
      v.push_back(mesh.add_vertex({0.1f * float(c), 0.1f * float(r), std::sin(0.3f * float(c))}));
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      const int i = r * (columns + 1) + c, up = i + columns + 1;
      mesh.add_face(v[i], v[i + 1], v[up]);
      mesh.add_face(v[i + 1], v[up + 1], v[up]);
    }
  mesh.request_face_normals();
  mesh.request_vertex_normals();
  mesh.update_normals();
  mesh.request_vertex_colors();
  for (auto vh : mesh.vertices())
    mesh.set_color(vh, {uint8_t(vh.idx() % 256), 128, uint8_t(255 - vh.idx() % 256)});
  mesh.request_face_texture_index();
  for (auto fh : mesh.faces()) mesh.set_texture_index(fh, fh.idx() < columns * rows ? 0 : 1);
  std::vector<uint8_t> bytes;
  std::string error;
  if (!pmz::openmesh::encode(mesh, bytes, error)) {
    std::printf("encode: %s\n", error.c_str());
    return 1;
  }
  std::printf("encode: %zu faces with normals, colours and materials -> %zu bytes\n",
              mesh.n_faces(), bytes.size());
  FILE* f = std::fopen(argv[1], "wb");
  if (!f || std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size()) return 1;
  return std::fclose(f) == 0 ? 0 : 1;
}
