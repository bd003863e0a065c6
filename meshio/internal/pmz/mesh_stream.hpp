// SPDX-License-Identifier: MIT
// Reading a mesh file as a stream (pmz/mesh.hpp's read_polygon_soup reads its files so): the
// readers of OBJ, OFF, PLY and STL parse the bytes through a window refilled from the file, so
// reading holds the window and the polygon soup, never the file's bytes (a glTF is read whole).
#pragma once
#include <cstddef>
#include <cstdio>
#include <functional>
#include <string>

#include "pmz/mesh.hpp"

namespace pmz {

// The window's size: what a reader holds of the file at a time (a longer line or token grows it).
inline constexpr size_t kReadWindow = size_t(1) << 20;

// read_polygon_soup of an open `file`, from its position to its end (the caller opens and
// closes it, so it words the errors of opening). `path` names the format (extension) and the
// messages; a failed read reads "path: cannot read: reason". A file whose size cannot be told
// (a pipe, stdin) is read as it comes too, to its end, with the same soup or error as the same
// bytes from a file; a binary OFF, or an STL that starts with "solid", from such a file is first
// copied to an unnamed temporary file (their layout depends on the size). `progress`, if set,
// is told the fraction of a file of known size read so far.
bool read_polygon_soup(const std::string& path, std::FILE* file, PolygonSoup& out,
                       std::string& error, const std::function<void(double)>& progress = {},
                       size_t window = kReadWindow);

}  // namespace pmz
