// SPDX-License-Identifier: MIT
// Split counts at every prefix of the conformance vectors, read from the container alone
// (spec/format.md sections 3, 4, 8 and 14.1) and not from any expected bytes: a stream cut at
// the end of a chunk makes available exactly the splits of the SPLT chunks it holds whole (with
// attributes: those whose ATTR chunk followed), one byte less makes only the chunks before
// available, and refining applies all of them, one vertex each; the whole stream gives HEAD's
// total_splits, base_vertices + total_splits vertices and full_faces faces.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "pmz/decoder.hpp"

namespace {

uint64_t varint(const std::vector<uint8_t>& b, size_t& at) {
  uint64_t v = 0;
  for (int shift = 0; at < b.size() && shift < 70; shift += 7) {
    const uint8_t x = b[at++];
    v |= uint64_t(x & 0x7F) << shift;
    if (!(x & 0x80)) return v;
  }
  ADD_FAILURE() << "varint malformed at " << at;
  return 0;
}

// The container as a reader of spec/format.md sections 3 and 8 sees it: after each chunk, the
// stream length up to its end and the splits available there.
struct Layout {
  uint64_t base_vertices = 0, base_faces = 0, total_splits = 0, full_faces = 0;
  bool attributes = false;
  std::vector<size_t> chunk_end;
  std::vector<uint64_t> available;  // at chunk_end
};

Layout layout(const std::vector<uint8_t>& b) {
  Layout l;
  size_t at = 8;                    // the signature
  uint64_t whole = 0, pending = 0;  // splits of SPLT chunks made available; awaiting their ATTR
  while (at < b.size()) {
    const uint8_t type = b[at++];
    const uint64_t size = varint(b, at);
    at += 4;  // crc
    const size_t payload = at;
    if (type == 1) {  // HEAD: version (2 bytes), flags, 4 bytes of u8 fields, then the counts
      size_t p = payload + 2;
      l.attributes = varint(b, p) & 1;
      p += 4;
      l.base_vertices = varint(b, p);
      l.base_faces = varint(b, p);
      l.total_splits = varint(b, p);
      l.full_faces = varint(b, p);
    } else if (type == 3) {  // SPLT: split_count first
      size_t p = payload;
      (l.attributes ? pending : whole) += varint(b, p);
    } else if (type == 5) {  // ATTR: after BASE, or making the SPLT before it available
      whole += pending, pending = 0;
    }
    at = payload + size;
    l.chunk_end.push_back(at);
    l.available.push_back(whole);
    if (type == 4) break;  // END
  }
  EXPECT_EQ(at, b.size());
  return l;
}

std::vector<std::filesystem::path> vectors() {
  std::vector<std::filesystem::path> out;
  for (const auto& e :
       std::filesystem::directory_iterator(PMZ_SOURCE_DIR "/tests/conformance/vectors"))
    if (e.path().extension() == ".pmz") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

// Fed a prefix (whole, then finished) and refined fully: the counts the container promises.
void expect_prefix(const std::vector<uint8_t>& b, const Layout& l, size_t length,
                   uint64_t available) {
  SCOPED_TRACE("prefix of " + std::to_string(length) + " bytes");
  pmz::Decoder d;
  ASSERT_EQ(d.feed(b.data(), length), pmz::Status::ok) << d.error_message();
  const bool whole = length == b.size();
  ASSERT_EQ(d.finish(), whole ? pmz::Status::ok : pmz::Status::truncated);
  ASSERT_EQ(d.splits_available(), available);
  if (!d.info().base_done) return;
  EXPECT_EQ(d.refine(), available);
  ASSERT_EQ(d.splits_applied(), available);
  EXPECT_EQ(d.vertex_count(), l.base_vertices + available);
  // A split adds one face on a boundary, two elsewhere.
  EXPECT_GE(d.face_count(), l.base_faces + available);
  EXPECT_LE(d.face_count(), l.base_faces + 2 * available);
  if (whole) {
    EXPECT_EQ(d.splits_applied(), l.total_splits);
    EXPECT_EQ(d.splits_applied(), d.info().total_splits);
    EXPECT_EQ(d.vertex_count(), d.info().full_vertices);
    EXPECT_EQ(d.face_count(), l.full_faces);
    EXPECT_EQ(d.face_count(), d.info().full_faces);
  }
}

TEST(PrefixCounts, EveryChunkBoundaryOfEveryVector) {
  size_t streams = 0, boundaries = 0, several = 0;
  for (const auto& path : vectors()) {
    SCOPED_TRACE(path.filename().string());
    std::ifstream in(path, std::ios::binary);
    const std::vector<uint8_t> b{std::istreambuf_iterator<char>(in), {}};
    ASSERT_GT(b.size(), 8u);
    const Layout l = layout(b);
    ASSERT_EQ(l.available.back(), l.total_splits);
    ++streams;
    several += std::find_if(l.available.begin(), l.available.end(), [&](uint64_t a) {
                 return a > 0 && a < l.total_splits;
               }) != l.available.end();
    for (size_t i = 0; i < l.chunk_end.size(); ++i) {
      const uint64_t before = i ? l.available[i - 1] : 0;
      ASSERT_NO_FATAL_FAILURE(expect_prefix(b, l, l.chunk_end[i], l.available[i]));
      ASSERT_NO_FATAL_FAILURE(expect_prefix(b, l, l.chunk_end[i] - 1, before));
      ++boundaries;
    }
    // Fed chunk by chunk into one decoder, refining after each: the same counts.
    pmz::Decoder d;
    size_t at = 0;
    for (size_t i = 0; i < l.chunk_end.size(); ++i) {
      ASSERT_EQ(d.feed(b.data() + at, l.chunk_end[i] - at), pmz::Status::ok);
      at = l.chunk_end[i];
      d.refine();
      ASSERT_EQ(d.splits_available(), l.available[i]) << "after chunk " << i;
      ASSERT_EQ(d.splits_applied(), l.available[i]) << "after chunk " << i;
    }
    ASSERT_EQ(d.finish(), pmz::Status::ok);
  }
  // The checks ran: every vector (HEAD, BASE, SPLT and END at least), several streams whose
  // splits come in several chunks.
  EXPECT_GT(streams, 20u);
  EXPECT_GE(boundaries, 4 * streams);
  EXPECT_GE(several, 3u);
}

}  // namespace
