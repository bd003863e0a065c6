// SPDX-License-Identifier: MIT
// The OpenMesh adapter: to_mesh turns a TriMesh's standard properties into wedges, encode gives
// a stream that decodes back to the mesh, and MeshView keeps a TriMesh equal to the decoder's
// arrays (counts, positions, each face's vertices in order, every corner's attributes, each
// face's material as its texture index) through refining, coarsening, face targets and
// streaming, updating incrementally.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>

#include "pmz/openmesh.hpp"
#include "pmz/sample_mesh.hpp"

namespace {

using pmz::openmesh::TriMesh;

// A TriMesh from pmz's indexed mesh (the sample mesh, a corpus file).
template <class Mesh = TriMesh>
Mesh from_indexed(const pmz::IndexedMesh& in) {
  Mesh m;
  for (uint32_t v = 0; v < in.vertex_count(); ++v)
    m.add_vertex(typename Mesh::Point(in.positions[v * 3], in.positions[v * 3 + 1],
                                      in.positions[v * 3 + 2]));
  for (uint32_t f = 0; f < in.face_count(); ++f) {
    const auto fh = m.add_face(OpenMesh::VertexHandle(int(in.indices[f * 3])),
                               OpenMesh::VertexHandle(int(in.indices[f * 3 + 1])),
                               OpenMesh::VertexHandle(int(in.indices[f * 3 + 2])));
    EXPECT_TRUE(fh.is_valid()) << "face " << f;
  }
  return m;
}

// An open (n x n)-quad bumpy grid: boundary edges and vertices.
TriMesh grid(uint32_t n) {
  pmz::IndexedMesh in;
  for (uint32_t j = 0; j <= n; ++j)
    for (uint32_t i = 0; i <= n; ++i)
      in.positions.insert(in.positions.end(),
                          {float(i), float(j), float(std::sin(i * 0.7) * std::cos(j * 0.5))});
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      in.indices.insert(in.indices.end(), {a, b, d, a, d, c});
    }
  return from_indexed(in);
}

// The colour a decoded float value gives in the mesh's colour type.
template <class Color>
Color expected_color(const float* c, uint32_t n) {
  Color out;
  using S = std::decay_t<decltype(out[0])>;
  for (int k = 0; k < int(pmz::openmesh::detail::color_size<Color>()); ++k) {
    const float x = uint32_t(k) < n ? c[k] : 1.0f;
    if constexpr (std::is_integral_v<S>)
      out[k] = S(std::lround(x * 255));
    else
      out[k] = S(x);
  }
  return out;
}

// Creased normals (halfedge normals with OpenMesh's feature angle, and vertex normals),
// texture charts by the face's dominant axis (halfedge texcoords: seams where charts meet) and
// colours by position (vertex colours): every attribute kind, with wedges.
template <class Mesh>
void add_attributes(Mesh& m) {
  m.request_face_normals();
  m.request_vertex_normals();
  m.request_halfedge_normals();
  m.update_normals();
  m.request_halfedge_texcoords2D();
  m.request_vertex_colors();
  typename Mesh::Point lo = m.point(*m.vertices_begin()), hi = lo;
  for (auto v : m.vertices()) {
    lo.minimize(m.point(v));
    hi.maximize(m.point(v));
  }
  for (auto f : m.faces()) {
    const auto n = m.normal(f);
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (std::abs(n[k]) > std::abs(n[axis])) axis = k;
    for (auto h : m.fh_range(f)) {
      const auto p = m.point(m.to_vertex_handle(h));
      m.set_texcoord2D(h, typename Mesh::TexCoord2D(float(p[(axis + 1) % 3]) + float(axis),
                                                    float(p[(axis + 2) % 3])));
    }
  }
  for (auto v : m.vertices()) {
    const auto p = m.point(v);
    float c[4];
    for (int k = 0; k < 3; ++k) c[k] = float((p[k] - lo[k]) / (hi[k] - lo[k]));
    c[3] = 0.5f;
    m.set_color(v, expected_color<typename Mesh::Color>(c, 4));
  }
}

