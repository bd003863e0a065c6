// SPDX-License-Identifier: MIT
// glTF 2.0 in and out through tinygltf (Debian libtinygltf-dev; JSON by nlohmann-json3-dev).
// tinygltf parses the JSON, the GLB container and buffers (embedded, data: URIs, or files beside
// the input); everything it hands back is checked here before use: accessor ranges against their
// buffer views and buffers, index ranges, attribute counts, finite values, the node tree.
// Images are never decoded (pmz carries texture file names as metadata only).
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <set>
#include <sstream>

#include "mesh_formats.hpp"
#include "pmz/progressive_glb.hpp"
#include "reader_support.hpp"

namespace pmz {

namespace {

constexpr uint64_t kMaxGltfCorners = uint64_t(1) << 31;  // also bounds vertices: ids are uint32
constexpr int kMaxTexcoordSets = 8;

using Matrix = std::array<double, 16>;  // column-major, as glTF stores it

Matrix identity() { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; }

Matrix multiply(const Matrix& a, const Matrix& b) {
  Matrix r{};
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 4; ++row)
      for (int k = 0; k < 4; ++k) r[c * 4 + row] += a[k * 4 + row] * b[c * 4 + k];
  return r;
}

// The node's local transform: its matrix, or translation * rotation * scale.
bool local_transform(const tinygltf::Node& n, Matrix& m) {
  m = identity();
  if (n.matrix.size() == 16) {
    std::copy(n.matrix.begin(), n.matrix.end(), m.begin());
  } else {
    if (n.matrix.size() || (n.scale.size() && n.scale.size() != 3) ||
        (n.rotation.size() && n.rotation.size() != 4) ||
        (n.translation.size() && n.translation.size() != 3))
      return false;
    double s[3] = {1, 1, 1}, q[4] = {0, 0, 0, 1}, t[3] = {0, 0, 0};
    std::copy(n.scale.begin(), n.scale.end(), s);
    std::copy(n.rotation.begin(), n.rotation.end(), q);
    std::copy(n.translation.begin(), n.translation.end(), t);
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),
                         2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                         2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)};
    for (int c = 0; c < 3; ++c)
      for (int row = 0; row < 3; ++row) m[c * 4 + row] = r[c * 3 + row] * s[c];
    for (int row = 0; row < 3; ++row) m[12 + row] = t[row];
  }
  for (double v : m)
    if (!std::isfinite(v)) return false;
  return true;
}

// A checked view of an accessor's elements in its buffer.
struct AccessorView {
  const unsigned char* data = nullptr;
  size_t stride = 0, count = 0;
  int components = 0, type = 0;
  bool normalized = false;

  double value(size_t i, int k) const {
    const unsigned char* p = data + i * stride;
    switch (type) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float v;
        std::memcpy(&v, p + k * 4, 4);
        return v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return normalized ? p[k] / 255.0 : p[k];
      case TINYGLTF_COMPONENT_TYPE_BYTE: {
        double v = int8_t(p[k]);
        return normalized ? std::max(v / 127.0, -1.0) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v;
        std::memcpy(&v, p + k * 2, 2);
        return normalized ? v / 65535.0 : v;
      }
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t v;
        std::memcpy(&v, p + k * 2, 2);
        return normalized ? std::max(v / 32767.0, -1.0) : v;
      }
      default: {  // UNSIGNED_INT (indices)
        uint32_t v;
        std::memcpy(&v, p + k * 4, 4);
        return v;
      }
    }
  }
};

size_t component_size(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return 4;
    default:
      return 0;
  }
}

int hex_digit(char c) {
  return c >= '0' && c <= '9'   ? c - '0'
         : c >= 'a' && c <= 'f' ? c - 'a' + 10
         : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                : -1;
}

// glTF URIs are percent-encoded (tinygltf hands them over as written).
std::string uri_decode(const std::string& s) {
  std::string r;
  for (size_t i = 0; i < s.size(); ++i) {
    int hi, lo;
    if (s[i] == '%' && i + 2 < s.size() && (hi = hex_digit(s[i + 1])) >= 0 &&
        (lo = hex_digit(s[i + 2])) >= 0) {
      r += char(hi * 16 + lo);
      i += 2;
    } else {
      r += s[i];
    }
  }
  return r;
}

class Reader {
 public:
  // With `only_mesh`, that mesh alone in its own coordinates.
  Reader(const std::string& path, const tinygltf::Model& model, PolygonSoup& out,
         int only_mesh = -1)
      : path_(path), model_(model), out_(out), only_mesh_(only_mesh) {}

  // The default scene's nodes in the order the walk reached them, and its meshes in the order
  // it first reached them.
  std::vector<int> node_order, mesh_order;

  bool run(std::string& error) {
    const tinygltf::Model& m = model_;
    if (only_mesh_ >= 0) {
      if (!mesh(only_mesh_, identity(), error)) return false;
    } else if (!m.scenes.empty()) {
      int scene = m.defaultScene >= 0 ? m.defaultScene : 0;
      if (size_t(scene) >= m.scenes.size())
        return fail("default scene " + std::to_string(scene) + " does not exist", error);
      visited_.assign(m.nodes.size(), 0);
      mesh_seen_.assign(m.meshes.size(), 0);
      for (int n : m.scenes[size_t(scene)].nodes)
        if (!node(n, identity(), error)) return false;
    } else {
      for (size_t i = 0; i < m.meshes.size(); ++i)
        if (!mesh(int(i), identity(), error)) return false;
    }
    if (out_.face_count() == 0 && skipped_primitives_) {
      return fail(std::string(only_mesh_ >= 0 ? "mesh " + std::to_string(only_mesh_) + " " : "") +
                      "has no triangles (" + std::to_string(skipped_primitives_) +
                      " point or line primitives)",
                  error);
    }
    finish();
    return true;
  }

