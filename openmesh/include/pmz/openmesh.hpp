// SPDX-License-Identifier: MIT
// pmz for OpenMesh: encode an OpenMesh triangle mesh, and keep one in step with a streaming
// decoder. Header-only; the `openmesh` component of the installed CMake package:
//
//   find_package(pmz REQUIRED COMPONENTS openmesh)
//   target_link_libraries(app PRIVATE pmz::openmesh)
//
// pmz::openmesh brings pmz::decoder, OpenMesh's OpenMeshCore and, when installed, pmz::encoder.
//
// Usage:
//
//   #include <pmz/openmesh.hpp>
//   OpenMesh::TriMesh_ArrayKernelT<> tri = ...;  // with any standard properties
//   std::vector<uint8_t> bytes;
//   std::string error;
//   if (!pmz::openmesh::encode(tri, bytes, error)) die(error);
//
//   pmz::Decoder decoder;
//   pmz::openmesh::MeshView<> view(decoder);  // owns an OpenMesh::TriMesh_ArrayKernelT<>
//   decoder.feed(bytes.data(), bytes.size());
//   view.set_face_target(5000);   // decoder.set_face_target, then view.update()
//   view.refine(100);             // or call the decoder, then view.update()
//   use(view.mesh());             // vertex i and face i are the decoder's vertex i and face i
//
// Encoding (to_mesh, encode): the mesh's vertices (deleted ones skipped), its triangles, and per
// corner the attributes pmz carries: normals, texture coordinates (texcoords2D) and colours, each
// from the halfedge property (per corner: seams and creases kept), else the vertex property,
// else (colours only) the face property; ConvertOptions picks another source or none. Corners
// of one vertex with equal values share a wedge (pmz/mesh.hpp). Integer colours are scaled by
// their type's maximum to [0, 1]. Materials: with face texture indices
// (request_face_texture_index), each face's index is its material; material i is named
// "texture<i>" (as pmz names a PLY file's texnumber textures) and its base colour texture is
// entry i of the mesh property "TextureMapping" (std::map<int, std::string>, index -> file
// name, as OpenMesh's importer sets it for its readers) when there is one. Indices run
// 0..65535; the table holds index 0 up to the highest used or mapped one.
//
// Decoding (MeshView): update() brings the owned mesh to the decoder's current level through
// Decoder::changes() and clears that report (a renderer that uploads the same deltas reads
// changes() before update()). Vertices are appended or removed at the end; each rewritten face
// is deleted and added again so that it lands at its own index, and the holes the deleted
// elements left are filled as OpenMesh's garbage collection would, touching only them and
// what moves into them (not the whole mesh). Attributes: halfedge properties get each corner's
// wedge (exact); vertex properties the vertex's lowest-numbered wedge (one side of a seam); face
// colours, when asked for, the face's first corner's. Only the texture coordinate set
// ViewOptions::texcoord_set is kept (OpenMesh has one 2D set). A stream with materials gives
// each face its material as face texture index, and the materials' base colour textures as the
// mesh property "TextureMapping" (std::map<int, std::string>: index -> file name), so that the
// two round-trip through encode.
//
// Cost: see MeshView.
#pragma once
#if defined(__GNUC__) && !defined(__clang__)
// OpenMesh's properties push default-constructed vectors (Property.hh), whose components are
// uninitialized: GCC's -Wmaybe-uninitialized reports each colour property type instantiated.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/Utils/vector_traits.hh>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include "pmz/decoder.hpp"
#if __has_include("pmz/writer.hpp")
#include "pmz/mesh.hpp"
#include "pmz/simplify.hpp"
#include "pmz/writer.hpp"
#define PMZ_OPENMESH_HAS_ENCODER 1
#endif

