// SPDX-License-Identifier: MIT
// PLY, ascii and binary either endian: the reader into a PolygonSoup (per-vertex or per-corner
// attributes, MeshLab's TextureFile materials) and the binary little-endian writer.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "mesh_formats.hpp"
#include "reader_support.hpp"
#include "writer_support.hpp"

namespace pmz {

namespace {

enum class PlyFormat : uint8_t { ascii, binary_little_endian, binary_big_endian };

enum class PlyType : uint8_t { i8, u8, i16, u16, i32, u32, f32, f64, invalid };

PlyType ply_type(std::string_view s) {
  if (s == "char" || s == "int8") return PlyType::i8;
  if (s == "uchar" || s == "uint8") return PlyType::u8;
  if (s == "short" || s == "int16") return PlyType::i16;
  if (s == "ushort" || s == "uint16") return PlyType::u16;
  if (s == "int" || s == "int32") return PlyType::i32;
  if (s == "uint" || s == "uint32") return PlyType::u32;
  if (s == "float" || s == "float32") return PlyType::f32;
  if (s == "double" || s == "float64") return PlyType::f64;
  return PlyType::invalid;
}

size_t ply_size(PlyType t) {
  static const size_t sizes[] = {1, 1, 2, 2, 4, 4, 4, 8, 0};
  return sizes[size_t(t)];
}

struct PlyProperty {
  std::string name;
  PlyType type;        // value type (item type for lists)
  PlyType count_type;  // PlyType::invalid for a scalar
};

struct PlyElement {
  std::string name;
  uint64_t count;
  std::vector<PlyProperty> properties;
};

// Reads one value of the body, ascii or binary; false when the data ends or is malformed.
struct PlyBody {
  ByteSource& in;
  bool ascii, big_endian;