 private:
  bool fail(const std::string& what, std::string& error) {
    error = path_ + ": " + what;
    return false;
  }

  bool node(int index, const Matrix& parent, std::string& error) {
    if (index < 0 || size_t(index) >= model_.nodes.size())
      return fail("scene refers to node " + std::to_string(index) + ", which does not exist",
                  error);
    // glTF nodes form a forest: a node reached twice is a cycle or a shared child.
    if (visited_[size_t(index)]++)
      return fail("node " + std::to_string(index) + " is reached twice (nodes must form a tree)",
                  error);
    const tinygltf::Node& n = model_.nodes[size_t(index)];
    Matrix local;
    if (!local_transform(n, local))
      return fail("node " + std::to_string(index) + " has a malformed transform", error);
    Matrix world = multiply(parent, local);
    node_order.push_back(index);
    if (n.mesh >= 0 && size_t(n.mesh) < model_.meshes.size() && !mesh_seen_[size_t(n.mesh)]++)
      mesh_order.push_back(n.mesh);
    if (n.mesh >= 0 && !mesh(n.mesh, world, error)) return false;
    for (int c : n.children)
      if (!node(c, world, error)) return false;
    return true;
  }

  bool view(int index, const std::string& what, AccessorView& v, std::string& error) {
    const tinygltf::Model& m = model_;
    if (index < 0 || size_t(index) >= m.accessors.size())
      return fail(what + " refers to accessor " + std::to_string(index) + ", which does not exist",
                  error);
    const tinygltf::Accessor& a = m.accessors[size_t(index)];
    std::string name = what + " (accessor " + std::to_string(index) + ")";
    if (a.sparse.isSparse) return fail(name + " is sparse, which pmz does not read", error);
    v.components = a.type == TINYGLTF_TYPE_SCALAR ? 1
                   : a.type == TINYGLTF_TYPE_VEC2 ? 2
                   : a.type == TINYGLTF_TYPE_VEC3 ? 3
                   : a.type == TINYGLTF_TYPE_VEC4 ? 4
                                                  : 0;
    const size_t size = component_size(a.componentType);
    if (!v.components || !size) return fail(name + " has an unsupported type", error);
    v.type = a.componentType, v.normalized = a.normalized, v.count = a.count;
    if (a.count == 0) return true;
    if (a.bufferView < 0 || size_t(a.bufferView) >= m.bufferViews.size())
      return fail(name + " has no buffer view", error);
    const tinygltf::BufferView& bv = m.bufferViews[size_t(a.bufferView)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= m.buffers.size())
      return fail(name + "'s buffer view refers to a missing buffer", error);
    const std::vector<unsigned char>& buffer = m.buffers[size_t(bv.buffer)].data;
    const size_t element = size * size_t(v.components);
    v.stride = bv.byteStride ? bv.byteStride : element;
    if (bv.byteOffset > buffer.size() || bv.byteLength > buffer.size() - bv.byteOffset)
      return fail(name + "'s buffer view lies outside its buffer (missing or short buffer?)",
                  error);
    if (v.stride < element || a.byteOffset > bv.byteLength ||
        element > bv.byteLength - a.byteOffset ||
        a.count - 1 > (bv.byteLength - a.byteOffset - element) / v.stride)
      return fail(name + " reaches beyond its buffer view", error);
    v.data = buffer.data() + bv.byteOffset + a.byteOffset;
    return true;
  }

  bool mesh(int index, const Matrix& world, std::string& error) {
    if (index < 0 || size_t(index) >= model_.meshes.size())
      return fail("node refers to mesh " + std::to_string(index) + ", which does not exist", error);
    const tinygltf::Mesh& mesh = model_.meshes[size_t(index)];
    for (size_t p = 0; p < mesh.primitives.size(); ++p)
      if (!primitive(mesh.primitives[p],
                     "mesh " + std::to_string(index) + " primitive " + std::to_string(p), world,
                     error))
        return false;
    return true;
  }

