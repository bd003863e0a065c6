// SPDX-License-Identifier: MIT
// The container: signature, chunk framing and the HEAD/BASE/SPLT/END payload parsers. Random
// bytes almost never get past the CRCs, so this target repairs them: the input is a .pmz
// stream (the signature is prepended when missing) whose chunk CRCs are recomputed before
// decoding, so mutations of sizes, types and payloads reach the parsers. Also checks that
// read_head_payload/write_head_payload round-trip every field.
#include <cstring>
#include <vector>

#include "fuzz_common.hpp"
#include "pmz/format.hpp"

using pmz_fuzz::check_mesh;

namespace {

// A HEAD payload that parses writes back as the same fields (at least as many bytes: varints
// may have been written longer than needed, and trailing bytes are ignored).
void head_round_trip(const uint8_t* p, size_t n) {
  pmz::FileHeader h;
  if (!pmz::read_head_payload(p, n, h)) return;
  std::vector<uint8_t> out;
  pmz::write_head_payload(out, h);
  pmz::FileHeader back;
  PMZ_FUZZ_CHECK(pmz::read_head_payload(out.data(), out.size(), back));
  PMZ_FUZZ_CHECK(std::memcmp(&back, &h, sizeof h) == 0);  // the floats' bits too (NaN included)
  PMZ_FUZZ_CHECK(out.size() <= n);
  // The fixed bytes (version, position_bits, curvatures) are copied as they are.
  PMZ_FUZZ_CHECK(out[0] == p[0] && out[1] == p[1]);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<uint8_t> b;
  if (size < 8 || std::memcmp(data, pmz::kSignature, 8) != 0)
    b.assign(pmz::kSignature, pmz::kSignature + 8);
  b.insert(b.end(), data, data + size);

  for (size_t at = 8; at < b.size();) {
    pmz::ChunkFrame f;
    if (pmz::parse_chunk_frame(&b[at], b.size() - at, f) != pmz::FrameStatus::ok) break;
    if (f.payload_size > b.size() - at - f.header_size) break;
    const uint8_t* payload = &b[at + f.header_size];
    if (f.type == pmz::kChunkHead) head_round_trip(payload, size_t(f.payload_size));
    pmz::repair_chunk_crc(&b[at], f);
    at += f.header_size + size_t(f.payload_size);
  }

  pmz::DecoderLimits limits;
  limits.max_vertices = 1u << 20;
  limits.max_faces = 1u << 21;
  limits.max_chunk_bytes = 1u << 22;
  pmz::Decoder d(limits);
  const pmz::Status s = d.feed(b.data(), b.size());
  PMZ_FUZZ_CHECK(s != pmz::Status::bad_checksum);  // every complete chunk was repaired
  PMZ_FUZZ_CHECK(s != pmz::Status::truncated);     // only finish() says that
  check_mesh(d);
  d.refine();
  check_mesh(d);
  const pmz::Status f = d.finish();
  PMZ_FUZZ_CHECK(f != pmz::Status::ok || d.info().complete);
  PMZ_FUZZ_CHECK(f == pmz::Status::ok || !d.error_message().empty());
  d.coarsen();
  check_mesh(d);
  PMZ_FUZZ_CHECK(d.face_count() == (d.info().base_done ? d.info().base_faces : 0));
  return 0;
}