pmz::openmesh::EncodeOptions lossless() {
  pmz::openmesh::EncodeOptions o;
  o.write.position_bits = o.write.texcoord_bits = o.write.normal_bits = o.write.color_bits = 0;
  return o;
}

// mesh() is exactly the decoder's current mesh.
template <class Mesh>
void expect_matches(const pmz::openmesh::MeshView<Mesh>& view, const pmz::Decoder& d,
                    const std::string& where, bool vertex_properties = true) {
  SCOPED_TRACE(where);
  const Mesh& m = view.mesh();
  ASSERT_EQ(view.error(), "");
  ASSERT_EQ(m.n_vertices(), d.vertex_count());
  ASSERT_EQ(m.n_faces(), d.face_count());
  for (uint32_t v = 0; v < d.vertex_count(); ++v)
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(m.point(OpenMesh::VertexHandle(int(v)))[k], d.positions()[v * 3 + k])
          << "vertex " << v;
  std::set<std::pair<uint32_t, uint32_t>> edges;
  for (uint32_t f = 0; f < d.face_count(); ++f) {
    const OpenMesh::FaceHandle fh{int(f)};
    ASSERT_FALSE(m.status(fh).deleted());
    int k = 0;
    for (auto vh : m.fv_range(fh)) {
      ASSERT_LT(k, 3);
      ASSERT_EQ(uint32_t(vh.idx()), d.indices()[f * 3 + k]) << "face " << f << " corner " << k;
      ++k;
    }
    ASSERT_EQ(k, 3);
    for (k = 0; k < 3; ++k) {
      const uint32_t a = d.indices()[f * 3 + k], b = d.indices()[f * 3 + (k + 1) % 3];
      edges.insert({std::min(a, b), std::max(a, b)});
    }
  }
  ASSERT_EQ(m.n_edges(), edges.size());
  // Materials: each face's texture index.
  const uint32_t* materials = d.face_materials();
  ASSERT_EQ(m.has_face_texture_index(), materials != nullptr);
  for (uint32_t f = 0; materials && f < d.face_count(); ++f)
    ASSERT_EQ(m.texture_index(OpenMesh::FaceHandle(int(f))), int(materials[f])) << "face " << f;
  // OpenMesh's own links agree: next / prev, opposite, faces' and vertices' halfedges, and no
  // element left deleted.
  for (auto h : m.halfedges()) {
    ASSERT_FALSE(m.status(h.edge()).deleted());
    ASSERT_EQ(m.prev_halfedge_handle(m.next_halfedge_handle(h)), h);
    ASSERT_EQ(m.to_vertex_handle(h), m.from_vertex_handle(m.next_halfedge_handle(h)));
    ASSERT_EQ(m.face_handle(h), m.face_handle(m.next_halfedge_handle(h)));
    ASSERT_NE(m.to_vertex_handle(h), m.to_vertex_handle(m.opposite_halfedge_handle(h)));
    ASSERT_FALSE(m.is_boundary(h) && m.is_boundary(m.opposite_halfedge_handle(h)));
  }
  for (auto f : m.faces()) ASSERT_EQ(m.face_handle(m.halfedge_handle(f)), f);
  for (auto v : m.vertices()) {
    ASSERT_FALSE(m.status(v).deleted());
    if (!m.is_isolated(v)) {
      ASSERT_EQ(m.from_vertex_handle(m.halfedge_handle(v)), v);
      // OpenMesh keeps a boundary vertex's halfedge on the boundary.
      bool boundary = false;
      for (auto h : m.voh_range(v)) boundary = boundary || m.is_boundary(h);
      ASSERT_EQ(m.is_boundary(m.halfedge_handle(v)), boundary) << "vertex " << v.idx();
    }
  }
  if (d.wedge_count() == 0) {
    EXPECT_FALSE(m.has_halfedge_normals() || m.has_halfedge_texcoords2D() ||
                 m.has_halfedge_colors());
    return;
  }
  const float* normals = d.normals();
  const float* tex = d.texcoords(0);
  const float* colors = d.colors();
  const uint32_t cn = d.color_components();
  using Color = typename Mesh::Color;
  ASSERT_EQ(m.has_halfedge_normals(), normals != nullptr);
  ASSERT_EQ(m.has_halfedge_texcoords2D(), tex != nullptr);
  ASSERT_EQ(m.has_halfedge_colors(), colors != nullptr);
  for (uint32_t f = 0; f < d.face_count(); ++f) {
    auto h = m.halfedge_handle(OpenMesh::FaceHandle(int(f)));
    for (int k = 0; k < 3; ++k, h = m.next_halfedge_handle(h)) {
      const uint32_t w = d.wedge_indices()[f * 3 + k];
      for (int c = 0; normals && c < 3; ++c)
        ASSERT_EQ(m.normal(h)[c], normals[w * 3 + c]) << "face " << f << " corner " << k;
      for (int c = 0; tex && c < 2; ++c)
        ASSERT_EQ(m.texcoord2D(h)[c], tex[w * 2 + c]) << "face " << f << " corner " << k;
      if (colors) {
        ASSERT_EQ(m.color(h), expected_color<Color>(colors + w * cn, cn))
            << "face " << f << " corner " << k;
      }
    }
  }
  // Vertex properties: the vertex's lowest-numbered wedge.
  ASSERT_EQ(m.has_vertex_normals(), vertex_properties && normals);
  ASSERT_EQ(m.has_vertex_texcoords2D(), vertex_properties && tex);
  ASSERT_EQ(m.has_vertex_colors(), vertex_properties && colors);
  if (!vertex_properties) return;
  std::vector<uint32_t> lowest(d.vertex_count(), UINT32_MAX);
  for (uint32_t w = d.wedge_count(); w-- > 0;) lowest[d.wedge_vertices()[w]] = w;
  for (uint32_t v = 0; v < d.vertex_count(); ++v) {
    const uint32_t w = lowest[v];
    if (w == UINT32_MAX) continue;
    const OpenMesh::VertexHandle vh{int(v)};
    for (int c = 0; normals && c < 3; ++c) ASSERT_EQ(m.normal(vh)[c], normals[w * 3 + c]);
    for (int c = 0; tex && c < 2; ++c) ASSERT_EQ(m.texcoord2D(vh)[c], tex[w * 2 + c]);
    if (colors) {
      ASSERT_EQ(m.color(vh), expected_color<Color>(colors + w * cn, cn));
    }
  }
}