namespace pmz::openmesh {

using TriMesh = OpenMesh::TriMesh_ArrayKernelT<>;

namespace detail {

inline constexpr uint32_t kNone = 0xFFFFFFFFu;
inline constexpr int64_t kMaterials = 65536;  // a stream's material table holds at most these
inline constexpr const char* kTextureMapping = "TextureMapping";
using TextureMapping = OpenMesh::MPropHandleT<std::map<int, std::string>>;

template <class Color>
constexpr uint32_t color_size() {
  return uint32_t(OpenMesh::vector_traits<Color>::size_);
}
template <class Color>
constexpr float color_scale() {
  using Scalar = typename OpenMesh::vector_traits<Color>::value_type;
  if constexpr (std::is_integral_v<Scalar>) return float(std::numeric_limits<Scalar>::max());
  return 1.0f;
}
// Colour -> count floats in [0, 1] (alpha 1 when the type has none).
template <class Color>
void color_to_floats(const Color& c, float* out, uint32_t count) {
  for (uint32_t k = 0; k < count; ++k)
    out[k] = k < color_size<Color>() ? float(c[int(k)]) / color_scale<Color>() : 1.0f;
}
template <class Color>
Color color_from_floats(const float* in, uint32_t count) {
  using Scalar = typename OpenMesh::vector_traits<Color>::value_type;
  Color c;
  for (uint32_t k = 0; k < color_size<Color>(); ++k) {
    const float x = k < count ? in[k] : 1.0f;
    if constexpr (std::is_integral_v<Scalar>)
      c[int(k)] = Scalar(std::clamp(x, 0.0f, 1.0f) * color_scale<Color>() + 0.5f);
    else
      c[int(k)] = Scalar(x);
  }
  return c;
}

}  // namespace detail

#ifdef PMZ_OPENMESH_HAS_ENCODER

// Where an attribute's per-corner values come from. automatic: the halfedge property if the
// mesh has it, else the vertex property, else (colours) the face property, else none. face is
// accepted for normals and colours.
enum class Source { automatic, none, vertex, halfedge, face };

struct ConvertOptions {
  Source normals = Source::automatic;
  Source texcoords = Source::automatic;
  Source colors = Source::automatic;
  bool materials = true;  // face texture indices, when the mesh has them, as materials
};

namespace detail {

inline bool resolve(Source wanted, bool has_h, bool has_v, bool has_f, bool face_ok,
                    const char* what, Source& out, std::string& error) {
  has_f = has_f && face_ok;
  if (wanted == Source::automatic)
    wanted = has_h   ? Source::halfedge
             : has_v ? Source::vertex
             : has_f ? Source::face
                     : Source::none;
  const bool has = wanted == Source::none || (wanted == Source::halfedge && has_h) ||
                   (wanted == Source::vertex && has_v) || (wanted == Source::face && has_f);
  if (!has) {
    error = std::string("pmz::openmesh::to_mesh: ") + what + " requested from " +
            (wanted == Source::halfedge ? "halfedge"
             : wanted == Source::vertex ? "vertex"
                                        : "face") +
            " properties, which the mesh does not have" + (face_ok ? "" : " (or cannot have)");
    return false;
  }
  out = wanted;
  return true;
}

// The faces' texture indices as materials (see the top of this file). False with a one-line
// message for an index pmz cannot carry.
template <class Mesh>
bool texture_materials(const Mesh& mesh, MeshAttributes& a, std::string& error) {
  int64_t top = -1;
  a.face_materials.reserve(mesh.n_faces());
  for (auto f : mesh.faces()) {
    const int64_t t = int64_t(mesh.texture_index(f));
    if (t < 0 || t >= kMaterials) {
      error = "pmz::openmesh::to_mesh: face " + std::to_string(f.idx()) + " has texture index " +
              std::to_string(t) + ", outside 0.." + std::to_string(kMaterials - 1);
      return false;
    }
    a.face_materials.push_back(uint32_t(t));
    top = std::max(top, t);
  }
  TextureMapping mapping;
  const bool mapped = mesh.get_property_handle(mapping, kTextureMapping);
  if (mapped)
    for (const auto& [id, file] : mesh.property(mapping))
      if (id >= 0 && id < kMaterials) top = std::max(top, int64_t(id));
  a.materials.resize(size_t(top + 1));
  for (size_t i = 0; i < a.materials.size(); ++i)
    a.materials[i].name = "texture" + std::to_string(i);
  if (mapped)
    for (const auto& [id, file] : mesh.property(mapping))
      if (id >= 0 && id < kMaterials) a.materials[size_t(id)].base_color_texture = file;
  return true;
}

}  // namespace detail

// The mesh as pmz's encoder takes it: vertices in handle order (deleted ones skipped), faces in
// handle order with their corners in face-halfedge order, and the attributes and materials (see
// the top of this file). False with a one-line message when an explicitly requested property is
// missing or a texture index is out of range.
template <class Mesh>
bool to_mesh(const Mesh& mesh, IndexedMesh& out, std::string& error,
             const ConvertOptions& options = {}) {
  static_assert(Mesh::is_trimesh(), "pmz::openmesh::to_mesh takes a triangle mesh");
  out = {};
  Source ns, ts, cs;
  if (!detail::resolve(options.normals, mesh.has_halfedge_normals(), mesh.has_vertex_normals(),
                       mesh.has_face_normals(), true, "normals", ns, error) ||
      !detail::resolve(options.texcoords, mesh.has_halfedge_texcoords2D(),
                       mesh.has_vertex_texcoords2D(), false, false, "texture coordinates", ts,
                       error) ||
      !detail::resolve(options.colors, mesh.has_halfedge_colors(), mesh.has_vertex_colors(),
                       mesh.has_face_colors(), true, "colours", cs, error))
    return false;
  if (mesh.n_vertices() >= detail::kNone || mesh.n_faces() >= detail::kNone / 3) {
    error = "pmz::openmesh::to_mesh: more than 2^32 vertices or corners";
    return false;
  }
  if (options.materials && mesh.has_face_texture_index() &&
      !detail::texture_materials(mesh, out.attributes, error))
    return false;
  using Color = typename Mesh::Color;
  const uint32_t color_n = cs == Source::none ? 0 : std::min(detail::color_size<Color>(), 4u);

  std::vector<uint32_t> id(mesh.n_vertices(), detail::kNone);
  out.positions.reserve(mesh.n_vertices() * 3);
  for (auto v : mesh.vertices()) {
    id[size_t(v.idx())] = out.vertex_count();
    const auto& p = mesh.point(v);
    out.positions.insert(out.positions.end(), {float(p[0]), float(p[1]), float(p[2])});
  }
  MeshAttributes& a = out.attributes;
  const bool wedges = ns != Source::none || ts != Source::none || cs != Source::none;
  if (wedges) {
    if (ts != Source::none) a.texcoords.resize(1);
    a.color_components = color_n < 3 ? 0 : color_n;
  }
  // Per vertex, its wedges as a list (head, next); a corner reuses an equal one.
  std::vector<uint32_t> head(wedges ? out.vertex_count() : 0, detail::kNone), next;
  out.indices.reserve(mesh.n_faces() * 3);
  if (wedges) a.corner_wedges.reserve(mesh.n_faces() * 3);
  for (auto f : mesh.faces()) {
    for (auto h : mesh.fh_range(f)) {
      const auto vh = mesh.to_vertex_handle(h);
      const uint32_t v = id[size_t(vh.idx())];
      out.indices.push_back(v);
      if (!wedges) continue;
      float value[9];
      float* at = value;
      if (ts != Source::none) {
        const auto& t = ts == Source::halfedge ? mesh.texcoord2D(h) : mesh.texcoord2D(vh);
        *at++ = float(t[0]);
        *at++ = float(t[1]);
      }
      if (ns != Source::none) {
        const auto& n = ns == Source::halfedge ? mesh.normal(h)
                        : ns == Source::vertex ? mesh.normal(vh)
                                               : mesh.normal(f);
        for (int k = 0; k < 3; ++k) *at++ = float(n[k]);
      }
      if (a.color_components) {
        detail::color_to_floats(cs == Source::halfedge ? mesh.color(h)
                                : cs == Source::vertex ? mesh.color(vh)
                                                       : mesh.color(f),
                                at, a.color_components);
        at += a.color_components;
      }
      auto same = [&](uint32_t w) {
        const float* x = value;
        if (ts != Source::none)
          for (int k = 0; k < 2; ++k)
            if (a.texcoords[0][size_t(w) * 2 + k] != *x++) return false;
        if (ns != Source::none)
          for (int k = 0; k < 3; ++k)
            if (a.normals[size_t(w) * 3 + k] != *x++) return false;
        for (uint32_t k = 0; k < a.color_components; ++k)
          if (a.colors[size_t(w) * a.color_components + k] != *x++) return false;
        return true;
      };
      uint32_t w = head[v];
      while (w != detail::kNone && !same(w)) w = next[w];
      if (w == detail::kNone) {
        w = a.wedge_count();
        a.wedge_vertices.push_back(v);
        next.push_back(head[v]);
        head[v] = w;
        const float* x = value;
        if (ts != Source::none) a.texcoords[0].insert(a.texcoords[0].end(), x, x + 2), x += 2;
        if (ns != Source::none) a.normals.insert(a.normals.end(), x, x + 3), x += 3;
        a.colors.insert(a.colors.end(), x, x + a.color_components);
      }
      a.corner_wedges.push_back(w);
    }
  }
  return true;
}

struct EncodeOptions {
  ConvertOptions convert;
  SimplifyOptions simplify;
  WriteOptions write;
  // When set: decoded vertex i is to_mesh's vertex (*vertex_order)[i] (the mesh's i-th
  // non-deleted vertex).
  std::vector<uint32_t>* vertex_order = nullptr;
};

// to_mesh, pmz::simplify and pmz::write_pmz: the .pmz bytes in `out`. False with a one-line
// message (from whichever step refused).
template <class Mesh>
bool encode(const Mesh& mesh, std::vector<uint8_t>& out, std::string& error,
            const EncodeOptions& options = {}) {
  IndexedMesh indexed;
  CollapseSequence seq;
  if (!to_mesh(mesh, indexed, error, options.convert) ||
      !simplify(indexed, options.simplify, seq, error) ||
      !write_pmz(seq, options.write, out, error))
    return false;
  if (options.vertex_order) *options.vertex_order = decoded_vertex_order(seq, options.write);
  return true;
}

#endif  // PMZ_OPENMESH_HAS_ENCODER

struct ViewOptions {
  bool vertex_attributes = true;    // vertex normals, texcoords2D, colours: lowest wedge's
  bool halfedge_attributes = true;  // halfedge normals, texcoords2D, colours: per corner
  bool face_colors = false;         // face colours: the first corner's
  bool materials = true;            // face texture indices and "TextureMapping"
  uint32_t texcoord_set = 0;        // which of the file's texture coordinate sets
  // An update that deletes and adds more than this fraction of the faces rebuilds the mesh
  // instead (measured at the middle level of bunny00: see MeshView).
  double rebuild_fraction = 0.25;
};

// An OpenMesh triangle mesh kept at the decoder's level. Vertex i and face i of mesh() are the
// decoder's vertex i and face i (positions(), indices(): face i's vertices in order, starting
// at its halfedge), with the attributes the file has (see the top of this file).
//
// Cost of update(): about the faces it deletes and adds (OpenMesh's add_face, delete_face and
// property writes), with no pass over the whole mesh (a larger mesh costs more per face only
// through the cache). Measured with bench-openmesh-view (CPU time, median of 7, a shared 2-core
// machine) at the middle level of bunny00 (37.7k faces): for 1 / 10 / 100 / 1000 splits, the
// decoder's refine or coarsen 0.001 / 0.003 / 0.01 / 0.1 ms, update() 0.003 / 0.02 / 0.18 /
// 2.3 ms; a rebuild 8.4-8.9 ms. Of bunny00-loop2 (603k faces, median of 5): update() 0.004 /
// 0.02 / 0.32 / 7.2 ms (10000 splits: 103 ms); a rebuild 460-650 ms. Past
// ViewOptions::rebuild_fraction of the faces, update() rebuilds (bunny00, 10000 splits: 21 ms
// incremental, 15 ms rebuilt). A rebuild reserves exactly, so the first updates after one grow
// OpenMesh's arrays.
template <class Mesh = TriMesh>
class MeshView {
 public:
  explicit MeshView(Decoder& decoder, const ViewOptions& options = {})
      : decoder_(&decoder), options_(options) {}

