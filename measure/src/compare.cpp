// SPDX-License-Identifier: MIT
// Metro-style surface distance: sample vertices, edges and faces of one mesh, find the nearest
// point of the other surface through a BVH, accumulate max / mean / rms, both directions.
#include "pmz/compare.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "bvh.hpp"
#include "compare_attributes.hpp"
#include "sampling.hpp"

namespace pmz {

namespace {

// Work is cut into fixed blocks whose partial sums are reduced in block order, so the result
// is the same for any thread count.
constexpr uint32_t kBlockItems = 2048;

struct Partial {
  double max_at[3] = {0, 0, 0};
  DistanceStats::Site max_on = DistanceStats::Site::vertex;
  double max = 0, face_sum = 0, face_sum2 = 0, all_sum = 0, all_sum2 = 0;
  uint64_t face_samples = 0, samples = 0;
};

using sampling::triangle_area;
using sampling::uniform01;

bool validate(const IndexedMesh& m, const char* name, std::string& error) {
  if (m.face_count() == 0) {
    error = std::string(name) + " mesh has no faces";
    return false;
  }
  const uint32_t n = m.vertex_count();
  for (uint32_t i : m.indices)
    if (i >= n) {
      error =
          std::string(name) + " mesh has a vertex index out of range (" + std::to_string(i) + ")";
      return false;
    }
  return true;
}

double length(const float* a, const float* b) {
  double dx = double(b[0]) - a[0], dy = double(b[1]) - a[1], dz = double(b[2]) - a[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// Samples on `from`, distances to the surface in `to`.
DistanceStats one_direction(const IndexedMesh& from, const TriangleBvh& to, uint64_t face_samples,
                            uint64_t seed, unsigned threads) {
  const float* pos = from.positions.data();
  const uint32_t* idx = from.indices.data();
  const uint32_t faces = from.face_count();

  // Items: referenced vertices (one sample each), unique edges, faces.
  std::vector<uint32_t> vertices(from.indices);
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  std::vector<uint64_t> edges;
  edges.reserve(size_t(faces) * 3);
  for (uint32_t f = 0; f < faces; ++f)
    for (int j = 0; j < 3; ++j) {
      uint64_t a = idx[f * 3 + j], b = idx[f * 3 + (j + 1) % 3];
      edges.push_back(std::min(a, b) << 32 | std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());

  double total_area = 0, total_length = 0;
  for (uint32_t f = 0; f < faces; ++f)
    total_area += triangle_area(pos + idx[f * 3] * size_t(3), pos + idx[f * 3 + 1] * size_t(3),
                                pos + idx[f * 3 + 2] * size_t(3));
  for (uint64_t e : edges) total_length += length(pos + (e >> 32) * 3, pos + (e & 0xFFFFFFFFu) * 3);
  const double face_density = total_area > 0 ? double(face_samples) / total_area : 0;
  const double edge_density = total_length > 0 ? double(face_samples / 10) / total_length : 0;

  const uint64_t n_vertices = vertices.size(), n_edges = edges.size();
  const uint64_t n_items = n_vertices + n_edges + faces;
  const uint64_t n_blocks = (n_items + kBlockItems - 1) / kBlockItems;
  std::vector<Partial> partials(n_blocks);
  sampling::for_each_block(n_blocks, threads, [&](uint64_t block, uint32_t& hint) {
    Partial acc;
    auto measure = [&](const double p[3], DistanceStats::Site site) {
      double d = std::sqrt(to.closest_distance2(p, hint));
      if (d > acc.max) acc.max = d, std::copy(p, p + 3, acc.max_at), acc.max_on = site;
      const bool on_face = site == DistanceStats::Site::face;
      acc.all_sum += d, acc.all_sum2 += d * d, acc.samples++;
      if (on_face) acc.face_sum += d, acc.face_sum2 += d * d, acc.face_samples++;
    };
    const uint64_t end = std::min(n_items, (block + 1) * kBlockItems);
    for (uint64_t item = block * kBlockItems; item < end; ++item) {
      uint64_t rng = seed ^ (item * 0xD1B54A32D192ED03ull);
      if (item < n_vertices) {
        const float* v = pos + size_t(vertices[item]) * 3;
        const double p[3] = {v[0], v[1], v[2]};
        measure(p, DistanceStats::Site::vertex);
      } else if (item < n_vertices + n_edges) {
        const uint64_t e = edges[item - n_vertices];
        const float* a = pos + (e >> 32) * 3;
        const float* b = pos + (e & 0xFFFFFFFFu) * 3;
        // Stratified along the edge; the fractional expected count is rounded at random.
        const uint64_t n = uint64_t(length(a, b) * edge_density + uniform01(rng));
        for (uint64_t k = 0; k < n; ++k) {
          const double t = (double(k) + uniform01(rng)) / double(n);
          const double p[3] = {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]),
                               a[2] + t * (b[2] - a[2])};
          measure(p, DistanceStats::Site::edge);
        }
      } else {
        const uint32_t f = uint32_t(item - n_vertices - n_edges);
        const float* a = pos + size_t(idx[f * 3]) * 3;
        const float* b = pos + size_t(idx[f * 3 + 1]) * 3;
        const float* c = pos + size_t(idx[f * 3 + 2]) * 3;
        const uint64_t n = uint64_t(triangle_area(a, b, c) * face_density + uniform01(rng));
        for (uint64_t k = 0; k < n; ++k) {
          double w[3];
          sampling::uniform_barycentric(rng, w);
          const double p[3] = {w[0] * a[0] + w[1] * b[0] + w[2] * c[0],
                               w[0] * a[1] + w[1] * b[1] + w[2] * c[1],
                               w[0] * a[2] + w[1] * b[2] + w[2] * c[2]};
          measure(p, DistanceStats::Site::face);
        }
      }
    }
    partials[block] = acc;
  });

  Partial total;
  for (const Partial& p : partials) {
    if (p.max > total.max)
      total.max = p.max, std::copy(p.max_at, p.max_at + 3, total.max_at), total.max_on = p.max_on;
    total.face_sum += p.face_sum, total.face_sum2 += p.face_sum2,
        total.face_samples += p.face_samples;
    total.all_sum += p.all_sum, total.all_sum2 += p.all_sum2, total.samples += p.samples;
  }
  DistanceStats s;
  s.max = total.max;
  std::copy(total.max_at, total.max_at + 3, s.max_at);
  s.max_on = total.max_on;
  s.samples = total.samples;
  // Mean and rms are surface integrals: face samples only, unless the surface has no area.
  const bool use_faces = total.face_samples > 0;
  const double n = double(use_faces ? total.face_samples : std::max<uint64_t>(total.samples, 1));
  s.mean = (use_faces ? total.face_sum : total.all_sum) / n;
  s.rms = std::sqrt((use_faces ? total.face_sum2 : total.all_sum2) / n);
  return s;
}

}  // namespace

uint64_t default_compare_samples(uint64_t faces_a, uint64_t faces_b) {
  return std::clamp<uint64_t>(10 * std::max(faces_a, faces_b), 200000, 2000000);
}

bool compare(const IndexedMesh& original, const IndexedMesh& other, const CompareOptions& options,
             CompareResult& result, std::string& error) {
  if (!validate(original, "original", error) || !validate(other, "other", error)) return false;
  const auto start = std::chrono::steady_clock::now();
  result = CompareResult();

  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) lo[k] = hi[k] = original.positions[k];
  for (size_t i = 0; i < original.positions.size(); i += 3)
    for (int k = 0; k < 3; ++k)
      lo[k] = std::min(lo[k], double(original.positions[i + k])),
      hi[k] = std::max(hi[k], double(original.positions[i + k]));
  result.diag = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                          (hi[2] - lo[2]) * (hi[2] - lo[2]));

