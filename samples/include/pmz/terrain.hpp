// SPDX-License-Identifier: MIT
// A procedural terrain of any size, written as a binary PLY while it is made, so that tests and
// benchmarks of large meshes need no download and the generator's memory does not grow with the
// size: a height field on a square grid with fractal relief, sharp ridges, terraces that meet
// in creases and a valley cut into it (features a simplifier must keep). Deterministic: the same
// size and seed give the same bytes on every machine.
#pragma once
#include <cstdint>
#include <functional>
#include <string>

namespace pmz {

struct TerrainOptions {
  uint64_t faces = 1000000;  // about this many (the grid's exact count: 2 (n - 1)^2, n >= 2)
  uint64_t seed = 1;
  // Called now and then with the fraction written (0..1); may be empty.
  std::function<void(double)> progress;
};

// The grid side n of a terrain of about `faces` faces: 2 (n - 1)^2 faces, n^2 vertices.
uint32_t terrain_grid_side(uint64_t faces);

// The height of the terrain at (x, y) in [0, 1]^2 (the same function the PLY samples).
float terrain_height(double x, double y, uint64_t seed);

// Writes the terrain as a binary little-endian PLY through `write` (called with consecutive
// pieces of the file; returns false to stop: the function then returns false). A vertex is
// (x, y, height) with x, y in [0, 1]; faces are counter-clockwise seen from +z.
bool write_terrain_ply(const TerrainOptions& options,
                       const std::function<bool(const void*, size_t)>& write);

}  // namespace pmz