  // Brings mesh() to the decoder's level and clears the decoder's change report. False (with
  // error()) when OpenMesh refused a face the decoder has (not a manifold mesh there); the mesh
  // then lacks that face.
  bool update() {
    error_.clear();
    const bool ok =
        decoder_->changes().all || !layout_matches() || !incremental() ? rebuild() : true;
    decoder_->clear_changes();
    return ok && error_.empty();
  }
  uint64_t refine(uint64_t max_splits = UINT64_MAX) {
    const uint64_t n = decoder_->refine(max_splits);
    update();
    return n;
  }
  uint64_t coarsen(uint64_t max_splits = UINT64_MAX) {
    const uint64_t n = decoder_->coarsen(max_splits);
    update();
    return n;
  }
  void set_face_target(uint64_t faces) {
    decoder_->set_face_target(faces);
    update();
  }

  const Mesh& mesh() const { return mesh_; }
  // For adding properties (e.g. face normals) or changing their values. Changing connectivity,
  // points or the status flags breaks the correspondence; call rebuild() after doing so.
  Mesh& mesh() { return mesh_; }
  Decoder& decoder() const { return *decoder_; }
  const std::string& error() const { return error_; }  // empty when the last update was ok
  // How the last update went: rebuilt from scratch, or how many faces it deleted and added.
  bool last_rebuilt() const { return rebuilt_; }
  uint64_t last_faces_added() const { return faces_added_; }