  const uint64_t samples = options.samples
                               ? options.samples
                               : default_compare_samples(original.face_count(), other.face_count());
  TriangleBvh to_other, to_original;
  auto build_other = [&] {
    to_other.build(other.positions.data(), other.indices.data(), other.face_count());
  };
  if (options.both_directions && options.threads > 1) {
    std::thread t(build_other);
    to_original.build(original.positions.data(), original.indices.data(), original.face_count());
    t.join();
  } else {
    build_other();
    if (options.both_directions)
      to_original.build(original.positions.data(), original.indices.data(), original.face_count());
  }

  result.forward = one_direction(original, to_other, samples, options.seed, options.threads);
  if (options.attributes)
    compare_attributes(original, other, to_other, options.both_directions ? &to_original : nullptr,
                       samples, options.seed ^ 0x61747472ull, options.threads, result.attributes);
  if (options.both_directions) {
    result.backward =
        one_direction(other, to_original, samples, options.seed ^ 0x5bd1e995ull, options.threads);
    const DistanceStats &f = result.forward, &b = result.backward;
    result.symmetric = f.max >= b.max ? f : b;  // max, where it is
    result.symmetric.mean = 0.5 * (f.mean + b.mean);
    result.symmetric.rms = std::sqrt(0.5 * (f.rms * f.rms + b.rms * b.rms));
    result.symmetric.samples = f.samples + b.samples;
  } else {
    result.symmetric = result.forward;
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return true;
}

}  // namespace pmz
