// SPDX-License-Identifier: MIT
#include "encode_plan.hpp"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <type_traits>

#include "pmz/app_support.hpp"

namespace pmz::tool {

namespace {

constexpr char kMeshMagic[8] = {'P', 'M', 'Z', 'M', 'E', 'S', 'H', '1'};

struct Out {
  std::vector<uint8_t>& bytes;
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* b = reinterpret_cast<const uint8_t*>(&v);
    bytes.insert(bytes.end(), b, b + sizeof v);
  }
  template <class T>
  void put(const std::vector<T>& v) {
    put(uint64_t(v.size()));
    const auto* b = reinterpret_cast<const uint8_t*>(v.data());
    bytes.insert(bytes.end(), b, b + v.size() * sizeof(T));
  }
  void put(const std::string& s) { put(std::vector<char>(s.begin(), s.end())); }
};

struct In {
  const uint8_t *p, *end;
  bool ok = true;
  template <class T>
  void get(T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (!ok || size_t(end - p) < sizeof v) return void(ok = false);
    std::memcpy(&v, p, sizeof v), p += sizeof v;
  }
  template <class T>
  void get(std::vector<T>& v) {
    uint64_t n = 0;
    get(n);
    if (!ok || n > uint64_t(end - p) / sizeof(T)) return void(ok = false);
    v.resize(n);
    if (n) std::memcpy(v.data(), p, n * sizeof(T)), p += n * sizeof(T);  // (data() may be null)
  }
  void get(std::string& s) {
    std::vector<char> c;
    get(c);
    s.assign(c.begin(), c.end());
  }
};

// Every field of the mesh, in one order for both directions.
template <class Stream, class Mesh>
void fields(Stream& s, Mesh& mesh) {
  auto& a = mesh.attributes;
  s.put_or_get(mesh.positions), s.put_or_get(mesh.indices), s.put_or_get(a.corner_wedges);
  s.put_or_get(a.wedge_vertices), s.put_or_get(a.normals), s.put_or_get(a.colors);
  s.put_or_get(a.color_components), s.put_or_get(a.face_materials);
  s.put_or_get(a.material_library);
  s.count(a.texcoords);
  for (auto& t : a.texcoords) s.put_or_get(t);
  s.count(a.materials);
  for (auto& m : a.materials) {
    s.put_or_get(m.name), s.put_or_get(m.base_color_texture), s.put_or_get(m.normal_texture);
    s.put_or_get(m.base_color);
  }
}

struct Writer : Out {
  template <class T>
  void put_or_get(const T& v) {
    put(v);
  }
  template <class T>
  void count(const std::vector<T>& v) {
    put(uint64_t(v.size()));
  }
};

struct Reader : In {
  template <class T>
  void put_or_get(T& v) {
    get(v);
  }
  template <class T>
  void count(std::vector<T>& v) {
    uint64_t n = 0;
    get(n);
    // Each element takes at least 8 bytes (a length).
    if (!ok || n > uint64_t(end - p) / 8) return void(ok = false);
    v.resize(n);
  }
};

bool read_file(const std::string& path, std::vector<uint8_t>& bytes, std::string& error) {
  return app_support::read_input(path, bytes, error);
}

}  // namespace

void mesh_to_bytes(const IndexedMesh& mesh, std::vector<uint8_t>& out) {
  out.assign(kMeshMagic, kMeshMagic + 8);
  Writer w{{out}};
  fields(w, mesh);
}

bool mesh_from_bytes(const std::vector<uint8_t>& bytes, IndexedMesh& mesh, std::string& error) {
  if (bytes.size() < 8 || std::memcmp(bytes.data(), kMeshMagic, 8) != 0)
    return error = "not a mesh of an encode plan", false;
  Reader r{{bytes.data() + 8, bytes.data() + bytes.size()}};
  IndexedMesh m;
  fields(r, m);
  if (!r.ok || r.p != r.end) return error = "cut short or damaged", false;
  mesh = std::move(m);
  return true;
}

std::string EncodePlan::file(const std::string& name) const {
  return (std::filesystem::path(dir) / name).string();
}

bool EncodePlan::exists() const {
  std::error_code ec;
  return std::filesystem::exists(file("tasks"), ec);
}

bool EncodePlan::write(const IndexedMesh& mesh, const std::vector<std::string>& args,
                       uint32_t tasks, std::string& error) const {
  if (exists()) return error = dir + ": holds a plan already (give a new or empty folder)", false;
  std::vector<uint8_t> bytes;
  mesh_to_bytes(mesh, bytes);
  if (!app_support::write_output(file("mesh"), bytes.data(), bytes.size(), error)) return false;
  std::string text;
  for (const std::string& a : args) text += a, text += '\0';
  if (!app_support::write_output(file("options"), text.data(), text.size(), error)) return false;
  text.clear();
  for (uint32_t t = 0; t < tasks; ++t) text += std::to_string(t) + "\n";
  return app_support::write_output(file("tasks"), text.data(), text.size(), error);
}

bool EncodePlan::read_mesh(IndexedMesh& mesh, std::string& error) const {
  std::vector<uint8_t> bytes;
  if (!read_file(file("mesh"), bytes, error)) return false;
  if (!mesh_from_bytes(bytes, mesh, error)) return error = file("mesh") + ": " + error, false;
  return true;
}

bool EncodePlan::read_options(std::vector<std::string>& args, std::string& error) const {
  std::vector<uint8_t> bytes;
  if (!read_file(file("options"), bytes, error)) return false;
  if (!bytes.empty() && bytes.back() != 0)
    return error = file("options") + ": cut short or damaged", false;
  args.clear();
  for (size_t i = 0; i < bytes.size();) {
    const size_t end = std::find(bytes.begin() + i, bytes.end(), 0) - bytes.begin();
    args.emplace_back(bytes.begin() + i, bytes.begin() + end);
    i = end + 1;
  }
  return true;
}

bool EncodePlan::read_tasks(std::vector<std::string>& ids, std::string& error) const {
  std::vector<uint8_t> bytes;
  if (!read_file(file("tasks"), bytes, error)) return false;
  ids.clear();
  std::string line;
  for (uint8_t c : bytes) {
    if (c != '\n') {
      line += char(c);
      continue;
    }
    if (!line.empty()) ids.push_back(line);
    line.clear();
  }
  if (!line.empty()) return error = file("tasks") + ": cut short (no final newline)", false;
  return true;
}

}  // namespace pmz::tool