  // Rebuilds mesh() from the decoder's arrays (does not clear the change report).
  bool rebuild() {
    const Decoder& d = *decoder_;
    rebuilt_ = true;
    faces_added_ = 0;
    error_.clear();
    mesh_.clean_keep_reservation();
    request_properties();
    const uint32_t nv = d.vertex_count(), nf = d.face_count();
    mesh_.reserve(nv, size_t(nf) * 3 / 2 + 16, nf);
    const float* p = d.positions();
    for (uint32_t v = 0; v < nv; ++v) mesh_.add_vertex(point(p + size_t(v) * 3));
    for (uint32_t f = 0; f < nf; ++f)
      if (!add_face(f)) return false;
    wedge_vertices_.assign(d.wedge_vertices(), d.wedge_vertices() + d.wedge_count());
    first_wedge_.assign(nv, detail::kNone);
    for (uint32_t w = d.wedge_count(); w-- > 0;) first_wedge_[wedge_vertices_[w]] = w;
    if (attributes_) {
      for (uint32_t f = 0; f < nf; ++f) face_attributes(f);
      for (uint32_t v = 0; v < nv; ++v) vertex_attributes(v);
    }
    return true;
  }

 private:
  using VH = OpenMesh::VertexHandle;
  using FH = OpenMesh::FaceHandle;
  using HH = OpenMesh::HalfedgeHandle;

