// SPDX-License-Identifier: MIT
// Internal: attribute error at corresponding surface points (pmz::AttributeErrors).
#pragma once
#include <cstdint>

#include "bvh.hpp"
#include "pmz/compare.hpp"

namespace pmz {

// Samples ORIGINAL's faces (about face_samples, area-proportional, seeded), finds the closest
// point of OTHER through to_other (built from OTHER's faces) and compares the attributes
// interpolated at both points (texture coordinates: chart-aware, pmz::AttributeErrorStats).
// to_original (ORIGINAL's faces; built here when null and needed) matches OTHER's texture
// charts to ORIGINAL's. An attribute either mesh lacks is left unmeasured.
void compare_attributes(const IndexedMesh& original, const IndexedMesh& other,
                        const TriangleBvh& to_other, const TriangleBvh* to_original,
                        uint64_t face_samples, uint64_t seed, unsigned threads,
                        AttributeErrors& out);

}  // namespace pmz