// The full decode against the encoded TriMesh (lossless): positions, faces and every corner's
// normal, texture coordinates and colour.
void expect_original(const TriMesh& decoded, const TriMesh& in, const std::vector<uint32_t>& order,
                     bool wedges = true) {
  ASSERT_EQ(decoded.n_vertices(), in.n_vertices());
  ASSERT_EQ(decoded.n_faces(), in.n_faces());
  for (auto v : decoded.vertices())
    ASSERT_EQ(decoded.point(v), in.point(OpenMesh::VertexHandle(int(order[v.idx()]))));
  std::map<std::array<int, 3>, OpenMesh::FaceHandle> faces;
  auto key = [](std::array<int, 3> t) {
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    return t;
  };
  for (auto f : in.faces()) {
    std::array<int, 3> t;
    int k = 0;
    for (auto v : in.fv_range(f)) t[k++] = v.idx();
    faces[key(t)] = f;
  }
  for (auto f : decoded.faces()) {
    std::array<int, 3> t;
    int k = 0;
    for (auto v : decoded.fv_range(f)) t[k++] = int(order[v.idx()]);
    const auto it = faces.find(key(t));
    ASSERT_NE(it, faces.end()) << "decoded face " << f.idx();
    if (in.has_face_texture_index()) {
      ASSERT_EQ(decoded.texture_index(f), in.texture_index(it->second)) << "face " << f.idx();
    }
    if (!wedges) continue;
    for (auto h : decoded.fh_range(f)) {
      const int want = int(order[decoded.to_vertex_handle(h).idx()]);
      auto g = in.halfedge_handle(it->second);
      while (in.to_vertex_handle(g).idx() != want) g = in.next_halfedge_handle(g);
      ASSERT_EQ(decoded.normal(h), in.normal(g));
      ASSERT_EQ(decoded.texcoord2D(h), in.texcoord2D(g));
      ASSERT_EQ(decoded.color(h), in.color(in.to_vertex_handle(g)));
    }
  }
}

