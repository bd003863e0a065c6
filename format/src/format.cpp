// SPDX-License-Identifier: MIT
#include "pmz/format.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace pmz {

void put_u32le(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}

void put_f32le(std::vector<uint8_t>& out, float v) {
  uint32_t u;
  std::memcpy(&u, &v, 4);
  put_u32le(out, u);
}

void write_head_payload(std::vector<uint8_t>& out, const FileHeader& h) {
  out.push_back(uint8_t(h.version_major));
  out.push_back(uint8_t(h.version_minor));
  put_varint(out, h.flags);
  out.push_back(uint8_t(h.position_bits));
  out.push_back(uint8_t(h.curvature));
  out.push_back(uint8_t(h.fine_curvature));
  out.push_back(uint8_t(h.level));
  put_varint(out, h.base_vertices);
  put_varint(out, h.base_faces);
  put_varint(out, h.total_splits);
  put_varint(out, h.full_faces);
  for (float f : h.bbox_min) put_f32le(out, f);
  for (float f : h.bbox_max) put_f32le(out, f);
}

bool read_head_payload(const uint8_t* p, size_t size, FileHeader& h, size_t* consumed) {
  ByteReader r(p, size);
  h.version_major = r.u8();
  h.version_minor = r.u8();
  bool fits = true;
  auto u32 = [&] {
    const uint64_t v = r.varint();
    fits = fits && v <= 0xFFFFFFFFu;
    return uint32_t(v);
  };
  h.flags = u32();
  h.position_bits = r.u8();
  h.curvature = r.u8();
  h.fine_curvature = r.u8();
  h.level = r.u8();
  h.base_vertices = u32();
  h.base_faces = u32();
  h.total_splits = u32();
  h.full_faces = u32();
  for (float& f : h.bbox_min) f = r.f32le();
  for (float& f : h.bbox_max) f = r.f32le();
  if (consumed) *consumed = size - r.remaining();
  return r.ok && fits;
}

FrameStatus parse_chunk_frame(const uint8_t* p, size_t n, ChunkFrame& f) {
  if (n < 1) return FrameStatus::more;
  f.type = p[0];
  uint64_t v = 0;
  size_t at = 1;
  for (int shift = 0;; shift += 7) {
    if (shift == 70) return FrameStatus::malformed;  // an 11th byte
    if (at >= n) return FrameStatus::more;
    const uint8_t b = p[at++];
    if (shift == 63 && b > 1) return FrameStatus::malformed;  // beyond 64 bits
    v |= uint64_t(b & 0x7F) << shift;
    if (!(b & 0x80)) break;
  }
  if (n - at < 4) return FrameStatus::more;
  f.payload_size = v;
  f.header_size = at + 4;
  f.crc = uint32_t(p[at]) | uint32_t(p[at + 1]) << 8 | uint32_t(p[at + 2]) << 16 |
          uint32_t(p[at + 3]) << 24;
  return FrameStatus::ok;
}

void repair_chunk_crc(uint8_t* frame, const ChunkFrame& f) {
  const uint32_t crc = chunk_crc(frame, f, frame + f.header_size);
  for (int i = 0; i < 4; ++i) frame[f.header_size - 4 + i] = uint8_t(crc >> (8 * i));
}

void append_chunk(std::vector<uint8_t>& out, uint8_t type, const std::vector<uint8_t>& payload) {
  const size_t at = out.size();
  out.push_back(type);
  put_varint(out, payload.size());
  const size_t crc_at = out.size();
  const uint32_t crc = crc32(payload.data(), payload.size(), crc32(out.data() + at, crc_at - at));
  put_u32le(out, crc);
  out.insert(out.end(), payload.begin(), payload.end());
}

void Quantizer::init(uint32_t position_bits, const float bmin[3], const float bmax[3]) {
  bits = position_bits;
  float range = 0;
  for (int a = 0; a < 3; ++a) {
    min[a] = bmin[a];
    range = std::max(range, bmax[a] - bmin[a]);
  }
  if (!bits) return;
  max_q = bits >= 31 ? 0x7FFFFFFFu : (1u << bits) - 1;
  scale = range > 0 ? range / float(max_q) : 0.0f;
  inv = range > 0 ? double(max_q) / double(range) : 0.0;
}

int32_t Quantizer::quantize(float x, int axis) const {
  if (!bits) return float_to_ordered(x);
  double q = std::floor((double(x) - double(min[axis])) * inv + 0.5);
  q = std::clamp(q, 0.0, double(max_q));
  return int32_t(q);
}

int32_t float_to_ordered(float f) {
  int32_t i;
  std::memcpy(&i, &f, 4);
  return i < 0 ? i ^ 0x7FFFFFFF : i;
}

float ordered_to_float(int32_t i) {
  if (i < 0) i ^= 0x7FFFFFFF;
  float f;
  std::memcpy(&f, &i, 4);
  return f;
}

}  // namespace pmz