  bool read(PlyType t, double& v) {
    if (ascii) {
      std::string_view tok = next_token(in);
      if (t == PlyType::f32 || t == PlyType::f64) {
        float f;
        if (!parse_float(tok, f)) return false;
        v = f;
        return true;
      }
      int64_t i;
      if (!parse_int(tok, i)) return false;
      v = double(i);
      return true;
    }
    size_t n = ply_size(t);
    std::string_view bytes = in.peek(n);
    if (bytes.size() < n) return false;
    unsigned char b[8];
    std::memcpy(b, bytes.data(), n);
    in.skip(n);
    if (big_endian != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
    switch (t) {
      case PlyType::i8:
        v = double(int8_t(b[0]));
        break;
      case PlyType::u8:
        v = double(b[0]);
        break;
      case PlyType::i16: {
        int16_t x;
        std::memcpy(&x, b, 2);
        v = x;
        break;
      }
      case PlyType::u16: {
        uint16_t x;
        std::memcpy(&x, b, 2);
        v = x;
        break;
      }
      case PlyType::i32: {
        int32_t x;
        std::memcpy(&x, b, 4);
        v = x;
        break;
      }
      case PlyType::u32: {
        uint32_t x;
        std::memcpy(&x, b, 4);
        v = x;
        break;
      }
      case PlyType::f32: {
        float x;
        std::memcpy(&x, b, 4);
        v = x;
        break;
      }
      case PlyType::f64: {
        double x;
        std::memcpy(&x, b, 8);
        v = x;
        break;
      }
      case PlyType::invalid:
        return false;
    }
    return true;
  }
  uint64_t remaining() const { return in.remaining(); }
  uint64_t reservable() const { return in.reservable(); }
};

// Scale of an integer colour channel (uchar 0..255, ushort 0..65535); floats are 0..1 already.
double color_scale(PlyType t) {
  return t == PlyType::f32 || t == PlyType::f64 ? 1.0 : t == PlyType::u16 ? 1.0 / 65535 : 1.0 / 255;
}

// The header up to end_header: the format, the elements with their properties, and MeshLab's
// TextureFile comments as materials (the face property texnumber picks one).
bool read_ply_header(const std::string& path, Lines& lines, std::vector<PlyElement>& elements,
                     PlyFormat& format, std::vector<Material>& materials, std::string& error) {
  std::string_view line;
  if (!lines.next(line) || next_token(line) != "ply") {
    error = path + ": not a PLY file (no 'ply' magic)";
    return false;
  }
  bool have_format = false, ended = false;
  while (!ended && lines.next(line)) {
    std::string_view key = next_token(line);
    if (key == "format") {
      std::string_view f = next_token(line);
      have_format = true;
      if (f == "ascii")
        format = PlyFormat::ascii;
      else if (f == "binary_little_endian")
        format = PlyFormat::binary_little_endian;
      else if (f == "binary_big_endian")
        format = PlyFormat::binary_big_endian;
      else {
        error = line_error(path, lines.number, "unknown PLY format '" + std::string(f) + "'");
        return false;
      }
    } else if (key == "element") {
      PlyElement e;
      e.name = next_token(line);
      int64_t n;
      if (!parse_int(next_token(line), n) || n < 0) {
        error = line_error(path, lines.number, "PLY element count must be a non-negative integer");
        return false;
      }
      e.count = uint64_t(n);
      elements.push_back(std::move(e));
    } else if (key == "property") {
      if (elements.empty()) {
        error = line_error(path, lines.number, "PLY property before any element");
        return false;
      }
      PlyProperty p;
      std::string_view t = next_token(line);
      p.count_type = PlyType::invalid;
      if (t == "list") {
        p.count_type = ply_type(next_token(line));
        t = next_token(line);
        if (p.count_type == PlyType::invalid || p.count_type == PlyType::f32 ||
            p.count_type == PlyType::f64) {
          error = line_error(path, lines.number, "PLY list count type must be an integer type");
          return false;
        }
      }
      p.type = ply_type(t);
      if (p.type == PlyType::invalid) {
        error =
            line_error(path, lines.number, "unknown PLY property type '" + std::string(t) + "'");
        return false;
      }
      p.name = next_token(line);
      elements.back().properties.push_back(std::move(p));
    } else if (key == "end_header") {
      ended = true;
    } else if (key == "comment" && next_token(line) == "TextureFile") {
      std::string_view file = line.substr(std::min(line.find_first_not_of(" \t"), line.size()));
      while (!file.empty() && is_space(file.back())) file.remove_suffix(1);
      Material m = named_material("texture" + std::to_string(materials.size()));
      m.base_color_texture = file;
      materials.push_back(std::move(m));
    }
    // Any other line ("comment", "obj_info", or free text such as Blender 2.4x's "Created by
    // Blender3D ...") is skipped: only format, element and property lines shape the body, and
    // Blender, MeshLab and assimp read such files.
  }
  if (!ended || !have_format) {
    error = path + ": PLY header has no " + std::string(ended ? "format line" : "end_header");
    return false;
  }
  return true;
}

// Which property of an element feeds which value (-1: none): xyz, normal, colour (rgba), uv of
// a vertex; per face the corner list, per-corner uvs (MeshLab's texcoord list) and the texture
// number. min_bytes: what one instance takes at least in a binary body.
struct PlyRoles {
  bool is_vertex = false, is_face = false;
  int xyz[3] = {-1, -1, -1}, normal[3] = {-1, -1, -1}, rgba[4] = {-1, -1, -1, -1}, uv[2] = {-1, -1},
      list = -1, face_uv = -1, texnumber = -1;
  size_t min_bytes = 0;
  bool has_normals() const {
    return is_vertex && normal[0] >= 0 && normal[1] >= 0 && normal[2] >= 0;
  }
  bool has_uv() const { return is_vertex && uv[0] >= 0 && uv[1] >= 0; }
  uint32_t color_components() const {
    return is_vertex && rgba[0] >= 0 && rgba[1] >= 0 && rgba[2] >= 0 ? (rgba[3] >= 0 ? 4 : 3) : 0;
  }
};

PlyRoles assign_roles(const PlyElement& e) {
  PlyRoles r;
  r.is_vertex = e.name == "vertex";
  r.is_face = e.name == "face";
  for (size_t i = 0; i < e.properties.size(); ++i) {
    const PlyProperty& p = e.properties[i];
    bool scalar = p.count_type == PlyType::invalid;
    r.min_bytes += scalar ? ply_size(p.type) : ply_size(p.count_type);
    const std::string& n = p.name;
    if (r.is_vertex && scalar) {
      if (n == "x" || n == "y" || n == "z") r.xyz[n[0] - 'x'] = int(i);
      if (n == "nx" || n == "ny" || n == "nz") r.normal[n[1] - 'x'] = int(i);
      static const char* const color_names[2][4] = {
          {"red", "green", "blue", "alpha"},
          {"diffuse_red", "diffuse_green", "diffuse_blue", "diffuse_alpha"}};
      static const char* const uv_names[4][2] = {
          {"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}};
      for (int k = 0; k < 4; ++k)
        if (n == color_names[0][k] || n == color_names[1][k]) r.rgba[k] = int(i);
      for (int k = 0; k < 2; ++k)
        for (const auto& names : uv_names)
          if (n == names[k]) r.uv[k] = int(i);
    }
    if (r.is_face && !scalar && (n == "vertex_indices" || n == "vertex_index")) r.list = int(i);
    if (r.is_face && !scalar && n == "texcoord") r.face_uv = int(i);
    if (r.is_face && scalar && n == "texnumber") r.texnumber = int(i);
  }
  return r;
}

std::string too_many_error(const std::string& path, const PlyElement& e) {
  return path + ": PLY element '" + e.name + "' declares " + std::to_string(e.count) +
         " entries, more than the file holds";
}

// Before an element's data: its attribute pools set up, the properties it must have and its
// count checked (a count the remaining bytes cannot hold is refused before anything is
// allocated; from a source of unknown size, read_ply refuses it once the data has ended), room
// reserved within what the data can hold.
bool begin_element(const std::string& path, const PlyElement& e, const PlyRoles& roles,
                   const PlyBody& body, PolygonSoup& out, std::string& error) {
  SoupAttributes& attrs = out.attributes;
  if (roles.is_vertex) {
    // Bounded by the bytes left, as the positions below (a huge count threw length_error).
    if (roles.has_normals()) attrs.normals.reserve(plausible(e.count, body.reservable(), 2) * 3);
    if (roles.has_uv()) attrs.texcoords.assign(1, {});
    attrs.color_components = roles.color_components();
  }
  if (roles.is_face && roles.face_uv >= 0) {
    attrs.texcoords.assign(1, {});
    attrs.corner_texcoords.assign(1, {});
  }
  if (roles.is_vertex && (roles.xyz[0] < 0 || roles.xyz[1] < 0 || roles.xyz[2] < 0)) {
    error = path + ": PLY vertex element lacks x, y or z";
    return false;
  }
  if (roles.is_face && roles.list < 0) {
    error = path + ": PLY face element has no vertex_indices list";
    return false;
  }
  if (roles.is_vertex && e.count >= kMaxVertices) {
    error = path + ": declares " + std::to_string(e.count) + " vertices, more than supported";
    return false;
  }
  const size_t min_bytes = std::max<size_t>(roles.min_bytes, 1);
  if (!body.ascii && e.count > body.remaining() / min_bytes) {
    error = too_many_error(path, e);
    return false;
  }
  size_t reserve = plausible(e.count, body.reservable(), body.ascii ? 2 : min_bytes);
  if (roles.is_vertex) out.positions.reserve(out.positions.size() + reserve * 3);
  if (roles.is_face) out.face_offsets.reserve(reserve + 1), out.corners.reserve(reserve * 3);
  return true;
}

// The values of one vertex or face as read; corners and per-corner uvs go to the soup directly.
struct PlyInstance {
  float p[3] = {0, 0, 0}, nrm[3] = {0, 0, 0}, color[4] = {0, 0, 0, 1}, t[2] = {0, 0};
  uint32_t face_texture = kNoAttribute;
};

std::string malformed_error(const std::string& path, const PlyElement& e, uint64_t n) {
  return path + ": PLY data ends or is malformed in " + e.name + " " + std::to_string(n);
}

// A scalar property's value into the instance. Refuses a texture number that names no
// TextureFile of the header.
bool take_scalar(const std::string& path, const PlyRoles& roles, int i, PlyType type, double v,
                 uint64_t n, const PolygonSoup& out, PlyInstance& x, std::string& error) {
  for (int k = 0; k < 3; ++k) {
    if (i == roles.xyz[k]) x.p[k] = float(v);
    if (i == roles.normal[k]) x.nrm[k] = float(v);
  }
  for (int k = 0; k < 4; ++k)
    if (i == roles.rgba[k]) x.color[k] = float(v * color_scale(type));
  for (int k = 0; k < 2; ++k)
    if (i == roles.uv[k]) x.t[k] = float(v);
  if (i == roles.texnumber) {
    const size_t textures = out.attributes.materials.size();
    if (!(v >= 0 && v < double(textures))) {
      error = path + ": PLY face " + std::to_string(n) + " has texture number " +
              std::to_string(v) + " but the header names " + std::to_string(textures) +
              " texture files";
      return false;
    }
    x.face_texture = uint32_t(v);
  }
  return true;
}

// One item of a list property: a per-corner texture coordinate or a corner's vertex index.
bool take_list_item(const std::string& path, const PlyRoles& roles, int i, double v, uint64_t n,
                    PolygonSoup& out, std::string& error) {
  if (i == roles.face_uv) {
    if (!std::isfinite(v)) {
      error =
          path + ": PLY face " + std::to_string(n) + " has a NaN or infinite texture coordinate";
      return false;
    }
    out.attributes.texcoords[0].push_back(float(v));
  }
  if (i != roles.list) return true;
  if (v < 0 || v >= double(kMaxVertices) || v != std::floor(v)) {
    // A float index may be fractional, NaN or beyond int64_t: only a whole number in range
    // converts (anything else is undefined behaviour) and is named as a vertex.
    if (v == std::floor(v) && std::fabs(v) < 0x1p62) {
      error = range_error(path, n, 0, int64_t(v), out.vertex_count());
    } else {
      char text[32];
      std::snprintf(text, sizeof text, "%g", v);
      error = path + ": PLY face " + std::to_string(n) + " has vertex index " + text +
              ", not a whole vertex number";
    }
    return false;
  }
  out.corners.push_back(uint32_t(v));
  return true;
}

// Every property of instance n of e, in header order.
bool read_instance(const std::string& path, const PlyElement& e, const PlyRoles& roles, uint64_t n,
                   PlyBody& body, PolygonSoup& out, PlyInstance& x, std::string& error) {
  for (size_t i = 0; i < e.properties.size(); ++i) {
    const PlyProperty& prop = e.properties[i];
    double v = 0;
    if (prop.count_type == PlyType::invalid) {
      if (!body.read(prop.type, v)) {
        error = malformed_error(path, e, n);
        return false;
      }
      if (!take_scalar(path, roles, int(i), prop.type, v, n, out, x, error)) return false;
      continue;
    }
    double count = 0;
    if (!body.read(prop.count_type, count) || count < 0 ||
        (!body.ascii && count * double(ply_size(prop.type)) > double(body.remaining()))) {
      error = malformed_error(path, e, n);
      return false;
    }
    // From a source of unknown size, a count the bytes after it cannot hold is refused when the
    // list fails (its size then learnt), with the message a file of known size gives.
    const uint64_t list_start = body.in.offset();
    const bool checked = body.ascii || body.in.size_known();
    for (uint64_t c = 0; c < uint64_t(count); ++c) {
      bool ok = body.read(prop.type, v);
      if (!ok) error = malformed_error(path, e, n);
      if (ok && take_list_item(path, roles, int(i), v, n, out, error)) continue;
      if (!checked &&
          count * double(ply_size(prop.type)) > double(body.in.learn_size() - list_start))
        error = malformed_error(path, e, n);
      return false;
    }
  }
  return true;
}

bool add_vertex(const std::string& path, const PlyRoles& roles, const PlyInstance& x,
                PolygonSoup& out, std::string& error) {
  if (!push_vertex(out, x.p, path, 0, error)) return false;
  if (!all_finite(x.nrm, 3) || !all_finite(x.color, 4) || !all_finite(x.t, 2)) {
    error = path + ": vertex " + std::to_string(out.vertex_count() - 1) +
            " has a NaN or infinite attribute";
    return false;
  }
  SoupAttributes& attrs = out.attributes;
  if (roles.has_normals()) attrs.normals.insert(attrs.normals.end(), x.nrm, x.nrm + 3);
  if (roles.has_uv()) attrs.texcoords[0].insert(attrs.texcoords[0].end(), x.t, x.t + 2);
  attrs.colors.insert(attrs.colors.end(), x.color, x.color + roles.color_components());
  return true;
}

// Ends a face whose corners are read; uv_before: the size of the uv pool before it.
void add_face(const PlyRoles& roles, const PlyInstance& x, size_t uv_before, PolygonSoup& out) {
  SoupAttributes& attrs = out.attributes;
  end_face(out);
  if (roles.face_uv >= 0) {
    // One u v pair per corner, in corner order; a face with another count has none.
    std::vector<float>& pool = attrs.texcoords[0];
    std::vector<uint32_t>& ids = attrs.corner_texcoords[0];
    size_t corners = out.corners.size() - ids.size();
    bool matches = pool.size() - uv_before == corners * 2;
    if (!matches) pool.resize(uv_before);
    for (size_t c = 0; c < corners; ++c)
      ids.push_back(matches ? uint32_t(uv_before / 2 + c) : kNoAttribute);
  }
  if (roles.texnumber >= 0) attrs.face_materials.push_back(x.face_texture);
}

bool read_element_data(const std::string& path, const PlyElement& e, const PlyRoles& roles,
                       PlyBody& body, PolygonSoup& out, std::string& error) {
  for (uint64_t n = 0; n < e.count; ++n) {
    PlyInstance x;
    const size_t uv_before = roles.face_uv >= 0 ? out.attributes.texcoords[0].size() : 0;
    if (!read_instance(path, e, roles, n, body, out, x, error)) return false;
    if (roles.is_vertex && !add_vertex(path, roles, x, out, error)) return false;
    if (roles.is_face) add_face(roles, x, uv_before, out);
  }
  return true;
}

// Per-vertex attributes (normals, colours, vertex uvs) get one index per corner, the corner's
// vertex; face materials are kept only when every face has one. True when any attribute was
// per vertex (the file then split vertices at seams, which weld_vertices merges again).
bool index_vertex_attributes(PolygonSoup& out) {
  SoupAttributes& attrs = out.attributes;
  const bool per_vertex = !attrs.normals.empty() || attrs.color_components ||
                          (!attrs.texcoords.empty() && attrs.corner_texcoords.empty());
  if (!attrs.normals.empty()) attrs.corner_normals = out.corners;
  if (attrs.color_components) attrs.corner_colors = out.corners;
  if (!attrs.texcoords.empty() && attrs.corner_texcoords.empty())
    attrs.corner_texcoords.assign(1, out.corners);
  if (attrs.face_materials.size() != out.face_count()) attrs.face_materials.clear();
  if (attrs.face_materials.empty()) attrs.materials.clear();
  return per_vertex;
}

// Faces may precede vertices in a PLY file, so indices are checked once all are read.
bool check_corner_vertices(const std::string& path, const PolygonSoup& out, std::string& error) {
  for (uint32_t f = 0; f < out.face_count(); ++f)
    for (uint32_t c = out.face_offsets[f]; c < out.face_offsets[f + 1]; ++c)
      if (out.corners[c] >= out.vertex_count()) {
        error = range_error(path, f, 0, out.corners[c], out.vertex_count());
        return false;
      }
  return true;
}

}  // namespace

bool read_ply(const std::string& path, ByteSource& data, PolygonSoup& out, std::string& error) {
  Lines lines{data, 0, 0};
  std::vector<PlyElement> elements;
  PlyFormat format = PlyFormat::ascii;
  if (!read_ply_header(path, lines, elements, format, out.attributes.materials, error))
    return false;
  PlyBody body{data, format == PlyFormat::ascii, format == PlyFormat::binary_big_endian};
  bool have_vertices = false, have_faces = false;
  for (const PlyElement& e : elements) {
    if (e.properties.empty()) continue;  // holds no bytes; its count must not drive a loop
    const PlyRoles roles = assign_roles(e);
    if (!begin_element(path, e, roles, body, out, error)) return false;
    have_vertices = have_vertices || roles.is_vertex;
    have_faces = have_faces || roles.is_face;
    // From a source of unknown size, a count the data cannot hold is refused when the data
    // fails, with begin_element's message, as from a file.
    const uint64_t start = data.offset();
    const bool checked = body.ascii || data.size_known();
    if (!read_element_data(path, e, roles, body, out, error)) {
      if (!checked && e.count > (data.learn_size() - start) / std::max<size_t>(roles.min_bytes, 1))
        error = too_many_error(path, e);
      return false;
    }
  }
  const bool per_vertex = index_vertex_attributes(out);
  if (!have_vertices || !have_faces) {
    error =
        path + ": PLY file has no " + std::string(have_vertices ? "face" : "vertex") + " element";
    return false;
  }
  if (!check_corner_vertices(path, out, error)) return false;
  if (per_vertex) weld_vertices(out);
  return true;
}

namespace {

// PLY with attributes: one vertex per wedge (normals, 8-bit colours, texture coordinates set 0),
// the texture files as MeshLab's TextureFile comments with a texnumber per face.
void write_ply_wedges(Writer& w, const IndexedMesh& m) {
  const MeshAttributes& a = m.attributes;
  const uint32_t nw = a.wedge_count(), nf = m.face_count();
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by pmz\n";
  for (const Material& mat : a.materials)
    header += "comment TextureFile " + mat.base_color_texture + "\n";
  header += "element vertex " + std::to_string(nw) +
            "\nproperty float x\nproperty float y\nproperty float z\n";
  if (!a.normals.empty()) header += "property float nx\nproperty float ny\nproperty float nz\n";
  if (a.color_components)
    header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (a.color_components == 4) header += "property uchar alpha\n";
  if (!a.texcoords.empty()) header += "property float texture_u\nproperty float texture_v\n";
  header += "element face " + std::to_string(nf) + "\nproperty list uchar uint vertex_indices\n";
  if (!a.face_materials.empty()) header += "property int texnumber\n";
  header += "end_header\n";
  w.put(header.data(), header.size());
  for (uint32_t wd = 0; wd < nw; ++wd) {
    for (int k = 0; k < 3; ++k) w.f32le(m.positions[size_t(a.wedge_vertices[wd]) * 3 + k]);
    if (!a.normals.empty())
      for (int k = 0; k < 3; ++k) w.f32le(a.normals[size_t(wd) * 3 + k]);
    for (uint32_t k = 0; k < a.color_components; ++k) {
      float c = a.colors[size_t(wd) * a.color_components + k];
      uint8_t b = uint8_t(std::lround(std::clamp(c, 0.0f, 1.0f) * 255));
      w.put(&b, 1);
    }
    if (!a.texcoords.empty())
      for (int k = 0; k < 2; ++k) w.f32le(a.texcoords[0][size_t(wd) * 2 + k]);
  }
  for (uint32_t f = 0; f < nf; ++f) {
    const uint8_t three = 3;
    w.put(&three, 1);
    for (int k = 0; k < 3; ++k) w.u32le(a.corner_wedges[f * 3 + k]);
    if (!a.face_materials.empty()) w.u32le(a.face_materials[f]);
  }
}

// PLY without attributes: the positions as one block (the float array is the file's layout on a
// little-endian host), the faces 13 bytes each, a buffer's worth at a time.
void write_ply_geometry(Writer& w, const IndexedMesh& m) {
  const uint32_t nv = m.vertex_count(), nf = m.face_count();
  w.str("ply\nformat binary_little_endian 1.0\ncomment written by pmz\nelement vertex ")
      .num(nv)
      .str("\nproperty float x\nproperty float y\nproperty float z\nelement face ")
      .num(nf)
      .str("\nproperty list uchar uint vertex_indices\nend_header\n");
  if constexpr (std::endian::native == std::endian::little) {
    w.put(m.positions.data(), size_t(nv) * 12);
  } else {
    for (size_t i = 0; i < size_t(nv) * 3; ++i) w.f32le(m.positions[i]);
  }
  const uint32_t* ix = m.indices.data();
  for (uint32_t f = 0; f < nf;) {
    char* o = w.room(13);
    const uint32_t n = uint32_t(std::min<size_t>(nf - f, w.room_left() / 13));
    for (const uint32_t e = f + n; f < e; ++f, o += 13) {
      *o = 3;
      if constexpr (std::endian::native == std::endian::little) {
        std::memcpy(o + 1, ix + size_t(f) * 3, 12);  // the file's layout: one copy per face
      } else {
        for (int k = 0; k < 3; ++k) {
          const uint32_t v = ix[size_t(f) * 3 + k];
          const unsigned char b[4] = {uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16),
                                      uint8_t(v >> 24)};
          std::memcpy(o + 1 + 4 * k, b, 4);
        }
      }
    }
    w.commit(o);
  }
}

}  // namespace

void write_ply(Writer& w, const IndexedMesh& m) {
  if (m.attributes.has_wedges())
    write_ply_wedges(w, m);
  else
    write_ply_geometry(w, m);
}

}  // namespace pmz
