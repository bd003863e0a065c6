// SPDX-License-Identifier: MIT
// A procedural sample mesh for pmz-demo and the tests: no downloaded data needed.
#pragma once
#include <cstdint>

#include "pmz/mesh.hpp"

namespace pmz {

// A closed, manifold, genus-0 "rippled drum": a cylinder whose side carries smooth bumps and
// a sharp V-groove at mid-height, closed by flat caps that meet the side at sharp creases.
// Roughly target_faces triangles (the exact count follows from the grid; >= 1000).
IndexedMesh make_sample_mesh(uint32_t target_faces = 50000);

}  // namespace pmz
