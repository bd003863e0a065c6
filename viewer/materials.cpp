// SPDX-License-Identifier: MIT
#include "materials.hpp"

#include <stb/stb_image.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <map>

#include "source.hpp"

namespace pmzview {

std::string texture_path(const std::string& directory, const std::string& reference,
                         std::string& error) {
  auto starts = [&](const char* prefix) { return reference.rfind(prefix, 0) == 0; };
  if (reference.empty()) {
    error = "empty file name";
    return "";
  }
  if (starts("data:")) {
    error = "embedded (data:) images are not read";
    return "";
  }
  if (starts("http://") || starts("https://")) return reference;
  std::string path = starts("file://") ? reference.substr(7) : reference;
  // MTL files written on Windows name textures like ".\\tex.jpg".
  for (char& c : path)
    if (c == '\\') c = '/';
  if (path[0] == '/' || directory.empty()) return path;
  return directory.back() == '/' ? directory + path : directory + "/" + path;
}

bool load_image(const std::string& path, Image& out, std::string& error) {
  int width = 0, height = 0, channels = 0;
  stbi_uc* pixels = nullptr;
  if (is_url(path)) {
    // Fetched whole (textures are small next to meshes), with the stream's own HTTP client.
    std::unique_ptr<Source> source = open_source(path, error);
    std::vector<uint8_t> bytes;
    std::atomic<bool> stop{false};
    if (source)
      error = source->run(
          [&](const uint8_t* data, size_t size) {
            bytes.insert(bytes.end(), data, data + size);
            return bytes.size() < (size_t(1) << 30);
          },
          stop);
    if (!source || !error.empty()) return false;
    if (bytes.size() > size_t(INT_MAX)) {
      error = "image too large";
      return false;
    }
    pixels = stbi_load_from_memory(bytes.data(), int(bytes.size()), &width, &height, &channels, 4);
  } else {
    FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) {
      error = std::strerror(errno);
      return false;
    }
    pixels = stbi_load_from_file(f, &width, &height, &channels, 4);
    std::fclose(f);
  }
  if (!pixels) {
    const char* reason = stbi_failure_reason();
    error = std::string("not a readable image (") + (reason ? reason : "unknown format") + ")";
    return false;
  }
  out.width = width;
  out.height = height;
  out.rgba.assign(pixels, pixels + size_t(width) * size_t(height) * 4);
  stbi_image_free(pixels);
  return true;
}

void load_textures(const std::vector<ViewMaterial>& materials, const std::string& directory,
                   std::vector<Image>& images, std::vector<std::string>& warnings) {
  images.assign(materials.size(), Image{});
  std::map<std::string, size_t> loaded;  // path -> first material that read it
  for (size_t m = 0; m < materials.size(); ++m) {
    const ViewMaterial& material = materials[m];
    if (material.texture.empty()) continue;
    std::string error;
    const std::string path = texture_path(directory, material.texture, error);
    if (!path.empty()) {
      auto it = loaded.find(path);
      if (it != loaded.end()) {
        images[m] = images[it->second];
        continue;
      }
      if (load_image(path, images[m], error)) {
        loaded.emplace(path, m);
        continue;
      }
      error = "cannot read " + path + ": " + error;
    }
    warnings.push_back("texture '" + material.texture + "' of material '" + material.name +
                       "': " + error + "; drawn untextured");
  }
}

}  // namespace pmzview