struct Stream {
  std::vector<uint8_t> bytes;
  std::vector<uint32_t> order;
};

template <class Mesh>
Stream encode(const Mesh& m, pmz::openmesh::EncodeOptions options = lossless()) {
  Stream s;
  std::string error;
  options.vertex_order = &s.order;
  EXPECT_TRUE(pmz::openmesh::encode(m, s.bytes, error, options)) << error;
  return s;
}

TEST(OpenMeshToMesh, CornersShareWedgesOnlyWithEqualValues) {
  TriMesh m = grid(4);
  m.request_halfedge_texcoords2D();
  m.request_vertex_colors();
  // Texture coordinates by position, except that faces right of x = 2 are shifted: the
  // vertices on x = 2 have two wedges, the rest one.
  for (auto f : m.faces()) {
    float cx = 0;
    for (auto v : m.fv_range(f)) cx += m.point(v)[0] / 3;
    for (auto h : m.fh_range(f)) {
      const auto p = m.point(m.to_vertex_handle(h));
      m.set_texcoord2D(h, TriMesh::TexCoord2D(p[0] + (cx > 2 ? 10.f : 0.f), p[1]));
    }
  }
  for (auto v : m.vertices()) m.set_color(v, TriMesh::Color(255, 0, uint8_t(v.idx())));
  pmz::IndexedMesh out;
  std::string error;
  ASSERT_TRUE(pmz::openmesh::to_mesh(m, out, error)) << error;
  ASSERT_EQ(out.vertex_count(), 25u);
  ASSERT_EQ(out.face_count(), 32u);
  const pmz::MeshAttributes& a = out.attributes;
  EXPECT_EQ(a.wedge_count(), 25u + 5u);  // the five vertices on x = 2 twice
  EXPECT_TRUE(a.normals.empty());
  ASSERT_EQ(a.texcoords.size(), 1u);
  ASSERT_EQ(a.color_components, 3u);
  ASSERT_EQ(a.corner_wedges.size(), 96u);
  uint32_t c = 0;
  for (auto f : m.faces())
    for (auto h : m.fh_range(f)) {
      const uint32_t w = a.corner_wedges[c], v = out.indices[c];
      ++c;
      ASSERT_EQ(v, uint32_t(m.to_vertex_handle(h).idx()));
      ASSERT_EQ(a.wedge_vertices[w], v);
      EXPECT_EQ(a.texcoords[0][w * 2], m.texcoord2D(h)[0]);
      EXPECT_EQ(a.texcoords[0][w * 2 + 1], m.texcoord2D(h)[1]);
      EXPECT_EQ(a.colors[w * 3], 1.0f);
      EXPECT_EQ(a.colors[w * 3 + 2], float(v) / 255);
    }

  // Other sources; a missing one is refused.
  pmz::openmesh::ConvertOptions only_colors;
  only_colors.texcoords = pmz::openmesh::Source::none;
  ASSERT_TRUE(pmz::openmesh::to_mesh(m, out, error, only_colors));
  EXPECT_EQ(out.attributes.wedge_count(), 25u);
  EXPECT_TRUE(out.attributes.texcoords.empty());
  pmz::openmesh::ConvertOptions vertex_normals;
  vertex_normals.normals = pmz::openmesh::Source::vertex;
  EXPECT_FALSE(pmz::openmesh::to_mesh(m, out, error, vertex_normals));
  EXPECT_NE(error.find("normals requested from vertex properties"), std::string::npos) << error;
  pmz::openmesh::ConvertOptions face_tex;
  face_tex.texcoords = pmz::openmesh::Source::face;
  EXPECT_FALSE(pmz::openmesh::to_mesh(m, out, error, face_tex));
  pmz::openmesh::ConvertOptions none;
  none.texcoords = none.colors = pmz::openmesh::Source::none;
  ASSERT_TRUE(pmz::openmesh::to_mesh(m, out, error, none));
  EXPECT_TRUE(out.attributes.empty());
  EXPECT_TRUE(out.attributes.corner_wedges.empty());
}

