// SPDX-License-Identifier: MIT
// The whole streaming decoder on arbitrary bytes, fed in arbitrary slices, with level moves
// between slices. Input: [n][n (size, op) byte pairs][stream bytes]; n = data[0] % 16, and
// n = 0 feeds the stream in one call. Checks, besides ASan/UBSan:
//  - after every call the mesh is valid (indices < vertex_count, no degenerate face, ...);
//  - the face count never drops while only refining;
//  - coarsen(k) then refine(k) returns to the identical mesh;
//  - slicing does not matter: status, message and info equal a one-call feed, and the fully
//    refined mesh equals the one-call decoder's.
#include <algorithm>
#include <cstring>

#include "fuzz_common.hpp"

using pmz_fuzz::check_mesh;
using pmz_fuzz::snapshot;

namespace {

struct Plan {
  const uint8_t* pairs = nullptr;
  size_t count = 0;
  size_t slice(size_t i) const {
    if (!count) return SIZE_MAX;
    uint8_t b = pairs[2 * (i % count)];
    return b < 128 ? size_t(b) + 1 : size_t(b - 127) * 61;  // 1..128, then 61..7869
  }
  uint8_t op(size_t i) const { return count ? pairs[2 * (i % count) + 1] : 0; }
};

pmz::DecoderLimits fuzz_limits() {
  // Tighter than the defaults so that libFuzzer's malloc limit flags allocations the limits
  // should have prevented, not legitimate big meshes.
  pmz::DecoderLimits l;
  l.max_vertices = 1u << 20;
  l.max_faces = 1u << 21;
  l.max_chunk_bytes = 1u << 22;
  return l;
}

template <class Fn>
void feed_sliced(pmz::Decoder& d, const uint8_t* p, size_t n, const Plan& plan, Fn between) {
  size_t at = 0;
  for (size_t i = 0; at < n; ++i) {
    size_t k = std::min(n - at, plan.slice(i));
    d.feed(p + at, k);
    at += k;
    between(i);
  }
}

void level_move(pmz::Decoder& d, uint8_t op) {
  const uint64_t k = op >> 2;
  switch (op & 3) {
    case 0: {  // refine: never fewer faces
      uint32_t before = d.face_count();
      uint64_t applied = d.splits_applied();
      uint64_t n = d.refine(k);
      PMZ_FUZZ_CHECK(n <= k);
      PMZ_FUZZ_CHECK(d.splits_applied() == applied + n);
      PMZ_FUZZ_CHECK(d.face_count() >= before);
      break;
    }
    case 1: {  // coarsen
      uint64_t applied = d.splits_applied();
      uint64_t n = d.coarsen(k);
      PMZ_FUZZ_CHECK(n == std::min(k, applied));
      PMZ_FUZZ_CHECK(d.splits_applied() == applied - n);
      break;
    }
    case 2: {  // face target, anywhere from 0 to a bit above the full count
      uint64_t target = d.info().full_faces * k / 48;
      d.set_face_target(target);
      if (d.status() == pmz::Status::ok && d.splits_applied() < d.splits_available())
        PMZ_FUZZ_CHECK(d.face_count() >= target);
      break;
    }
    case 3: {  // coarsen then refine: the identical mesh
      const pmz_fuzz::Snapshot before = snapshot(d);
      uint64_t n = d.coarsen(k + 1);
      check_mesh(d);
      uint64_t m = d.refine(n);
      if (m == n) PMZ_FUZZ_CHECK(snapshot(d) == before);
      break;
    }
  }
  check_mesh(d);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  Plan plan;
  plan.count = data[0] % 16;
  if (size < 1 + 2 * plan.count) return 0;
  plan.pairs = data + 1;
  const uint8_t* stream = data + 1 + 2 * plan.count;
  const size_t n = size - 1 - 2 * plan.count;
  const pmz::DecoderLimits limits = fuzz_limits();

  // Reference: one call.
  pmz::Decoder whole(limits);
  whole.feed(stream, n);
  check_mesh(whole);

  // Same bytes in slices, nothing else: identical outcome.
  pmz::Decoder sliced(limits);
  feed_sliced(sliced, stream, n, plan, [&](size_t) { check_mesh(sliced); });
  PMZ_FUZZ_CHECK(sliced.status() == whole.status());
  PMZ_FUZZ_CHECK(sliced.error_message() == whole.error_message());
  PMZ_FUZZ_CHECK(sliced.splits_available() == whole.splits_available());
  // After an error the count depends on where the failing slice ended; before, it may not.
  if (whole.status() == pmz::Status::ok)
    PMZ_FUZZ_CHECK(sliced.bytes_consumed() == whole.bytes_consumed());
  PMZ_FUZZ_CHECK(pmz_fuzz::same_info(sliced.info(), whole.info()));
  PMZ_FUZZ_CHECK(snapshot(sliced) == snapshot(whole));

  // Slices with level moves in between.
  pmz::Decoder moving(limits);
  feed_sliced(moving, stream, n, plan, [&](size_t i) {
    check_mesh(moving);
    level_move(moving, plan.op(i));
  });
  moving.finish();
  PMZ_FUZZ_CHECK(moving.status() != pmz::Status::ok || moving.info().complete);
  moving.refine();
  check_mesh(moving);
  whole.refine();
  check_mesh(whole);
  // A split that fails to apply truncates the available splits at the same index in both.
  if (moving.splits_applied() == whole.splits_applied())
    PMZ_FUZZ_CHECK(snapshot(moving) == snapshot(whole));
  // Down to the base mesh and back.
  const pmz_fuzz::Snapshot full = snapshot(moving);
  const uint64_t applied = moving.splits_applied();
  PMZ_FUZZ_CHECK(moving.coarsen() == applied);
  check_mesh(moving);
  moving.set_face_target(UINT64_MAX);
  check_mesh(moving);
  if (moving.splits_applied() == applied) PMZ_FUZZ_CHECK(snapshot(moving) == full);
  return 0;
}
