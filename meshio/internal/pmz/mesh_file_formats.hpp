// SPDX-License-Identifier: MIT
// The mesh file formats meshio reads and writes, as one list: the tools' --format options, their
// output rule and every --help that names formats go by it. A format is named by its file
// extension, lower case, without the dot ("obj"). Internal to the build (meshio, tools, viewer):
// not an installed header.
#pragma once
#include <string>
#include <string_view>
#include <vector>

namespace pmz {

struct MeshFileFormat {
  const char* name;  // "obj"
  bool read;         // read_polygon_soup / read_mesh parse it
  bool write;        // write_mesh / write_mesh_to write it
  bool binary;       // written as binary data (never to a terminal)
};

// Every format, in the order they are listed to users.
const std::vector<MeshFileFormat>& mesh_file_formats();
// The format named `name` (lower case, no dot), or nullptr.
const MeshFileFormat* find_mesh_file_format(std::string_view name);
bool mesh_format_readable(std::string_view name);
bool mesh_format_writable(std::string_view name);

// The names of the formats read (`written` false) or written, in list order.
std::vector<std::string> mesh_format_names(bool written);
// Those names joined for messages: each after `prefix`, separated by `separator`, the last by
// `last` (default: `separator`). ("|"): "obj|off|ply|stl|glb"; (", ", " or ", "."):
// ".obj, .off, .ply, .stl or .glb".
std::string mesh_format_list(bool written, std::string_view separator, std::string_view last = {},
                             std::string_view prefix = {});

// The files a glTF (the JSON of a .gltf, or a whole .glb) names as its buffers' URIs, other than
// data: URIs: what its reader would look up beside the file. Empty when there are none, or when
// the data is not glTF (the reader then says what is wrong with it).
std::vector<std::string> gltf_external_buffers(std::string_view data);

}  // namespace pmz