TEST(OpenMeshToMesh, FaceColoursAndDeletedElements) {
  TriMesh m = grid(3);
  m.request_face_colors();
  m.request_face_status();
  m.request_edge_status();
  m.request_vertex_status();
  for (auto f : m.faces()) m.set_color(f, TriMesh::Color(uint8_t(f.idx() * 10), 255, 0));
  // Deleting the corner vertex 0 deletes its face; the rest keep their order.
  m.delete_vertex(OpenMesh::VertexHandle(0));
  pmz::IndexedMesh out;
  std::string error;
  ASSERT_TRUE(pmz::openmesh::to_mesh(m, out, error)) << error;
  ASSERT_EQ(out.vertex_count(), 15u);
  ASSERT_EQ(out.face_count(), 16u);
  uint32_t c = 0;
  for (auto f : m.faces())
    for (auto v : m.fv_range(f)) {
      EXPECT_EQ(out.indices[c], uint32_t(v.idx() - 1));
      const uint32_t w = out.attributes.corner_wedges[c++];
      EXPECT_EQ(out.attributes.colors[w * 3], float(f.idx() * 10) / 255);
    }
}

TEST(OpenMeshView, FollowsRefineCoarsenAndFaceTargets) {
  const TriMesh in = [] {
    TriMesh m = from_indexed(pmz::make_sample_mesh(6000));
    add_attributes(m);
    return m;
  }();
  const Stream s = encode(in);
  pmz::Decoder d;
  ASSERT_EQ(d.feed(s.bytes.data(), s.bytes.size()), pmz::Status::ok) << d.error_message();
  pmz::openmesh::MeshView<> view(d);
  ASSERT_TRUE(view.update());
  expect_matches(view, d, "base");
  ASSERT_GT(d.wedge_count(), d.vertex_count());  // creases and chart seams
  const uint64_t total = d.info().total_splits;
  ASSERT_GT(total, 1000u);

  for (uint64_t step : {1u, 1u, 2u, 5u, 30u}) {
    view.refine(step);
    expect_matches(view, d, "refine " + std::to_string(step));
  }
  view.refine(total / 2);
  expect_matches(view, d, "refine to the middle");
  // Small steps are incremental: about the faces of the splits, not the mesh.
  for (uint64_t step : {1u, 2u, 5u, 30u}) {
    view.refine(step);
    expect_matches(view, d, "refine " + std::to_string(step));
    EXPECT_FALSE(view.last_rebuilt());
    EXPECT_LE(view.last_faces_added(), 40 * step);
  }
  for (uint64_t step : {1u, 3u, 40u}) {
    view.coarsen(step);
    expect_matches(view, d, "coarsen " + std::to_string(step));
    EXPECT_FALSE(view.last_rebuilt());
    EXPECT_LE(view.last_faces_added(), 40 * step);
  }
  for (uint64_t faces :
       {d.info().full_faces / 3, d.info().full_faces * 2 / 3, uint64_t(10), d.info().full_faces}) {
    view.set_face_target(faces);
    expect_matches(view, d, "face target " + std::to_string(faces));
  }
  ASSERT_EQ(d.splits_applied(), total);
  expect_original(view.mesh(), in, s.order);

  // Several calls between updates: the change report accumulates.
  d.coarsen(500);
  d.refine(120);
  d.coarsen(7);
  ASSERT_TRUE(view.update());
  expect_matches(view, d, "coarsen, refine, coarsen, one update");
  d.refine(30);
  d.coarsen(200);
  d.refine(250);
  ASSERT_TRUE(view.update());
  expect_matches(view, d, "refine, coarsen, refine, one update");
  view.coarsen();
  expect_matches(view, d, "base again");
  view.refine();
  expect_matches(view, d, "full again");
  expect_original(view.mesh(), in, s.order);
}

