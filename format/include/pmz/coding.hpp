// SPDX-License-Identifier: MIT
// Coding primitives shared by the writer and the decoder: CRC-32, LEB128 varints, zigzag.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace pmz {

// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320), as zlib's crc32().
uint32_t crc32(const void* data, size_t size, uint32_t crc = 0);

inline uint32_t zigzag_encode(int32_t v) { return (uint32_t(v) << 1) ^ uint32_t(v >> 31); }
inline int32_t zigzag_decode(uint32_t v) { return int32_t(v >> 1) ^ -int32_t(v & 1); }

void put_varint(std::vector<uint8_t>& out, uint64_t v);

// Bounded reader over a byte span: every read checks the end, and a failed read sets ok=false
// and returns 0, so parsers check once at the end instead of after every field.
struct ByteReader {
  const uint8_t* p;
  const uint8_t* end;
  bool ok = true;
  ByteReader(const void* data, size_t size) : p(static_cast<const uint8_t*>(data)), end(p + size) {}
  size_t remaining() const { return size_t(end - p); }
  uint8_t u8();
  uint32_t u32le();
  uint64_t u64le();
  float f32le();
  uint64_t varint();               // LEB128, at most 10 bytes
  const uint8_t* bytes(size_t n);  // nullptr (and ok=false) if fewer remain
};

}  // namespace pmz
