// SPDX-License-Identifier: MIT
#include "tool_mesh.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <utility>
#include <vector>

#include "pmz/app_support.hpp"
#include "pmz/mesh_file_formats.hpp"
#include "pmz/mesh_stream.hpp"

namespace pmz::tool {

namespace {

void replace_all(std::string& s, const std::string& from, const std::string& to) {
  if (from.empty()) return;
  for (size_t at = 0; (at = s.find(from, at)) != std::string::npos; at += to.size())
    s.replace(at, from.size(), to);
}

// A glTF read from stdin has no folder to look its buffer files up in (the temporary it is
// parsed from would give it /tmp): only embedded buffers are read.
bool no_external_gltf_buffers(const std::string& format, const std::vector<uint8_t>& bytes,
                              std::string& error) {
  if (format != "gltf" && format != "glb") return true;
  const std::vector<std::string> files = gltf_external_buffers(
      std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
  if (files.empty()) return true;
  error =
      "stdin: a glTF read from stdin can use only embedded buffers (a .glb's own or data: "
      "URIs), and this one references '" +
      files.front() + "'; give the file's path instead";
  return false;
}

}  // namespace

bool read_mesh_input(const std::string& path, const std::string& stdin_format, IndexedMesh& mesh,
                     std::string& error, app_support::Progress* progress) {
  const bool from_stdin = path == "-";
  const std::string shown = from_stdin ? "stdin" : path;
  std::vector<uint8_t> bytes;
  std::function<void(double)> read_progress;
  if (progress) {
    progress->update("reading", 0);
    read_progress = [progress](double f) { progress->update("reading", f); };
  }
  // A file is parsed as it is read (the bar follows the bytes), and so is stdin, pipe or not.
  // The parsers go by the path's extension and look for the files it refers to (MTL) beside it:
  // stdin is parsed under the name of an empty temporary file with the format's extension, and
  // messages say "stdin" instead of that name. A glTF from stdin is read whole (as a glTF file
  // is: its buffers are addressed by offset) into that temporary file.
  ScratchFile scratch;
  PolygonSoup soup;
  bool ok = true;
  const bool gltf = stdin_format == "gltf" || stdin_format == "glb";
  if (from_stdin && !gltf) {
    if (FILE* file = app_support::open_input(path, error))
      ok = scratch.create({}, app_support::name(), "." + stdin_format, error) &&
           read_polygon_soup(scratch.path(), file, soup, error, read_progress);
    else
      ok = false;
  } else if (from_stdin) {
    ok = app_support::read_input(path, bytes, error, read_progress) &&
         no_external_gltf_buffers(stdin_format, bytes, error) &&
         scratch.create(bytes, app_support::name(), "." + stdin_format, error) &&
         parse_polygon_soup(
             scratch.path(),
             std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), soup,
             error);
    bytes = std::vector<uint8_t>();
  } else if (FILE* file = app_support::open_input(path, error)) {
    ok = read_polygon_soup(path, file, soup, error, read_progress);
    std::fclose(file);
  } else {
    ok = false;
  }
  const std::string parsed = from_stdin ? scratch.path() : path;
  MeshRepairStats stats;
  if (ok) {
    repair_mesh(std::move(soup), mesh, stats);
    if (mesh.face_count() == 0)
      ok = false, error = parsed + ": no usable faces (all " +
                          std::to_string(stats.degenerate_faces_dropped) +
                          " faces are degenerate: fewer than three distinct vertices)";
  }
  if (!ok && from_stdin) replace_all(error, scratch.path(), shown);
  const std::string summary = stats.summary();
  if (ok && !summary.empty()) app_support::print_error(shown, summary);
  return ok;
}

CLI::Option* add_format_option(CLI::App& app, std::string& format, bool read, bool write,
                               const std::string& help) {
  std::vector<std::string> names;
  for (const MeshFileFormat& f : mesh_file_formats())
    if ((read && f.read) || (write && f.write)) names.push_back(f.name);
  std::string list;
  for (const std::string& name : names) list += (list.empty() ? "" : "|") + name;
  return app.add_option("--format", format, help + ": " + list)->check(CLI::IsMember(names));
}

std::string mesh_files_help(const std::string& what, bool written, const std::string& rest) {
  return what + " (" + mesh_format_list(written, ", ", " or ", ".") +
         (rest.empty() ? "" : "; " + rest) + ")";
}

std::string stdin_input_problem(const std::vector<std::string>& inputs, const std::string& format) {
  const auto n = std::count(inputs.begin(), inputs.end(), "-");
  if (n > 1) return "stdin given twice";
  if (n == 1 && format.empty())
    return "a mesh read from stdin needs --format " + mesh_format_list(false, "|");
  return "";
}

namespace {

// Into `out` through `write` (a meshio writer taking a sink). A refused write: OutputFile
// remembered its errno, and commit() fails with that reason (and removes the temporary);
// otherwise the data was refused before anything was written.
bool write_through(OutputFile& out, std::string& error,
                   const std::function<bool(const MeshSink&)>& write) {
  bool refused = false;
  const MeshSink sink = [&](const void* data, size_t size) {
    return out.write(data, size) || (refused = true, false);
  };
  if (write(sink)) return true;
  std::string reason;
  if (refused && !out.commit(reason)) error = reason;
  return false;
}

}  // namespace

bool write_mesh_into(OutputFile& out, const std::string& format, const IndexedMesh& mesh,
                     std::string& error) {
  // OBJ materials: the MTL goes beside the output first, named after it (mtllib names it
  // relative to the OBJ), as safely as the output itself. On stdout there is no "beside": the
  // usemtl lines stay, no MTL.
  std::string mtl;
  if (format == "obj" && !mesh.attributes.materials.empty() && out.path() != "-") {
    const std::filesystem::path target(out.path());
    mtl = target.stem().string() + ".mtl";
    const std::string mtl_path = (target.parent_path() / mtl).string();
    OutputFile mtl_out;
    if (!mtl_out.open(mtl_path, false, error) ||
        !write_through(mtl_out, error,
                       [&](const MeshSink& sink) {
                         return write_material_library_to(mtl_path, mesh.attributes.materials, sink,
                                                          error);
                       }) ||
        !mtl_out.commit(error))
      return false;
  }
  return write_through(out, error, [&](const MeshSink& sink) {
    return write_mesh_to(out.path() == "-" ? "stdout" : out.path(), format, mesh, sink, error, mtl);
  });
}

void warn_if_attributes_lost(const std::string& output, const std::string& format,
                             const IndexedMesh& mesh) {
  if (!mesh.attributes.empty() && (format == "off" || format == "stl"))
    app_support::print_error(
        output == "-" ? "stdout" : output,
        "." + format + " holds positions and triangles only; the attributes (" +
            mesh.attributes.describe() + ") are not written (use .obj, .ply or .glb)");
}

bool binary_mesh_format(const std::string& format) {
  const MeshFileFormat* f = find_mesh_file_format(format);
  return f && f->binary;
}

bool write_mesh_output(const std::string& path, const std::string& format, const IndexedMesh& mesh,
                       std::string& error) {
  OutputFile out;
  if (!out.open(path, binary_mesh_format(format), error)) return false;
  return write_mesh_into(out, format, mesh, error) && out.commit(error);
}

}  // namespace pmz::tool
