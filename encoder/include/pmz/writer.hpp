// SPDX-License-Identifier: MIT
// Turns a collapse sequence into a .pmz byte stream (spec/format.md).
//
// EXPERIMENTAL, as pmz/simplify.hpp: the encoder API may change in any release. The streams it
// writes are the stable .pmz format, which every decoder of the same major version reads.
// Errors, threads: as pmz/simplify.hpp says (no global state; the functions here use no thread
// of their own and print nothing).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "pmz/simplify.hpp"

namespace pmz {

struct WriteOptions {
  uint32_t position_bits = 14;  // 0 = lossless float32; else quantized over the largest extent
  uint64_t base_faces = 0;      // 0: as small as the sequence goes
  bool symbol_stats = false;    // fill WriteStats::symbol_bits
  // Attributes (when the mesh has them; spec/format.md section 14), bits per component, 0 =
  // lossless: texture coordinates over each set's bounding box, normals octahedral, colours over
  // [0, 1].
  uint32_t texcoord_bits = 12, normal_bits = 10, color_bits = 8;
  // Compression level (spec/format.md section 4): 0 the default (smallest), 1 the speed level
  // (simpler models: faster to decode, larger).
  uint32_t level = 0;
};

// The kinds of SPLT symbols (pmz::SymbolKind, format.hpp: groups, choice, wedge count, wedge
// rank, three residual slots), counted here so that this installed header needs no codec one.
inline constexpr int kWriteSymbolKinds = 7;

struct WriteStats {
  uint64_t header_bytes = 0, base_bytes = 0, split_bytes = 0;
  uint64_t attribute_bytes = 0;   // the ATTR chunks (within base_bytes and split_bytes)
  uint64_t node_table_bytes = 0;  // the NODE chunk (streams written in nodes)
  // Coded size of the SPLT streams over all splits: groups, vertex choice and wedges
  // (connectivity); position residuals (geometry).
  uint64_t connectivity_bits = 0, geometry_bits = 0;
  // With WriteOptions::symbol_stats: the code length of the SPLT symbols by kind (SymbolKind),
  // in bits: what each kind takes of its stream (the streams' endings add a few bits each).
  double symbol_bits[kWriteSymbolKinds] = {};
};

// Writes seq as a .pmz stream into `out` (replacing its contents) and returns true; with
// `stats` (may be null; not kept) also fills *stats. seq: as simplify() made it, on a mesh with
// finite positions; options within the ranges stated above (position_bits 0..30, level 0..1,
// texcoord_bits 0..24, normal_bits 0 or 2..16, color_bits 0..16). Returns false with a one-line
// message (the options' ranges, "non-finite vertex coordinate", a collapse inconsistent with
// the mesh, attribute tables beyond the format's limits) and `out` unchanged. Each stream is
// checked before it is returned: the full decode must give seq.mesh's faces back. The same seq
// and options give the same bytes on every run.
bool write_pmz(const CollapseSequence& seq, const WriteOptions& options, std::vector<uint8_t>& out,
               std::string& error, WriteStats* stats = nullptr);

// Vertex and face order of a full decode, relative to seq.mesh: decoded vertex i is input
// vertex vertex_order[i]. The round-trip tests use it. Only base_faces and position_bits of
// the options matter. Empty when the sequence does not replay on its mesh.
std::vector<uint32_t> decoded_vertex_order(const CollapseSequence& seq,
                                           const WriteOptions& options);

}  // namespace pmz