  bool primitive(const tinygltf::Primitive& prim, const std::string& where, const Matrix& world,
                 std::string& error) {
    if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
        prim.mode != TINYGLTF_MODE_TRIANGLE_FAN) {
      ++skipped_primitives_;
      return true;
    }
    auto attribute = [&](const std::string& name) {
      auto it = prim.attributes.find(name);
      return it == prim.attributes.end() ? -1 : it->second;
    };
    AccessorView pos, idx, nrm, col, tex[kMaxTexcoordSets];
    if (attribute("POSITION") < 0) return fail(where + " has no POSITION", error);
    if (!view(attribute("POSITION"), where + " POSITION", pos, error)) return false;
    if (pos.components != 3 || pos.type != TINYGLTF_COMPONENT_TYPE_FLOAT)
      return fail(where + " POSITION is not float VEC3", error);
    const bool has_normals = attribute("NORMAL") >= 0, has_colors = attribute("COLOR_0") >= 0;
    auto same_count = [&](const AccessorView& v, const std::string& name) {
      if (v.count == pos.count) return true;
      return fail(where + " has mismatched accessor counts: " + name + " " +
                      std::to_string(v.count) + ", POSITION " + std::to_string(pos.count),
                  error);
    };
    if (has_normals &&
        (!view(attribute("NORMAL"), where + " NORMAL", nrm, error) || !same_count(nrm, "NORMAL")))
      return false;
    if (has_normals && nrm.components != 3) return fail(where + " NORMAL is not VEC3", error);
    if (has_colors && (!view(attribute("COLOR_0"), where + " COLOR_0", col, error) ||
                       !same_count(col, "COLOR_0")))
      return false;
    if (has_colors && col.components < 3) return fail(where + " COLOR_0 is not VEC3/VEC4", error);
    int sets = 0;
    for (int s = 0; s < kMaxTexcoordSets; ++s) {
      std::string name = "TEXCOORD_" + std::to_string(s);
      if (attribute(name) < 0) continue;
      if (!view(attribute(name), where + " " + name, tex[s], error) || !same_count(tex[s], name))
        return false;
      if (tex[s].components != 2) return fail(where + " " + name + " is not VEC2", error);
      sets = s + 1;
    }
    const bool indexed = prim.indices >= 0;
    if (indexed) {
      if (!view(prim.indices, where + " indices", idx, error)) return false;
      if (idx.components != 1 || (idx.type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                                  idx.type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                                  idx.type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
        return fail(where + " indices are not unsigned integer scalars", error);
    }
    const size_t index_count = indexed ? idx.count : pos.count;
    if (total_corners_ + uint64_t(index_count) * 3 > kMaxGltfCorners ||
        vertex_total_ + pos.count > kMaxGltfCorners)
      return fail("has too many vertices or triangles for pmz", error);

    // Vertices (transformed) and their attributes, pooled per file vertex.
    const uint32_t base = uint32_t(vertex_total_);
    vertex_total_ += pos.count;
    // The cofactor matrix maps normals (the inverse transpose up to scale).
    const Matrix& w = world;
    const double cof[9] = {
        w[5] * w[10] - w[6] * w[9], w[6] * w[8] - w[4] * w[10], w[4] * w[9] - w[5] * w[8],
        w[9] * w[2] - w[10] * w[1], w[10] * w[0] - w[8] * w[2], w[8] * w[1] - w[9] * w[0],
        w[1] * w[6] - w[2] * w[5],  w[2] * w[4] - w[0] * w[6],  w[0] * w[5] - w[1] * w[4]};
    for (size_t i = 0; i < pos.count; ++i) {
      double p[3] = {pos.value(i, 0), pos.value(i, 1), pos.value(i, 2)};
      float q[3];
      for (int r = 0; r < 3; ++r)
        q[r] = float(w[r] * p[0] + w[4 + r] * p[1] + w[8 + r] * p[2] + w[12 + r]);
      if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2]))
        return fail(where + " vertex " + std::to_string(i) + " has a NaN or infinite coordinate",
                    error);
      out_.positions.insert(out_.positions.end(), q, q + 3);
      float n[3] = {0, 0, 0}, c[4] = {0, 0, 0, 1};
      if (has_normals) {
        double m[3] = {nrm.value(i, 0), nrm.value(i, 1), nrm.value(i, 2)};
        for (int r = 0; r < 3; ++r)
          n[r] = float(cof[r * 3] * m[0] + cof[r * 3 + 1] * m[1] + cof[r * 3 + 2] * m[2]);
        double len = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
        if (len > 0 && std::isfinite(len))
          for (float& x : n) x = float(x / len);
      }
      for (int k = 0; has_colors && k < col.components; ++k) c[k] = float(col.value(i, k));
      if (!std::isfinite(n[0] + n[1] + n[2]) || !std::isfinite(c[0] + c[1] + c[2] + c[3]))
        return fail(where + " vertex " + std::to_string(i) + " has a NaN or infinite attribute",
                    error);
      normals_.insert(normals_.end(), n, n + 3);
      colors_.insert(colors_.end(), c, c + 4);
      has_normal_.push_back(has_normals), has_color_.push_back(has_colors);
      color4_ |= has_colors && col.components == 4;
      any_normals_ |= has_normals, any_colors_ |= has_colors;
      if (sets > int(texcoords_.size())) {
        texcoords_.resize(size_t(sets));
        has_texcoord_.resize(size_t(sets));
      }
      for (size_t s = 0; s < texcoords_.size(); ++s) {
        bool has = int(s) < sets && tex[s].count;
        // glTF's v runs down the image; pmz keeps OBJ's (up), as MeshAttributes says.
        float t[2] = {has ? float(tex[s].value(i, 0)) : 0.0f,
                      has ? 1.0f - float(tex[s].value(i, 1)) : 0.0f};
        if (!std::isfinite(t[0]) || !std::isfinite(t[1]))
          return fail(
              where + " vertex " + std::to_string(i) + " has a NaN or infinite texture coordinate",
              error);
        texcoords_[s].resize((size_t(base) + i) * 2, 0.0f);  // earlier primitives without it
        texcoords_[s].insert(texcoords_[s].end(), t, t + 2);
        has_texcoord_[s].resize(size_t(base) + i, 0);
        has_texcoord_[s].push_back(has);
      }
    }

    // Triangles: lists, strips (alternating winding) and fans.
    std::vector<uint32_t> ids(index_count);
    for (size_t i = 0; i < index_count; ++i) {
      double v = indexed ? idx.value(i, 0) : double(i);
      if (v >= double(pos.count))
        return fail(where + " index " + std::to_string(i) + " is " + std::to_string(uint64_t(v)) +
                        ", but POSITION has " + std::to_string(pos.count) + " vertices",
                    error);
      ids[i] = base + uint32_t(v);
    }
    uint32_t material = prim.material;
    if (prim.material < 0 || size_t(prim.material) >= model_.materials.size()) {
      if (prim.material >= 0)
        return fail(where + " refers to material " + std::to_string(prim.material) +
                        ", which does not exist",
                    error);
      if (default_material_ == kNoAttribute)
        default_material_ = uint32_t(model_.materials.size());  // appended in finish()
      material = default_material_;
    } else {
      any_material_ = true;
    }
    auto triangle = [&](uint32_t a, uint32_t b, uint32_t c) {
      out_.corners.insert(out_.corners.end(), {a, b, c});
      out_.face_offsets.push_back(uint32_t(out_.corners.size()));
      face_materials_.push_back(material);
      total_corners_ += 3;
    };
    if (prim.mode == TINYGLTF_MODE_TRIANGLES)
      for (size_t i = 0; i + 2 < index_count; i += 3) triangle(ids[i], ids[i + 1], ids[i + 2]);
    else if (prim.mode == TINYGLTF_MODE_TRIANGLE_STRIP)
      for (size_t i = 0; i + 2 < index_count; ++i)
        i % 2 ? triangle(ids[i + 1], ids[i], ids[i + 2]) : triangle(ids[i], ids[i + 1], ids[i + 2]);
    else
      for (size_t i = 1; i + 1 < index_count; ++i) triangle(ids[0], ids[i], ids[i + 1]);
    return true;
  }

  // Pools and per-corner indices into them; materials; then the positions are welded.
  void finish() {
    SoupAttributes& a = out_.attributes;
    const std::vector<uint32_t>& corners = out_.corners;
    auto indices = [&](const std::vector<uint8_t>& has) {
      std::vector<uint32_t> ids(corners.size());
      for (size_t c = 0; c < corners.size(); ++c)
        ids[c] = has[corners[c]] ? corners[c] : kNoAttribute;
      return ids;
    };
    const uint32_t nv = uint32_t(vertex_total_);
    for (size_t s = 0; s < texcoords_.size(); ++s) {
      texcoords_[s].resize(size_t(nv) * 2, 0.0f);
      has_texcoord_[s].resize(nv, 0);
      a.corner_texcoords.push_back(indices(has_texcoord_[s]));
      a.texcoords.push_back(std::move(texcoords_[s]));
    }
    if (any_normals_) {
      a.corner_normals = indices(has_normal_);
      a.normals = std::move(normals_);
    }
    if (any_colors_) {
      a.color_components = color4_ ? 4 : 3;
      a.corner_colors = indices(has_color_);
      if (!color4_) {
        for (uint32_t v = 0; v < nv; ++v)
          for (int k = 0; k < 3; ++k) colors_[size_t(v) * 3 + k] = colors_[size_t(v) * 4 + k];
        colors_.resize(size_t(nv) * 3);
      }
      a.colors = std::move(colors_);
    }
    if (!any_material_) return weld_vertices(out_);  // no primitive names a material
    const tinygltf::Model& m = model_;
    for (const tinygltf::Material& gm : m.materials) {
      Material mat;
      mat.name = gm.name;
      const std::vector<double>& f = gm.pbrMetallicRoughness.baseColorFactor;
      for (size_t k = 0; k < 4 && k < f.size(); ++k)
        if (std::isfinite(f[k])) mat.base_color[k] = float(f[k]);
      mat.base_color_texture = texture_name(gm.pbrMetallicRoughness.baseColorTexture.index);
      mat.normal_texture = texture_name(gm.normalTexture.index);
      a.materials.push_back(std::move(mat));
    }
    if (default_material_ != kNoAttribute) {
      a.materials.emplace_back();
      a.materials.back().name = "default";
    }
    a.face_materials = std::move(face_materials_);
    weld_vertices(out_);
  }

  std::string texture_name(int texture) const {
    const tinygltf::Model& m = model_;
    if (texture < 0 || size_t(texture) >= m.textures.size()) return {};
    int image = m.textures[size_t(texture)].source;
    if (image < 0 || size_t(image) >= m.images.size()) return {};
    const tinygltf::Image& im = m.images[size_t(image)];
    return im.uri.empty() || im.uri.starts_with("data:") ? im.name : uri_decode(im.uri);
  }

  const std::string& path_;
  const tinygltf::Model& model_;
  PolygonSoup& out_;
  const int only_mesh_;
  std::vector<uint8_t> visited_, mesh_seen_;
  uint64_t vertex_total_ = 0, total_corners_ = 0, skipped_primitives_ = 0;
  std::vector<std::vector<float>> texcoords_;
  std::vector<std::vector<uint8_t>> has_texcoord_;
  std::vector<float> normals_, colors_;
  std::vector<uint8_t> has_normal_, has_color_;
  bool any_normals_ = false, any_colors_ = false, color4_ = false, any_material_ = false;
  std::vector<uint32_t> face_materials_;
  uint32_t default_material_ = kNoAttribute;
};

