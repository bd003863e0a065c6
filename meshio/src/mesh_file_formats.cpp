// SPDX-License-Identifier: MIT
#include "pmz/mesh_file_formats.hpp"

#include <algorithm>
#include <cstdint>
#include <nlohmann/json.hpp>

namespace pmz {

const std::vector<MeshFileFormat>& mesh_file_formats() {
  static const std::vector<MeshFileFormat> formats = {
      {"obj", true, true, false}, {"off", true, true, false},   {"ply", true, true, true},
      {"stl", true, true, true},  {"gltf", true, false, false}, {"glb", true, true, true},
  };
  return formats;
}

const MeshFileFormat* find_mesh_file_format(std::string_view name) {
  for (const MeshFileFormat& f : mesh_file_formats())
    if (name == f.name) return &f;
  return nullptr;
}

bool mesh_format_readable(std::string_view name) {
  const MeshFileFormat* f = find_mesh_file_format(name);
  return f && f->read;
}

bool mesh_format_writable(std::string_view name) {
  const MeshFileFormat* f = find_mesh_file_format(name);
  return f && f->write;
}

std::vector<std::string> mesh_format_names(bool written) {
  std::vector<std::string> names;
  for (const MeshFileFormat& f : mesh_file_formats())
    if (written ? f.write : f.read) names.push_back(f.name);
  return names;
}

std::string mesh_format_list(bool written, std::string_view separator, std::string_view last,
                             std::string_view prefix) {
  const std::vector<std::string> names = mesh_format_names(written);
  std::string list;
  for (size_t i = 0; i < names.size(); ++i) {
    if (i > 0) list += i + 1 == names.size() && !last.empty() ? last : separator;
    list += prefix;
    list += names[i];
  }
  return list;
}

std::vector<std::string> gltf_external_buffers(std::string_view data) {
  // A .glb: 12-byte header ("glTF", version, length), then the JSON chunk (length, "JSON").
  if (data.starts_with("glTF")) {
    if (data.size() < 20 || data.substr(16, 4) != "JSON") return {};
    uint32_t length = 0;
    for (int i = 3; i >= 0; --i) length = length << 8 | uint8_t(data[12 + i]);  // little endian
    data = data.substr(20, std::min<size_t>(length, data.size() - 20));
  }
  const nlohmann::json json = nlohmann::json::parse(data, nullptr, false);
  std::vector<std::string> files;
  if (!json.is_object() || !json.contains("buffers") || !json.at("buffers").is_array())
    return files;
  for (const nlohmann::json& buffer : json.at("buffers")) {
    if (!buffer.is_object() || !buffer.contains("uri") || !buffer.at("uri").is_string()) continue;
    const std::string uri = buffer.at("uri").get<std::string>();
    if (!uri.starts_with("data:")) files.push_back(uri);
  }
  return files;
}

}  // namespace pmz
