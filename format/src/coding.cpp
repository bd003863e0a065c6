// SPDX-License-Identifier: MIT
#include "pmz/coding.hpp"

#include <cstring>

#include "pmz/range_coder.hpp"
#include "pmz/wasm_hints.hpp"

namespace pmz {

namespace {
// Slicing by 8: t[0] is the byte-wise table; t[k][b] is the CRC of byte b followed by k zero
// bytes, so eight table lookups advance the CRC by eight bytes at once. Built on first use
// (8 KB of bss, not of the library file: the decoder library has a size budget).
struct CrcTables {
  uint32_t t[8][256];
  CrcTables() {
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[0][i] = c;
    }
    for (int k = 1; k < 8; ++k)
      for (uint32_t i = 0; i < 256; ++i) t[k][i] = (t[k - 1][i] >> 8) ^ t[0][t[k - 1][i] & 0xFF];
  }
};
inline uint32_t load_u32le(const uint8_t* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}
}  // namespace

PMZ_SMALL_IN_WASM uint32_t crc32(const void* data, size_t size, uint32_t crc) {
  static const CrcTables tables;
  const auto& t = tables.t;
  const auto* p = static_cast<const uint8_t*>(data);
  crc = ~crc;
  for (; size >= 8; size -= 8, p += 8) {
    const uint32_t a = crc ^ load_u32le(p), b = load_u32le(p + 4);
    crc = t[7][a & 0xFF] ^ t[6][(a >> 8) & 0xFF] ^ t[5][(a >> 16) & 0xFF] ^ t[4][a >> 24] ^
          t[3][b & 0xFF] ^ t[2][(b >> 8) & 0xFF] ^ t[1][(b >> 16) & 0xFF] ^ t[0][b >> 24];
  }
  for (; size; --size) crc = t[0][(crc ^ *p++) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

void put_varint(std::vector<uint8_t>& out, uint64_t v) {
  while (v >= 0x80) {
    out.push_back(uint8_t(v) | 0x80);
    v >>= 7;
  }
  out.push_back(uint8_t(v));
}

uint8_t ByteReader::u8() {
  if (p >= end) {
    ok = false;
    return 0;
  }
  return *p++;
}

uint32_t ByteReader::u32le() {
  const uint8_t* b = bytes(4);
  if (!b) return 0;
  return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
}

uint64_t ByteReader::u64le() {
  uint64_t lo = u32le();
  uint64_t hi = u32le();
  return lo | hi << 32;
}

float ByteReader::f32le() {
  uint32_t u = u32le();
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

PMZ_SMALL_IN_WASM uint64_t ByteReader::varint() {
  uint64_t v = 0;
  for (int shift = 0; shift < 70; shift += 7) {
    if (p >= end) break;
    uint8_t b = *p++;
    if (shift == 63 && b > 1) break;  // would overflow 64 bits
    v |= uint64_t(b & 0x7F) << shift;
    if (!(b & 0x80)) return v;
  }
  ok = false;
  return 0;
}

const uint8_t* ByteReader::bytes(size_t n) {
  if (remaining() < n) {
    ok = false;
    p = end;
    return nullptr;
  }
  const uint8_t* r = p;
  p += n;
  return r;
}

RangeDecoder::RangeDecoder(const uint8_t* p, size_t size) : buf_(p, p + size) {
  buf_.resize(size + kStreamPad, 0);
  s_ = {0xFFFFFFFFu, 0, buf_.data(), buf_.data() + buf_.size(), true};
  for (int i = 0; i < 4; ++i) s_.code = (s_.code << 8) | s_.next();
  ok = s_.ok;
}

#if defined(__wasm__)
std::string decimal_in_wasm(uint64_t v) {
  char text[20], *p = text + sizeof text;
  do *--p = char('0' + v % 10);
  while (v /= 10);
  return std::string(p, text + sizeof text);
}
#endif

}  // namespace pmz
