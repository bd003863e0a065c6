// The mesh side of the tools' shared behaviour (pmz/app_support.hpp): a mesh read from a file or
// stdin, a mesh written to any output pmz::OutputFile handles. Needs the mesh module.
#pragma once
#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "pmz/mesh.hpp"
#include "pmz/output_file.hpp"

namespace pmz::tool {

// Reads `path` ("-": stdin, parsed as `stdin_format`: obj, off, ply or stl) and repairs it;
// repairs are reported on stderr ("pmz: FILE: ...") as by pmz::read_mesh. Errors name the file
// ("stdin" for -).
bool read_mesh_input(const std::string& path, const std::string& stdin_format, IndexedMesh& mesh,
                     std::string& error);

// --format FORMAT (obj, off, ply, stl): how a mesh read from stdin (-) is parsed; `help` says
// what else it applies to.
CLI::Option* add_stdin_format_option(CLI::App& app, std::string& format,
                                     const std::string& help = "format of a mesh read from stdin");
// The usage error of `inputs` reading stdin: "-" given twice, or without --format (`format`).
// "" when there is none.
std::string stdin_input_problem(const std::vector<std::string>& inputs, const std::string& format);

// Writes `mesh` as `format` (obj, off, ply, stl; "": by the extension) to `path` ("-": stdout)
// through an OutputFile: symlinks keep pointing at the updated file, devices and FIFOs are
// written directly, a failed or interrupted write leaves no temporary behind.
bool write_mesh_output(const std::string& path, const std::string& format, const IndexedMesh& mesh,
                       std::string& error);

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
