// SPDX-License-Identifier: MIT
// Materials as pmz-view draws them: a base colour times an optional base-colour texture, read
// with stb_image (Debian's libstb) from the file the mesh's MTL / glTF material names.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace pmzview {

struct ViewMaterial {
  std::string name;
  float base_color[4] = {1, 1, 1, 1};
  std::string texture;  // base-colour texture as the file names it (relative path or URI)
};

struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;  // top row first
  bool empty() const { return rgba.empty(); }
};

// The file a texture reference names: relative references are resolved against `directory`
// (the folder or URL folder of the file that holds the material; "" = the working directory).
// Returns "" with `error` set for references pmz-view cannot read (data: URIs).
std::string texture_path(const std::string& directory, const std::string& reference,
                         std::string& error);

// Reads PNG, JPEG, BMP, TGA, ... into 8-bit RGBA from a file or an http(s) URL. False with a
// reason on failure.
bool load_image(const std::string& path, Image& out, std::string& error);

// Loads each material's texture; a texture that cannot be loaded leaves its image empty and
// adds one warning line ("texture 'x.png' of material 'm': cannot read ...: drawn untextured").
// Images are shared by path: several materials naming one file read it once.
void load_textures(const std::vector<ViewMaterial>& materials, const std::string& directory,
                   std::vector<Image>& images, std::vector<std::string>& warnings);

}  // namespace pmzview