TEST(OpenMeshView, FollowsTheStreamAsItArrives) {
  TriMesh in = grid(40);  // boundary splits
  add_attributes(in);
  const Stream s = encode(in);
  pmz::Decoder d;
  pmz::openmesh::ViewOptions incremental_only;  // (however large the step)
  incremental_only.rebuild_fraction = 1e9;
  pmz::openmesh::MeshView<> view(d, incremental_only);
  size_t at = 0, updates = 0;
  while (at < s.bytes.size()) {
    const size_t n = std::min<size_t>(1500, s.bytes.size() - at);
    ASSERT_EQ(d.feed(s.bytes.data() + at, n), pmz::Status::ok) << d.error_message();
    at += n;
    view.refine();
    expect_matches(view, d, "after " + std::to_string(at) + " bytes");
    ++updates;
  }
  ASSERT_EQ(d.finish(), pmz::Status::ok);
  ASSERT_GT(updates, 3u);
  ASSERT_EQ(d.face_count(), in.n_faces());
  expect_original(view.mesh(), in, s.order);
  // Random walk over the levels, one incremental update each.
  std::srand(7);
  int incremental = 0;
  for (int i = 0; i < 60; ++i) {
    const uint64_t n = uint64_t(std::rand() % 200);
    if (std::rand() % 2)
      view.refine(n);
    else
      view.coarsen(n);
    expect_matches(view, d, "walk step " + std::to_string(i));
    incremental += !view.last_rebuilt();
  }
  EXPECT_EQ(incremental, 60);
}

// Double-precision points and normals, float RGBA colours, halfedge and face colours only.
struct DoubleTraits : OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
  typedef OpenMesh::Vec3d Normal;
  typedef OpenMesh::Vec2d TexCoord2D;
  typedef OpenMesh::Vec4f Color;
};
using DoubleMesh = OpenMesh::TriMesh_ArrayKernelT<DoubleTraits>;

TEST(OpenMeshView, OtherScalarTypesAndFaceColours) {
  pmz::IndexedMesh sample = pmz::make_sample_mesh(2000);
  DoubleMesh in = from_indexed<DoubleMesh>(sample);
  add_attributes(in);
  const Stream s = encode(in);
  pmz::Decoder d;
  ASSERT_EQ(d.feed(s.bytes.data(), s.bytes.size()), pmz::Status::ok);
  ASSERT_EQ(d.color_components(), 4u);
  pmz::openmesh::ViewOptions options;
  options.vertex_attributes = false;
  options.face_colors = true;
  pmz::openmesh::MeshView<DoubleMesh> view(d, options);
  ASSERT_TRUE(view.update());
  EXPECT_FALSE(view.mesh().has_vertex_normals());
  ASSERT_TRUE(view.mesh().has_face_colors());
  for (uint64_t step : {3u, 300u, 10000u}) {
    view.refine(step);
    expect_matches(view, d, "refine " + std::to_string(step), false);
    for (uint32_t f = 0; f < d.face_count(); ++f)
      ASSERT_EQ(view.mesh().color(OpenMesh::FaceHandle(int(f))),
                expected_color<DoubleMesh::Color>(d.colors() + d.wedge_indices()[f * 3] * 4, 4));
  }
  view.coarsen(100);
  expect_matches(view, d, "coarsen 100", false);
}

TEST(OpenMeshView, GeometryOnly) {
  const TriMesh in = grid(30);
  const Stream s = encode(in, {});
  pmz::Decoder d;
  ASSERT_EQ(d.feed(s.bytes.data(), s.bytes.size()), pmz::Status::ok);
  pmz::openmesh::MeshView<> view(d);
  for (uint64_t faces : {uint64_t(0), uint64_t(500), uint64_t(100), uint64_t(2000)}) {
    view.set_face_target(faces);
    expect_matches(view, d, "face target " + std::to_string(faces));
  }
  EXPECT_FALSE(view.mesh().has_vertex_normals());
}

