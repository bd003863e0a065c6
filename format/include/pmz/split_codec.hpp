// Coding of one SPLT chunk: groups of vertex splits into seven range-coded streams with
// adaptive context models (spec/format.md, "SPLT"). Writer and decoder share this code.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace pmz {

struct SplitCode {
  uint32_t v;                // vertex that splits
  uint32_t code_l, code_r;   // wedge codes (spec: closed/open ring rules)
  int32_t residual[3];       // position residual per axis
};

// Appends the SPLT payload for the given groups (sizes sum to count). stream_bytes[k]
// receives the coded size of stream k (optional).
void encode_split_chunk(const std::vector<uint32_t>& group_sizes, const SplitCode* splits, size_t count,
                        std::vector<uint8_t>& payload, uint64_t* stream_bytes = nullptr);

// Decodes a SPLT payload, appending its splits to out. Every v must be below the vertex count
// at the start of its group (vertices_before + splits of earlier groups); at most max_splits.
// Validates everything before appending; false + message on any problem.
bool decode_split_chunk(const uint8_t* p, size_t size, uint64_t vertices_before, uint64_t max_splits,
                        std::vector<SplitCode>& out, std::string& error);

// Coded stream sizes of a SPLT payload without decoding it (for pmz-info).
bool split_chunk_stream_sizes(const uint8_t* p, size_t size, uint64_t& count, uint64_t stream_bytes[7]);

}  // namespace pmz
