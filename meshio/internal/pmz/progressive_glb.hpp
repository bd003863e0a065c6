// SPDX-License-Identifier: MIT
// A .pmz stream carried in binary glTF (docs/gltf-binding.md, draft): pmz-encode's .glb output.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "pmz/mesh.hpp"

namespace pmz {

// The extension of a glTF primitive that carries a .pmz stream (docs/gltf-binding.md, draft).
inline constexpr const char* kProgressiveExtension = "PMZ_progressive_mesh";
// A .pmz stream for write_progressive_glb: its bytes and the HEAD fields the extension repeats.
struct GlbStream {
  std::string_view bytes;
  std::string version;  // "MAJOR.MINOR"
  uint64_t full_vertices = 0, full_faces = 0;
  float bbox_min[3] = {0, 0, 0}, bbox_max[3] = {0, 0, 0};
};
// Texture files to embed: material texture names are read relative to `dir`; a file that cannot
// be read or is not PNG or JPEG stays a URI, with one line saying why in `not_embedded`.
struct GlbTextures {
  std::string dir;
  std::vector<std::string> not_embedded;
};
// A binary glTF of `base`, the stream's level-0 mesh (as write_mesh writes .glb: one vertex per
// wedge, one primitive per material, materials in the stream's order), each primitive carrying
// the PMZ_progressive_mesh extension that names the stream's buffer view, the buffer's last.
// Texture files are embedded as images before the stream.
bool write_progressive_glb(const IndexedMesh& base, const GlbStream& stream, GlbTextures& textures,
                           std::string& bytes, std::string& error);

}  // namespace pmz
