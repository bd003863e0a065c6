// The mesh side of the tools' shared behaviour (tool_common.hpp): a mesh read from a file or
// stdin, a mesh written to any output tool_common::OutputFile handles. Needs the mesh module.
#pragma once
#include <string>

#include "pmz/mesh.hpp"

namespace pmz::tool {

// Reads `path` ("-": stdin, parsed as `stdin_format`: obj, off, ply or stl) and repairs it;
// repairs are reported on stderr ("pmz: FILE: ...") as by pmz::read_mesh. Errors name the file
// ("stdin" for -).
bool read_mesh_input(const std::string& path, const std::string& stdin_format, IndexedMesh& mesh,
                     std::string& error);

// Writes `mesh` as `format` (obj, off, ply, stl; "": by the extension) to `path` ("-": stdout)
// through an OutputFile: symlinks keep pointing at the updated file, devices and FIFOs are
// written directly, a failed or interrupted write leaves no temporary behind.
bool write_mesh_output(const std::string& path, const std::string& format, const IndexedMesh& mesh,
                       std::string& error);

}  // namespace pmz::tool
