// SPDX-License-Identifier: MIT
// The cells of a hierarchical simplification: at every level a grid of cubes over the file's
// integer coordinates (spec/format.md section 5), its cells holding about as many of the
// vertices left as the first level's hold of the mesh's, its planes half a cell of the level
// below away from that level's planes.
//
// A collapse is confined to a cell when u, v and every neighbour of both lie in it; such a
// collapse reads and writes only faces and vertices of its cell, so the collapses of different
// cells of one level commute, and their inverses (vertex splits) decode independently once the
// cells of the coarser level that overlap theirs are decoded. Because each level's planes lie
// between the planes of the level below, a vertex held back by a border at one level is inside
// a cell at the next: no border stays at full detail up the hierarchy (nested cells, as a k-d
// tree gives, keep the coarsest cut at full detail until the last level).
#pragma once
#include <cstdint>
#include <vector>

#include "pmz/simplify.hpp"

namespace pmz::detail {

// The area of the triangle (p, q, r) of integer coordinates.
double triangle_area(const int32_t p[3], const int32_t q[3], const int32_t r[3]);

// The integer coordinates of `vertices` vertices span the box [lo, hi] (each axis's smallest and
// largest coordinate).
struct CoordBox {
  int64_t lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  uint64_t vertices = 0;
};

// The finest grid for cells of about `cell_vertices` vertices on a surface of `area` with the
// vertices of `box`: the side s with s^2 / area * vertices = cell_vertices, at least 2 and more
// than extent / 2^20 (so fewer than 2^20 cells per axis), its planes from the smallest
// coordinates.
CellGrid cell_grid_for(const CoordBox& box, double area, uint32_t cell_vertices);

// The grid of the level after one on grid g, which left `live` of the mesh's vertices: the
// side of cells of about `cell_vertices` of them on a surface of `area` (so every level's cells
// hold about as many vertices as the first level's, and the levels go on until few are left),
// but at least 5/4 of g's side (levels end) and at most twice it; its planes half of g's side
// from g's.
CellGrid next_cell_grid(const CellGrid& g, double area, uint32_t cell_vertices, uint64_t live);

// Whether a grid still cuts the box's vertices (more than one cell along some axis: the vertices
// at an axis's two ends lie in different cells).
bool grid_cuts(const CellGrid& g, const CoordBox& box);

}  // namespace pmz::detail
