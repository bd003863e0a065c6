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
  std::string_view data;
  size_t pos = 0;
  bool ascii, big_endian;

  bool read(PlyType t, double& v) {
    if (ascii) {
      std::string_view rest = data.substr(pos);
      size_t before = rest.size();
      std::string_view tok = next_token(rest);
      pos += before - rest.size();
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
    if (data.size() - pos < n) return false;
    unsigned char b[8];
    std::memcpy(b, data.data() + pos, n);
    pos += n;
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
  size_t remaining() const { return data.size() - pos; }
};

// Scale of an integer colour channel (uchar 0..255, ushort 0..65535); floats are 0..1 already.
double color_scale(PlyType t) {
  return t == PlyType::f32 || t == PlyType::f64 ? 1.0 : t == PlyType::u16 ? 1.0 / 65535 : 1.0 / 255;
}

}  // namespace

bool read_ply(const std::string& path, std::string_view data, PolygonSoup& out,
              std::string& error) {
  Lines lines{data, 0, 0};
  std::string_view line;
  if (!lines.next(line) || next_token(line) != "ply") {
    error = path + ": not a PLY file (no 'ply' magic)";
    return false;
  }
  std::vector<PlyElement> elements;
  int format = -1;  // 0 ascii, 1 binary little endian, 2 binary big endian
  bool ended = false;
  while (!ended && lines.next(line)) {
    std::string_view key = next_token(line);
    if (key == "format") {
      std::string_view f = next_token(line);
      format = f == "ascii"                  ? 0
               : f == "binary_little_endian" ? 1
               : f == "binary_big_endian"    ? 2
                                             : -1;
      if (format < 0) {
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
      // MeshLab's texture reference; the face property texnumber picks one.
      std::string_view file = line.substr(std::min(line.find_first_not_of(" \t"), line.size()));
      while (!file.empty() && is_space(file.back())) file.remove_suffix(1);
      Material m = named_material("texture" + std::to_string(out.attributes.materials.size()));
      m.base_color_texture = file;
      out.attributes.materials.push_back(std::move(m));
    }
    // Any other line ("comment", "obj_info", or free text such as Blender 2.4x's "Created by
    // Blender3D ...") is skipped: only format, element and property lines shape the body, and
    // Blender, MeshLab and assimp read such files.
  }
  if (!ended || format < 0) {
    error = path + ": PLY header has no " + std::string(ended ? "format line" : "end_header");
    return false;
  }
  PlyBody body{lines.rest, 0, format == 0, format == 2};
  bool have_vertices = false, have_faces = false;
  for (const PlyElement& e : elements) {
    if (e.properties.empty()) continue;  // holds no bytes; its count must not drive a loop
    bool is_vertex = e.name == "vertex", is_face = e.name == "face";
    // Which property feeds which value: xyz, normal, colour (rgba), uv; per face the corner list,
    // per-corner uvs (MeshLab's texcoord list) and the texture number.
    int xyz[3] = {-1, -1, -1}, normal[3] = {-1, -1, -1}, rgba[4] = {-1, -1, -1, -1},
        uv[2] = {-1, -1}, list = -1, face_uv = -1, texnumber = -1;
    size_t min_bytes = 0;  // bytes an instance takes at least (binary)
    for (size_t i = 0; i < e.properties.size(); ++i) {
      const PlyProperty& p = e.properties[i];
      bool scalar = p.count_type == PlyType::invalid;
      min_bytes += scalar ? ply_size(p.type) : ply_size(p.count_type);
      const std::string& n = p.name;
      if (is_vertex && scalar) {
        if (n == "x" || n == "y" || n == "z") xyz[n[0] - 'x'] = int(i);
        if (n == "nx" || n == "ny" || n == "nz") normal[n[1] - 'x'] = int(i);
        static const char* const color_names[2][4] = {
            {"red", "green", "blue", "alpha"},
            {"diffuse_red", "diffuse_green", "diffuse_blue", "diffuse_alpha"}};
        static const char* const uv_names[4][2] = {
            {"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}};
        for (int k = 0; k < 4; ++k)
          if (n == color_names[0][k] || n == color_names[1][k]) rgba[k] = int(i);
        for (int k = 0; k < 2; ++k)
          for (const auto& names : uv_names)
            if (n == names[k]) uv[k] = int(i);
      }
      if (is_face && !scalar && (n == "vertex_indices" || n == "vertex_index")) list = int(i);
      if (is_face && !scalar && n == "texcoord") face_uv = int(i);
      if (is_face && scalar && n == "texnumber") texnumber = int(i);
    }
    SoupAttributes& attrs = out.attributes;
    const bool has_normals = is_vertex && normal[0] >= 0 && normal[1] >= 0 && normal[2] >= 0;
    const bool has_uv = is_vertex && uv[0] >= 0 && uv[1] >= 0;
    const uint32_t color_components =
        is_vertex && rgba[0] >= 0 && rgba[1] >= 0 && rgba[2] >= 0 ? (rgba[3] >= 0 ? 4 : 3) : 0;
    if (is_vertex) {
      // Bounded by the bytes left, as the positions below (a huge count threw length_error).
      if (has_normals) attrs.normals.reserve(plausible(e.count, body.remaining(), 2) * 3);
      if (has_uv) attrs.texcoords.assign(1, {});
      attrs.color_components = color_components;
    }
    if (is_face && face_uv >= 0) {
      attrs.texcoords.assign(1, {});
      attrs.corner_texcoords.assign(1, {});
    }
    if (is_vertex && (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0)) {
      error = path + ": PLY vertex element lacks x, y or z";
      return false;
    }
    if (is_face && list < 0) {
      error = path + ": PLY face element has no vertex_indices list";
      return false;
    }
    if (is_vertex && e.count >= kMaxVertices) {
      error = path + ": declares " + std::to_string(e.count) + " vertices, more than supported";
      return false;
    }
    // A count the remaining bytes cannot hold is refused before anything is allocated.
    if (min_bytes == 0) min_bytes = 1;
    if (!body.ascii && e.count > body.remaining() / min_bytes) {
      error = path + ": PLY element '" + e.name + "' declares " + std::to_string(e.count) +
              " entries, more than the file holds";
      return false;
    }
    size_t reserve = plausible(e.count, body.remaining(), body.ascii ? 2 : min_bytes);
    if (is_vertex) out.positions.reserve(out.positions.size() + reserve * 3), have_vertices = true;
    if (is_face)
      out.face_offsets.reserve(reserve + 1), out.corners.reserve(reserve * 3), have_faces = true;
    for (uint64_t n = 0; n < e.count; ++n) {
      float p[3] = {0, 0, 0}, nrm[3] = {0, 0, 0}, color[4] = {0, 0, 0, 1}, t[2] = {0, 0};
      uint32_t face_texture = kNoAttribute;
      const size_t uv_before = face_uv >= 0 ? attrs.texcoords[0].size() : 0;
      for (size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& prop = e.properties[i];
        double v;
        if (prop.count_type == PlyType::invalid) {
          if (!body.read(prop.type, v)) {
            error = path + ": PLY data ends or is malformed in " + e.name + " " + std::to_string(n);
            return false;
          }
          for (int k = 0; k < 3; ++k) {
            if (int(i) == xyz[k]) p[k] = float(v);
            if (int(i) == normal[k]) nrm[k] = float(v);
          }
          for (int k = 0; k < 4; ++k)
            if (int(i) == rgba[k]) color[k] = float(v * color_scale(prop.type));
          for (int k = 0; k < 2; ++k)
            if (int(i) == uv[k]) t[k] = float(v);
          if (int(i) == texnumber) {
            if (!(v >= 0 && v < double(attrs.materials.size()))) {
              error = path + ": PLY face " + std::to_string(n) + " has texture number " +
                      std::to_string(v) + " but the header names " +
                      std::to_string(attrs.materials.size()) + " texture files";
              return false;
            }
            face_texture = uint32_t(v);
          }
          continue;
        }
        double count;
        if (!body.read(prop.count_type, count) || count < 0 ||
            (!body.ascii && count * double(ply_size(prop.type)) > double(body.remaining()))) {
          error = path + ": PLY data ends or is malformed in " + e.name + " " + std::to_string(n);
          return false;
        }
        for (uint64_t c = 0; c < uint64_t(count); ++c) {
          if (!body.read(prop.type, v)) {
            error = path + ": PLY data ends or is malformed in " + e.name + " " + std::to_string(n);
            return false;
          }
          if (int(i) == face_uv) {
            if (!std::isfinite(v)) {
              error = path + ": PLY face " + std::to_string(n) +
                      " has a NaN or infinite texture coordinate";
              return false;
            }
            attrs.texcoords[0].push_back(float(v));
          }
          if (int(i) != list) continue;
          if (v < 0 || v >= double(kMaxVertices) || v != std::floor(v)) {
            // A float index may be fractional, NaN or beyond int64_t: only a whole number in
            // range converts (anything else is undefined behaviour) and is named as a vertex.
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
        }
      }
      if (is_vertex) {
        if (!push_vertex(out, p, path, 0, error)) return false;
        if (!all_finite(nrm, 3) || !all_finite(color, 4) || !all_finite(t, 2)) {
          error = path + ": vertex " + std::to_string(out.vertex_count() - 1) +
                  " has a NaN or infinite attribute";
          return false;
        }
        if (has_normals) attrs.normals.insert(attrs.normals.end(), nrm, nrm + 3);
        if (has_uv) attrs.texcoords[0].insert(attrs.texcoords[0].end(), t, t + 2);
        attrs.colors.insert(attrs.colors.end(), color, color + color_components);
      }
      if (is_face) {
        end_face(out);
        if (face_uv >= 0) {
          // One u v pair per corner, in corner order; a face with another count has none.
          std::vector<float>& pool = attrs.texcoords[0];
          std::vector<uint32_t>& ids = attrs.corner_texcoords[0];
          size_t corners = out.corners.size() - ids.size();
          bool matches = pool.size() - uv_before == corners * 2;
          if (!matches) pool.resize(uv_before);
          for (size_t c = 0; c < corners; ++c)
            ids.push_back(matches ? uint32_t(uv_before / 2 + c) : kNoAttribute);
        }
        if (texnumber >= 0) attrs.face_materials.push_back(face_texture);
      }
    }
  }
  SoupAttributes& attrs = out.attributes;
  const bool per_vertex = !attrs.normals.empty() || attrs.color_components ||
                          (!attrs.texcoords.empty() && attrs.corner_texcoords.empty());
  if (!attrs.normals.empty()) attrs.corner_normals = out.corners;
  if (attrs.color_components) attrs.corner_colors = out.corners;
  if (!attrs.texcoords.empty() && attrs.corner_texcoords.empty())
    attrs.corner_texcoords.assign(1, out.corners);
  if (attrs.face_materials.size() != out.face_count()) attrs.face_materials.clear();
  if (attrs.face_materials.empty()) attrs.materials.clear();
  if (!have_vertices || !have_faces) {
    error =
        path + ": PLY file has no " + std::string(have_vertices ? "face" : "vertex") + " element";
    return false;
  }
  // Faces may precede vertices in a PLY file, so indices are checked at the end.
  for (uint32_t f = 0; f < out.face_count(); ++f)
    for (uint32_t c = out.face_offsets[f]; c < out.face_offsets[f + 1]; ++c)
      if (out.corners[c] >= out.vertex_count()) {
        error = range_error(path, f, 0, out.corners[c], out.vertex_count());
        return false;
      }
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
