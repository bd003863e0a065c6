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

uint32_t load_u32(const uint8_t* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

void head_round_trip(const uint8_t* p, size_t n) {
  pmz::FileHeader h;
  const bool ok = pmz::read_head_payload(p, n, h);
  PMZ_FUZZ_CHECK(ok == (n >= pmz::kHeadPayloadSize));
  if (!ok) return;
  std::vector<uint8_t> out;
  pmz::write_head_payload(out, h);
  PMZ_FUZZ_CHECK(out.size() == pmz::kHeadPayloadSize);
  // Bytes 5..7 are reserved (written as zero, ignored on read).
  PMZ_FUZZ_CHECK(std::memcmp(out.data(), p, 5) == 0);
  PMZ_FUZZ_CHECK(std::memcmp(out.data() + 8, p + 8, pmz::kHeadPayloadSize - 8) == 0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<uint8_t> b;
  if (size < 8 || std::memcmp(data, pmz::kSignature, 8) != 0)
    b.assign(pmz::kSignature, pmz::kSignature + 8);
  b.insert(b.end(), data, data + size);

  for (size_t at = 8; b.size() - at >= pmz::kChunkHeaderSize;) {
    const uint32_t n = load_u32(&b[at + 4]);
    if (b.size() - at - pmz::kChunkHeaderSize < n) break;
    const uint8_t* payload = &b[at + pmz::kChunkHeaderSize];
    if (load_u32(&b[at]) == pmz::kChunkHead) head_round_trip(payload, n);
    const uint32_t crc = pmz::chunk_crc(&b[at], payload, n);
    for (int i = 0; i < 4; ++i) b[at + 8 + i] = uint8_t(crc >> (8 * i));
    at += pmz::kChunkHeaderSize + n;
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
