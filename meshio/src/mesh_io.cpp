// SPDX-License-Identifier: MIT
// Mesh input/output, the dispatch by file extension: each format's reader (mesh_obj.cpp,
// mesh_off.cpp, mesh_ply.cpp, mesh_stl.cpp, mesh_gltf.cpp) into a raw polygon soup, the checks
// every reader's output passes before repair_mesh (mesh_repair.cpp) indexes it, and each
// format's writer from the flat IndexedMesh, to a sink or atomically to a file. OpenMesh is not
// used here on purpose: its mesh building detaches or drops faces it cannot represent (and its
// OFF reader hangs on huge counts and reads `nan` as garbage indices), while pmz must keep every
// face; repair_mesh does the repair instead.
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string_view>
#include <utility>

#include "mesh_formats.hpp"
#include "pmz/mesh.hpp"
#include "pmz/mesh_file_formats.hpp"
#include "pmz/mesh_stream.hpp"
#include "pmz/output_file.hpp"
#include "reader_support.hpp"
#include "writer_support.hpp"

namespace pmz {

namespace {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// The body of a mesh file in the format `ext` names (with its dot; checked by check_writable).
void write_body(Writer& w, const std::string& ext, const IndexedMesh& m, const std::string& mtl) {
  if (ext == ".obj")
    write_obj(w, m, mtl);
  else if (ext == ".ply")
    write_ply(w, m);
  else if (ext == ".off")
    write_off(w, m);
  else  // .stl
    write_stl(w, m);
}

}  // namespace

// The formats read and written are pmz/mesh_file_formats.hpp's list; `ext` here has its dot.
static bool known_input(const std::string& ext) {
  return ext.size() > 1 && mesh_format_readable(std::string_view(ext).substr(1));
}

static std::string unknown_format(const std::string& path, const std::string& ext, bool written) {
  return path + ": unknown mesh format '" + ext + "' (expected " +
         mesh_format_list(written, ", ", " or ", ".") + ")";
}

// One check of every reader's attribute output before repair indexes into it: each corner
// array covers every corner and each index is kNoAttribute or names an entry of its pool.
// (fuzz_mesh_ply found a PLY header whose attribute pools and corner indices disagreed.)
static bool check_attribute_indices(const std::string& path, const PolygonSoup& soup,
                                    std::string& error) {
  const SoupAttributes& a = soup.attributes;
  const size_t corners = soup.corners.size();
  auto bad = [&](const char* what) {
    error = path + ": " + what + " attribute index out of range";
    return false;
  };
  auto check = [&](const std::vector<uint32_t>& corner, size_t pool, size_t width,
                   const char* what) {
    if (corner.empty()) return true;
    if (corner.size() != corners || width == 0) return bad(what);
    for (uint32_t i : corner)
      if (i != kNoAttribute && (uint64_t(i) + 1) * width > pool) return bad(what);
    return true;
  };
  if (a.corner_texcoords.size() != a.texcoords.size()) return bad("texture coordinate");
  for (size_t s = 0; s < a.texcoords.size(); ++s)
    if (!check(a.corner_texcoords[s], a.texcoords[s].size(), 2, "texture coordinate")) return false;
  if (!check(a.corner_normals, a.normals.size(), 3, "normal")) return false;
  if (!check(a.corner_colors, a.colors.size(), a.color_components, "colour")) return false;
  if (!a.face_materials.empty() && a.face_materials.size() != soup.face_count())
    return bad("material");
  return true;
}

namespace {

// The format's reader on `in`, then the checks of what every reader returns. `read_failure`
// words a failed read of the file (the source ends where it failed).
bool parse_source(const std::string& path, const std::string& ext, ByteSource& in, PolygonSoup& out,
                  std::string& error, const std::function<std::string(int)>& read_failure) {
  out = PolygonSoup();
  out.face_offsets.push_back(0);
  bool ok = false;
  if (in.peek(1).empty())
    error = path + ": empty file";
  else if (ext == ".obj")
    ok = read_obj(path, in, out, error);
  else if (ext == ".off")
    ok = read_off(path, in, out, error);
  else if (ext == ".ply")
    ok = read_ply(path, in, out, error);
  else if (ext == ".stl")
    ok = read_stl(path, in, out, error);
  else
    ok = read_gltf(path, in.rest(), out, error);
  if (ok && out.face_count() == 0) {
    error = path + ": mesh has no faces";
    ok = false;
  }
  if (ok) ok = check_attribute_indices(path, out, error);
  if (in.read_errno()) error = read_failure(in.read_errno()), ok = false;
  if (!ok) out = PolygonSoup();
  return ok;
}

// Streams `file` from its position: a regular file with its size known, anything else (a pipe,
// a terminal) as a source of unknown size that ends where the file does. (glTF alone is read
// whole, by parse_source: its buffers are addressed by offset.)
bool read_open_file(const std::string& path, const std::string& ext, std::FILE* file,
                    PolygonSoup& out, std::string& error,
                    const std::function<void(double)>& progress, size_t window,
                    const std::function<std::string(int)>& read_failure) {
  const long at = std::ftell(file);
  long end = -1;
  if (at >= 0 && std::fseek(file, 0, SEEK_END) == 0) end = std::ftell(file);
  if (end >= at && at >= 0 && std::fseek(file, at, SEEK_SET) == 0) {
    ByteSource in(file, uint64_t(end - at), window, progress);
    return parse_source(path, ext, in, out, error, read_failure);
  }
  std::clearerr(file);
  ByteSource in(file, ByteSource::kUnknownSize, window, progress);
  return parse_source(path, ext, in, out, error, read_failure);
}

}  // namespace

bool parse_polygon_soup(const std::string& path, std::string_view data, PolygonSoup& out,
                        std::string& error) {
  out = PolygonSoup();
  std::string ext = lower_extension(path);
  if (!known_input(ext)) {
    error = unknown_format(path, ext, false);
    return false;
  }
  ByteSource in(data);
  return parse_source(path, ext, in, out, error, [&](int) { return path + ": read error"; });
}

bool read_polygon_soup(const std::string& path, std::FILE* file, PolygonSoup& out,
                       std::string& error, const std::function<void(double)>& progress,
                       size_t window) {
  out = PolygonSoup();
  std::string ext = lower_extension(path);
  if (!known_input(ext)) {
    error = unknown_format(path, ext, false);
    return false;
  }
  return read_open_file(path, ext, file, out, error, progress, window,
                        [&](int err) { return path + ": cannot read: " + std::strerror(err); });
}

bool read_polygon_soup(const std::string& path, PolygonSoup& out, std::string& error) {
  out = PolygonSoup();
  std::string ext = lower_extension(path);
  if (!known_input(ext)) {
    error = unknown_format(path, ext, false);
    return false;
  }
  std::FILE* file = open_file(path, error);
  if (!file) return false;
  const bool ok = read_open_file(path, ext, file, out, error, {}, kReadWindow,
                                 [&](int) { return path + ": read error"; });
  std::fclose(file);
  return ok;
}

bool read_mesh(const std::string& path, IndexedMesh& out, MeshRepairStats& stats,
               std::string& error) {
  PolygonSoup soup;
  stats = MeshRepairStats();
  if (!read_polygon_soup(path, soup, error)) return false;
  repair_mesh(std::move(soup), out, stats);
  if (out.face_count() == 0) {
    error = path + ": no usable faces (all " + std::to_string(stats.degenerate_faces_dropped) +
            " faces are degenerate: fewer than three distinct vertices)";
    return false;
  }
  return true;
}

bool read_mesh(const std::string& path, IndexedMesh& out, std::string& error) {
  MeshRepairStats stats;
  if (!read_mesh(path, out, stats, error)) return false;
  std::string summary = stats.summary();
  if (!summary.empty()) std::fprintf(stderr, "pmz: %s: %s\n", path.c_str(), summary.c_str());
  return true;
}

namespace {

// Through OutputFile (pmz/output_file.hpp): a temporary renamed over the target when `body` has
// written everything, removed on any error; symlinks, devices and FIFOs as every tool does.
bool write_atomic(const std::string& path, const std::function<void(Writer&)>& body,
                  std::string& error) {
  OutputFile out;
  if (!out.open(path, false, error)) return false;
  const MeshSink sink = [&](const void* p, size_t n) { return out.write(p, n); };
  Writer w(sink);
  body(w);
  w.finish();  // a failed write is remembered by `out` and reported by commit()
  return out.commit(error);
}

// A mesh's attribute arrays must agree with its geometry before anything is written.
bool check_attributes(const std::string& path, const IndexedMesh& m, std::string& error) {
  const MeshAttributes& a = m.attributes;
  const size_t wedges = a.wedge_count();
  auto bad = [&](const std::string& what) {
    error = path + ": mesh to write has " + what;
    return false;
  };
  if (a.has_wedges() && a.corner_wedges.size() != m.indices.size())
    return bad("attributes for " + std::to_string(a.corner_wedges.size()) + " of " +
               std::to_string(m.indices.size()) + " corners");
  for (size_t c = 0; c < a.corner_wedges.size(); ++c)
    if (a.corner_wedges[c] >= wedges || a.wedge_vertices[a.corner_wedges[c]] != m.indices[c])
      return bad("corner " + std::to_string(c) + " with a wedge of another vertex");
  for (const std::vector<float>& t : a.texcoords)
    if (t.size() != wedges * 2) return bad("texture coordinates not one pair per wedge");
  if (!a.normals.empty() && a.normals.size() != wedges * 3) return bad("normals not one per wedge");
  if (a.colors.size() != wedges * a.color_components) return bad("colours not one per wedge");
  if (!a.face_materials.empty() && a.face_materials.size() != m.face_count())
    return bad("material ids not one per face");
  for (uint32_t id : a.face_materials)
    if (id >= a.materials.size()) return bad("a face with material " + std::to_string(id));
  return true;
}

}  // namespace

namespace {

// What both writers check first: a known format (ext with its dot), indices and attributes that
// agree with the geometry.
bool check_writable(const std::string& path, const std::string& ext, const IndexedMesh& mesh,
                    std::string& error) {
  if (ext.size() < 2 || !mesh_format_writable(std::string_view(ext).substr(1))) {
    error = unknown_format(path, ext, true);
    return false;
  }
  for (uint32_t i : mesh.indices)
    if (i >= mesh.vertex_count()) {
      error = path + ": mesh to write references vertex " + std::to_string(i) + " of " +
              std::to_string(mesh.vertex_count());
      return false;
    }
  return check_attributes(path, mesh, error);
}

}  // namespace

bool write_mesh_to(const std::string& name, const std::string& format, const IndexedMesh& mesh,
                   const MeshSink& sink, std::string& error, const std::string& mtl_name) {
  const std::string ext = "." + format;
  if (!check_writable(name, ext, mesh, error)) return false;
  Writer w(sink);
  if (ext == ".glb") {
    std::string bytes;
    if (!write_glb(mesh, bytes, error)) {
      error = name + ": " + error;
      return false;
    }
    w.put(bytes.data(), bytes.size());
  } else {
    write_body(w, ext, mesh, ext == ".obj" ? mtl_name : "");
  }
  if (w.finish()) return true;
  error = name + ": write failed";
  return false;
}

bool write_material_library_to(const std::string& name, const std::vector<Material>& materials,
                               const MeshSink& sink, std::string& error) {
  Writer w(sink);
  write_mtl(w, materials);
  if (w.finish()) return true;
  error = name + ": write failed";
  return false;
}

bool write_material_library(const std::string& path, const std::vector<Material>& materials,
                            std::string& error) {
  return write_atomic(
      path, [&](Writer& w) { write_mtl(w, materials); }, error);
}

bool write_mesh(const std::string& path, const IndexedMesh& mesh, std::string& error) {
  std::string ext = lower_extension(path);
  if (!check_writable(path, ext, mesh, error)) return false;
  if (ext == ".glb") {
    std::string bytes;
    if (!write_glb(mesh, bytes, error)) {
      error = path + ": " + error;
      return false;
    }
    return write_atomic(
        path, [&](Writer& w) { w.put(bytes.data(), bytes.size()); }, error);
  }
  std::string mtl;
  if (ext == ".obj" && !mesh.attributes.materials.empty()) {
    // The MTL goes first, beside the OBJ, named after it (mtllib names it relative to the OBJ).
    std::filesystem::path target(path);
    mtl = target.stem().string() + ".mtl";
    if (!write_material_library((target.parent_path() / mtl).string(), mesh.attributes.materials,
                                error))
      return false;
  }
  return write_atomic(
      path, [&](Writer& w) { write_body(w, ext, mesh, mtl); }, error);
}

}  // namespace pmz