  static typename Mesh::Point point(const float* p) {
    using S = typename OpenMesh::vector_traits<typename Mesh::Point>::value_type;
    return typename Mesh::Point(S(p[0]), S(p[1]), S(p[2]));
  }

  // The properties this decoder's attributes fill, as requested on the mesh.
  struct Layout {
    bool normals = false, texcoords = false, colors = false, materials = false;
    bool wedges() const { return normals || texcoords || colors; }
    bool operator==(const Layout&) const = default;
  };
  Layout wanted() const {
    const Decoder& d = *decoder_;
    Layout l;
    l.normals = d.normals() != nullptr;
    l.texcoords = d.texcoords(options_.texcoord_set) != nullptr;
    l.colors = d.colors() != nullptr && d.color_components() >= 3;
    l.materials = d.face_materials() != nullptr && options_.materials;
    return l;
  }
  bool layout_matches() const { return built_ && wanted() == layout_; }
  void request_properties() {
    built_ = true;
    mesh_.request_vertex_status();
    mesh_.request_edge_status();
    mesh_.request_halfedge_status();
    mesh_.request_face_status();
    const Layout l = wanted();
    const bool v = options_.vertex_attributes, h = options_.halfedge_attributes;
    // (Requested once per kind: OpenMesh counts requests.)
    if (l.normals && !layout_.normals) {
      if (v) mesh_.request_vertex_normals();
      if (h) mesh_.request_halfedge_normals();
    }
    if (l.texcoords && !layout_.texcoords) {
      if (v) mesh_.request_vertex_texcoords2D();
      if (h) mesh_.request_halfedge_texcoords2D();
    }
    if (l.colors && !layout_.colors) {
      if (v) mesh_.request_vertex_colors();
      if (h) mesh_.request_halfedge_colors();
      if (options_.face_colors) mesh_.request_face_colors();
    }
    if (l.materials && !layout_.materials) {
      mesh_.request_face_texture_index();
      texture_mapping();
    }
    layout_ = l;
    attributes_ = l.wedges() || l.materials;
  }
  // The materials' base colour textures as "TextureMapping" (the table is the stream's, read
  // with its header: written once). Added only when some material has one.
  void texture_mapping() {
    const Decoder& d = *decoder_;
    detail::TextureMapping mapping;
    for (uint32_t i = 0; i < d.material_count(); ++i) {
      const std::string& file = d.material(i)->base_color_texture;
      if (file.empty()) continue;
      if (!mapping.is_valid() && !mesh_.get_property_handle(mapping, detail::kTextureMapping))
        mesh_.add_property(mapping, detail::kTextureMapping);
      mesh_.property(mapping)[int(i)] = file;
    }
  }