bool no_image_loading(tinygltf::Image*, const int, std::string*, std::string*, int, int,
                      const unsigned char*, int, void*) {
  return true;
}

// Percent-encodes what a URI may not hold (texture names may have spaces).
std::string uri_encode(const std::string& s) {
  std::string r;
  for (unsigned char c : s) {
    if (std::isalnum(c) || std::strchr("-._~/", c)) {
      r += char(c);
    } else {
      char buf[4];
      std::snprintf(buf, sizeof buf, "%%%02X", c);
      r += buf;
    }
  }
  return r;
}

// glTF's JSON must be UTF-8, but OBJ/MTL and .pmz names are bytes (regr01.mtl has a Latin-1
// "Terraind\xebk"). Valid UTF-8 passes unchanged; any other byte is read as Latin-1, which keeps
// the name readable and distinct instead of refusing the whole mesh over it.
std::string utf8_name(const std::string& s) {
  std::string r;
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  const size_t n = s.size();
  for (size_t i = 0; i < n;) {
    const unsigned char c = p[i];
    size_t len = c < 0x80 ? 1 : (c >> 5) == 6 ? 2 : (c >> 4) == 14 ? 3 : (c >> 3) == 30 ? 4 : 0;
    bool valid = len > 0 && i + len <= n;
    uint32_t cp = len == 1 ? c : len == 2 ? c & 0x1f : len == 3 ? c & 0x0f : c & 0x07;
    for (size_t k = 1; valid && k < len; ++k) {
      valid = (p[i + k] & 0xc0) == 0x80;
      cp = (cp << 6) | (p[i + k] & 0x3f);
    }
    // RFC 3629: shortest form only, no surrogates, nothing above U+10FFFF.
    static constexpr uint32_t kShortest[5] = {0, 0, 0x80, 0x800, 0x10000};
    valid = valid && cp >= kShortest[len] && cp <= 0x10ffff && (cp < 0xd800 || cp > 0xdfff);
    if (valid) {
      r.append(s, i, len);
      i += len;
    } else {
      r += char(0xc0 | (c >> 6));
      r += char(0x80 | (c & 0x3f));
      i += 1;
    }
  }
  return r;
}

}  // namespace

