// SPDX-License-Identifier: MIT
// Every mesh format's reader and writer, one file each, behind mesh_io.cpp's dispatch by
// extension. A reader parses the bytes of a ByteSource, read forward (glTF: a whole file's
// bytes), into `out` (started with one face offset, 0) and returns false with "path: ..." in
// error; mesh_io.cpp checks what every reader returns (faces, attribute indices). A writer
// writes a mesh that mesh_io.cpp has checked (indices and attributes consistent). Internal to
// meshio.
#pragma once
#include <string>
#include <string_view>
#include <vector>

#include "pmz/mesh.hpp"

namespace pmz {

class Writer;      // writer_support.hpp
class ByteSource;  // reader_support.hpp

// OBJ and its MTL library (mesh_obj.cpp). write_obj names `mtl` in an mtllib line if not empty.
bool read_obj(const std::string& path, ByteSource& data, PolygonSoup& out, std::string& error);
void write_obj(Writer& w, const IndexedMesh& m, const std::string& mtl);
void write_mtl(Writer& w, const std::vector<Material>& materials);

// OFF (mesh_off.cpp): text or binary in, text out.
bool read_off(const std::string& path, ByteSource& data, PolygonSoup& out, std::string& error);
void write_off(Writer& w, const IndexedMesh& m);

// PLY (mesh_ply.cpp): ascii or binary in, binary little endian out (one vertex per wedge when
// the mesh has attributes).
bool read_ply(const std::string& path, ByteSource& data, PolygonSoup& out, std::string& error);
void write_ply(Writer& w, const IndexedMesh& m);

// STL (mesh_stl.cpp): ascii or binary in, binary out.
bool read_stl(const std::string& path, ByteSource& data, PolygonSoup& out, std::string& error);
void write_stl(Writer& w, const IndexedMesh& m);

// glTF 2.0 (mesh_gltf.cpp, through Debian's tinygltf), .gltf or .glb in: the triangles of every
// mesh the default scene draws (node transforms applied; all meshes when the file has no scene),
// with POSITION, NORMAL, TEXCOORD_n, COLOR_0 and the material per face (one id per glTF
// material). Vertices with equal positions are welded.
bool read_gltf(const std::string& path, std::string_view data, PolygonSoup& out,
               std::string& error);
// The mesh as a binary glTF: one vertex per wedge (one per vertex without attributes), one
// primitive per material. Normals are written normalised and colours clamped to [0, 1], as
// glTF requires; texture file names become image URIs.
bool write_glb(const IndexedMesh& mesh, std::string& bytes, std::string& error);

}  // namespace pmz