// A real scan with holes (boundaries at every level), if the corpus is there.
TEST(OpenMeshView, CorpusMeshWithHoles) {
  const char* env = std::getenv("PMZ_CORPUS");
  const std::string path = std::string(env ? env : "") + "/elephant-with-holes.off";
  if (!env || !std::filesystem::exists(path)) GTEST_SKIP() << "no corpus (set PMZ_CORPUS)";
  pmz::IndexedMesh indexed;
  pmz::MeshRepairStats stats;
  std::string error;
  ASSERT_TRUE(pmz::read_mesh(path, indexed, stats, error)) << error;
  TriMesh in = from_indexed(indexed);
  add_attributes(in);
  const Stream s = encode(in);
  pmz::Decoder d;
  ASSERT_EQ(d.feed(s.bytes.data(), s.bytes.size()), pmz::Status::ok);
  pmz::openmesh::MeshView<> view(d);
  ASSERT_TRUE(view.update());
  expect_matches(view, d, "base");
  for (int i = 0; i < 12; ++i) {
    view.refine(uint64_t(1) << i);
    expect_matches(view, d, "refine " + std::to_string(1 << i));
  }
  view.refine();
  expect_matches(view, d, "full");
  expect_original(view.mesh(), in, s.order);
  for (int i = 0; i < 12; ++i) {
    view.coarsen(uint64_t(1) << i);
    expect_matches(view, d, "coarsen " + std::to_string(1 << i));
  }
}

// Two materials as face texture indices (with "TextureMapping", as OpenMesh's OBJ reader sets
// them): the stream carries them as materials, and the view gives every face the decoded
// material as its texture index at every level, and the texture file names back.
TEST(OpenMeshView, MaterialsAsFaceTextureIndices) {
  for (const bool wedges : {true, false}) {
    SCOPED_TRACE(wedges ? "with attributes" : "materials only");
    TriMesh in = from_indexed(pmz::make_sample_mesh(6000));
    if (wedges) add_attributes(in);
    in.request_face_texture_index();
    for (auto f : in.faces()) {  // the faces right of x = 0 are metal, the others paint
      float cx = 0;
      for (auto v : in.fv_range(f)) cx += in.point(v)[0] / 3;
      in.set_texture_index(f, cx > 0 ? 1 : 0);
    }
    OpenMesh::MPropHandleT<std::map<int, std::string>> mapping;
    in.add_property(mapping, "TextureMapping");
    in.property(mapping) = {{0, "paint.png"}, {1, "metal.png"}};

    pmz::IndexedMesh indexed;
    std::string error;
    ASSERT_TRUE(pmz::openmesh::to_mesh(in, indexed, error)) << error;
    const pmz::MeshAttributes& a = indexed.attributes;
    ASSERT_EQ(a.materials.size(), 2u);
    EXPECT_EQ(a.materials[0].name, "texture0");
    EXPECT_EQ(a.materials[1].base_color_texture, "metal.png");
    ASSERT_EQ(a.face_materials.size(), in.n_faces());
    for (auto f : in.faces())
      ASSERT_EQ(a.face_materials[size_t(f.idx())], uint32_t(in.texture_index(f)));

    const Stream s = encode(in);
    pmz::Decoder d;
    ASSERT_EQ(d.feed(s.bytes.data(), s.bytes.size()), pmz::Status::ok) << d.error_message();
    ASSERT_EQ(d.material_count(), 2u);
    EXPECT_EQ(d.material(0)->base_color_texture, "paint.png");
    pmz::openmesh::MeshView<> view(d);
    ASSERT_TRUE(view.update());
    expect_matches(view, d, "base");
    ASSERT_TRUE(view.mesh().has_face_texture_index());
    std::set<int> seen;
    for (auto f : view.mesh().faces()) seen.insert(view.mesh().texture_index(f));
    EXPECT_EQ(seen, (std::set<int>{0, 1}));
    OpenMesh::MPropHandleT<std::map<int, std::string>> out;
    ASSERT_TRUE(view.mesh().get_property_handle(out, "TextureMapping"));
    EXPECT_EQ(view.mesh().property(out), in.property(mapping));

    const uint64_t total = d.info().total_splits;
    view.refine(total / 2);
    expect_matches(view, d, "refine to the middle");
    for (uint64_t step : {1u, 7u, 100u}) {  // incremental: the change report's faces
      view.refine(step);
      expect_matches(view, d, "refine " + std::to_string(step));
      EXPECT_FALSE(view.last_rebuilt());
    }
    for (uint64_t step : {1u, 3u, 60u}) {
      view.coarsen(step);
      expect_matches(view, d, "coarsen " + std::to_string(step));
      EXPECT_FALSE(view.last_rebuilt());
    }
    for (uint64_t faces : {d.info().full_faces / 4, d.info().full_faces * 3 / 5, uint64_t(50),
                           d.info().full_faces}) {
      view.set_face_target(faces);
      expect_matches(view, d, "face target " + std::to_string(faces));
    }
    // Several calls between updates (coarsening < 0, refining > 0), then the full mesh: the
    // input's materials.
    for (const auto& calls : {std::vector<int>{-400, 150, -9}, std::vector<int>{30, -200, 250}}) {
      for (int n : calls) n < 0 ? d.coarsen(uint64_t(-n)) : d.refine(uint64_t(n));
      ASSERT_TRUE(view.update());
      expect_matches(view, d, "several calls, one update");
    }
    view.refine();
    expect_matches(view, d, "full");
    expect_original(view.mesh(), in, s.order, wedges);
  }
}