// Parses .gltf or .glb bytes (external buffers beside `path`) with the loader's image callback.
static bool load_model(const std::string& path, std::string_view data, tinygltf::TinyGLTF& loader,
                       tinygltf::Model& model, std::string& error) {
  std::string err, warn;
  const std::string base_dir = std::filesystem::path(path).parent_path().string();
  const auto* bytes = reinterpret_cast<const unsigned char*>(data.data());
  bool ok = data.starts_with("glTF")
                ? loader.LoadBinaryFromMemory(&model, &err, &warn, bytes,
                                              unsigned(std::min<size_t>(data.size(), UINT32_MAX)),
                                              base_dir)
                : loader.LoadASCIIFromString(&model, &err, &warn, data.data(),
                                             unsigned(std::min<size_t>(data.size(), UINT32_MAX)),
                                             base_dir);
  if (!ok) {
    // tinygltf's messages run over several lines; the first names the problem.
    std::string first = err.empty() ? "not a valid glTF file" : err.substr(0, err.find('\n'));
    while (!first.empty() && std::isspace(static_cast<unsigned char>(first.back())))
      first.pop_back();
    error = path + ": " + first;
    return false;
  }
  return true;
}

bool read_gltf(const std::string& path, std::string_view data, PolygonSoup& out,
               std::string& error) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(no_image_loading, nullptr);
  tinygltf::Model model;
  if (!load_model(path, data, loader, model, error)) return false;
  Reader reader(path, model, out);
  return reader.run(error);
}

