// SPDX-License-Identifier: MIT
// Coding of the BASE mesh (spec/format.md section 7): one range-coded stream holding a face
// traversal (each face after a component's first is attached to an open edge of the faces
// coded before; its third vertex is new, a neighbour on the front, or an earlier vertex) and
// the positions of new vertices, predicted by the parallelogram across that edge. Writer and
// decoder share the traversal, so both number vertices and faces the same way.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "pmz/status.hpp"

namespace pmz {

// The base mesh as decoded: n vertices (3 int32 coordinates each) and faces (3 vertex ids each,
// counter-clockwise), numbered in traversal order.
struct BaseMesh {
  std::vector<int32_t> coords;
  std::vector<uint32_t> faces;
};

// Codes a mesh of n vertices and fn faces (edge-manifold, consistently oriented: no directed
// edge twice, no face with a repeated vertex) and appends the stream to out. given_of[d] is the
// input id of decoded vertex d; decoded.faces are the faces as the decoder numbers and rotates
// them (decoded ids). False (with a message) when the input breaks those rules.
bool encode_base(const int32_t* coords, uint32_t n, const uint32_t* faces, uint32_t fn,
                 std::vector<uint8_t>& out, std::vector<uint32_t>& given_of, BaseMesh& decoded,
                 std::string& error);

// Decodes a stream of `size` bytes holding n vertices and fn faces. Checks the counts against
// the stream size before allocating (spec/format.md sections 7 and 12), every reference, and the
// end of input; edge-manifoldness of the result is left to ProgressiveMesh::build. Status::ok, or
// corrupt / limit_exceeded with a one-line message in error.
Status decode_base(const uint8_t* p, size_t size, uint32_t n, uint32_t fn, BaseMesh& out,
                   std::string& error);

}  // namespace pmz