  // Adds the decoder's face f as the mesh's next face, its halfedge at the first corner.
  bool add_face(uint32_t f) {
    const uint32_t* t = decoder_->indices() + size_t(f) * 3;
    const FH fh = mesh_.add_face(VH(int(t[0])), VH(int(t[1])), VH(int(t[2])));
    ++faces_added_;
    if (!fh.is_valid()) {
      error_ = "pmz::openmesh::MeshView: OpenMesh refused face " + std::to_string(f) + " (" +
               std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) +
               "): the mesh is not manifold there";
      return false;
    }
    HH h = mesh_.halfedge_handle(fh);
    while (mesh_.to_vertex_handle(h).idx() != int(t[0])) h = mesh_.next_halfedge_handle(h);
    mesh_.set_halfedge_handle(fh, h);
    return true;
  }
  // The mesh's face f has the decoder's face f's corners, in order.
  bool face_matches(uint32_t f) const {
    const uint32_t* t = decoder_->indices() + size_t(f) * 3;
    HH h = mesh_.halfedge_handle(FH(int(f)));
    for (int k = 0; k < 3; ++k, h = mesh_.next_halfedge_handle(h))
      if (mesh_.to_vertex_handle(h).idx() != int(t[k])) return false;
    return true;
  }

  void face_attributes(uint32_t f) {
    const Decoder& d = *decoder_;
    const FH fh{int(f)};
    if (layout_.materials)
      mesh_.set_texture_index(fh, typename Mesh::TextureIndex(d.face_materials()[f]));
    if (!layout_.wedges()) return;
    const uint32_t* wedges = d.wedge_indices() + size_t(f) * 3;
    if (options_.halfedge_attributes) {
      HH h = mesh_.halfedge_handle(fh);
      for (int k = 0; k < 3; ++k, h = mesh_.next_halfedge_handle(h)) {
        const uint32_t w = wedges[k];
        if (layout_.normals) mesh_.set_normal(h, normal(w));
        if (layout_.texcoords) mesh_.set_texcoord2D(h, texcoord(w));
        if (layout_.colors) mesh_.set_color(h, color(w));
      }
    }
    if (options_.face_colors && layout_.colors) mesh_.set_color(fh, color(wedges[0]));
  }
  void vertex_attributes(uint32_t v) {
    const uint32_t w = first_wedge_[v];
    if (!options_.vertex_attributes || w == detail::kNone) return;
    const VH vh{int(v)};
    if (layout_.normals) mesh_.set_normal(vh, normal(w));
    if (layout_.texcoords) mesh_.set_texcoord2D(vh, texcoord(w));
    if (layout_.colors) mesh_.set_color(vh, color(w));
  }
  typename Mesh::Normal normal(uint32_t w) const {
    using S = typename OpenMesh::vector_traits<typename Mesh::Normal>::value_type;
    const float* n = decoder_->normals() + size_t(w) * 3;
    return typename Mesh::Normal(S(n[0]), S(n[1]), S(n[2]));
  }
  typename Mesh::TexCoord2D texcoord(uint32_t w) const {
    using S = typename OpenMesh::vector_traits<typename Mesh::TexCoord2D>::value_type;
    const float* t = decoder_->texcoords(options_.texcoord_set) + size_t(w) * 2;
    return typename Mesh::TexCoord2D(S(t[0]), S(t[1]));
  }
  typename Mesh::Color color(uint32_t w) const {
    const uint32_t n = decoder_->color_components();
    return detail::color_from_floats<typename Mesh::Color>(decoder_->colors() + size_t(w) * n, n);
  }