namespace {

// The image of a texture file: PNG and JPEG (glTF's core image types) by their signature.
std::string image_mime_type(const std::string& data) {
  if (data.starts_with("\x89PNG\r\n\x1a\n")) return "image/png";
  if (data.starts_with("\xff\xd8\xff")) return "image/jpeg";
  return "";
}

// Texture names made relative by backslashes (OBJ from Windows) read as folders.
std::filesystem::path texture_path(const std::string& dir, std::string name) {
  std::replace(name.begin(), name.end(), '\\', '/');
  return std::filesystem::path(dir) / name;
}

// The image of a texture name: a glTF input's own or the file, PNG or JPEG; false with a line
// saying why in t.not_embedded.
bool texture_image(GlbTextures& t, const std::string& name, std::string& data) {
  std::string why;
  if (auto it = t.images.find(name); it != t.images.end())
    data = it->second;
  else if (!read_file(texture_path(t.dir, name).string(), data, why))
    return t.not_embedded.push_back(why), false;
  if (!image_mime_type(data).empty()) return true;
  t.not_embedded.push_back(name + ": not a PNG or JPEG image");
  return false;
}

// A buffer view of `data` at the buffer's end (4-byte aligned), no target: its index.
int add_bytes(tinygltf::Model& model, std::string_view data) {
  std::vector<unsigned char>& buffer = model.buffers[0].data;
  buffer.resize((buffer.size() + 3) & ~size_t(3));
  tinygltf::BufferView bv;
  bv.buffer = 0, bv.byteOffset = buffer.size(), bv.byteLength = data.size();
  buffer.insert(buffer.end(), data.begin(), data.end());
  model.bufferViews.push_back(bv);
  return int(model.bufferViews.size() - 1);
}

// Adds the PMZ_progressive_mesh extension (docs/gltf-binding.md) to every primitive of mesh
// `mesh`, the stream as the buffer's last view.
void add_stream(tinygltf::Model& model, size_t mesh, const GlbStream& stream) {
  const int view = add_bytes(model, stream.bytes);
  using tinygltf::Value;
  auto vec3 = [](const float* v) {
    return Value(Value::Array{Value(double(v[0])), Value(double(v[1])), Value(double(v[2]))});
  };
  Value::Object bounds{{"min", vec3(stream.bbox_min)}, {"max", vec3(stream.bbox_max)}};
  Value::Object ext{{"bufferView", Value(view)},
                    {"version", Value(stream.version)},
                    {"fullVertexCount", Value(int(stream.full_vertices))},
                    {"fullFaceCount", Value(int(stream.full_faces))},
                    {"fullBounds", Value(bounds)}};
  for (tinygltf::Primitive& prim : model.meshes[mesh].primitives)
    prim.extensions[kProgressiveExtension] = Value(ext);
  auto& used = model.extensionsUsed;
  if (std::find(used.begin(), used.end(), kProgressiveExtension) == used.end())
    used.push_back(kProgressiveExtension);
}

// An accessor of `count` 4-byte components (floats, else unsigned ints) in a view of its own,
// 4-byte aligned (embedded images between views have any length).
int add_accessor(tinygltf::Model& model, const void* src, size_t count, bool floats, int type,
                 int target) {
  std::vector<unsigned char>& buffer = model.buffers[0].data;
  size_t offset = (buffer.size() + 3) & ~size_t(3);
  size_t size = count * 4;
  buffer.resize(offset + size);
  if (size) std::memcpy(buffer.data() + offset, src, size);
  tinygltf::BufferView bv;
  bv.buffer = 0, bv.byteOffset = offset, bv.byteLength = size, bv.target = target;
  model.bufferViews.push_back(bv);
  tinygltf::Accessor acc;
  acc.bufferView = int(model.bufferViews.size() - 1);
  acc.componentType = floats ? TINYGLTF_COMPONENT_TYPE_FLOAT : TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
  acc.type = type;
  acc.count = count / (type == TINYGLTF_TYPE_SCALAR ? 1 : size_t(type));
  model.accessors.push_back(acc);
  return int(model.accessors.size() - 1);
}

// The vertex accessors of `mesh` (one vertex per wedge when it has attributes) by attribute.
std::map<std::string, int> add_vertices(tinygltf::Model& model, const IndexedMesh& mesh) {
  const MeshAttributes& a = mesh.attributes;
  const bool wedges = a.has_wedges();
  const uint32_t nv = wedges ? a.wedge_count() : mesh.vertex_count();
  auto vertex_of = [&](uint32_t v) { return wedges ? a.wedge_vertices[v] : v; };
  auto add = [&](const std::vector<float>& values, int type) {
    return add_accessor(model, values.data(), values.size(), true, type,
                        TINYGLTF_TARGET_ARRAY_BUFFER);
  };
  std::vector<float> values(size_t(nv) * 3);
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (uint32_t v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k) {
      float x = mesh.positions[size_t(vertex_of(v)) * 3 + k];
      values[size_t(v) * 3 + k] = x;
      lo[k] = std::min(lo[k], double(x)), hi[k] = std::max(hi[k], double(x));
    }
  std::map<std::string, int> attributes;
  attributes["POSITION"] = add(values, TINYGLTF_TYPE_VEC3);
  model.accessors.back().minValues.assign(lo, lo + 3);
  model.accessors.back().maxValues.assign(hi, hi + 3);
  if (!a.normals.empty()) {
    for (uint32_t v = 0; v < nv; ++v) {
      const float* n = &a.normals[size_t(v) * 3];
      double len = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
      for (int k = 0; k < 3; ++k)
        values[size_t(v) * 3 + k] = len > 0 ? float(n[k] / len) : k == 2 ? 1.0f : 0.0f;
    }
    attributes["NORMAL"] = add(values, TINYGLTF_TYPE_VEC3);
  }
  for (size_t s = 0; s < a.texcoords.size(); ++s) {
    values.assign(a.texcoords[s].begin(), a.texcoords[s].end());
    for (size_t i = 1; i < values.size(); i += 2) values[i] = 1.0f - values[i];  // v down
    attributes["TEXCOORD_" + std::to_string(s)] = add(values, TINYGLTF_TYPE_VEC2);
  }
  if (a.color_components) {
    values.resize(a.colors.size());
    for (size_t i = 0; i < a.colors.size(); ++i) values[i] = std::clamp(a.colors[i], 0.0f, 1.0f);
    attributes["COLOR_0"] =
        add(values, a.color_components == 4 ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3);
  }
  return attributes;
}

// The primitives of `mesh` sharing `attributes`: one per material with faces (faces in file
// order within each), glTF material k for the mesh's material k.
tinygltf::Mesh add_primitives(tinygltf::Model& model, const IndexedMesh& mesh,
                              const std::map<std::string, int>& attributes) {
  const MeshAttributes& a = mesh.attributes;
  const bool wedges = a.has_wedges();
  tinygltf::Mesh gmesh;
  const size_t groups = a.face_materials.empty() ? 1 : a.materials.size();
  std::vector<std::vector<uint32_t>> indices(groups);
  for (uint32_t f = 0; f < mesh.face_count(); ++f) {
    std::vector<uint32_t>& out = indices[a.face_materials.empty() ? 0 : a.face_materials[f]];
    for (int k = 0; k < 3; ++k)
      out.push_back(wedges ? a.corner_wedges[f * 3 + k] : mesh.indices[f * 3 + k]);
  }
  for (size_t g = 0; g < groups; ++g) {
    if (indices[g].empty()) continue;
    tinygltf::Primitive prim;
    prim.attributes = attributes;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.material = a.face_materials.empty() ? -1 : int(g);
    prim.indices = add_accessor(model, indices[g].data(), indices[g].size(), false,
                                TINYGLTF_TYPE_SCALAR, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    gmesh.primitives.push_back(prim);
  }
  return gmesh;
}

// The model of write_glb's layout; with `textures`, texture files found relative to
// textures->dir are embedded.
bool build_model(const IndexedMesh& mesh, GlbTextures* textures, tinygltf::Model& model,
                 std::string& error) {
  const MeshAttributes& a = mesh.attributes;
  if (mesh.face_count() == 0) {
    error = "no faces to write";
    return false;
  }
  model = {};
  model.asset.version = "2.0";
  model.asset.generator = "pmz";
  model.buffers.resize(1);
  const std::map<std::string, int> attributes = add_vertices(model, mesh);
  // Materials, their textures and images (URIs, or with `textures` the images embedded), one
  // texture per file name.
  std::map<std::string, int> texture_of;
  for (const Material& m : a.materials) {
    tinygltf::Material gm;
    gm.name = utf8_name(m.name);
    gm.pbrMetallicRoughness.baseColorFactor.assign(m.base_color, m.base_color + 4);
    for (double& c : gm.pbrMetallicRoughness.baseColorFactor) c = std::clamp(c, 0.0, 1.0);
    gm.pbrMetallicRoughness.metallicFactor = 0;  // OBJ / PLY materials are not metallic
    auto texture = [&](const std::string& file) {
      if (auto it = texture_of.find(file); it != texture_of.end()) return it->second;
      tinygltf::Image image;
      image.uri = uri_encode(file);
      std::string data;
      if (textures && texture_image(*textures, file, data)) {
        // The image's bytes in the buffer, after the mesh's; named as the material names it.
        image.uri.clear();
        image.name = utf8_name(file);
        image.bufferView = add_bytes(model, data);
        image.mimeType = image_mime_type(data);
      }
      model.images.push_back(image);
      tinygltf::Texture t;
      t.source = int(model.images.size() - 1);
      model.textures.push_back(t);
      return texture_of[file] = int(model.textures.size() - 1);
    };
    if (!m.base_color_texture.empty())
      gm.pbrMetallicRoughness.baseColorTexture.index = texture(m.base_color_texture);
    if (!m.normal_texture.empty()) gm.normalTexture.index = texture(m.normal_texture);
    model.materials.push_back(gm);
  }
  tinygltf::Mesh gmesh = add_primitives(model, mesh, attributes);
  model.meshes.push_back(gmesh);
  tinygltf::Node node;
  node.mesh = 0;
  model.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes.push_back(0);
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  return true;
}

bool serialise_glb(const tinygltf::Model& model, std::string& bytes, std::string& error) {
  std::ostringstream stream;
  tinygltf::TinyGLTF writer;
  bool written = false;
  try {  // tinygltf's JSON library reports what it cannot serialise by throwing
    written = writer.WriteGltfSceneToStream(&model, stream, false, true);
  } catch (const std::exception& e) {
    error = std::string("glTF serialisation failed: ") + e.what();
    return false;
  }
  if (!written) {
    error = "glTF serialisation failed";
    return false;
  }
  bytes = stream.str();
  return true;
}

// The image's bytes as the file has them (the loader is given them undecoded).
bool keep_image_bytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*) {
  image->image.assign(bytes, bytes + size);
  return true;
}

}  // namespace

