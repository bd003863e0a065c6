// SPDX-License-Identifier: MIT
// The encoder component from the installed package: simplify a small generated grid, write it
// as .pmz (argv[1]) and check that the installed decoder reads it back to the full mesh.
#include <cmath>
#include <cstdio>
#include <pmz/decoder.hpp>
#include <pmz/mesh.hpp>
#include <pmz/simplify.hpp>
#include <pmz/writer.hpp>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc < 2) return 2;
  pmz::IndexedMesh mesh;
  const uint32_t n = 24;
  for (uint32_t y = 0; y <= n; ++y)
    for (uint32_t x = 0; x <= n; ++x)
      mesh.positions.insert(mesh.positions.end(),
                            {float(x), float(y), float(std::sin(x * 0.4) * std::cos(y * 0.3))});
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, d, a, d, c});
    }
  pmz::CollapseSequence seq;
  std::vector<uint8_t> bytes;
  std::string error;
  if (!pmz::simplify(mesh, {}, seq, error) || !pmz::write_pmz(seq, {}, bytes, error)) {
    std::printf("encode: %s\n", error.c_str());
    return 1;
  }
  if (!pmz::write_mesh(std::string(argv[1]) + ".obj", mesh, error)) return 1;
  pmz::Decoder dec;
  if (dec.feed(bytes.data(), bytes.size()) != pmz::Status::ok || dec.finish() != pmz::Status::ok)
    return 1;
  dec.refine();
  std::printf("encode: %u faces -> %zu bytes -> %u faces\n", mesh.face_count(), bytes.size(),
              dec.face_count());
  FILE* f = std::fopen(argv[1], "wb");
  if (!f || std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size()) return 1;
  std::fclose(f);
  return dec.face_count() == mesh.face_count() ? 0 : 1;
}
