// SPDX-License-Identifier: MIT
// pmz::compare's texture error across a texture seam of a decoded stream: quantizing positions
// moves the seam by a fraction of a step, which must not read as a jump between the charts.
#include <gtest/gtest.h>

#include "../../tools/decoded_mesh.hpp"
#include "pmz/compare.hpp"
#include "pmz/decoder.hpp"
#include "pmz/simplify.hpp"
#include "pmz/writer.hpp"
#include "seamed_grid.hpp"

namespace {

// The seamed grid encoded with lossless texture coordinates and `position_bits`, fully decoded.
pmz::IndexedMesh round_trip(const pmz::IndexedMesh& mesh, uint32_t position_bits) {
  pmz::CollapseSequence seq;
  std::vector<uint8_t> bytes;
  std::string error;
  pmz::WriteOptions opt;
  opt.position_bits = position_bits;
  opt.texcoord_bits = 0;
  EXPECT_TRUE(pmz::simplify(mesh, {}, seq, error)) << error;
  EXPECT_TRUE(pmz::write_pmz(seq, opt, bytes, error)) << error;
  pmz::Decoder d;
  EXPECT_EQ(d.feed(bytes.data(), bytes.size()), pmz::Status::ok) << d.error_message();
  EXPECT_EQ(d.finish(), pmz::Status::ok);
  d.refine();
  return pmz::tool::decoded_mesh(d);
}

pmz::AttributeErrorStats texture_error(const pmz::IndexedMesh& a, const pmz::IndexedMesh& b) {
  pmz::CompareResult r;
  std::string error;
  EXPECT_TRUE(pmz::compare(a, b, {}, r, error)) << error;
  return r.attributes.texcoord;
}

// Lossless texture coordinates at 14 position bits: the error is the moved geometry's (u and v
// change by at most 1.2 per unit of length, positions by up to half a step, 1 / 32766, per
// axis), next to none with lossless positions; the seam's jump in u (about 0.5) does not appear.
TEST(CompareSeams, QuantizedPositionsLosslessTexcoords) {
  const pmz::IndexedMesh mesh = pmz_test::seamed_grid(16, 7);
  const pmz::AttributeErrorStats lossless = texture_error(mesh, round_trip(mesh, 0));
  const pmz::AttributeErrorStats quantized = texture_error(mesh, round_trip(mesh, 14));
  EXPECT_GT(quantized.samples, 100000u);
  EXPECT_LT(lossless.max, 1e-6);
  EXPECT_LT(quantized.max, 1e-4);
  EXPECT_LT(quantized.mean, 3e-5);
}

// u + 0.05 on the decoded right chart's corners is measured as 0.05.
TEST(CompareSeams, ShiftedChartIsMeasured) {
  const pmz::IndexedMesh mesh = pmz_test::seamed_grid(16, 7);
  pmz::IndexedMesh decoded = round_trip(mesh, 14);
  std::vector<float>& uv = decoded.attributes.texcoords[0];
  for (size_t w = 0; w < uv.size(); w += 2)
    if (uv[w] > 0.5f) uv[w] += 0.05f;  // the right chart: u >= 0.55
  EXPECT_NEAR(texture_error(mesh, decoded).max, 0.05, 1e-4);
}

}  // namespace