bool read_gltf_images(const std::string& path, std::map<std::string, std::string>& images,
                      std::string& error) {
  std::string data;
  if (!read_file(path, data, error)) return false;
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keep_image_bytes, nullptr);
  tinygltf::Model model;
  if (!load_model(path, data, loader, model, error)) return false;
  for (const tinygltf::Image& im : model.images)
    if (!im.name.empty() && !im.image.empty() && (im.uri.empty() || im.uri.starts_with("data:")))
      images.emplace(im.name, std::string(im.image.begin(), im.image.end()));
  return true;
}

bool write_glb(const IndexedMesh& mesh, std::string& bytes, std::string& error) {
  tinygltf::Model model;
  return build_model(mesh, nullptr, model, error) && serialise_glb(model, bytes, error);
}

bool write_progressive_glb(const IndexedMesh& base, const GlbStream& stream, GlbTextures& textures,
                           std::string& bytes, std::string& error) {
  tinygltf::Model model;
  if (!build_model(base, &textures, model, error)) return false;
  add_stream(model, 0, stream);
  return serialise_glb(model, bytes, error);
}

struct GltfScene::State {
  std::string path;
  tinygltf::Model model;
  int scene = -1;
  std::vector<int> node_order, mesh_order;
  std::vector<std::string> left_out;
};

GltfScene::GltfScene() : state_(std::make_unique<State>()) {}
GltfScene::~GltfScene() = default;

bool GltfScene::read(const std::string& path, std::string_view data, std::string& error) {
  state_ = std::make_unique<State>();
  State& s = *state_;
  s.path = path;
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keep_image_bytes, nullptr);
  if (!load_model(path, data, loader, s.model, error)) return false;
  // Read whole as read_gltf reads it: every accessor checked before anything is encoded.
  PolygonSoup whole;
  whole.face_offsets.push_back(0);
  Reader reader(s.path, s.model, whole);
  if (!reader.run(error)) return false;
  if (!s.model.scenes.empty()) s.scene = std::max(s.model.defaultScene, 0);
  s.node_order = std::move(reader.node_order);
  for (int m : reader.mesh_order) {
    const std::vector<tinygltf::Primitive>& prims = s.model.meshes[size_t(m)].primitives;
    if (std::any_of(prims.begin(), prims.end(), [](const tinygltf::Primitive& p) {
          return p.mode == TINYGLTF_MODE_TRIANGLES || p.mode == TINYGLTF_MODE_TRIANGLE_STRIP ||
                 p.mode == TINYGLTF_MODE_TRIANGLE_FAN;
        }))
      s.mesh_order.push_back(m);
    else
      s.left_out.push_back("mesh " + std::to_string(m) +
                           " has no triangles (points or lines): not carried");
  }
  return true;
}

const std::vector<std::string>& GltfScene::meshes_left_out() const { return state_->left_out; }

size_t GltfScene::mesh_nodes() const {
  const State& s = *state_;
  return size_t(std::count_if(s.node_order.begin(), s.node_order.end(), [&](int n) {
    const int m = s.model.nodes[size_t(n)].mesh;
    return m >= 0 && std::count(s.mesh_order.begin(), s.mesh_order.end(), m) > 0;
  }));
}

size_t GltfScene::mesh_count() const { return state_->mesh_order.size(); }

std::string GltfScene::mesh_name(size_t i) const {
  const int index = state_->mesh_order[i];
  const std::string& name = state_->model.meshes[size_t(index)].name;
  return "mesh " + std::to_string(index) + (name.empty() ? "" : " \"" + name + "\"");
}

