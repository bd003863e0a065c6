// SPDX-License-Identifier: MIT
// The mesh side of the tools' shared behaviour (pmz/app_support.hpp): a mesh read from a file or
// stdin, a mesh written to any output pmz::OutputFile handles. Needs the mesh module.
#pragma once
#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "pmz/app_support.hpp"
#include "pmz/mesh.hpp"
#include "pmz/output_file.hpp"

namespace pmz::tool {

// Reads `path` ("-": stdin, parsed as `stdin_format`, any format meshio reads) and repairs it;
// repairs are reported on stderr as one line ("pmz-encode: FILE: triangulated ..."). Errors name
// the file ("stdin" for -). A glTF on stdin has no folder around it: one that names external
// buffer files is refused (only embedded buffers: a .glb's own or data: URIs). `progress`, if
// given, shows stage "reading" by the bytes read of the file's size.
bool read_mesh_input(const std::string& path, const std::string& stdin_format, IndexedMesh& mesh,
                     std::string& error, app_support::Progress* progress = nullptr);

// --format FORMAT, one of the formats meshio reads (`read`), writes (`write`) or either; `help`
// says what it applies to, and the accepted names are appended to it.
CLI::Option* add_format_option(CLI::App& app, std::string& format, bool read, bool write,
                               const std::string& help);
// "input mesh (.obj, .off, .ply, .stl, .gltf or .glb; ...)": `what` and the formats read
// (`written` false) or written, then `rest` ("- for stdin with --format").
std::string mesh_files_help(const std::string& what, bool written, const std::string& rest);
// The usage error of `inputs` reading stdin: "-" given twice, or without --format (`format`).
// "" when there is none.
std::string stdin_input_problem(const std::vector<std::string>& inputs, const std::string& format);

// Writes `mesh` as `format` (a format meshio writes, e.g. from app_support::mesh_output_format)
// to `path` ("-": stdout) through an OutputFile: symlinks keep pointing at the updated file,
// devices and FIFOs are written directly, a failed or interrupted write leaves no temporary
// behind. Binary formats are never written to a terminal.
bool write_mesh_output(const std::string& path, const std::string& format, const IndexedMesh& mesh,
                       std::string& error);
// Whether `format` is written as binary data (OutputFile::open's `binary`).
bool binary_mesh_format(const std::string& format);

// Never a silent loss: one line on stderr when `format` (off, stl) cannot hold the mesh's
// attributes.
void warn_if_attributes_lost(const std::string& output, const std::string& format,
                             const IndexedMesh& mesh);

// The same into an output already open (opened before the work, so an unwritable output fails
// first): meshio's writer straight into it (format: obj, off, ply, stl, glb; an OBJ with
// materials gets its MTL beside it, unless it goes to stdout). The caller commits.
bool write_mesh_into(OutputFile& out, const std::string& format, const IndexedMesh& mesh,
                     std::string& error);

}  // namespace pmz::tool