// A stream with materials from an OBJ file (the seamed-q conformance vector: two materials
// with map_Kd textures): texture indices and "TextureMapping" through level moves.
TEST(OpenMeshView, MaterialsOfAStreamFromObj) {
  std::ifstream file(PMZ_SOURCE_DIR "/tests/conformance/vectors/seamed-q.pmz", std::ios::binary);
  const std::vector<uint8_t> bytes{std::istreambuf_iterator<char>(file), {}};
  ASSERT_FALSE(bytes.empty());
  pmz::Decoder d;
  ASSERT_EQ(d.feed(bytes.data(), bytes.size()), pmz::Status::ok) << d.error_message();
  ASSERT_EQ(d.material_count(), 2u);
  pmz::openmesh::MeshView<> view(d);
  ASSERT_TRUE(view.update());
  expect_matches(view, d, "base");
  OpenMesh::MPropHandleT<std::map<int, std::string>> mapping;
  ASSERT_TRUE(view.mesh().get_property_handle(mapping, "TextureMapping"));
  EXPECT_EQ(view.mesh().property(mapping),
            (std::map<int, std::string>{{0, "paint.png"}, {1, "metal.png"}}));
  for (uint64_t step : {1u, 20u, 200u}) {
    view.refine(step);
    expect_matches(view, d, "refine " + std::to_string(step));
  }
  view.coarsen(50);
  expect_matches(view, d, "coarsen 50");
  view.set_face_target(d.info().full_faces);
  expect_matches(view, d, "full");
  view.set_face_target(d.info().full_faces / 3);
  expect_matches(view, d, "a third");
  pmz::openmesh::ViewOptions no_materials;
  no_materials.materials = false;
  pmz::openmesh::MeshView<> plain(d, no_materials);
  ASSERT_TRUE(plain.update());
  EXPECT_FALSE(plain.mesh().has_face_texture_index());
}

TEST(OpenMeshToMesh, TextureIndicesOutOfRangeOrLeftOut) {
  TriMesh m = grid(2);
  m.request_face_texture_index();
  for (auto f : m.faces()) m.set_texture_index(f, 4);
  pmz::IndexedMesh out;
  std::string error;
  ASSERT_TRUE(pmz::openmesh::to_mesh(m, out, error)) << error;
  EXPECT_EQ(out.attributes.materials.size(), 5u);  // indices 0..4, one used
  EXPECT_EQ(out.attributes.face_materials, std::vector<uint32_t>(8, 4));
  pmz::openmesh::ConvertOptions none;
  none.materials = false;
  ASSERT_TRUE(pmz::openmesh::to_mesh(m, out, error, none)) << error;
  EXPECT_TRUE(out.attributes.empty());
  m.set_texture_index(OpenMesh::FaceHandle(3), -1);
  EXPECT_FALSE(pmz::openmesh::to_mesh(m, out, error));
  EXPECT_EQ(error, "pmz::openmesh::to_mesh: face 3 has texture index -1, outside 0..65535");
  m.set_texture_index(OpenMesh::FaceHandle(3), 65536);
  EXPECT_FALSE(pmz::openmesh::to_mesh(m, out, error));
}

}  // namespace
