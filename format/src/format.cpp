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
  out.push_back(uint8_t(h.flags));
  out.push_back(uint8_t(h.flags >> 8));
  out.push_back(uint8_t(h.position_bits));
  out.push_back(uint8_t(h.curvature));
  out.push_back(uint8_t(h.fine_curvature));
  out.push_back(0);
  put_u32le(out, h.base_vertices);
  put_u32le(out, h.base_faces);
  put_u32le(out, h.full_vertices);
  put_u32le(out, h.full_faces);
  put_u32le(out, h.total_splits);
  for (float f : h.bbox_min) put_f32le(out, f);
  for (float f : h.bbox_max) put_f32le(out, f);
}

bool read_head_payload(const uint8_t* p, size_t size, FileHeader& h) {
  if (size < kHeadPayloadSize) return false;
  ByteReader r(p, size);
  h.version_major = r.u8();
  h.version_minor = r.u8();
  h.flags = r.u8();
  h.flags |= uint32_t(r.u8()) << 8;
  h.position_bits = r.u8();
  h.curvature = r.u8();
  h.fine_curvature = r.u8();
  r.bytes(1);
  h.base_vertices = r.u32le();
  h.base_faces = r.u32le();
  h.full_vertices = r.u32le();
  h.full_faces = r.u32le();
  h.total_splits = r.u32le();
  for (float& f : h.bbox_min) f = r.f32le();
  for (float& f : h.bbox_max) f = r.f32le();
  return r.ok;
}

void append_chunk(std::vector<uint8_t>& out, uint32_t type, const std::vector<uint8_t>& payload) {
  size_t at = out.size();
  put_u32le(out, type);
  put_u32le(out, uint32_t(payload.size()));
  put_u32le(out, chunk_crc(out.data() + at, payload.data(), payload.size()));
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
