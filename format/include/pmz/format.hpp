// The .pmz container (spec/format.md): signature, chunk framing, header and quantization.
// Shared by writer and decoder.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "pmz/coding.hpp"

namespace pmz {

inline constexpr uint8_t kSignature[8] = {0x89, 'P', 'M', 'Z', 0x0D, 0x0A, 0x1A, 0x0A};
inline constexpr uint32_t kVersionMajor = 6;
inline constexpr uint32_t kVersionMinor = 0;

// Chunk = fourcc[4] | u32le payload_size | u32le crc32(fourcc, size, payload) | payload.
inline constexpr size_t kChunkHeaderSize = 12;
inline constexpr uint32_t fourcc(char a, char b, char c, char d) {
  return uint32_t(uint8_t(a)) | uint32_t(uint8_t(b)) << 8 | uint32_t(uint8_t(c)) << 16 |
         uint32_t(uint8_t(d)) << 24;
}
inline constexpr uint32_t kChunkHead = fourcc('H', 'E', 'A', 'D');
inline constexpr uint32_t kChunkBase = fourcc('B', 'A', 'S', 'E');
inline constexpr uint32_t kChunkSplits = fourcc('S', 'P', 'L', 'T');
inline constexpr uint32_t kChunkEnd = fourcc('E', 'N', 'D', ' ');

// Streams of one SPLT chunk, in payload order.
enum SplitStream : int {
  kStreamGroups = 0,  // per group: splits - 1, near flag
  kStreamChoice,      // per candidate vertex of a group: whether it splits
  kStreamWedgeCount,  // wedge: interior count (spec, section 4)
  kStreamWedgeRank,   // wedge: rank among the candidates of that count
  kStreamResidualX,  // position residual slot 0 (first tangent axis; spec section 5)
  kStreamResidualY,  // slot 1 (second tangent axis)
  kStreamResidualZ,  // slot 2 (normal axis, predicted from the tangent plane)
  kSplitStreamCount
};

inline constexpr size_t kHeadPayloadSize = 52;
inline constexpr uint32_t kKnownFlags = 0;  // HEAD flags: none defined in 1.0

struct FileHeader {
  uint32_t version_major = kVersionMajor, version_minor = kVersionMinor;
  uint32_t flags = 0;
  uint32_t position_bits = 14;  // 0 = lossless float32
  uint32_t curvature = 0;       // prediction offset weights, 0..kMaxCurvature (eighths; spec section 5)
  uint32_t fine_curvature = 0;
  uint32_t base_vertices = 0, base_faces = 0, full_vertices = 0, full_faces = 0;
  uint32_t total_splits = 0;
  float bbox_min[3] = {0, 0, 0}, bbox_max[3] = {0, 0, 0};
};

void put_u32le(std::vector<uint8_t>& out, uint32_t v);
void put_f32le(std::vector<uint8_t>& out, float v);
void write_head_payload(std::vector<uint8_t>& out, const FileHeader& h);
// Parses the fixed fields; semantic checks (version, counts) are the caller's.
bool read_head_payload(const uint8_t* p, size_t size, FileHeader& h);
// Appends a framed chunk (header + payload) to out.
void append_chunk(std::vector<uint8_t>& out, uint32_t type, const std::vector<uint8_t>& payload);
inline uint32_t chunk_crc(const uint8_t* header8, const uint8_t* payload, size_t size) {
  return crc32(payload, size, crc32(header8, 8));
}

// Quantization as Draco's -qp: one step for all axes over the largest bounding-box extent.
// Float bits <-> int32 that orders like the float (lossless mode coordinates).
int32_t float_to_ordered(float f);
float ordered_to_float(int32_t i);

struct Quantizer {
  float min[3] = {0, 0, 0};
  float scale = 0;      // dequantization step: range / max_q
  double inv = 0;       // quantization: max_q / range
  uint32_t max_q = 0;
  uint32_t bits = 0;    // 0 = lossless: coordinates are the order-preserving float bit patterns
  void init(uint32_t position_bits, const float bbox_min[3], const float bbox_max[3]);
  int32_t quantize(float x, int axis) const;
  float dequantize(int32_t q, int axis) const {
    return bits ? min[axis] + float(q) * scale : ordered_to_float(q);
  }
};


}  // namespace pmz
