// SPDX-License-Identifier: MIT
// Metro-style surface distance (Cignoni, Rocchini, Scopigno 1998): dense deterministic sampling
// of one mesh (vertices, edges, faces), nearest point on the other surface through a BVH,
// both directions. The measuring stick for every quality figure of the project.
#pragma once
#include <cstdint>
#include <string>

#include "pmz/mesh.hpp"

namespace pmz {

struct CompareOptions {
  // Area-proportional face samples per direction; 0 = default: 10 x the larger face count,
  // clamped to [200k, 2M]. Each direction adds all referenced vertices and edge samples
  // (a tenth of the face samples, proportional to length).
  uint64_t samples = 0;
  uint64_t seed = 0x706d7a2d6d6574ull;  // fixed: results are reproducible run to run
  unsigned threads = 2;                 // results do not depend on it (fixed-block reduction)
  bool both_directions = true;          // false: only ORIGINAL -> OTHER (backward stays zero)
  bool attributes = true;               // attribute error too, when both meshes carry the attribute
};

// Distances from samples on one surface to the other, absolute (model units).
// max is over every sample (vertices, edges, faces); mean and rms are over the
// area-proportional face samples, i.e. estimates of the surface integrals divided by area,
// so vertex-dense regions do not bias them.
struct DistanceStats {
  double max = 0, mean = 0, rms = 0;
  uint64_t samples = 0;  // all samples taken
  // Where the max was found: the sample point (on the measured-from mesh) and what it sampled
  // (a vertex, an edge or a face interior), to tell which region holds the worst case.
  enum class Site : uint8_t { vertex, edge, face };
  double max_at[3] = {0, 0, 0};
  Site max_on = Site::vertex;
};

// Attribute error at corresponding surface points: for area-proportional samples on ORIGINAL,
// the closest point of OTHER; the attribute interpolated there (from OTHER's corners) against
// the sample's own. mean and rms over the samples, max the largest.
// Texture coordinates are compared on the sample's own chart (charts: faces joined across
// edges whose ends agree in position and texture coordinates). Along a texture seam they are
// several-valued, and a seam moved a little (quantized positions, say) puts the closest point
// of samples next to it on the other chart; where two sheets touch or cross, the closest point
// can lie on another sheet. So the texture error is the smallest |delta uv| over: the closest
// face of OTHER; the closest of the faces of OTHER that stand for the sample's chart (each
// chart of OTHER stands for the ORIGINAL chart under most of its area); and, at each of the
// two, the faces across a seam at its corners, each at its point closest to the sample. A
// difference that the sample's chart in OTHER does not explain is still measured (up to the
// jump in texture space to another chart's values there): a shifted chart reads as its shift.
struct AttributeErrorStats {
  double max = 0, mean = 0, rms = 0;
  uint64_t samples = 0;  // 0: not measured (a mesh lacks the attribute)
};
struct AttributeErrors {
  AttributeErrorStats texcoord;  // |delta (u, v)| of texture coordinate set 0, texture units,
                                 // on the sample's own chart (above)
  AttributeErrorStats normal;    // angle between the interpolated normals, degrees
  AttributeErrorStats color;     // |delta| of the colour (RGB or RGBA, channels 0..1)
};

struct CompareResult {
  double diag = 0;             // bounding-box diagonal of ORIGINAL (divide by it for relative)
  DistanceStats forward;       // samples on ORIGINAL, distance to OTHER
  DistanceStats backward;      // samples on OTHER, distance to ORIGINAL
  DistanceStats symmetric;     // max of both maxima (the Hausdorff distance); mean and rms of
                               // both directions with equal weight
  AttributeErrors attributes;  // CompareOptions::attributes and both meshes carry them
  double seconds = 0;          // wall time of the comparison (BVH builds + queries)
};

// Returns false with a one-line message when a mesh has no faces or indices out of range.
bool compare(const IndexedMesh& original, const IndexedMesh& other, const CompareOptions& options,
             CompareResult& result, std::string& error);

// Default number of face samples per direction for meshes of these face counts.
uint64_t default_compare_samples(uint64_t faces_a, uint64_t faces_b);

}  // namespace pmz
