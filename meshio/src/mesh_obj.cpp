// SPDX-License-Identifier: MIT
// OBJ (with its MTL material library): the reader into a PolygonSoup (positions, vertex colours,
// texture coordinates, normals, materials by usemtl) and the writer of an IndexedMesh.
#include <cmath>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "mesh_formats.hpp"
#include "reader_support.hpp"
#include "writer_support.hpp"

namespace pmz {

namespace {

// Texture file of an MTL map statement: what follows the options (-bm 1, -s 1 1 1, -clamp on,
// each a dash word and its numeric or on/off arguments); file names may hold spaces.
std::string_view map_file(std::string_view rest) {
  for (;;) {
    std::string_view probe = rest, t = next_token(probe);
    float ignored;
    if (t.empty() || !(t[0] == '-' || parse_float(t, ignored) || t == "on" || t == "off")) break;
    rest = probe;
  }
  size_t begin = rest.find_first_not_of(" \t"), end = rest.find_last_not_of(" \t\r");
  return begin == std::string_view::npos ? std::string_view() : rest.substr(begin, end - begin + 1);
}

// Fills the named materials from an MTL file beside the OBJ. A missing or unreadable MTL keeps
// the names only: the geometry does not depend on it (and OBJ files often ship without theirs).
void read_mtl(const std::string& obj_path, const std::string& library,
              std::vector<Material>& materials) {
  std::string data, ignored;
  std::filesystem::path mtl = std::filesystem::path(obj_path).parent_path() / library;
  if (!read_file(mtl.string(), data, ignored)) return;
  ByteSource in(data);
  Lines lines{in, 0, '#'};
  std::string_view line;
  Material* m = nullptr;
  while (lines.next(line)) {
    std::string_view key = next_token(line);
    if (key == "newmtl") {
      std::string_view name = next_token(line);
      m = nullptr;
      for (Material& x : materials)
        if (x.name == name) m = &x;
    } else if (!m) {
      continue;
    } else if (key == "Kd") {
      for (int k = 0; k < 3; ++k) {
        float v;
        if (parse_float(next_token(line), v) && std::isfinite(v)) m->base_color[k] = v;
      }
    } else if (key == "d") {
      float v;
      if (parse_float(next_token(line), v) && std::isfinite(v)) m->base_color[3] = v;
    } else if (key == "map_Kd") {
      m->base_color_texture = map_file(line);
    } else if (key == "norm" || key == "map_Bump" || key == "map_bump" || key == "bump") {
      m->normal_texture = map_file(line);
    }
  }
}

// Parses `count` floats of an OBJ record; false when one is missing or malformed.
bool parse_floats(std::string_view& line, float* v, int count) {
  for (int k = 0; k < count; ++k)
    if (!parse_float(next_token(line), v[k])) return false;
  return true;
}

}  // namespace

bool read_obj(const std::string& path, ByteSource& data, PolygonSoup& out, std::string& error) {
  Lines lines{data, 0, '#'};
  std::string_view line;
  // Positive indices are checked once all vertices are known; remember where faces came from.
  std::vector<uint64_t> face_lines;
  std::vector<float> texcoords, normals, colors;  // pools; colours per vertex (v x y z r g b)
  std::vector<uint32_t> corner_texcoords, corner_normals, face_materials;
  bool any_texcoord = false, any_normal = false, any_material = false;
  uint32_t material = kNoAttribute;
  SoupAttributes& attrs = out.attributes;
  auto fail = [&](const std::string& what) {
    error = line_error(path, lines.number, what);
    return false;
  };
  while (lines.next(line)) {
    std::string_view key = next_token(line);
    if (key == "v") {
      float p[3];
      if (!parse_floats(line, p, 3)) return fail("vertex needs three numeric coordinates");
      if (!push_vertex(out, p, path, lines.number, error)) return false;
      float c[3];
      std::string_view probe = line;
      if (!next_token(probe).empty()) {  // vertex colour extension: v x y z r g b
        if (!parse_floats(line, c, 3)) return fail("vertex colour needs three numbers");
        if (!all_finite(c, 3))
          return fail("vertex " + std::to_string(out.vertex_count() - 1) +
                      " has a NaN or infinite colour");
        colors.resize(size_t(out.vertex_count() - 1) * 3, 0.0f);
        colors.insert(colors.end(), c, c + 3);
      }
    } else if (key == "vt") {
      float t[2] = {0, 0};
      if (!parse_float(next_token(line), t[0])) return fail("texture coordinate needs a numeric u");
      std::string_view probe = line;
      if (!next_token(probe).empty() && !parse_float(next_token(line), t[1]))
        return fail("texture coordinate has a malformed v");
      if (!all_finite(t, 2))
        return fail("texture coordinate " + std::to_string(texcoords.size() / 2) +
                    " is NaN or infinite");
      texcoords.insert(texcoords.end(), t, t + 2);
    } else if (key == "vn") {
      float n[3];
      if (!parse_floats(line, n, 3)) return fail("normal needs three numeric coordinates");
      if (!all_finite(n, 3))
        return fail("normal " + std::to_string(normals.size() / 3) + " is NaN or infinite");
      normals.insert(normals.end(), n, n + 3);
    } else if (key == "usemtl") {
      std::string_view name = next_token(line);
      material = uint32_t(attrs.materials.size());
      for (uint32_t m = 0; m < attrs.materials.size(); ++m)
        if (attrs.materials[m].name == name) material = m;
      if (material == attrs.materials.size())
        attrs.materials.push_back(named_material(std::string(name)));
    } else if (key == "mtllib") {
      if (attrs.material_library.empty()) attrs.material_library = next_token(line);
    } else if (key == "f" || key == "fo") {
      uint64_t face = face_lines.size();
      for (std::string_view t = next_token(line); !t.empty(); t = next_token(line)) {
        // v, v/vt, v//vn or v/vt/vn; negative indices count back from the last entry so far.
        int64_t ids[3] = {0, 0, 0};
        const uint64_t pools[3] = {out.vertex_count(), texcoords.size() / 2, normals.size() / 3};
        std::string_view rest = t;
        for (int k = 0; k < 3 && !rest.empty(); ++k) {
          size_t slash = rest.find('/');
          std::string_view part = rest.substr(0, slash);
          rest = slash == std::string_view::npos ? std::string_view() : rest.substr(slash + 1);
          if (k > 0 && part.empty()) continue;  // v//vn: no texture coordinate
          if (!parse_int(part, ids[k]) || ids[k] == 0)
            return fail("face " + std::to_string(face) + " has a malformed index '" +
                        std::string(t) + "'");
          const int64_t written = ids[k];
          if (ids[k] < 0) ids[k] += int64_t(pools[k]) + 1;
          if (ids[k] <= 0 || ids[k] > int64_t(kMaxVertices)) {
            if (k == 0) {
              // The index as the file writes it (1-based, or negative counting back).
              error = line_error(path, lines.number,
                                 "face references vertex " + std::to_string(written) +
                                     (written < 0 ? ", but only " : ", but the file has ") +
                                     std::to_string(out.vertex_count()) +
                                     (written < 0 ? " vertices precede it" : " vertices"));
              return false;
            }
            return fail("face " + std::to_string(face) + " references a " +
                        (k == 1 ? "texture coordinate" : "normal") + " before the first");
          }
        }
        out.corners.push_back(uint32_t(ids[0] - 1));
        corner_texcoords.push_back(ids[1] ? uint32_t(ids[1] - 1) : kNoAttribute);
        corner_normals.push_back(ids[2] ? uint32_t(ids[2] - 1) : kNoAttribute);
        any_texcoord |= ids[1] != 0, any_normal |= ids[2] != 0;
      }
      end_face(out);
      face_lines.push_back(lines.number);
      face_materials.push_back(material);
      any_material |= material != kNoAttribute;
    }
    // Other records (l, p, g, o, s, ...) do not describe triangles or their attributes.
  }
  for (uint32_t f = 0; f < out.face_count(); ++f)
    for (uint32_t c = out.face_offsets[f]; c < out.face_offsets[f + 1]; ++c) {
      if (out.corners[c] >= out.vertex_count()) {
        error = line_error(path, face_lines[f],
                           "face references vertex " + std::to_string(out.corners[c] + 1ull) +
                               ", but the file has " + std::to_string(out.vertex_count()) +
                               " vertices");
        return false;
      }
      if ((corner_texcoords[c] != kNoAttribute && corner_texcoords[c] >= texcoords.size() / 2) ||
          (corner_normals[c] != kNoAttribute && corner_normals[c] >= normals.size() / 3)) {
        error = line_error(
            path, face_lines[f],
            "face " + std::to_string(f) + " references a " +
                (corner_normals[c] == kNoAttribute || corner_normals[c] < normals.size() / 3
                     ? "texture coordinate"
                     : "normal") +
                " the file does not have");
        return false;
      }
    }
  if (any_texcoord) {
    attrs.texcoords.push_back(std::move(texcoords));
    attrs.corner_texcoords.push_back(std::move(corner_texcoords));
  }
  if (any_normal) {
    attrs.normals = std::move(normals);
    attrs.corner_normals = std::move(corner_normals);
  }
  if (!colors.empty()) {
    colors.resize(size_t(out.vertex_count()) * 3, 0.0f);
    attrs.colors = std::move(colors);
    attrs.color_components = 3;
    attrs.corner_colors = out.corners;
  }
  if (any_material) {
    // Faces before the first usemtl get a material of their own.
    uint32_t fallback = kNoAttribute;
    for (uint32_t& m : face_materials)
      if (m == kNoAttribute) {
        if (fallback == kNoAttribute) {
          fallback = uint32_t(attrs.materials.size());
          attrs.materials.push_back(named_material("default"));
        }
        m = fallback;
      }
    attrs.face_materials = std::move(face_materials);
  }
  if (!attrs.material_library.empty()) read_mtl(path, attrs.material_library, attrs.materials);
  return true;
}

void write_mtl(Writer& w, const std::vector<Material>& materials) {
  w.str("# written by pmz\n");
  for (const Material& m : materials) {
    w.str("newmtl ").str(m.name.empty() ? "unnamed" : m.name).str("\nKd ");
    w.num(m.base_color[0]).str(" ").num(m.base_color[1]).str(" ").num(m.base_color[2]).str("\n");
    if (m.base_color[3] != 1) w.str("d ").num(m.base_color[3]).str("\n");
    if (!m.base_color_texture.empty()) w.str("map_Kd ").str(m.base_color_texture).str("\n");
    if (!m.normal_texture.empty()) w.str("norm ").str(m.normal_texture).str("\n");
  }
}

// OBJ: positions per vertex (with the colour of the vertex's first wedge: OBJ colours are per
// vertex), texture coordinates (set 0) and normals per wedge, usemtl where the material changes.
void write_obj(Writer& w, const IndexedMesh& m, const std::string& mtl) {
  const MeshAttributes& a = m.attributes;
  const uint32_t nv = m.vertex_count(), nf = m.face_count();
  const float* p = m.positions.data();
  const uint32_t* ix = m.indices.data();
  if (!mtl.empty()) w.str("mtllib ").str(mtl).str("\n");
  std::vector<uint32_t> vertex_wedge;
  if (a.color_components) {
    vertex_wedge.assign(nv, kNoAttribute);
    for (uint32_t wd = a.wedge_count(); wd-- > 0;) vertex_wedge[a.wedge_vertices[wd]] = wd;
  }
  for (uint32_t v = 0; v < nv; ++v) {
    if (!a.color_components) {
      put_line(w, "v ", p + size_t(v) * 3, 3);
      continue;
    }
    const float* c = vertex_wedge[v] == kNoAttribute
                         ? nullptr
                         : &a.colors[size_t(vertex_wedge[v]) * a.color_components];
    const float xyzrgb[6] = {p[v * 3],        p[v * 3 + 1],    p[v * 3 + 2],
                             c ? c[0] : 0.0f, c ? c[1] : 0.0f, c ? c[2] : 0.0f};
    put_line(w, "v ", xyzrgb, 6);
  }
  const bool uv = !a.texcoords.empty(), normals = !a.normals.empty();
  for (uint32_t wd = 0; uv && wd < a.wedge_count(); ++wd)
    put_line(w, "vt ", &a.texcoords[0][size_t(wd) * 2], 2);
  for (uint32_t wd = 0; normals && wd < a.wedge_count(); ++wd)
    put_line(w, "vn ", &a.normals[size_t(wd) * 3], 3);
  uint32_t material = kNoAttribute;
  const bool wedges = uv || normals;
  for (uint32_t f = 0; f < nf; ++f) {
    if (!a.face_materials.empty() && a.face_materials[f] != material) {
      material = a.face_materials[f];
      const std::string& name = a.materials[material].name;
      w.str("usemtl ").str(name.empty() ? "unnamed" : name).str("\n");
    }
    if (!wedges) {
      put_line(w, "f ", ix + size_t(f) * 3, 3, 1u);
      continue;
    }
    char* o = w.room(Writer::kMaxRoom);
    *o++ = 'f';
    for (int k = 0; k < 3; ++k) {
      const uint32_t wd = a.corner_wedges[f * 3 + k] + 1;
      *o++ = ' ';
      o = Writer::number(o, ix[f * 3 + k] + 1);
      if (uv) *o++ = '/', o = Writer::number(o, wd);
      if (normals) {
        if (!uv) *o++ = '/';
        *o++ = '/', o = Writer::number(o, wd);
      }
    }
    *o++ = '\n';
    w.commit(o);
  }
}

}  // namespace pmz
