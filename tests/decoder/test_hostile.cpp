// SPDX-License-Identifier: MIT
// Hostile input: streams crafted byte by byte (no encoder needed) that claim huge counts, bomb
// the decompressor, or are cut/damaged at every byte. The decoder must refuse with an error
// and a message, keep a valid mesh, allocate no more than the input can justify, and take
// time linear in the input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <vector>

#include "pmz/base_codec.hpp"
#include "pmz/decoder.hpp"
#include "pmz/fan_wedge.hpp"
#include "pmz/format.hpp"
#include "pmz/progressive_mesh.hpp"
#include "pmz/split_chunk.hpp"
#include "pmz/vertex_choice.hpp"

// ---- peak heap use of this test binary, through a replaced global operator new ----
namespace {
size_t g_live = 0, g_peak = 0, g_allocations = 0;
// Allocations still allowed before one fails with bad_alloc; the ones after it succeed again
// (negative: no injected failure; -2 once the failure happened).
long g_allocations_before_failure = -1;
constexpr size_t kHeader = 16;  // keeps the returned pointer 16-byte aligned
void* counted_alloc(size_t n) {
  if (g_allocations_before_failure == 0) {
    g_allocations_before_failure = -2;
    throw std::bad_alloc();
  }
  if (g_allocations_before_failure > 0) --g_allocations_before_failure;
  auto* p = static_cast<unsigned char*>(std::malloc(n + kHeader));
  if (!p) throw std::bad_alloc();
  std::memcpy(p, &n, sizeof n);
  g_live += n;
  ++g_allocations;
  if (g_live > g_peak) g_peak = g_live;
  return p + kHeader;
}
void counted_free(void* q) {
  if (!q) return;
  auto* p = static_cast<unsigned char*>(q) - kHeader;
  size_t n;
  std::memcpy(&n, p, sizeof n);
  g_live -= n;
  std::free(p);
}
}  // namespace
// Every form that pairs with the plain deletes (aligned forms keep the library's own pair).
void* operator new(size_t n) { return counted_alloc(n); }
void* operator new[](size_t n) { return counted_alloc(n); }
void* operator new(size_t n, const std::nothrow_t&) noexcept {
  try {
    return counted_alloc(n);
  } catch (const std::bad_alloc&) {
    return nullptr;
  }
}
void* operator new[](size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void operator delete(void* p) noexcept { counted_free(p); }
void operator delete[](void* p) noexcept { counted_free(p); }
void operator delete(void* p, size_t) noexcept { counted_free(p); }
void operator delete[](void* p, size_t) noexcept { counted_free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { counted_free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { counted_free(p); }

namespace {

// Bytes allocated with new above what was live when the scope began.
struct PeakScope {
  size_t start = g_live;
  PeakScope() { g_peak = g_live; }
  size_t peak() const { return g_peak - start; }
};

// ---- stream construction, following spec/format.md ----
using Bytes = std::vector<uint8_t>;

void varint(Bytes& out, uint64_t v) { pmz::put_varint(out, v); }
pmz::FileHeader header(uint32_t base_vertices, uint32_t base_faces, uint32_t splits,
                       uint32_t full_faces) {
  pmz::FileHeader h;
  h.position_bits = 14;
  h.base_vertices = base_vertices;
  h.base_faces = base_faces;
  h.total_splits = splits;
  h.full_faces = full_faces;
  for (int a = 0; a < 3; ++a) h.bbox_min[a] = -1, h.bbox_max[a] = 1;
  return h;
}

Bytes signature() { return Bytes(pmz::kSignature, pmz::kSignature + 8); }
void head(Bytes& file, const pmz::FileHeader& h) {
  Bytes p;
  pmz::write_head_payload(p, h);
  pmz::append_chunk(file, pmz::kChunkHead, p);
}

// A BASE payload coded as the writer codes it. encode_base numbers vertices and faces in its
// traversal order: coords and faces are replaced by the decoded ones (what the decoder's mesh
// holds); returns the decoded id of each given vertex.
std::vector<uint32_t> base_payload(std::vector<int32_t>& coords, std::vector<uint32_t>& faces,
                                   Bytes& payload) {
  const uint32_t n = uint32_t(coords.size() / 3), fn = uint32_t(faces.size() / 3);
  Bytes stream;
  std::vector<uint32_t> given_of, decoded_of(n);
  pmz::BaseMesh decoded;
  std::string error;
  EXPECT_TRUE(
      pmz::encode_base(coords.data(), n, faces.data(), fn, stream, given_of, decoded, error))
      << error;
  payload = stream;  // BASE: the stream alone (the counts are HEAD's)
  for (uint32_t d = 0; d < n; ++d) decoded_of[given_of[d]] = d;
  coords = decoded.coords;
  faces = decoded.faces;
  return decoded_of;
}

// Octahedron: 6 vertices, 8 faces, closed (every vertex interior, valence 4), as BASE codes it.
struct Octahedron {
  std::vector<uint32_t> faces = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4,
                                 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  std::vector<int32_t> coords = {16383, 8192, 8192, 0,    8192, 8192,  8192, 16383, 8192,
                                 8192,  0,    8192, 8192, 8192, 16383, 8192, 8192,  0};
  Bytes payload;
  Octahedron() { base_payload(coords, faces, payload); }
};
const Octahedron& octa() {
  static const Octahedron o;
  return o;
}
Bytes octa_base_payload() { return octa().payload; }

// Replays the decoder's mesh so crafted SPLT payloads carry the contexts the decoder computes
// (wedge and residual models depend on the mesh). Stops replaying once the ring work exceeds
// the decoder's budget: splits past it are never decoded, their contexts stay 0.
struct Replay {
  pmz::ProgressiveMesh pm;
  std::vector<int32_t> coords;
  pmz::WedgeScratch scratch;
  std::unique_ptr<pmz::SplitModels> models =
      std::make_unique<pmz::SplitModels>();  // carried across chunks
  pmz::VertexChoice choice;
  uint64_t work = 0, vertices = 6;  // vertices: as the decoder counts them (all splits)
  Replay() {
    std::string error;
    pm.build(6, octa().faces.data(), 8, error);
    coords = octa().coords;
    choice.reset(pm, coords.data(), 14);
  }
  // A group of one split at v: its code, choice bits appended to bits.
  pmz::GroupCode group(uint32_t v, std::vector<uint32_t>& bits) {
    choice.start_group();
    const uint32_t vs[1] = {v};
    bool near = false;
    EXPECT_TRUE(pmz::choice_bits(choice, pm, pm.vertex_count(), vs, bits, near));
    return {1, near};
  }
  // Applies the split at v with wedge symbols (0, 0) (valid on any ring) as the decoder does,
  // setting c's contexts (its residuals as given); false without a ring or a valid wedge.
  bool apply(uint32_t v, pmz::SplitSymbols& c) {
    if (!pm.gather_ring(v)) return false;
    work += pm.ring().size();
    c.wedge_context = pmz::wedge_context(uint32_t(pm.ring().size()), pm.ring_closed());
    const bool closed = pm.ring_closed();
    uint32_t a, b;
    if (!pmz::wedge_ranks(coords.data(), choice.degrees(), v, pm, 0, 0, a, b, scratch) ||
        !pm.split_gathered(v, a, b))
      return false;
    c.rank_context = pmz::rank_context(closed, scratch.confident);
    pmz::PositionPrediction pred;  // HEAD curvature 0, as header() writes
    pmz::predict_position(coords.data(), pm.u_ring(), pm.ring(), 0, 0, pred);
    std::copy(pred.context, pred.context + 3, c.residual_context);
    std::copy(pred.mix, pred.mix + 3, c.mix_context);
    int32_t cu[3];
    pmz::position_from_residuals(pred, c.residual, cu);
    coords.insert(coords.end(), cu, cu + 3);
    choice.applied(pm, coords.data(), a != pmz::kNoRank,
                   b != pmz::kNoRank);  // needs u's coordinates
    return true;
  }
};

// SPLT payload (the shared codec): splits at the given vertices, one group each, wedge
// symbols (0, 0) (valid on any ring: the best-scored candidate without interior vertices),
// residuals r.
Bytes split_payload(Replay& rp, const std::vector<uint32_t>& at, int32_t r = 0) {
  std::vector<pmz::SplitSymbols> codes;
  std::vector<pmz::GroupCode> groups;
  std::vector<uint32_t> bits;
  for (uint32_t v : at) {
    pmz::SplitSymbols c{v, 0, 0, 0, 0, {0, 0, 0}, {r, r, r}, {0, 0, 0}};
    groups.push_back(rp.group(v, bits));
    if (rp.work < (8u << 20)) rp.apply(v, c);
    codes.push_back(c);
  }
  Bytes p;
  pmz::encode_split_chunk(groups, bits, codes.data(), codes.size(), *rp.models, p);
  rp.vertices += at.size();
  return p;
}
Bytes split_payload(const std::vector<uint32_t>& at, int32_t r = 0) {
  Replay rp;
  return split_payload(rp, at, r);
}

// A small valid stream: octahedron, then `splits` splits in chunks of `per_chunk`, then END.
Bytes small_file(uint32_t splits = 12, uint32_t per_chunk = 4) {
  Bytes f = signature();
  head(f, header(6, 8, splits, 8 + 2 * splits));
  pmz::append_chunk(f, pmz::kChunkBase, octa_base_payload());
  Replay rp;
  for (uint32_t done = 0; done < splits;) {
    std::vector<uint32_t> at;
    for (uint32_t i = 0; i < per_chunk && done < splits; ++i, ++done)
      at.push_back((done * 7) % (6 + done));
    pmz::append_chunk(f, pmz::kChunkSplits, split_payload(rp, at, int32_t(done % 5) - 2));
  }
  pmz::append_chunk(f, pmz::kChunkEnd, {});
  return f;
}

void expect_valid(const pmz::Decoder& d) {
  for (uint32_t f = 0; f < d.face_count(); ++f) {
    const uint32_t* t = d.indices() + size_t(f) * 3;
    for (int k = 0; k < 3; ++k) ASSERT_LT(t[k], d.vertex_count());
    ASSERT_TRUE(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
  }
  if (d.info().base_done) {
    ASSERT_EQ(d.vertex_count(), d.info().base_vertices + d.splits_applied());
  }
  // Attribute wedges (spec/format.md section 14): every corner names an a-wedge of its own vertex.
  for (uint32_t c = 0; c < d.face_count() * 3 && d.wedge_count(); ++c) {
    ASSERT_LT(d.wedge_indices()[c], d.wedge_count());
    ASSERT_EQ(d.wedge_vertices()[d.wedge_indices()[c]], d.indices()[c]);
  }
  if (d.face_materials()) {
    for (uint32_t f = 0; f < d.face_count(); ++f)
      ASSERT_LT(d.face_materials()[f], d.material_count());
  }
}

// The frame of the chunk at p, if its header parses (spec/format.md section 3).
bool frame_at(const Bytes& b, size_t p, pmz::ChunkFrame& f) {
  return p < b.size() && pmz::parse_chunk_frame(&b[p], b.size() - p, f) == pmz::FrameStatus::ok;
}

void fix_crc(Bytes& b, size_t chunk_at) {
  pmz::ChunkFrame f;
  ASSERT_TRUE(frame_at(b, chunk_at, f));
  pmz::repair_chunk_crc(&b[chunk_at], f);
}

std::vector<size_t> chunk_offsets(const Bytes& b) {
  std::vector<size_t> at;
  pmz::ChunkFrame f;
  for (size_t p = 8; frame_at(b, p, f); p += f.header_size + size_t(f.payload_size))
    at.push_back(p);
  return at;
}

TEST(Hostile, SmallFileDecodes) {
  const Bytes f = small_file();
  pmz::Decoder d;
  ASSERT_EQ(d.feed(f.data(), f.size()), pmz::Status::ok) << d.error_message();
  ASSERT_EQ(d.finish(), pmz::Status::ok);
  EXPECT_EQ(d.refine(), 12u);
  EXPECT_EQ(d.face_count(), 8u + 24u);
  EXPECT_EQ(d.status(), pmz::Status::ok) << d.error_message();
  expect_valid(d);
}

// Bytes after END are ignored, whatever they are: a frame with a wrong CRC, a size varint of
// 11 bytes, a chunk over max_chunk_bytes (each refused before END), fed whole or byte by byte.
TEST(Hostile, BytesAfterEndAreIgnoredEvenMalformed) {
  const Bytes tails[] = {
      {pmz::kChunkSplits, 1, 0, 0, 0, 0, 0x5a},
      {pmz::kChunkHead, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0},
      {pmz::kChunkBase, 0xFF, 0xFF, 0xFF, 0xFF, 0x0F, 0, 0, 0, 0},
  };
  for (const Bytes& tail : tails) {
    Bytes f = small_file();
    f.insert(f.end(), tail.begin(), tail.end());
    for (size_t slice : {f.size(), size_t(1)}) {
      pmz::Decoder d(pmz::DecoderLimits{1 << 20, 1 << 20, 1 << 20});
      for (size_t at = 0; at < f.size(); at += slice)
        ASSERT_EQ(d.feed(f.data() + at, std::min(slice, f.size() - at)), pmz::Status::ok)
            << d.error_message();
      EXPECT_EQ(d.finish(), pmz::Status::ok);
      EXPECT_EQ(d.refine(), 12u);
    }
  }
}

// HEAD curvature and fine_curvature (spec/format.md section 4): 0..8; 9 and above are refused, 8
// decodes.
TEST(Hostile, CurvatureAboveEightIsRefused) {
  for (uint32_t value : {8u, 9u, 255u, 8u | 0x100u, 9u | 0x100u, 255u | 0x100u}) {
    const uint32_t curvature = value & 0xFF;
    const bool fine = value & 0x100;
    Bytes f = signature();
    pmz::FileHeader h = header(6, 8, 0, 8);
    (fine ? h.fine_curvature : h.curvature) = curvature;
    head(f, h);
    pmz::append_chunk(f, pmz::kChunkBase, octa_base_payload());
    pmz::append_chunk(f, pmz::kChunkEnd, {});
    pmz::Decoder d;
    const pmz::Status s = d.feed(f.data(), f.size());
    if (curvature <= pmz::kMaxCurvature) {
      EXPECT_EQ(s, pmz::Status::ok) << d.error_message();
      EXPECT_EQ(fine ? d.info().fine_curvature : d.info().curvature, curvature);
      EXPECT_EQ(d.face_count(), 8u);
    } else {
      EXPECT_EQ(s, pmz::Status::corrupt) << curvature;
      EXPECT_NE(d.error_message().find("curvature"), std::string::npos) << d.error_message();
    }
  }
}

// HEAD level (spec/format.md section 4): 0 and 1 decode (and are reported), 2 and above are
// refused as corrupt.
TEST(Hostile, LevelAboveOneIsRefused) {
  for (uint32_t level : {0u, 1u, 2u, 255u}) {
    Bytes f = signature();
    pmz::FileHeader h = header(6, 8, 0, 8);
    h.level = level;
    head(f, h);
    pmz::append_chunk(f, pmz::kChunkBase, octa_base_payload());
    pmz::append_chunk(f, pmz::kChunkEnd, {});
    pmz::Decoder d;
    const pmz::Status s = d.feed(f.data(), f.size());
    if (level <= 1) {
      EXPECT_EQ(s, pmz::Status::ok) << d.error_message();
      EXPECT_EQ(d.info().level, level);
      EXPECT_EQ(d.face_count(), 8u);
    } else {
      EXPECT_EQ(s, pmz::Status::corrupt) << level;
      EXPECT_NE(d.error_message().find("level"), std::string::npos) << d.error_message();
    }
  }
}

// HEAD's varint fields (spec/format.md section 4): a payload cut anywhere before bbox_max ends, or
// a flags / count varint of 2^32 or more (or of 11 bytes), is corrupt; bytes after bbox_max are
// ignored, and a varint written longer than needed reads as its value.
TEST(Hostile, HeadVarintsCutShortOrBeyondUint32AreCorrupt) {
  Bytes payload;
  pmz::write_head_payload(payload, header(6, 8, 0, 8));
  auto decode = [](const Bytes& p, std::string* message = nullptr) {
    Bytes f = signature();
    pmz::append_chunk(f, pmz::kChunkHead, p);
    pmz::append_chunk(f, pmz::kChunkBase, octa_base_payload());
    pmz::append_chunk(f, pmz::kChunkEnd, {});
    pmz::Decoder d;
    const pmz::Status s = d.feed(f.data(), f.size());
    if (message) *message = d.error_message();
    return s == pmz::Status::ok && d.face_count() == 8 ? pmz::Status::ok : s;
  };
  ASSERT_EQ(payload.size(), 35u);  // 2 + 1 + 4 + 4 one-byte varints + 24
  EXPECT_EQ(decode(payload), pmz::Status::ok);
  for (size_t n = 0; n < payload.size(); ++n) {
    std::string message;
    EXPECT_EQ(decode(Bytes(payload.begin(), payload.begin() + ptrdiff_t(n)), &message),
              pmz::Status::corrupt)
        << n;
    EXPECT_NE(message.find("HEAD"), std::string::npos) << message;
  }
  Bytes longer = payload;
  longer.insert(longer.end(), {1, 2, 3});  // fields of a later minor
  EXPECT_EQ(decode(longer), pmz::Status::ok);
  // Field k (0 flags, 1 base_vertices, 2 base_faces, 3 total_splits, 4 full_faces) replaced by
  // the varint bytes v. The fields' offsets in payload: flags at 2, the counts at 7 .. 10.
  auto with_field = [&](int k, const Bytes& v) {
    const size_t at = k == 0 ? 2 : size_t(6 + k);
    Bytes p(payload.begin(), payload.begin() + ptrdiff_t(at));
    p.insert(p.end(), v.begin(), v.end());
    p.insert(p.end(), payload.begin() + ptrdiff_t(at + 1), payload.end());
    return p;
  };
  const Bytes two32 = {0x80, 0x80, 0x80, 0x80, 0x10};  // 2^32
  const Bytes eleven = {0x80, 0x80, 0x80, 0x80, 0x80, 0x80,
                        0x80, 0x80, 0x80, 0x80, 0x00};  // 0 in 11 bytes
  for (int k = 0; k < 5; ++k) {
    std::string message;
    EXPECT_EQ(decode(with_field(k, two32), &message), pmz::Status::corrupt) << k;
    EXPECT_NE(message.find("HEAD malformed"), std::string::npos) << k << ": " << message;
    EXPECT_EQ(decode(with_field(k, eleven), &message), pmz::Status::corrupt) << k;
    EXPECT_NE(message.find("HEAD malformed"), std::string::npos) << k << ": " << message;
  }
  // base_vertices 6 written in 5 bytes: the same HEAD.
  EXPECT_EQ(decode(with_field(1, {0x86, 0x80, 0x80, 0x80, 0x00})), pmz::Status::ok);
}

// ---- counts beyond the limits ----

// Vertex ids are uint32 (0xFFFFFFFF is "none"): base_vertices + total_splits must stay below
// 2^32 whatever the limits allow (spec/format.md section 4; format 6.0 stored full_vertices as a
// u32).
TEST(Hostile, FullVerticesBeyondUint32AreCorruptWhateverTheLimits) {
  pmz::DecoderLimits limits;
  limits.max_vertices = ~uint64_t(0);
  limits.max_faces = ~uint64_t(0);
  for (const auto& [bv, splits] : {std::pair<uint32_t, uint32_t>{6, 0xFFFFFFFFu - 5},
                                   {0xFFFFFFFFu, 1},
                                   {0x80000000u, 0x80000000u}}) {
    Bytes f = signature();
    head(f, header(bv, 8, splits, 8));
    pmz::Decoder d(limits);
    EXPECT_EQ(d.feed(f.data(), f.size()), pmz::Status::corrupt) << bv << " + " << splits;
    EXPECT_NE(d.error_message().find("vertices"), std::string::npos) << d.error_message();
  }
  // 2^32 - 1 vertices in all is still a valid HEAD (ids up to 0xFFFFFFFE).
  Bytes f = signature();
  head(f, header(6, 8, 0xFFFFFFFFu - 6, 8));
  pmz::Decoder d(limits);
  EXPECT_EQ(d.feed(f.data(), f.size()), pmz::Status::ok) << d.error_message();
  EXPECT_EQ(d.info().full_vertices, 0xFFFFFFFFull);
}

TEST(Hostile, HeaderCountsBeyondLimitsAreRefusedWithoutAllocating) {
  pmz::DecoderLimits limits;
  limits.max_vertices = 1000;
  limits.max_faces = 1500;
  struct Case {
    uint32_t bv, bf, splits, ff;
  } cases[] = {
      {1001, 8, 0, 8},                       // base vertices over the limit
      {6, 1501, 0, 1501},                    // base faces over the limit
      {6, 8, 995, 8 + 1990},                 // full vertices over the limit
      {6, 8, 900, 1501},                     // full faces over the limit
      {0xFFFFFFFFu - 5, 8, 5, 18},           // full vertices near 2^32
      {6, 8, 0xFFFFFFFFu - 6, 0xFFFFFFFFu},  // billions of splits
  };
  for (const Case& c : cases) {
    Bytes f = signature();
    pmz::FileHeader h = header(c.bv, c.bf, c.splits, c.ff);
    head(f, h);
    pmz::append_chunk(f, pmz::kChunkBase, octa_base_payload());
    PeakScope scope;
    pmz::Decoder d(limits);
    const pmz::Status s = d.feed(f.data(), f.size());
    EXPECT_TRUE(s == pmz::Status::limit_exceeded || s == pmz::Status::corrupt)
        << c.bv << " " << c.splits << ": " << pmz::status_name(s);
    EXPECT_FALSE(d.error_message().empty());
    EXPECT_EQ(d.face_count(), 0u);
    EXPECT_LT(scope.peak(), 64u << 10) << "bytes allocated for a refused header";
  }
}

TEST(Hostile, ChunkClaimingHugePayloadBuffersOnlyWhatArrived) {
  // Within max_chunk_bytes, so the decoder waits for the payload; it must not reserve it.
  Bytes f = signature();
  head(f, header(6, 8, 4, 16));
  const uint8_t big[] = {
      pmz::kChunkSplits, 0x80, 0x80, 0x80, 0x78, 0, 0, 0, 0};  // 240 MB (15 << 24)
  f.insert(f.end(), big, big + sizeof big);
  f.resize(f.size() + 1000, 0x55);
  PeakScope scope;
  pmz::Decoder d;
  for (size_t at = 0; at < f.size(); at += 100)
    ASSERT_EQ(d.feed(&f[at], std::min<size_t>(100, f.size() - at)), pmz::Status::ok);
  EXPECT_LT(scope.peak(), 256u << 10);
  EXPECT_EQ(d.finish(), pmz::Status::truncated);
}

// The payload size is checked against max_chunk_bytes when the frame header is complete, before
// anything of the payload is buffered; a size varint of more than 10 bytes is malformed.
TEST(Hostile, ChunkOverTheLimitIsRefusedFromItsHeader) {
  pmz::DecoderLimits limits;
  limits.max_chunk_bytes = 4096;
  struct Case {
    std::vector<uint8_t> size;  // the varint
    pmz::Status want;
  } cases[] = {
      {{0x81, 0x20}, pmz::Status::limit_exceeded},                    // 4097
      {{0xFF, 0xFF, 0xFF, 0xFF, 0x0F}, pmz::Status::limit_exceeded},  // 2^32 - 1
      {{0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x01},
       pmz::Status::limit_exceeded},  // 2^63
      {{0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x02},
       pmz::Status::corrupt},  // beyond 64 bits
      {{0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x00},
       pmz::Status::corrupt},  // 11 bytes
  };
  for (const Case& c : cases)
    for (size_t slice : {size_t(1), size_t(1) << 20}) {
      Bytes f = signature();
      head(f, header(6, 8, 4, 16));
      f.push_back(0x7F);  // an unknown type: its size is checked all the same
      f.insert(f.end(), c.size.begin(), c.size.end());
      f.insert(f.end(), 4, 0);  // CRC
      PeakScope scope;
      pmz::Decoder d(limits);
      pmz::Status s = pmz::Status::ok;
      for (size_t at = 0; at < f.size() && s == pmz::Status::ok; at += slice)
        s = d.feed(&f[at], std::min(slice, f.size() - at));
      EXPECT_EQ(s, c.want) << c.size.size() << "-byte size, slices of " << slice;
      EXPECT_NE(d.error_message().find("chunk"), std::string::npos) << d.error_message();
      EXPECT_LT(scope.peak(), 64u << 10);
    }
}

// BASE counts far beyond what its bytes can hold (spec/format.md section 7: at most 384 faces and
// 64 vertices per byte of the range-coded stream): refused before the per-vertex and per-face
// arrays are allocated. The same counts are fine for the limits, so only that check stops them.
TEST(Hostile, BaseCountsBeyondItsBytesDoNotAllocate) {
  for (const auto& [nv, nf] : {std::pair<uint32_t, uint32_t>{1000000, 8}, {6, 4000000}}) {
    Bytes f = signature();
    head(f, header(nv, nf, 0, nf));  // BASE's counts are HEAD's
    pmz::append_chunk(f, pmz::kChunkBase, octa().payload);
    PeakScope scope;
    pmz::Decoder d;
    EXPECT_EQ(d.feed(f.data(), f.size()), pmz::Status::corrupt) << nv << " " << nf;
    EXPECT_NE(d.error_message().find("can hold"), std::string::npos) << d.error_message();
    EXPECT_LE(scope.peak(), size_t(64) << 10)
        << nv << " " << nf << ": allocation driven by a claimed count";
    expect_valid(d);
    EXPECT_EQ(d.face_count(), 0u);
  }
}

// The octahedron's BASE cut short at every length, and with counts that do not match its
// stream (fewer vertices than it creates, more faces than it holds): corrupt, no mesh.
TEST(Hostile, BaseTruncatedOrMiscountedIsCorrupt) {
  const Bytes& full = octa().payload;
  auto feed_base = [](const Bytes& payload, uint32_t nv, uint32_t nf) {
    Bytes f = signature();
    head(f, header(nv, nf, 0, nf));
    pmz::append_chunk(f, pmz::kChunkBase, payload);
    pmz::Decoder d;
    const pmz::Status s = d.feed(f.data(), f.size());
    expect_valid(d);
    return std::pair<pmz::Status, bool>(s, d.info().base_done);
  };
  ASSERT_EQ(feed_base(full, 6, 8).first, pmz::Status::ok);
  for (size_t n = 0; n < full.size(); ++n) {
    const auto [s, done] = feed_base(Bytes(full.begin(), full.begin() + n), 6, 8);
    EXPECT_EQ(s, pmz::Status::corrupt) << "cut at " << n;
    EXPECT_FALSE(done);
  }
  for (const auto& [nv, nf] : {std::pair<uint32_t, uint32_t>{5, 8}, {3, 8}, {6, 9}, {6, 12}}) {
    const auto [s, done] = feed_base(full, nv, nf);
    EXPECT_EQ(s, pmz::Status::corrupt) << nv << " vertices, " << nf << " faces";
    EXPECT_FALSE(done);
  }
}

// A BASE vertex whose faces form several fans (two triangles meeting at a vertex, two
// octahedron halves meeting at their apex) is refused: the spec defines splits only at a
// vertex with one fan. The writer never emits one (mesh repair gives each fan its own vertex).
TEST(Hostile, BaseVertexInSeveralFansIsRefused) {
  struct Case {
    std::vector<uint32_t> faces;
    uint32_t vertices;
  };
  const Case cases[] = {
      {{0, 1, 2, 0, 3, 4}, 5},  // open fans: a bow tie
      // closed fans: two square pyramids (apex 0, rims 1-4 and 5-8) glued at the apex, each
      // closed by its base
      {{0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1, 2, 1, 4, 2, 4, 3,  //
        0, 6, 5, 0, 7, 6, 0, 8, 7, 0, 5, 8, 5, 6, 8, 6, 7, 8},
       9},
  };
  for (const Case& c : cases) {
    std::vector<int32_t> coords;
    for (uint32_t v = 0; v < c.vertices; ++v)
      for (int a = 0; a < 3; ++a) coords.push_back(int32_t((v * 37 + uint32_t(a) * 11) % 97));
    std::vector<uint32_t> faces = c.faces;
    Bytes payload;
    base_payload(coords, faces, payload);
    const uint32_t fn = uint32_t(faces.size() / 3);
    Bytes f = signature();
    head(f, header(c.vertices, fn, 0, fn));
    pmz::append_chunk(f, pmz::kChunkBase, payload);
    pmz::append_chunk(f, pmz::kChunkEnd, {});
    pmz::Decoder d;
    EXPECT_EQ(d.feed(f.data(), f.size()), pmz::Status::corrupt) << c.vertices << " vertices";
    EXPECT_NE(d.error_message().find("several fans"), std::string::npos) << d.error_message();
    EXPECT_FALSE(d.info().base_done);
    expect_valid(d);
  }
}

// Random BASE streams with small counts, and the octahedron's with a byte changed: decoded or
// refused, never a crash; the decoder's mesh is valid either way.
TEST(Hostile, RandomAndMutatedBaseStreams) {
  uint64_t state = 0x9E3779B97F4A7C15ull;
  auto rnd = [&] {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return state;
  };
  int decoded = 0, refused = 0;
  for (int trial = 0; trial < 6000; ++trial) {
    const bool mutated = trial % 2;
    const uint32_t nv = mutated ? 6 : 3 + rnd() % 12, nf = mutated ? 8 : 1 + rnd() % 16;
    Bytes p;
    if (mutated) {
      p = octa().payload;
      p[rnd() % p.size()] ^= uint8_t(1 + rnd() % 255);
    } else {
      p.push_back(0);
      for (size_t i = 0, len = 4 + rnd() % 200; i < len; ++i) p.push_back(uint8_t(rnd()));
    }
    Bytes f = signature();
    head(f, header(nv, nf, 0, nf));
    pmz::append_chunk(f, pmz::kChunkBase, p);
    pmz::Decoder d;
    const pmz::Status s = d.feed(f.data(), f.size());
    EXPECT_TRUE(s == pmz::Status::ok || s == pmz::Status::corrupt ||
                s == pmz::Status::limit_exceeded)
        << int(s);
    if (s == pmz::Status::ok) {
      decoded += mutated;
      EXPECT_EQ(d.face_count(), nf);
    } else {
      ++refused;
      EXPECT_FALSE(d.error_message().empty());
      EXPECT_EQ(d.face_count(), 0u);
    }
    expect_valid(d);
  }
  EXPECT_GT(decoded, 0);
  EXPECT_GT(refused, 3000);
}

// A SPLT chunk claiming 60 splits per byte (within the 64 allowed) over streams of zeros: every
// bit decodes as 0, so its groups are all of one split and cheap enough (about 0.05 bit each)
// to be accepted; the group and split records it allocates stay proportional to the chunk, and
// its first split is refused (the vertex choice reads only 0 bits: the candidates run out).
// With 0xFF streams the first group's size reads a bit length above 32: refused on arrival.
TEST(Hostile, SplitCountIsBoundedByTheChunkBytes) {
  const uint32_t n = 1u << 24;
  for (const uint8_t fill : {uint8_t(0), uint8_t(0xFF)})
    for (size_t junk : {size_t(100), size_t(1000), size_t(10000)}) {
      Bytes f = signature();
      head(f, header(6, 8, n, 8 + 2 * n));
      pmz::append_chunk(f, pmz::kChunkBase, octa_base_payload());
      Bytes p;
      varint(p, junk * 60);  // claimed splits, within 64 per byte
      varint(p, junk / 2);   // connectivity, then geometry to the end
      p.resize(p.size() + junk, fill);
      pmz::append_chunk(f, pmz::kChunkSplits, p);
      PeakScope scope;
      pmz::Decoder d;
      d.feed(f.data(), f.size());
      // Per split its record and at most one group's, plus the file's models (allocated once).
      EXPECT_LT(scope.peak(), 64 * 24 * p.size() + sizeof(pmz::SplitModels) + (64u << 10)) << junk;
      EXPECT_EQ(d.splits_available(), fill ? 0u : junk * 60) << junk;
      EXPECT_EQ(d.status(), fill ? pmz::Status::corrupt : pmz::Status::ok) << junk;
      EXPECT_EQ(d.refine(), 0u);
      EXPECT_EQ(d.status(), pmz::Status::corrupt) << junk;
      expect_valid(d);
    }
}

TEST(Hostile, SplitCountBeyondItsStreamsIsRefusedBeforeAllocating) {
  // HEAD and SPLT agree on 100 M splits (under the default limits), but the streams hold 4.
  const uint32_t n = 100000000;
  Bytes f = signature();
  head(f, header(6, 8, n, 8 + 2 * n));
  pmz::append_chunk(f, pmz::kChunkBase, octa_base_payload());
  Bytes p = split_payload({0, 1, 2, 3});
  Bytes q;
  varint(q, n);
  const size_t count_len = 1;  // split_payload wrote varint(4): one byte
  q.insert(q.end(), p.begin() + ptrdiff_t(count_len), p.end());
  pmz::append_chunk(f, pmz::kChunkSplits, q);
  PeakScope scope;
  pmz::Decoder d;
  EXPECT_EQ(d.feed(f.data(), f.size()), pmz::Status::corrupt);
  EXPECT_LT(scope.peak(), 1u << 20);
  EXPECT_EQ(d.face_count(), 8u);
}

// ---- time linear in the input ----

TEST(Hostile, ManyTinyChunksDecodeInLinearTime) {
  // Unknown empty chunks: 6 bytes each, the cheapest work per byte an attacker can ask for.
  // The work is counted, not timed: a feed() copies at most its slice and what was left of
  // one incomplete chunk, and parses from there, so what it holds between calls (the heap's
  // peak: no more than a chunk header and a slice) and its allocations bound the work per byte.
  // A decoder that kept or re-parsed the stream from an earlier point would hold more.
  auto make = [](size_t chunks) {
    Bytes f = signature();
    head(f, header(6, 8, 0, 8));
    pmz::append_chunk(f, pmz::kChunkBase, octa_base_payload());
    for (size_t i = 0; i < chunks; ++i) pmz::append_chunk(f, 0x7F, {});
    pmz::append_chunk(f, pmz::kChunkEnd, {});
    return f;
  };
  struct Work {
    size_t peak, allocations;
  };
  auto decode = [](const Bytes& f, size_t slice) {
    const size_t allocations = g_allocations;
    PeakScope scope;
    {
      pmz::Decoder d;
      for (size_t at = 0; at < f.size(); at += slice)
        d.feed(&f[at], std::min(slice, f.size() - at));
      EXPECT_EQ(d.finish(), pmz::Status::ok) << d.error_message();
      EXPECT_EQ(d.bytes_consumed(), f.size());
    }
    return Work{scope.peak(), g_allocations - allocations};
  };
  const Bytes small = make(50000), large = make(200000);  // 300 KB, 1.2 MB
  for (size_t slice : {size_t(1), size_t(7), size_t(1) << 20}) {
    const Work ws = decode(small, slice), wl = decode(large, slice);
    // What stays buffered does not grow with the stream (the mesh and models: under 64 KB).
    EXPECT_LT(wl.peak, (64u << 10) + 2 * std::min(slice, large.size())) << "slice " << slice;
    EXPECT_LE(wl.peak, ws.peak + 2 * slice) << "slice " << slice;
    // 4x the chunks: at most 4x the allocations (linear), plus a constant.
    EXPECT_LE(wl.allocations, 4 * ws.allocations + 16)
        << "slice " << slice << ": " << ws.allocations << " -> " << wl.allocations;
  }
}

// Every split at the same vertex grows its valence by one, and each split walks the ring of
// its vertex (O(valence)): without a bound, refining is quadratic in a stream the range coder
// shrinks to ~1 byte per 8 splits (measured at c8f2892: 4000 splits 0.07 s CPU, 16000 splits
// 1.16 s). The decoder must refuse (limit_exceeded) or stay linear. The work is counted: the
// valence of each split's vertex just before its split (faces around it, kept up to date here
// from the decoder's change report), summed; spec/format.md section 12 bounds it by 64 splits +
// 2^22.
TEST(Hostile, SplitsPilingOnOneVertexStayLinear) {
  auto make = [](uint32_t n) {
    Bytes f = signature();
    head(f, header(6, 8, n, 8 + 2 * n));
    pmz::append_chunk(f, pmz::kChunkBase, octa_base_payload());
    pmz::append_chunk(f, pmz::kChunkSplits, split_payload(std::vector<uint32_t>(n, 0)));
    pmz::append_chunk(f, pmz::kChunkEnd, {});
    return f;
  };
  auto ring_work = [](const Bytes& f, uint32_t n) {
    pmz::Decoder d;
    d.feed(f.data(), f.size());
    std::vector<uint32_t> faces_at, indices(d.indices(), d.indices() + d.face_count() * 3);
    faces_at.assign(d.vertex_count(), 0);
    for (uint32_t x : indices) ++faces_at[x];
    uint64_t work = 0, applied = 0;
    for (;;) {
      d.clear_changes();
      if (d.refine(1) != 1) break;
      ++applied;
      const pmz::MeshChanges& c = d.changes();
      const uint32_t u = d.vertex_count() - 1, v = d.split_parents()[u];
      work += faces_at[v];  // v's fan before its split: the ring the split walked
      faces_at.resize(d.vertex_count(), 0);
      auto rewrite = [&](uint32_t face) {
        for (int k = 0; k < 3; ++k) {
          if (face * 3 + k < indices.size()) --faces_at[indices[face * 3 + k]];
          const uint32_t now = d.indices()[face * 3 + k];
          if (face * 3 + k < indices.size())
            indices[face * 3 + k] = now;
          else
            indices.push_back(now);
          ++faces_at[now];
        }
      };
      for (uint32_t face : c.modified_faces) rewrite(face);
      for (uint32_t face = c.face_begin; face < d.face_count(); ++face) rewrite(face);
    }
    expect_valid(d);
    if (applied < n) {
      EXPECT_EQ(d.status(), pmz::Status::limit_exceeded) << d.error_message();
      EXPECT_FALSE(d.error_message().empty());
    }
    EXPECT_LE(work, 65 * applied + (1u << 22) + 64) << applied << " splits applied";
    return work;
  };
  const uint32_t small = 4000, large = 16000;
  const uint64_t ws = ring_work(make(small), small), wl = ring_work(make(large), large);
  // 4x the splits: linear is at most 4x the work, quadratic 16x.
  EXPECT_GT(ws, 0u);
  EXPECT_LE(wl, 4 * ws + (1u << 22))
      << ws << " ring steps for " << small << " splits, " << wl << " for " << large;
}

// Wedge symbols at 2^32 - 1 (count or rank): out of range for every ring, so the split is
// refused and the mesh stays at the split before; no 32-bit wrap-around may turn them into a
// wedge taken modulo k. The first split gives u = 6 a closed fan of 3 faces.
TEST(Hostile, WedgeSymbolsAtUint32MaxAreInvalid) {
  for (int which = 0; which < 2; ++which) {
    // Split 0 as the decoder sees it (contexts from a replay), then split 6 with the bad symbol.
    Replay rp;
    std::vector<pmz::SplitSymbols> codes(2);
    std::vector<pmz::GroupCode> groups;
    std::vector<uint32_t> bits;
    groups.push_back(rp.group(0, bits));
    ASSERT_TRUE(rp.pm.gather_ring(0));
    codes[0] = {0,
                pmz::wedge_context(uint32_t(rp.pm.ring().size()), rp.pm.ring_closed()),
                0,
                0,
                rp.pm.ring_closed() ? 1u : 0u,
                {0, 0, 0},
                {0, 0, 0},
                {0, 0, 0}};
    uint32_t a, b;
    ASSERT_TRUE(
        pmz::wedge_ranks(rp.coords.data(), rp.choice.degrees(), 0, rp.pm, 0, 0, a, b, rp.scratch));
    codes[0].rank_context = pmz::rank_context(rp.pm.ring_closed(), rp.scratch.confident);
    ASSERT_TRUE(rp.pm.split_gathered(0, a, b));
    pmz::PositionPrediction pred;
    pmz::predict_position(rp.coords.data(), rp.pm.u_ring(), rp.pm.ring(), 0, 0, pred);
    std::copy(pred.context, pred.context + 3, codes[0].residual_context);
    std::copy(pred.mix, pred.mix + 3, codes[0].mix_context);
    int32_t cu[3];
    pmz::position_from_residuals(pred, codes[0].residual, cu);
    rp.coords.insert(rp.coords.end(), cu, cu + 3);
    rp.choice.applied(rp.pm, rp.coords.data(), a != pmz::kNoRank, b != pmz::kNoRank);
    groups.push_back(rp.group(6, bits));
    ASSERT_TRUE(rp.pm.gather_ring(6));
    ASSERT_TRUE(rp.pm.ring_closed());
    ASSERT_EQ(rp.pm.ring().size(), 3u);
    // The rank's context as the decoder computes it for count 0 (which == 1; unused for which ==
    // 0).
    ASSERT_TRUE(pmz::wedge_scores(rp.coords.data(), rp.choice.degrees(), 6, rp.pm, 0, rp.scratch));
    codes[1] = {6,
                pmz::wedge_context(3, true),
                which == 0 ? 0xFFFFFFFFu : 0u,
                which == 1 ? 0xFFFFFFFFu : 0u,
                pmz::rank_context(true, rp.scratch.confident),
                {0, 0, 0},
                {0, 0, 0},
                {0, 0, 0}};
    Bytes f = signature();
    head(f, header(6, 8, 2, 12));
    pmz::append_chunk(f, pmz::kChunkBase, octa_base_payload());
    Bytes p;
    pmz::encode_split_chunk(groups, bits, codes.data(), codes.size(), *rp.models, p);
    pmz::append_chunk(f, pmz::kChunkSplits, p);
    pmz::append_chunk(f, pmz::kChunkEnd, {});
    pmz::Decoder d;
    ASSERT_EQ(d.feed(f.data(), f.size()), pmz::Status::ok) << d.error_message();
    EXPECT_EQ(d.refine(), 1u) << which;
    EXPECT_EQ(d.status(), pmz::Status::corrupt) << which;
    expect_valid(d);
    EXPECT_EQ(d.face_count(), 10u);
    EXPECT_EQ(d.coarsen(), 1u);
    EXPECT_EQ(d.refine(), 1u);  // the split before the bad one stays usable
    EXPECT_EQ(d.face_count(), 10u);
  }
}

// Vertex choice exclusion (spec/format.md section 9.2) acts kChoiceLag splits behind: a group that
// splits two adjacent vertices closer than that (0, then 2 in 0's ring on the octahedron; a writer
// never codes it) is within the syntax and decodes consistently, split after split: the mesh
// stays valid and levels reproduce both ways.
TEST(Hostile, VertexChoiceAdjacentWithinTheLagDecodesConsistently) {
  Replay rp;
  Bytes f = signature();
  head(f, header(6, 8, 2, 12));
  pmz::append_chunk(f, pmz::kChunkBase, octa_base_payload());
  std::vector<uint32_t> bits;
  rp.choice.start_group();
  rp.choice.begin_scan(false, rp.pm.vertex_count(), 2);
  EXPECT_EQ(rp.choice.scan(&rp.pm, 2,
                           [&](uint32_t w, uint32_t ctx) {
                             const bool hit = w == 0 || w == 2;
                             bits.push_back(ctx << 1 | (hit ? 1u : 0u));
                             return hit ? 1 : 0;
                           }),
            1);
  ASSERT_EQ(bits.size(), 3u);  // 0, 1, 2
  // The symbols the decoder reads: wedges (0, 0) with its contexts, residuals 0.
  std::vector<pmz::SplitSymbols> codes;
  for (uint32_t v : {0u, 2u}) {
    pmz::SplitSymbols c{v, 0, 0, 0, 0, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    ASSERT_TRUE(rp.apply(v, c));
    codes.push_back(c);
  }
  Bytes p;
  pmz::encode_split_chunk({{2, false}}, bits, codes.data(), codes.size(), *rp.models, p);
  pmz::append_chunk(f, pmz::kChunkSplits, p);
  pmz::append_chunk(f, pmz::kChunkEnd, {});
  pmz::Decoder d;
  ASSERT_EQ(d.feed(f.data(), f.size()), pmz::Status::ok) << d.error_message();
  EXPECT_EQ(d.refine(), 2u);
  EXPECT_EQ(d.status(), pmz::Status::ok) << d.error_message();
  expect_valid(d);
  EXPECT_EQ(d.face_count(), 12u);
  EXPECT_EQ(d.vertex_count(), 8u);
  const std::vector<uint32_t> full(d.indices(), d.indices() + d.face_count() * 3);
  EXPECT_EQ(std::vector<uint32_t>(rp.pm.corner_vertex.begin(), rp.pm.corner_vertex.end()), full);
  EXPECT_EQ(d.coarsen(), 2u);
  EXPECT_EQ(d.refine(), 2u);
  EXPECT_EQ(std::vector<uint32_t>(d.indices(), d.indices() + d.face_count() * 3), full);
}

// Vertex choice (spec/format.md section 9.2): a group whose candidates run out before its splits
// are all found (a near group with no previous group; no candidate bit set among all vertices; none
// set among a near list) passes the chunk checks, and is refused when its first split is
// applied: status corrupt, the mesh at the split before, which stays usable.
TEST(Hostile, VertexChoiceRunningOutOfCandidatesIsRefused) {
  for (int which = 0; which < 3; ++which) {
    Replay rp;
    Bytes f = signature();
    head(f, header(6, 8, which == 2 ? 2 : 1, which == 2 ? 12 : 10));
    pmz::append_chunk(f, pmz::kChunkBase, octa_base_payload());
    if (which == 2)
      pmz::append_chunk(f, pmz::kChunkSplits, split_payload(rp, {0}));  // a good first group
    std::vector<uint32_t> bits;
    rp.choice.start_group();
    const bool near = which != 1;
    // Every candidate's bit 0, with the contexts the decoder uses (none for an empty near list).
    rp.choice.begin_scan(near, rp.pm.vertex_count(), 1);
    EXPECT_EQ(rp.choice.scan(&rp.pm, 1,
                             [&](uint32_t, uint32_t ctx) {
                               bits.push_back(ctx << 1);
                               return 0;
                             }),
              0);
    EXPECT_EQ(bits.size(), which == 0 ? 0u : 6u);  // all 6 vertices / 0's ring of 4, 0 and u
    const pmz::SplitSymbols code{0, 0, 0, 0, 0, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    Bytes p;
    pmz::encode_split_chunk({{1, near}}, bits, &code, 1, *rp.models, p);
    pmz::append_chunk(f, pmz::kChunkSplits, p);
    pmz::append_chunk(f, pmz::kChunkEnd, {});
    pmz::Decoder d;
    ASSERT_EQ(d.feed(f.data(), f.size()), pmz::Status::ok) << which << ": " << d.error_message();
    const uint64_t good = which == 2 ? 1 : 0;
    EXPECT_EQ(d.refine(), good) << which;
    EXPECT_EQ(d.status(), pmz::Status::corrupt) << which;
    EXPECT_NE(d.error_message().find("vertex choice"), std::string::npos) << d.error_message();
    expect_valid(d);
    EXPECT_EQ(d.face_count(), 8u + 2 * good);
    EXPECT_EQ(d.coarsen(), good);
    EXPECT_EQ(d.refine(), good);
    EXPECT_EQ(d.face_count(), 8u + 2 * good);
  }
}

// An allocation failing anywhere while refining (out_of_memory) leaves the mesh valid at the
// level reached, with every count consistent; once memory is back, the decoder still reaches
// the same full mesh as without the failure (no split applied twice, no symbol lost). With
// clear_changes() first, the change list grows while refining too.
// Refines d by `step` with its n-th allocation from now failing; false when none failed (step
// allocates fewer). The failure is either reported or absorbed (the change list then says
// everything changed); the mesh stays valid.
template <class Step>
bool refine_failing_allocation(pmz::Decoder& d, long n, Step step) {
  d.clear_changes();
  g_allocations_before_failure = n;
  step();
  const bool failed = g_allocations_before_failure == -2;
  g_allocations_before_failure = -1;
  if (!failed) return false;
  if (d.status() != pmz::Status::ok)
    EXPECT_EQ(d.status(), pmz::Status::out_of_memory) << n;
  else
    EXPECT_TRUE(d.changes().all) << n;
  expect_valid(d);
  return true;
}

TEST(Hostile, AllocationFailureWhileRefiningKeepsALevel) {
  const Bytes f = small_file(24, 8);
  pmz::Decoder ref;
  ASSERT_EQ(ref.feed(f.data(), f.size()), pmz::Status::ok) << ref.error_message();
  ASSERT_EQ(ref.refine(), 24u);
  const std::vector<uint32_t> faces(ref.indices(), ref.indices() + size_t(ref.face_count()) * 3);
  const std::vector<float> positions(ref.positions(),
                                     ref.positions() + size_t(ref.vertex_count()) * 3);
  uint32_t failures = 0;
  for (long n = 0; n < 400; ++n) {
    pmz::Decoder d;
    ASSERT_EQ(d.feed(f.data(), f.size()), pmz::Status::ok);
    if (!refine_failing_allocation(d, n, [&] { d.set_face_target(8 + 2 * 24); })) break;
    ++failures;
    ASSERT_EQ(size_t(d.face_count()), 8 + 2 * d.splits_applied()) << n;
    // Memory is back: the same full mesh as without the failure.
    d.coarsen();
    d.refine();
    ASSERT_EQ(d.splits_applied(), 24u) << n;
    ASSERT_EQ(std::vector<uint32_t>(d.indices(), d.indices() + size_t(d.face_count()) * 3), faces)
        << n;
    ASSERT_EQ(std::vector<float>(d.positions(), d.positions() + size_t(d.vertex_count()) * 3),
              positions)
        << n;
  }
  EXPECT_GT(failures, 3u);
}

// u's fan can be larger than any fan walked before: a bipyramid apex of valence 62 split with
// 60 interior ring vertices gives u a fan of 63 faces. Coarsening does not walk it: it undoes
// the split from the sector recorded when the split was applied (60 faces, within the scratch
// v's ring needed then), so with every allocation failing it still undoes the split, and
// nothing escapes coarsen() (the C API lets no exception cross it).
TEST(Hostile, CoarseningNeedsNoAllocation) {
  constexpr uint32_t n = 62, nv = n + 2, nf = 2 * n;
  std::vector<uint32_t> faces;
  std::vector<int32_t> coords = {8192, 8192, 16383, 8192, 8192, 0};
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t a = 2 + i, b = 2 + (i + 1) % n;
    faces.insert(faces.end(), {0, a, b, 1, b, a});
    const double t = 2 * 3.14159265358979 * i / n;
    coords.insert(coords.end(),
                  {int32_t(8192 + 8000 * std::cos(t)), int32_t(8192 + 8000 * std::sin(t)), 8192});
  }
  Bytes base;
  const uint32_t apex = base_payload(coords, faces, base)[0];
  // The split at the apex, with the contexts the decoder computes.
  pmz::ProgressiveMesh pm;
  std::string error;
  ASSERT_TRUE(pm.build(nv, faces.data(), nf, error)) << error;
  pmz::VertexChoice choice;
  choice.reset(pm, coords.data(), 14);
  choice.start_group();
  std::vector<uint32_t> bits;
  const uint32_t vs[1] = {apex};
  bool near = false;
  ASSERT_TRUE(pmz::choice_bits(choice, pm, nv, vs, bits, near));
  const pmz::GroupCode group{1, near};
  ASSERT_TRUE(pm.gather_ring(apex));
  ASSERT_TRUE(pm.ring_closed());
  ASSERT_EQ(pm.ring().size(), n);
  pmz::SplitSymbols code{apex,     pmz::wedge_context(n, true), n - 2, 0, 1, {0, 0, 0}, {0, 0, 0},
                         {0, 0, 0}};
  pmz::WedgeScratch scratch;
  uint32_t ra, rb;
  ASSERT_TRUE(
      pmz::wedge_ranks(coords.data(), choice.degrees(), apex, pm, n - 2, 0, ra, rb, scratch));
  code.rank_context = pmz::rank_context(true, scratch.confident);
  ASSERT_TRUE(pm.split_gathered(apex, ra, rb));
  pmz::PositionPrediction pred;
  pmz::predict_position(coords.data(), pm.u_ring(), pm.ring(), 0, 0, pred);
  std::copy(pred.context, pred.context + 3, code.residual_context);
  std::copy(pred.mix, pred.mix + 3, code.mix_context);
  Bytes splt;
  auto models = std::make_unique<pmz::SplitModels>();
  pmz::encode_split_chunk({group}, bits, &code, 1, *models, splt);
  Bytes f = signature();
  head(f, header(nv, nf, 1, nf + 2));
  pmz::append_chunk(f, pmz::kChunkBase, base);
  pmz::append_chunk(f, pmz::kChunkSplits, splt);
  pmz::append_chunk(f, pmz::kChunkEnd, {});

  pmz::Decoder d;
  ASSERT_EQ(d.feed(f.data(), f.size()), pmz::Status::ok) << d.error_message();
  ASSERT_EQ(d.refine(), 1u) << d.error_message();
  ASSERT_EQ(d.face_count(), nf + 2);
  d.clear_changes();
  g_allocations_before_failure = 0;
  uint64_t undone = 0;
  EXPECT_NO_THROW(undone = d.coarsen());
  g_allocations_before_failure = -1;
  EXPECT_EQ(undone, 1u);
  EXPECT_EQ(d.status(), pmz::Status::ok);
  expect_valid(d);
  EXPECT_EQ(d.face_count(), nf);
  EXPECT_EQ(d.refine(), 1u);
  EXPECT_EQ(d.face_count(), nf + 2);
  EXPECT_EQ(d.coarsen(), 1u);
  EXPECT_EQ(d.face_count(), nf);
}

// ---- every prefix, every byte ----

TEST(Hostile, EveryPrefixIsValidAndFinishSaysTruncated) {
  const Bytes f = small_file();
  for (size_t n = 0; n <= f.size(); ++n) {
    pmz::Decoder d;
    ASSERT_EQ(d.feed(f.data(), n), pmz::Status::ok) << "prefix " << n << ": " << d.error_message();
    d.refine();
    expect_valid(d);
    const pmz::Status s = d.finish();
    if (n == f.size()) {
      EXPECT_EQ(s, pmz::Status::ok);
    } else {
      EXPECT_EQ(s, pmz::Status::truncated) << "prefix " << n;
      EXPECT_FALSE(d.error_message().empty());
    }
  }
}

// Each byte replaced by a few values, with the CRC left as is (the checksum catches it) and
// repaired (the parsers see it): never a crash, always ok or an error with a message, and a
// valid mesh that can still move between levels.
void corrupt_every_byte(const Bytes& file, bool repair_crc) {
  const std::vector<size_t> chunks = chunk_offsets(file);
  size_t errors = 0, trials = 0;
  for (size_t i = 0; i < file.size(); ++i) {
    for (uint8_t x : {uint8_t(0x01), uint8_t(0x80), uint8_t(0xFF)}) {
      Bytes b = file;
      b[i] ^= x;
      if (repair_crc) {
        // Repair the chunk holding byte i when its header is intact enough to frame it.
        for (size_t c : chunks) {
          pmz::ChunkFrame f;
          if (!frame_at(b, c, f)) continue;
          const size_t end = f.header_size + size_t(f.payload_size);
          const bool in_crc = i >= c + f.header_size - 4 && i < c + f.header_size;
          if (i >= c && f.payload_size <= b.size() - c && end <= b.size() - c && i < c + end &&
              !in_crc)
            fix_crc(b, c);
        }
      }
      pmz::Decoder d;
      pmz::Status s = d.feed(b.data(), b.size());
      if (s == pmz::Status::ok) s = d.finish();
      // Wedge and residual symbols are decoded as splits are first applied.
      d.refine();
      if (s == pmz::Status::ok) s = d.status();
      ++trials;
      if (s != pmz::Status::ok) {
        ++errors;
        ASSERT_FALSE(d.error_message().empty()) << "byte " << i;
      }
      expect_valid(d);
      d.coarsen(3);
      expect_valid(d);
      d.set_face_target(UINT64_MAX);
      expect_valid(d);
      d.coarsen();
      ASSERT_EQ(d.face_count(), d.info().base_done ? d.info().base_faces : 0u) << "byte " << i;
    }
  }
  // Without repair every change in a checksummed byte is caught.
  if (!repair_crc)
    EXPECT_EQ(errors, trials);
  else
    EXPECT_GT(errors, trials / 2);
}

TEST(Hostile, EveryByteCorruptedKeepsAValidMesh) { corrupt_every_byte(small_file(), false); }
TEST(Hostile, EveryByteCorruptedPastTheChecksumKeepsAValidMesh) {
  corrupt_every_byte(small_file(), true);
}

Bytes read_vector(const char* name) {
  Bytes b;
  if (FILE* fp = std::fopen(
          (std::string(PMZ_SOURCE_DIR "/tests/conformance/vectors/") + name).c_str(), "rb")) {
    b.resize(1 << 20);
    b.resize(std::fread(b.data(), 1, b.size(), fp));
    std::fclose(fp);
  }
  return b;
}

// Attributes: the HEAD fields, the ATTR chunks and their a-wedge references, corrupted
// everywhere (with and without the checksums repaired): a valid mesh with valid a-wedges stays.
TEST(Hostile, EveryByteOfAnAttributeStream) {
  const Bytes b = read_vector("seamed-coarse.pmz");
  ASSERT_FALSE(b.empty());
  corrupt_every_byte(b, false);
  corrupt_every_byte(b, true);
}

// AllocationFailureWhileRefiningKeepsALevel with attribute wedges (spec/format.md section
// 14.5): the decoder reserves what a split's a-wedges need before the mesh changes, so an
// allocation failure never leaves a split with its faces but without its wedges; the same full
// mesh and wedges follow once memory is back.
TEST(Hostile, AllocationFailureWithAttributesKeepsALevel) {
  const Bytes f = read_vector("seamed-q.pmz");
  ASSERT_FALSE(f.empty());
  // The level as bits: faces, positions, the wedges' vertices, corners and values.
  auto level = [](const pmz::Decoder& d) {
    std::vector<uint32_t> out(d.indices(), d.indices() + size_t(d.face_count()) * 3);
    auto floats = [&](const float* p, size_t n) {
      for (size_t i = 0; i < n && p; ++i) {
        uint32_t bits;
        std::memcpy(&bits, p + i, 4);
        out.push_back(bits);
      }
    };
    const size_t w = d.wedge_count();
    floats(d.positions(), size_t(d.vertex_count()) * 3);
    out.insert(out.end(), d.wedge_vertices(), d.wedge_vertices() + w);
    out.insert(out.end(), d.wedge_indices(), d.wedge_indices() + size_t(d.face_count()) * 3);
    for (uint32_t t = 0; t < d.texcoord_set_count(); ++t) floats(d.texcoords(t), w * 2);
    floats(d.normals(), w * 3);
    floats(d.colors(), w * d.color_components());
    return out;
  };
  pmz::Decoder ref;
  ASSERT_EQ(ref.feed(f.data(), f.size()), pmz::Status::ok) << ref.error_message();
  ASSERT_EQ(ref.finish(), pmz::Status::ok);
  const uint64_t splits = ref.refine();
  ASSERT_GT(splits, 20u);
  ASSERT_GT(ref.wedge_count(), ref.vertex_count());  // seams: some vertices have several
  const std::vector<uint32_t> full = level(ref);
  uint32_t failures = 0;
  for (long n = 0; n < 2000; ++n) {
    pmz::Decoder d;
    ASSERT_EQ(d.feed(f.data(), f.size()), pmz::Status::ok);
    ASSERT_EQ(d.finish(), pmz::Status::ok);
    if (!refine_failing_allocation(d, n, [&] { d.set_split_target(splits); })) break;
    ++failures;
    // A whole level, wedges included: the one a fresh decoder gives at the same split.
    pmz::Decoder same;
    ASSERT_EQ(same.feed(f.data(), f.size()), pmz::Status::ok);
    same.set_split_target(d.splits_applied());
    ASSERT_EQ(level(d), level(same)) << n;
    d.coarsen();
    d.refine();
    ASSERT_EQ(d.splits_applied(), splits) << n;
    ASSERT_EQ(level(d), full) << n;
  }
  EXPECT_GT(failures, 3u);
}

// Out-of-range attribute fields in HEAD are corrupt (spec/format.md section 14.1).
TEST(Hostile, AttributeFieldsOutOfRangeAreCorrupt) {
  const Bytes file = read_vector("seamed-q.pmz");
  ASSERT_FALSE(file.empty());
  pmz::ChunkFrame f;
  ASSERT_TRUE(frame_at(file, 8, f));
  pmz::FileHeader h;
  size_t fixed = 0;
  ASSERT_TRUE(pmz::read_head_payload(&file[8 + f.header_size], size_t(f.payload_size), h, &fixed));
  ASSERT_EQ(h.flags, 1u);
  const size_t at = 8 + f.header_size + fixed;  // texcoord_sets, texcoord_bits, boxes, ...
  const size_t normals = at + 2 + 16;           // one texture coordinate set
  struct Case {
    size_t offset;
    uint8_t value;
    const char* what;
  } cases[] = {
      {at, 9, "9 texture coordinate sets"}, {at + 1, 25, "25 texture coordinate bits"},
      {normals, 2, "normals flag 2"},       {normals + 1, 1, "1 normal bit"},
      {normals + 1, 17, "17 normal bits"},  {normals + 2, 2, "2 colour components"},
      {normals + 3, 17, "17 colour bits"},  {normals + 4, 0xFF, "base wedges beyond full wedges"}};
  for (const Case& c : cases) {
    Bytes b = file;
    b[c.offset] = c.value;
    fix_crc(b, 8);
    pmz::Decoder d;
    EXPECT_EQ(d.feed(b.data(), b.size()), pmz::Status::corrupt) << c.what;
    EXPECT_NE(d.error_message().find("attributes"), std::string::npos) << d.error_message();
  }
  // An unknown flag bit beside the attributes' is corrupt too, and so is the nodes' flag in a
  // stream that has no NODE chunk (at its END).
  for (const uint8_t flags : {5, 3}) {
    Bytes b = file;
    b[8 + f.header_size + 2] = flags;  // flags varint (one byte)
    fix_crc(b, 8);
    pmz::Decoder d;
    EXPECT_EQ(d.feed(b.data(), b.size()), pmz::Status::corrupt) << int(flags);
  }
}

// ATTR chunks only where spec/format.md section 14.1 puts them: dropped, doubled or moved ones are
// corrupt, and a SPLT chunk's splits wait for its ATTR chunk.
TEST(Hostile, AttributeChunksOutOfPlaceAreCorrupt) {
  const Bytes file = read_vector("seamed-q.pmz");
  ASSERT_FALSE(file.empty());
  const std::vector<size_t> at = chunk_offsets(file);
  ASSERT_GE(at.size(), 6u);  // HEAD BASE ATTR SPLT ATTR ... END
  auto chunk = [&](size_t i) {
    const size_t end = i + 1 < at.size() ? at[i + 1] : file.size();
    return Bytes(file.begin() + std::ptrdiff_t(at[i]), file.begin() + std::ptrdiff_t(end));
  };
  auto without = [&](size_t i) {
    Bytes b(file.begin(), file.begin() + std::ptrdiff_t(at[i]));
    const Bytes rest(file.begin() + std::ptrdiff_t(at[i]) + std::ptrdiff_t(chunk(i).size()),
                     file.end());
    b.insert(b.end(), rest.begin(), rest.end());
    return b;
  };
  for (size_t drop : {size_t(2), size_t(4)}) {  // the base ATTR, the first SPLT's ATTR
    const Bytes b = without(drop);
    pmz::Decoder d;
    EXPECT_EQ(d.feed(b.data(), b.size()), pmz::Status::corrupt) << "without chunk " << drop;
    expect_valid(d);
  }
  {  // an ATTR chunk twice after a SPLT
    Bytes b(file.begin(), file.begin() + std::ptrdiff_t(at[5]));
    const Bytes twice = chunk(4);
    b.insert(b.end(), twice.begin(), twice.end());
    b.insert(b.end(), file.begin() + std::ptrdiff_t(at[5]), file.end());
    pmz::Decoder d;
    EXPECT_EQ(d.feed(b.data(), b.size()), pmz::Status::corrupt);
  }
  {  // a SPLT chunk without its ATTR yet: no split available, nothing decoded from it
    const Bytes b(file.begin(), file.begin() + std::ptrdiff_t(at[4]));
    pmz::Decoder d;
    ASSERT_EQ(d.feed(b.data(), b.size()), pmz::Status::ok);
    EXPECT_EQ(d.splits_available(), 0u);
    EXPECT_GT(d.wedge_count(), 0u);
    EXPECT_EQ(d.finish(), pmz::Status::truncated);
  }
}

// A type-5 chunk in a stream without attributes is a chunk of unknown type (spec/format.md
// sections 3 and 14): its CRC is checked, its payload is not read, and the levels are those of
// the stream without it.
TEST(Hostile, AttributeChunkWithoutAttributesIsSkipped) {
  const Bytes file = read_vector("sphere-q14.pmz");
  ASSERT_FALSE(file.empty());
  const std::vector<size_t> at = chunk_offsets(file);
  ASSERT_GE(at.size(), 4u);  // HEAD BASE SPLT ... END
  pmz::Decoder plain;
  ASSERT_EQ(plain.feed(file.data(), file.size()), pmz::Status::ok);
  ASSERT_EQ(plain.finish(), pmz::Status::ok);
  plain.refine();
  const std::vector<float> want(plain.positions(), plain.positions() + plain.vertex_count() * 3);
  const std::vector<uint32_t> want_faces(plain.indices(), plain.indices() + plain.face_count() * 3);
  Bytes attr;  // not an ATTR payload at all: a decoder that read it would refuse it
  pmz::append_chunk(attr, 5, {0xFF, 0x00, 0x13, 0x37, 0xFF, 0xFF, 0xFF});
  for (const size_t before : {at[1], at[2], at[3]}) {  // before BASE, before / after a SPLT
    Bytes b(file.begin(), file.begin() + std::ptrdiff_t(before));
    b.insert(b.end(), attr.begin(), attr.end());
    b.insert(b.end(), file.begin() + std::ptrdiff_t(before), file.end());
    pmz::Decoder d;
    ASSERT_EQ(d.feed(b.data(), b.size()), pmz::Status::ok) << "at " << before;
    ASSERT_EQ(d.finish(), pmz::Status::ok) << "at " << before;
    d.refine();
    EXPECT_EQ(d.status(), pmz::Status::ok);
    EXPECT_EQ(d.wedge_count(), 0u);
    EXPECT_EQ(std::vector<float>(d.positions(), d.positions() + d.vertex_count() * 3), want);
    EXPECT_EQ(std::vector<uint32_t>(d.indices(), d.indices() + d.face_count() * 3), want_faces);
    b[before + 2] ^= 1;  // its CRC is checked all the same
    pmz::Decoder bad;
    EXPECT_EQ(bad.feed(b.data(), b.size()), pmz::Status::bad_checksum) << "at " << before;
  }
}

// With attributes BASE is accepted only once its ATTR chunk has decoded (spec/format.md section
// 14.1): before it, and after a refused one, there is no level 0.
TEST(Hostile, BaseWithAttributesWaitsForItsAttrChunk) {
  const Bytes file = read_vector("seamed-q.pmz");
  ASSERT_FALSE(file.empty());
  const std::vector<size_t> at = chunk_offsets(file);
  ASSERT_GE(at.size(), 6u);  // HEAD BASE ATTR SPLT ATTR ... END
  {                          // the stream ends before the base ATTR
    const Bytes b(file.begin(), file.begin() + std::ptrdiff_t(at[2]));
    pmz::Decoder d;
    ASSERT_EQ(d.feed(b.data(), b.size()), pmz::Status::ok);
    EXPECT_FALSE(d.info().base_done);
    EXPECT_EQ(d.vertex_count(), 0u);
    EXPECT_EQ(d.face_count(), 0u);
    EXPECT_EQ(d.splits_available(), 0u);
    EXPECT_EQ(d.finish(), pmz::Status::truncated);
    EXPECT_EQ(d.vertex_count(), 0u);
  }
  {  // the base ATTR cut short (its CRC repaired): refused, and still no level
    const size_t end = at[3];
    pmz::ChunkFrame f;
    ASSERT_TRUE(frame_at(file, at[2], f));
    ASSERT_GE(f.payload_size, 2u);
    Bytes b(file.begin(), file.begin() + std::ptrdiff_t(at[2]));
    Bytes attr;
    pmz::append_chunk(attr, 5,
                      Bytes(file.begin() + std::ptrdiff_t(at[2] + f.header_size),
                            file.begin() + std::ptrdiff_t(at[2] + f.header_size + 1)));
    b.insert(b.end(), attr.begin(), attr.end());
    b.insert(b.end(), file.begin() + std::ptrdiff_t(end), file.end());
    pmz::Decoder d;
    EXPECT_EQ(d.feed(b.data(), b.size()), pmz::Status::corrupt);
    EXPECT_FALSE(d.info().base_done);
    EXPECT_EQ(d.vertex_count(), 0u);
    EXPECT_EQ(d.face_count(), 0u);
  }
  {  // the whole base ATTR: level 0 with its a-wedges
    const Bytes b(file.begin(), file.begin() + std::ptrdiff_t(at[3]));
    pmz::Decoder d;
    ASSERT_EQ(d.feed(b.data(), b.size()), pmz::Status::ok);
    EXPECT_TRUE(d.info().base_done);
    EXPECT_EQ(d.vertex_count(), d.info().base_vertices);
    EXPECT_GT(d.wedge_count(), 0u);
  }
}

TEST(Hostile, EveryByteOfTheSampleFile) {
  FILE* fp = std::fopen(PMZ_SOURCE_DIR "/tests/data/sample.pmz", "rb");
  if (!fp) GTEST_SKIP() << "tests/data/sample.pmz absent";
  Bytes b(1 << 20);
  b.resize(std::fread(b.data(), 1, b.size(), fp));
  std::fclose(fp);
  corrupt_every_byte(b, true);
}

// A stream in nodes whose parallel batch of a level is refused at its first split (found by
// fuzz_container): the decoder stops there, on every thread count, and decodes nothing after the
// refusal (it once went on with a chunk reader the refusal had dropped).
TEST(Hostile, NodeBatchRefusedAtItsFirstSplit) {
  FILE* fp = std::fopen(PMZ_SOURCE_DIR
                        "/tests/data/fuzz-regressions/nodes-batch-refused-at-its-first-split.pmz",
                        "rb");
  ASSERT_TRUE(fp);
  Bytes b(1 << 16);
  b.resize(std::fread(b.data(), 1, b.size(), fp));
  std::fclose(fp);
  std::vector<std::pair<uint64_t, std::string>> seen;
  for (uint32_t threads : {1u, 2u}) {
    pmz::Decoder d;
    d.set_threads(threads);
    d.feed(b.data(), b.size());
    d.refine();
    EXPECT_EQ(d.status(), pmz::Status::corrupt) << threads;
    seen.emplace_back(d.splits_applied(), d.error_message());
  }
  EXPECT_EQ(seen[0], seen[1]);
}

}  // namespace
