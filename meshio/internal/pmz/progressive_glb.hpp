// SPDX-License-Identifier: MIT
// A .pmz stream carried in binary glTF (docs/gltf-binding.md, draft): pmz-encode's .glb output.
#pragma once
#include <cstdint>
#include <map>
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
// Textures to embed: a material's texture is the image of that name in `images` (a glTF
// input's own, read_gltf_images), else the file of that name relative to `dir`; one that cannot
// be read or is not PNG or JPEG stays a URI, with one line saying why in `not_embedded`.
struct GlbTextures {
  std::string dir;
  std::map<std::string, std::string> images;
  std::vector<std::string> not_embedded;
};
// The images a .gltf or .glb embeds (buffer views, data: URIs) by the name its materials' textures
// get when read (the image's name; unnamed ones are not named by the materials either).
bool read_gltf_images(const std::string& path, std::map<std::string, std::string>& images,
                      std::string& error);
// A binary glTF of `base`, the stream's level-0 mesh (as write_mesh writes .glb: one vertex per
// wedge, one primitive per material, materials in the stream's order), each primitive carrying
// the PMZ_progressive_mesh extension that names the stream's buffer view, the buffer's last.
// Textures are embedded as images (named as the materials name them) before the stream.
bool write_progressive_glb(const IndexedMesh& base, const GlbStream& stream, GlbTextures& textures,
                           std::string& bytes, std::string& error);

}  // namespace pmz
