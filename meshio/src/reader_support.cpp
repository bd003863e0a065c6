// SPDX-License-Identifier: MIT
// The format readers' shared parts (reader_support.hpp): file reading, error messages,
// vertex welding.
#include "reader_support.hpp"

#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <unordered_map>
#include <vector>

namespace pmz {

bool read_file(const std::string& path, std::string& data, std::string& error) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    error = path + ": no such file";
    return false;
  }
  if (std::filesystem::is_directory(path, ec)) {
    error = path + ": is a directory, not a mesh file";
    return false;
  }
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    error = path + ": cannot open: " + std::strerror(errno);
    return false;
  }
  data.clear();
  char buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) data.append(buf, n);
  bool failed = std::ferror(f);
  std::fclose(f);
  if (failed) {
    error = path + ": read error";
    return false;
  }
  if (data.empty()) {
    error = path + ": empty file";
    return false;
  }
  return true;
}

std::string line_error(const std::string& path, uint64_t line, const std::string& what) {
  return path + ": line " + std::to_string(line) + ": " + what;
}

std::string nonfinite_error(const std::string& path, uint64_t vertex, uint64_t line) {
  std::string where = line ? " (line " + std::to_string(line) + ")" : std::string();
  return path + ": vertex " + std::to_string(vertex) + where + " has a NaN or infinite coordinate";
}

std::string range_error(const std::string& path, uint64_t face, uint64_t line, int64_t index,
                        uint64_t vertices) {
  std::string where = line ? " (line " + std::to_string(line) + ")" : std::string();
  return path + ": face " + std::to_string(face) + where + " references vertex " +
         std::to_string(index) + ", but the file has " + std::to_string(vertices) +
         " vertices (0-based)";
}

void weld_vertices(PolygonSoup& soup) {
  std::unordered_map<uint64_t, std::vector<uint32_t>> buckets;
  std::vector<uint32_t> map(soup.vertex_count());
  std::vector<float> kept;
  kept.reserve(soup.positions.size());
  for (uint32_t v = 0; v < soup.vertex_count(); ++v) {
    float p[3];
    uint64_t h = 1469598103934665603ull;
    for (int k = 0; k < 3; ++k) {
      p[k] = soup.positions[size_t(v) * 3 + k];
      if (p[k] == 0) p[k] = 0;  // -0 -> +0
      h = (h ^ std::bit_cast<uint32_t>(p[k])) * 1099511628211ull;
    }
    std::vector<uint32_t>& bucket = buckets[h];
    map[v] = kNoAttribute;
    for (uint32_t w : bucket)
      if (std::memcmp(&kept[size_t(w) * 3], p, sizeof p) == 0) map[v] = w;
    if (map[v] == kNoAttribute) {
      map[v] = uint32_t(kept.size() / 3);
      bucket.push_back(map[v]);
      kept.insert(kept.end(), p, p + 3);
    }
  }
  soup.welded_vertices += soup.vertex_count() - kept.size() / 3;
  soup.positions = std::move(kept);
  for (uint32_t& c : soup.corners) c = map[c];
}

}  // namespace pmz
