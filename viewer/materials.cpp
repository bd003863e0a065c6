#include "materials.hpp"

#include <stb/stb_image.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>

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
  if (starts("http://") || starts("https://")) {
    error = "remote images are not fetched";
    return "";
  }
  std::string path = starts("file://") ? reference.substr(7) : reference;
  // MTL files written on Windows name textures like ".\\tex.jpg".
  for (char& c : path)
    if (c == '\\') c = '/';
  if (path[0] == '/' || directory.empty()) return path;
  return directory.back() == '/' ? directory + path : directory + "/" + path;
}

bool load_image(const std::string& path, Image& out, std::string& error) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    error = std::strerror(errno);
    return false;
  }
  int width = 0, height = 0, channels = 0;
  stbi_uc* pixels = stbi_load_from_file(f, &width, &height, &channels, 4);
  std::fclose(f);
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
