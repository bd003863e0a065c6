// SPDX-License-Identifier: MIT
// bench-openmesh-view MESH [REPEATS [REBUILD_FRACTION]]: the cost of keeping an OpenMesh TriMesh in
// step with the decoder (pmz::openmesh::MeshView). MESH is read, given OpenMesh's creased normals
// (halfedge and vertex normals, so the view fills attribute properties too), encoded and decoded;
// then, from the middle level, steps of k splits are taken up and back down, and each update() is
// timed (process CPU time, median of REPEATS) against the decoder's own refine/coarsen and
// against rebuilding the whole TriMesh at the same level. One JSON line per step size.
// REBUILD_FRACTION sets ViewOptions::rebuild_fraction (1000: always incremental).
#include <algorithm>
#include <cstdio>
#include <ctime>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "pmz/openmesh.hpp"

namespace {

double cpu_now() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const char* tool = "bench-openmesh-view";
  if (argc < 2 || argc > 4)
    return pmz_bench::fail(tool, "usage: bench-openmesh-view MESH [REPEATS [REBUILD_FRACTION]]");
  const unsigned long long repeats = argc >= 3 ? pmz_bench::parse_count(tool, argv[2]) : 5;
  pmz::openmesh::ViewOptions options;
  if (argc == 4) options.rebuild_fraction = double(pmz_bench::parse_count(tool, argv[3]));
  pmz::IndexedMesh indexed;
  pmz::MeshRepairStats stats;
  std::string error;
  if (!pmz::read_mesh(argv[1], indexed, stats, error)) return pmz_bench::fail(tool, error);
  pmz::openmesh::TriMesh mesh;
  for (uint32_t v = 0; v < indexed.vertex_count(); ++v)
    mesh.add_vertex(
        {indexed.positions[v * 3], indexed.positions[v * 3 + 1], indexed.positions[v * 3 + 2]});
  for (uint32_t f = 0; f < indexed.face_count(); ++f)
    if (!mesh.add_face(OpenMesh::VertexHandle(int(indexed.indices[f * 3])),
                       OpenMesh::VertexHandle(int(indexed.indices[f * 3 + 1])),
                       OpenMesh::VertexHandle(int(indexed.indices[f * 3 + 2])))
             .is_valid())
      return pmz_bench::fail(tool, std::string(argv[1]) + ": OpenMesh refused a face");
  mesh.request_face_normals();
  mesh.request_vertex_normals();
  mesh.request_halfedge_normals();
  mesh.update_normals();
  std::vector<uint8_t> bytes;
  if (!pmz::openmesh::encode(mesh, bytes, error)) return pmz_bench::fail(tool, error);

  pmz::Decoder decoder;
  if (decoder.feed(bytes.data(), bytes.size()) != pmz::Status::ok)
    return pmz_bench::fail(tool, decoder.error_message());
  pmz::openmesh::MeshView<> view(decoder, options);
  const uint64_t middle = decoder.info().total_splits / 2;
  decoder.set_split_target(middle);
  view.update();
  for (uint64_t k : {1u, 10u, 100u, 1000u, 10000u, 100000u}) {
    if (k > middle) break;
    std::vector<double> dec, up, rebuild;
    bool incremental = true;
    for (unsigned long long r = 0; r < repeats; ++r)
      for (int dir = 0; dir < 2; ++dir) {
        const double t0 = cpu_now();
        if (dir == 0)
          decoder.refine(k);
        else
          decoder.coarsen(k);
        const double t1 = cpu_now();
        if (!view.update()) return pmz_bench::fail(tool, view.error());
        dec.push_back(t1 - t0);
        up.push_back(cpu_now() - t1);
        incremental = incremental && !view.last_rebuilt();
      }
    // (Timed apart: a rebuild reserves exactly, so the next update would pay for growing the
    // arrays.)
    for (unsigned long long r = 0; r < repeats; ++r) {
      const double t0 = cpu_now();
      view.rebuild();
      rebuild.push_back(cpu_now() - t0);
    }
    std::printf(
        "{\"mesh\": \"%s\", \"faces\": %u, \"splits\": %llu, \"decoder_ms\": %.3f, "
        "\"update_ms\": %.3f, \"incremental\": %s, \"rebuild_ms\": %.3f}\n",
        argv[1], decoder.face_count(), (unsigned long long)k, 1e3 * median(dec), 1e3 * median(up),
        incremental ? "true" : "false", 1e3 * median(rebuild));
  }
  return 0;
}
