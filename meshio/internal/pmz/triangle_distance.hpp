// SPDX-License-Identifier: MIT
// Point to triangle distance, shared by the error measure (pmz-compare) and the writer's node
// error bounds.
#pragma once

namespace pmz {

// Squared distance from p to triangle (a, b, c), closest point by Voronoi regions (Ericson,
// Real-Time Collision Detection, 5.1.5); degenerate triangles fall back to their edges.
double point_triangle_distance2(const double p[3], const float* a, const float* b, const float* c);

}  // namespace pmz
