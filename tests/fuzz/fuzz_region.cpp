// SPDX-License-Identifier: MIT
// A cell's region as `pmz-encode --task` reads it from a plan's folder (a file any machine that
// sees the folder may have written, or damaged): [u32 cell, little-endian][region bytes].
// simplify_cell_region must refuse bytes that are not a region of that cell with one line, or
// simplify the cell; it must never crash, hang or allocate without bound.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "pmz/simplify.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 4) return 0;
  uint32_t cell = 0;
  std::memcpy(&cell, data, 4);
  const std::vector<uint8_t> region(data + 4, data + size);
  std::vector<uint8_t> result;
  std::string error;
  if (pmz::simplify_cell_region(region, cell, result, error)) {
    PMZ_FUZZ_CHECK(error.empty());
  } else {
    PMZ_FUZZ_CHECK(!error.empty() && error.find('\n') == std::string::npos);
    PMZ_FUZZ_CHECK(result.empty());
  }
  return 0;
}
