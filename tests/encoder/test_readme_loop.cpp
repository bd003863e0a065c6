// SPDX-License-Identifier: MIT
// README.md's embedding loop (tests/consumer/cxx/readme_loop.hpp, the same lines verbatim) on
// the 50k-face sample mesh: fed in small slices or 64 KiB reads it reaches the full mesh, the
// same mesh as one feed and a full refine.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "../consumer/cxx/readme_loop.hpp"
#include "pmz/sample_mesh.hpp"
#include "pmz/simplify.hpp"
#include "pmz/writer.hpp"

namespace {

std::vector<uint8_t> encoded_sample() {
  pmz::CollapseSequence seq;
  std::vector<uint8_t> bytes;
  std::string error;
  EXPECT_TRUE(pmz::simplify(pmz::make_sample_mesh(), {}, seq, error)) << error;
  EXPECT_TRUE(pmz::write_pmz(seq, {}, bytes, error)) << error;
  return bytes;
}

}  // namespace

TEST(ReadmeLoop, ReachesTheFullMeshInAnySlicing) {
  const std::vector<uint8_t> bytes = encoded_sample();
  ASSERT_GT(bytes.size(), 20000u);
  pmz::Decoder whole;
  ASSERT_EQ(whole.feed(bytes.data(), bytes.size()), pmz::Status::ok);
  ASSERT_EQ(whole.finish(), pmz::Status::ok);
  whole.refine();
  ASSERT_EQ(whole.face_count(), whole.info().full_faces);

  for (size_t slice : {size_t(997), size_t(65536)}) {
    size_t at = 0, uploads = 0;
    std::string logged;
    pmz::Decoder dec = readme_loop(
        [&](char* buf, size_t size) {
          size_t n = std::min({size, slice, bytes.size() - at});
          std::memcpy(buf, bytes.data() + at, n);
          at += n;
          return n;
        },
        [&](const pmz::Decoder&) { ++uploads; }, [&](const std::string& m) { logged = m; });
    EXPECT_EQ(logged, "") << "slice " << slice;
    EXPECT_EQ(dec.bytes_consumed(), bytes.size());
    EXPECT_EQ(dec.splits_applied(), dec.info().total_splits) << "slice " << slice;
    ASSERT_EQ(dec.face_count(), whole.face_count()) << "slice " << slice;
    ASSERT_EQ(dec.vertex_count(), whole.vertex_count());
    EXPECT_EQ(0, std::memcmp(dec.indices(), whole.indices(), dec.face_count() * 12u));
    EXPECT_EQ(0, std::memcmp(dec.positions(), whole.positions(), dec.vertex_count() * 12u));
    EXPECT_GT(uploads, 1u);
  }
}

TEST(ReadmeLoop, ReportsACutStream) {
  const std::vector<uint8_t> bytes = encoded_sample();
  const size_t cut = bytes.size() / 2;
  size_t at = 0;
  std::string logged;
  pmz::Decoder dec = readme_loop(
      [&](char* buf, size_t size) {
        size_t n = std::min({size, size_t(4096), cut - at});
        std::memcpy(buf, bytes.data() + at, n);
        at += n;
        return n;
      },
      [](const pmz::Decoder&) {}, [&](const std::string& m) { logged = m; });
  EXPECT_EQ(dec.status(), pmz::Status::truncated);
  EXPECT_NE(logged, "");
  // What arrived is applied: the mesh is drawable, between the base and the full mesh.
  EXPECT_EQ(dec.splits_applied(), dec.splits_available());
  EXPECT_GT(dec.face_count(), dec.info().base_faces);
  EXPECT_LT(dec.face_count(), dec.info().full_faces);
}
