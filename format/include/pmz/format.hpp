// SPDX-License-Identifier: MIT
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
inline constexpr uint32_t kVersionMajor = 13;
inline constexpr uint32_t kVersionMinor = 1;

// Chunk = u8 type | varint payload_size | u32le crc32(type, size varint, payload) | payload
// (spec/format.md section 3). Types other than these four are skipped (forward compatibility).
inline constexpr uint8_t kChunkHead = 1, kChunkBase = 2, kChunkSplits = 3, kChunkEnd = 4;
inline constexpr size_t kMaxChunkHeader = 1 + 10 + 4;  // a varint has at most 10 bytes

struct ChunkFrame {
  uint8_t type = 0;
  size_t header_size = 0;  // type, size varint and CRC: where the payload starts
  uint64_t payload_size = 0;
  uint32_t crc = 0;
};
enum class FrameStatus { ok, more, malformed };
// Parses the frame header at p[0 .. n): ok, or more when n ends inside it (a push parser waits
// for more bytes), or malformed when the size varint has more than 10 bytes or exceeds 64 bits.
FrameStatus parse_chunk_frame(const uint8_t* p, size_t n, ChunkFrame& f);
// CRC of a chunk whose header starts at frame (f parsed from it) and whose payload follows.
inline uint32_t chunk_crc(const uint8_t* frame, const ChunkFrame& f, const uint8_t* payload) {
  return crc32(payload, size_t(f.payload_size), crc32(frame, f.header_size - 4));
}
// Rewrites the CRC of the complete chunk at frame to match its contents (tests, fuzzing).
void repair_chunk_crc(uint8_t* frame, const ChunkFrame& f);
// Chunks before format 7.0 began with four ASCII type bytes, the first being "HEAD".
inline constexpr uint8_t kOldHeadType[4] = {'H', 'E', 'A', 'D'};

// Streams of one SPLT chunk, in payload order (spec/format.md section 8).
enum SplitStream : int {
  kStreamConnectivity =
      0,            // the groups, then vertex choice and wedge symbols in the decoder's order
  kStreamGeometry,  // the position residuals, three slots per split
  kSplitStreamCount
};
// Kinds of SPLT symbols, for the writer's accounting of ideal code lengths (pmz-encode).
enum SymbolKind : int {
  kSymbolGroups = 0,  // per group: splits - 1, near flag
  kSymbolChoice,      // per candidate vertex of a group: whether it splits
  kSymbolWedgeCount,  // wedge: interior count (spec/format.md section 9.4)
  kSymbolWedgeRank,   // wedge: rank among the candidates of that count
  kSymbolResidualT0,  // position residual slot 0 (first tangent axis; spec/format.md section 9.6)
  kSymbolResidualT1,  // slot 1 (second tangent axis)
  kSymbolResidualN,   // slot 2 (normal axis, predicted from the tangent plane)
  kSymbolKinds
};

inline constexpr uint32_t kKnownFlags =
    3;  // HEAD flags: bit 0 attributes (attribute_codec.hpp), bit 1 nodes (node_table.hpp)

// HEAD (spec/format.md section 4). full_vertices is not stored: base_vertices + total_splits.
struct FileHeader {
  uint32_t version_major = kVersionMajor, version_minor = kVersionMinor;
  uint32_t flags = 0;
  uint32_t position_bits = 14;  // 0 = lossless float32
  uint32_t curvature =
      0;  // prediction offset weights, 0..kMaxCurvature (eighths; spec/format.md section 9.6)
  uint32_t fine_curvature = 0;
  uint32_t level = 0;  // compression level: 0 default, 1 speed (speed_level.hpp)
  uint32_t base_vertices = 0, base_faces = 0, full_faces = 0;
  uint32_t total_splits = 0;
  float bbox_min[3] = {0, 0, 0}, bbox_max[3] = {0, 0, 0};
  uint64_t full_vertices() const { return uint64_t(base_vertices) + total_splits; }
};

void put_u32le(std::vector<uint8_t>& out, uint32_t v);
void put_f32le(std::vector<uint8_t>& out, float v);
void write_head_payload(std::vector<uint8_t>& out, const FileHeader& h);
// Parses the fields (bytes after them are ignored: later minors may append fields); false when
// the payload ends early, a varint is malformed or a field exceeds its range (flags and counts
// uint32). Semantic checks (version, counts) are the caller's.
// consumed (optional): the bytes the fields took (format 8.0's attribute fields follow them).
bool read_head_payload(const uint8_t* p, size_t size, FileHeader& h, size_t* consumed = nullptr);
// Appends a framed chunk (header + payload) to out.
void append_chunk(std::vector<uint8_t>& out, uint8_t type, const std::vector<uint8_t>& payload);

// Quantization as Draco's -qp: one step for all axes over the largest bounding-box extent.
// Float bits <-> int32 that orders like the float (lossless mode coordinates).
int32_t float_to_ordered(float f);
float ordered_to_float(int32_t i);

struct Quantizer {
  float min[3] = {0, 0, 0};
  float scale = 0;  // dequantization step: range / max_q
  double inv = 0;   // quantization: max_q / range
  uint32_t max_q = 0;
  uint32_t bits = 0;  // 0 = lossless: coordinates are the order-preserving float bit patterns
  void init(uint32_t position_bits, const float bbox_min[3], const float bbox_max[3]);
  int32_t quantize(float x, int axis) const;
  float dequantize(int32_t q, int axis) const {
    return bits ? min[axis] + float(q) * scale : ordered_to_float(q);
  }
};

}  // namespace pmz
