// SPDX-License-Identifier: MIT
// A .pmz stream carried in binary glTF (docs/gltf-binding.md, draft): pmz-encode's .glb output.
#pragma once
#include <cstdint>
#include <map>
#include <memory>
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

// A glTF input whose scene is kept in a GLB (docs/gltf-binding.md, "Scenes"): each mesh its own
// stream, the nodes, materials, textures, samplers and images as the input has them.
class GltfScene {
 public:
  GltfScene();
  ~GltfScene();
  // Parses a .gltf or .glb (`data`; external buffers and images beside `path`) and reads its
  // default scene whole, as read_mesh would: false with one line naming the file where it is
  // malformed.
  bool read(const std::string& path, std::string_view data, std::string& error);
  // The nodes of the default scene that name a mesh with triangles (a mesh two nodes name counts
  // twice).
  size_t mesh_nodes() const;
  // The meshes with triangles the default scene names, in the order a depth-first walk of it
  // first reaches them.
  size_t mesh_count() const;
  // One line for each mesh the scene names that has no triangles (points or lines only): it is
  // not carried, and its nodes name no mesh.
  const std::vector<std::string>& meshes_left_out() const;
  // Mesh `i` in its own coordinates (no node transform applied); its material table, when any of
  // its primitives names a material, is the asset's whole table (material k is glTF material k,
  // then "default" for primitives without one).
  bool read_mesh(size_t i, PolygonSoup& out, std::string& error) const;
  // "mesh K" (its index in the input) and its name, if any, for messages.
  std::string mesh_name(size_t i) const;
  // A binary glTF of the scene: mesh i's primitives hold bases[i] (as write_progressive_glb
  // writes one base) and carry streams[i]; the nodes the default scene reaches (depth-first
  // order), the materials, textures, samplers and images (embedded: the input's own, or the
  // files its URIs name; one that cannot be read stays a URI, named in not_embedded). The buffer
  // holds every base mesh, then the images, then the streams in mesh order.
  bool write_glb(const std::vector<IndexedMesh>& bases, const std::vector<GlbStream>& streams,
                 std::vector<std::string>& not_embedded, std::string& bytes,
                 std::string& error) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace pmz