  // OpenMesh's garbage collection, restricted to the holes this update made: it walks the whole
  // mesh, this touches only the holes and the elements moved into them. The same order as
  // OpenMesh's (the first hole takes the last live element): faces [0, rewritten holes, tail),
  // edges wherever deleted faces left them; the deleted vertices are the tail from `vertices`.
  void compact(uint32_t vertices) {
    // Faces: a face is its halfedge; its three halfedges name it.
    size_t last = mesh_.n_faces();
    auto face_deleted = [&](size_t f) { return mesh_.status(FH(int(f))).deleted(); };
    for (uint32_t f : rewritten_) {
      while (last > f + 1 && face_deleted(last - 1)) --last;
      if (last <= f + 1) break;
      const FH to{int(f)}, from{int(--last)};
      const HH h = mesh_.halfedge_handle(from);
      for (HH g = h;;) {
        mesh_.set_face_handle(g, to);
        if ((g = mesh_.next_halfedge_handle(g)) == h) break;
      }
      mesh_.set_halfedge_handle(to, h);
      for (size_t k = 0; k < mesh_.n_fprops(); ++k) mesh_._fprop(k).swap(f, last);
    }
    size_t faces = mesh_.n_faces();
    while (faces > 0 && face_deleted(faces - 1)) --faces;
    // Edges: both halfedges move; everything that names them is renamed.
    size_t edges = mesh_.n_edges();
    auto edge_deleted = [&](size_t e) {
      return mesh_.status(OpenMesh::EdgeHandle(int(e))).deleted();
    };
    for (uint32_t e : edge_holes_) {
      while (edges > e + 1 && edge_deleted(edges - 1)) --edges;
      if (edges <= e + 1) break;
      const int from = int(--edges), to = int(e);
      auto moved = [&](HH h) { return h.idx() / 2 == from ? HH(2 * to + (h.idx() & 1)) : h; };
      HH next[2], prev[2];
      for (int j = 0; j < 2; ++j) {
        const HH old{2 * from + j}, now{2 * to + j};
        next[j] = moved(mesh_.next_halfedge_handle(old));
        prev[j] = moved(mesh_.prev_halfedge_handle(old));
        mesh_.set_vertex_handle(now, mesh_.to_vertex_handle(old));
        mesh_.set_face_handle(now, mesh_.face_handle(old));
      }
      for (int j = 0; j < 2; ++j) {
        const HH old{2 * from + j}, now{2 * to + j};
        mesh_.set_next_halfedge_handle(now, next[j]);  // (each also sets the prev link)
        mesh_.set_next_halfedge_handle(prev[j], now);
        const FH fh = mesh_.face_handle(now);
        if (fh.is_valid() && mesh_.halfedge_handle(fh) == old) mesh_.set_halfedge_handle(fh, now);
        const VH vh = mesh_.to_vertex_handle(HH(2 * to + 1 - j));  // now's start
        if (mesh_.halfedge_handle(vh) == old) mesh_.set_halfedge_handle(vh, now);
      }
      for (size_t k = 0; k < mesh_.n_eprops(); ++k) mesh_._eprop(k).swap(size_t(to), size_t(from));
      for (size_t k = 0; k < mesh_.n_hprops(); ++k)
        for (int j = 0; j < 2; ++j) mesh_._hprop(k).swap(size_t(2 * to + j), size_t(2 * from + j));
    }
    edges = mesh_.n_edges();
    while (edges > 0 && edge_deleted(edges - 1)) --edges;
    mesh_.resize(vertices, edges, faces);
  }

