// SPDX-License-Identifier: MIT
// The openmesh component: a .pmz file (argv[1]) read SLICE bytes at a time (argv[2]), a
// pmz::openmesh::MeshView refined after each slice, then coarsened half way; the TriMesh must
// equal the decoder's mesh each time (counts, positions, faces' vertices in order, normals,
// materials as face texture indices).
#include <cstdio>
#include <cstdlib>
#include <pmz/openmesh.hpp>
#include <vector>

static bool same(const pmz::openmesh::MeshView<>& view, const pmz::Decoder& d) {
  const pmz::openmesh::TriMesh& m = view.mesh();
  if (!view.error().empty() || m.n_vertices() != d.vertex_count() || m.n_faces() != d.face_count())
    return false;
  for (auto v : m.vertices())
    for (int k = 0; k < 3; ++k)
      if (m.point(v)[k] != d.positions()[v.idx() * 3 + k]) return false;
  const uint32_t* materials = d.face_materials();
  if (materials && !m.has_face_texture_index()) return false;
  for (auto f : m.faces()) {
    if (materials && m.texture_index(f) != int(materials[f.idx()])) return false;
    int k = 0;
    for (auto h : m.fh_range(f)) {
      const int corner = f.idx() * 3 + k++;
      if (uint32_t(m.to_vertex_handle(h).idx()) != d.indices()[corner]) return false;
      if (d.normals() && m.normal(h)[0] != d.normals()[d.wedge_indices()[corner] * 3]) return false;
    }
  }
  return true;
}

int main(int argc, char** argv) {
  if (argc < 3) return 2;
  FILE* file = std::fopen(argv[1], "rb");
  if (!file) return 1;
  const size_t slice = std::strtoul(argv[2], nullptr, 10);
  std::vector<char> buf(slice);
  pmz::Decoder decoder;
  pmz::openmesh::MeshView<> view(decoder);
  bool ok = true;
  size_t n;
  while (ok && (n = std::fread(buf.data(), 1, slice, file)) > 0) {
    ok = decoder.feed(buf.data(), n) == pmz::Status::ok;
    view.refine();
    ok = ok && same(view, decoder);
  }
  std::fclose(file);
  ok = ok && decoder.finish() == pmz::Status::ok && decoder.info().complete &&
       decoder.face_count() == decoder.info().full_faces;
  const size_t full = view.mesh().n_faces();
  view.set_face_target(full / 2);
  ok = ok && same(view, decoder) && view.mesh().n_faces() < full;
  std::printf("openmesh consumer: %zu faces, %zu at half, %u materials (%s)\n", full,
              view.mesh().n_faces(), decoder.material_count(),
              ok                     ? "ok"
              : view.error().empty() ? "mismatch"
                                     : view.error().c_str());
  return ok ? 0 : 1;
}