bool GltfScene::read_mesh(size_t i, PolygonSoup& out, std::string& error) const {
  const State& s = *state_;
  out = PolygonSoup();
  out.face_offsets.push_back(0);
  Reader reader(s.path, s.model, out, s.mesh_order[i]);
  if (!reader.run(error)) return false;
  if (out.face_count() == 0) {
    error = s.path + ": mesh " + std::to_string(s.mesh_order[i]) + " has no faces";
    return false;
  }
  return true;
}

namespace {

// The names of the extensions a material uses, on itself and on its textures.
void material_extensions(const tinygltf::Material& m, std::set<std::string>& names) {
  const tinygltf::ExtensionMap* maps[] = {
      &m.extensions,
      &m.pbrMetallicRoughness.extensions,
      &m.pbrMetallicRoughness.baseColorTexture.extensions,
      &m.pbrMetallicRoughness.metallicRoughnessTexture.extensions,
      &m.normalTexture.extensions,
      &m.occlusionTexture.extensions,
      &m.emissiveTexture.extensions};
  for (const tinygltf::ExtensionMap* map : maps)
    for (const auto& entry : *map) names.insert(entry.first);
}

// The input's image in the output: its own bytes, or the file its URI names beside the input,
// embedded; else its URI, with a line saying why in `not_embedded`.
tinygltf::Image scene_image(tinygltf::Model& model, const tinygltf::Image& in,
                            const std::string& dir, std::vector<std::string>& not_embedded) {
  tinygltf::Image out;
  out.name = in.name, out.extras = in.extras, out.extensions = in.extensions;
  std::string data(in.image.begin(), in.image.end()), why;
  const bool external = !in.uri.empty() && !in.uri.starts_with("data:");
  if (data.empty() && external &&
      !read_file(texture_path(dir, uri_decode(in.uri)).string(), data, why))
    not_embedded.push_back(why);
  const std::string mime = !in.mimeType.empty() ? in.mimeType : image_mime_type(data);
  if (!data.empty() && mime.empty())
    not_embedded.push_back(uri_decode(in.uri) + ": not a PNG or JPEG image");
  if (data.empty() || mime.empty()) {
    out.uri = in.uri;
    return out;
  }
  out.bufferView = add_bytes(model, data);
  out.mimeType = mime;
  return out;
}

}  // namespace

bool GltfScene::write_glb(const std::vector<IndexedMesh>& bases,
                          const std::vector<GlbStream>& streams,
                          std::vector<std::string>& not_embedded, std::string& bytes,
                          std::string& error) const {
  const State& s = *state_;
  const tinygltf::Model& in = s.model;
  if (bases.size() != s.mesh_order.size() || streams.size() != bases.size() || s.scene < 0) {
    error = "the scene's meshes and streams do not match";
    return false;
  }
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "pmz";
  model.buffers.resize(1);
  // Every base first, then the images, then the streams: a reader of the file front to back
  // can draw the whole scene coarse before any stream arrives.
  size_t table = 0;
  for (size_t i = 0; i < bases.size(); ++i) {
    if (bases[i].face_count() == 0) {
      error = "no faces to write";
      return false;
    }
    tinygltf::Mesh mesh = add_primitives(model, bases[i], add_vertices(model, bases[i]));
    mesh.name = in.meshes[size_t(s.mesh_order[i])].name;
    model.meshes.push_back(std::move(mesh));
    table = std::max(table, bases[i].attributes.materials.size());
  }
  model.materials = in.materials;
  if (table > in.materials.size()) {  // the streams' material for primitives without one
    model.materials.emplace_back();
    model.materials.back().name = "default";
  }
  model.textures = in.textures;
  model.samplers = in.samplers;
  const std::string dir = std::filesystem::path(s.path).parent_path().string();
  for (const tinygltf::Image& im : in.images)
    model.images.push_back(scene_image(model, im, dir, not_embedded));
  // The input's extensions these use stay listed (those of what is not kept do not).
  std::set<std::string> names;
  auto used = [&](const auto& list) {
    for (const auto& item : list)
      for (const auto& entry : item.extensions) names.insert(entry.first);
  };
  for (const tinygltf::Material& m : model.materials) material_extensions(m, names);
  used(model.textures), used(model.samplers), used(model.images);
  for (const std::string& e : in.extensionsUsed)
    if (names.count(e)) model.extensionsUsed.push_back(e);
  for (const std::string& e : in.extensionsRequired)
    if (names.count(e)) model.extensionsRequired.push_back(e);
  for (size_t i = 0; i < streams.size(); ++i) add_stream(model, i, streams[i]);
  // The nodes the default scene reaches, numbered in the order of the walk that read them.
  std::vector<int> node_index(in.nodes.size(), -1), mesh_index(in.meshes.size(), -1);
  for (size_t k = 0; k < s.node_order.size(); ++k) node_index[size_t(s.node_order[k])] = int(k);
  for (size_t i = 0; i < s.mesh_order.size(); ++i) mesh_index[size_t(s.mesh_order[i])] = int(i);
  for (int index : s.node_order) {
    const tinygltf::Node& n = in.nodes[size_t(index)];
    tinygltf::Node node;
    node.name = n.name, node.extras = n.extras, node.matrix = n.matrix;
    node.translation = n.translation, node.rotation = n.rotation, node.scale = n.scale;
    node.mesh = n.mesh >= 0 ? mesh_index[size_t(n.mesh)] : -1;
    for (int c : n.children) node.children.push_back(node_index[size_t(c)]);
    model.nodes.push_back(std::move(node));
  }
  tinygltf::Scene scene;
  scene.name = in.scenes[size_t(s.scene)].name;
  for (int n : in.scenes[size_t(s.scene)].nodes) scene.nodes.push_back(node_index[size_t(n)]);
  model.scenes.push_back(std::move(scene));
  model.defaultScene = 0;
  return serialise_glb(model, bytes, error);
}

}  // namespace pmz