  // The change report applied to the mesh; false when a rebuild is the better (or only) way.
  bool incremental() {
    const Decoder& d = *decoder_;
    const MeshChanges& ch = d.changes();
    const uint32_t v0 = uint32_t(mesh_.n_vertices()), f0 = uint32_t(mesh_.n_faces());
    const uint32_t v1 = d.vertex_count(), f1 = d.face_count();
    const uint32_t w0 = uint32_t(wedge_vertices_.size()), w1 = d.wedge_count();
    const uint32_t fb = std::min(ch.face_begin, f0), vb = std::min(ch.vertex_begin, v0);
    const uint32_t wb = std::min(ch.wedge_begin, w0), keep = std::min(f0, f1);
    // Faces kept but rewritten, ascending: the listed ones below fb, then [fb, keep).
    rewritten_.clear();
    for (uint32_t f : ch.modified_faces)
      if (f < fb && f < keep) rewritten_.push_back(f);
    std::sort(rewritten_.begin(), rewritten_.end());
    rewritten_.erase(std::unique(rewritten_.begin(), rewritten_.end()), rewritten_.end());
    for (uint32_t f = fb; f < keep; ++f) rewritten_.push_back(f);
    const uint64_t work = rewritten_.size() + (f1 > f0 ? f1 - f0 : f0 - f1);
    if (double(work) > options_.rebuild_fraction * double(std::max(f0, f1))) return false;

    rebuilt_ = false;
    faces_added_ = 0;
    // Deleted: the rewritten faces, the faces and vertices past the new counts, and the edges
    // of deleted faces that no face keeps (OpenMesh deletes those with the face).
    edge_holes_.clear();
    auto delete_face = [&](uint32_t f) {
      for (HH h : mesh_.fh_range(FH(int(f)))) edge_holes_.push_back(uint32_t(h.idx() / 2));
      mesh_.delete_face(FH(int(f)), false);
    };
    for (uint32_t f : rewritten_) delete_face(f);
    for (uint32_t f = f1; f < f0; ++f) delete_face(f);
    for (uint32_t v = v1; v < v0; ++v) {
      if (!mesh_.is_isolated(VH(int(v)))) return false;  // (not what the decoder does)
      mesh_.status(VH(int(v))).set_deleted(true);
    }
    std::sort(edge_holes_.begin(), edge_holes_.end());
    edge_holes_.erase(std::unique(edge_holes_.begin(), edge_holes_.end()), edge_holes_.end());
    edge_holes_.erase(std::remove_if(edge_holes_.begin(), edge_holes_.end(),
                                     [&](uint32_t e) {
                                       return !mesh_.status(OpenMesh::EdgeHandle(int(e))).deleted();
                                     }),
                      edge_holes_.end());
    const float* p = d.positions();
    for (uint32_t v = vb; v < std::min(v0, v1); ++v) mesh_.set_point(VH(int(v)), point(p + v * 3));
    for (uint32_t v = v0; v < v1; ++v) mesh_.add_vertex(point(p + size_t(v) * 3));
    // New faces land at their indices; the rewritten ones are added in descending order, so
    // that compacting (which fills the first hole from the last element) moves each into its
    // own hole.
    for (uint32_t f = f0; f < f1; ++f)
      if (!add_face(f)) return false;
    for (size_t i = rewritten_.size(); i-- > 0;)
      if (!add_face(rewritten_[i])) return false;
    compact(v1);
    if (mesh_.n_vertices() != v1 || mesh_.n_faces() != f1) return false;
    for (uint32_t f : rewritten_)
      if (!face_matches(f)) return false;

    // Wedges: [wb, w0) are gone or replaced, [wb, w1) new; a vertex's lowest wedge changes only
    // when it is among them.
    changed_vertices_.clear();
    for (uint32_t w = wb; w < w0; ++w) {
      const uint32_t v = wedge_vertices_[w];
      if (v < v1 && first_wedge_[v] == w) first_wedge_[v] = detail::kNone;
    }
    first_wedge_.resize(v1, detail::kNone);
    wedge_vertices_.resize(wb);
    wedge_vertices_.insert(wedge_vertices_.end(), d.wedge_vertices() + wb, d.wedge_vertices() + w1);
    for (uint32_t w = wb; w < w1; ++w) {
      const uint32_t v = wedge_vertices_[w];
      if (first_wedge_[v] == detail::kNone || w < first_wedge_[v]) {
        first_wedge_[v] = w;
        changed_vertices_.push_back(v);
      }
    }
    if (attributes_) {
      for (uint32_t f : rewritten_) face_attributes(f);
      for (uint32_t f = f0; f < f1; ++f) face_attributes(f);
      for (uint32_t v : changed_vertices_) vertex_attributes(v);
    }
    return true;
  }

  Decoder* decoder_;
  ViewOptions options_;
  Mesh mesh_;
  std::string error_;
  bool built_ = false, attributes_ = false, rebuilt_ = false;
  Layout layout_;
  uint64_t faces_added_ = 0;
  std::vector<uint32_t> wedge_vertices_;  // the decoder's, as of the last update
  std::vector<uint32_t> first_wedge_;     // per vertex: its lowest-numbered wedge (or kNone)
  std::vector<uint32_t> rewritten_, changed_vertices_, edge_holes_;
};

}  // namespace pmz::openmesh
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
