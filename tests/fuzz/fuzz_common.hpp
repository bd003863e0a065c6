// SPDX-License-Identifier: MIT
// Shared by the fuzz targets: mesh invariants that must hold after every decoder call.
#pragma once
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "pmz/decoder.hpp"

namespace pmz_fuzz {

[[noreturn]] inline void fail(const char* what) {
  std::fprintf(stderr, "fuzz invariant violated: %s\n", what);
  std::abort();
}
#define PMZ_FUZZ_CHECK(cond)              \
  do {                                    \
    if (!(cond)) ::pmz_fuzz::fail(#cond); \
  } while (0)

struct Snapshot {
  std::vector<float> positions;
  std::vector<uint32_t> indices;
  bool operator==(const Snapshot& o) const {
    // Bitwise on positions: NaN payloads from lossless streams must round-trip too.
    return indices == o.indices && positions.size() == o.positions.size() &&
           (positions.empty() || std::memcmp(positions.data(), o.positions.data(),
                                             positions.size() * sizeof(float)) == 0);
  }
};

inline Snapshot snapshot(const pmz::Decoder& d) {
  Snapshot s;
  if (d.vertex_count())
    s.positions.assign(d.positions(), d.positions() + size_t(d.vertex_count()) * 3);
  if (d.face_count()) s.indices.assign(d.indices(), d.indices() + size_t(d.face_count()) * 3);
  return s;
}

inline bool same_info(const pmz::StreamInfo& a, const pmz::StreamInfo& b) {
  return a.header_done == b.header_done && a.base_done == b.base_done && a.complete == b.complete &&
         a.version_major == b.version_major && a.version_minor == b.version_minor &&
         a.flags == b.flags && a.position_bits == b.position_bits && a.level == b.level &&
         a.base_vertices == b.base_vertices && a.base_faces == b.base_faces &&
         a.full_vertices == b.full_vertices && a.full_faces == b.full_faces &&
         a.total_splits == b.total_splits &&
         std::memcmp(a.bbox_min, b.bbox_min, sizeof a.bbox_min) == 0 &&
         std::memcmp(a.bbox_max, b.bbox_max, sizeof a.bbox_max) == 0;
}

// The mesh is a consistent indexed triangle mesh, whatever bytes came in.
inline void check_mesh(const pmz::Decoder& d) {
  const uint32_t nv = d.vertex_count(), nf = d.face_count();
  PMZ_FUZZ_CHECK(nv == 0 || d.positions() != nullptr);
  PMZ_FUZZ_CHECK(nf == 0 || d.indices() != nullptr);
  PMZ_FUZZ_CHECK(nf == 0 || nv >= 3);
  for (uint32_t f = 0; f < nf; ++f) {
    const uint32_t* t = d.indices() + size_t(f) * 3;
    PMZ_FUZZ_CHECK(t[0] < nv && t[1] < nv && t[2] < nv);
    PMZ_FUZZ_CHECK(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
  }
  const pmz::StreamInfo& info = d.info();
  if (nv) {
    const uint32_t* parents = d.split_parents();
    PMZ_FUZZ_CHECK(parents != nullptr);
    for (uint32_t v = 0; v < nv; ++v)
      PMZ_FUZZ_CHECK(v < info.base_vertices ? parents[v] == UINT32_MAX : parents[v] < v);
  }
  PMZ_FUZZ_CHECK(d.splits_applied() <= d.splits_available());
  PMZ_FUZZ_CHECK(d.splits_available() <= info.total_splits);
  if (info.base_done) PMZ_FUZZ_CHECK(nv == info.base_vertices + d.splits_applied());
  const pmz::MeshChanges& c = d.changes();
  PMZ_FUZZ_CHECK(c.all || (c.vertex_begin <= nv && c.face_begin <= nf));
  PMZ_FUZZ_CHECK((d.status() == pmz::Status::ok) == d.error_message().empty());
}

}  // namespace pmz_fuzz
