// SPDX-License-Identifier: MIT
// Attribute wedges through writer and decoder (format 8.0, spec/format.md section 14): the full
// decode gives every corner its input values (exactly in lossless mode, within half a step
// quantized) and its face's material; every level is a consistent wedge mesh; coarsening and
// refining again restore the same arrays; any slicing of the stream gives the same result.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>

#include "pmz/decoder.hpp"
#include "pmz/mesh.hpp"
#include "pmz/simplify.hpp"
#include "pmz/writer.hpp"
#include "seamed_grid.hpp"

namespace {

using Face = std::array<uint32_t, 3>;
Face canonical(uint32_t a, uint32_t b, uint32_t c) {
  if (b < a && b < c) return {b, c, a};
  if (c < a && c < b) return {c, a, b};
  return {a, b, c};
}

struct Encoded {
  pmz::CollapseSequence seq;
  std::vector<uint8_t> bytes;
  std::vector<uint32_t> order;  // decoded vertex -> input vertex
};

void encode(const pmz::IndexedMesh& mesh, const pmz::WriteOptions& opt, Encoded& e) {
  std::string error;
  ASSERT_TRUE(pmz::simplify(mesh, {}, e.seq, error)) << error;
  ASSERT_TRUE(pmz::write_pmz(e.seq, opt, e.bytes, error)) << error;
  e.order = pmz::decoded_vertex_order(e.seq, opt);
}

// Encoded lossless (every attribute's bits 0) or with the defaults, then fully decoded.
void encode_and_decode(const pmz::IndexedMesh& mesh, bool lossless, Encoded& e, pmz::Decoder& d) {
  pmz::WriteOptions opt;
  if (lossless) opt.position_bits = opt.texcoord_bits = opt.normal_bits = opt.color_bits = 0;
  encode(mesh, opt, e);
  ASSERT_EQ(d.feed(e.bytes.data(), e.bytes.size()), pmz::Status::ok) << d.error_message();
  d.refine();
}

// Every live corner names a wedge of its own vertex; wedge positions are their vertices'.
void expect_consistent(const pmz::Decoder& d) {
  const uint32_t w = d.wedge_count();
  ASSERT_GT(w, 0u);
  for (uint32_t c = 0; c < d.face_count() * 3; ++c) {
    ASSERT_LT(d.wedge_indices()[c], w) << "corner " << c;
    ASSERT_EQ(d.wedge_vertices()[d.wedge_indices()[c]], d.indices()[c]) << "corner " << c;
  }
  for (uint32_t i = 0; i < w; ++i)
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(d.wedge_positions()[i * 3 + k], d.positions()[d.wedge_vertices()[i] * 3 + k]);
}

// The full decode against the input, corner by corner. tolerance: per attribute, the largest
// difference allowed (0: bit-exact).
void expect_full(const pmz::Decoder& d, const Encoded& e, float tex_tol, float normal_tol,
                 float color_tol) {
  const pmz::IndexedMesh& in = e.seq.mesh;
  const pmz::MeshAttributes& a = in.attributes;
  ASSERT_EQ(d.face_count(), in.face_count());
  std::map<Face, uint32_t> input_face;
  for (uint32_t f = 0; f < in.face_count(); ++f)
    input_face[canonical(in.indices[f * 3], in.indices[f * 3 + 1], in.indices[f * 3 + 2])] = f;
  auto close = [](float got, float want, float tol) {
    return tol == 0 ? std::memcmp(&got, &want, 4) == 0 : std::fabs(got - want) <= tol;
  };
  for (uint32_t f = 0; f < d.face_count(); ++f) {
    uint32_t t[3];
    for (int k = 0; k < 3; ++k) t[k] = e.order[d.indices()[f * 3 + k]];
    const auto it = input_face.find(canonical(t[0], t[1], t[2]));
    ASSERT_NE(it, input_face.end()) << "face " << f;
    const uint32_t slot = it->second;
    if (!a.face_materials.empty()) {
      ASSERT_NE(d.face_materials(), nullptr);
      EXPECT_EQ(d.face_materials()[f], a.face_materials[slot]) << "face " << f;
    }
    for (int k = 0; k < 3; ++k) {
      int j = 0;
      while (in.indices[slot * 3 + j] != t[k]) ++j;
      const uint32_t iw = a.corner_wedges[slot * 3 + j], dw = d.wedge_indices()[f * 3 + k];
      for (uint32_t s = 0; s < a.texcoords.size(); ++s)
        for (int x = 0; x < 2; ++x)
          ASSERT_TRUE(close(d.texcoords(s)[dw * 2 + x], a.texcoords[s][iw * 2 + x], tex_tol))
              << "face " << f << " corner " << k << " set " << s << ": "
              << d.texcoords(s)[dw * 2 + x] << " vs " << a.texcoords[s][iw * 2 + x];
      if (!a.normals.empty()) {
        // Quantized normals come back unit length; lossless ones as stored.
        const float* n = &a.normals[iw * 3];
        const float len =
            normal_tol == 0 ? 1.f : std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int x = 0; x < 3 && len > 0; ++x)
          ASSERT_TRUE(close(d.normals()[dw * 3 + x], n[x] / len, normal_tol))
              << "face " << f << " corner " << k << " normal " << x;
      }
      const uint32_t cc = a.color_components;
      for (uint32_t x = 0; x < cc && !a.colors.empty(); ++x)
        ASSERT_TRUE(close(d.colors()[dw * cc + x], a.colors[iw * cc + x], color_tol))
            << "face " << f << " corner " << k << " colour " << x;
    }
  }
}

struct Arrays {
  std::vector<uint32_t> wedge_indices, wedge_vertices, materials;
  std::vector<float> texcoords, normals, colors;
  bool operator==(const Arrays&) const = default;
};
Arrays arrays(const pmz::Decoder& d) {
  Arrays r;
  const uint32_t w = d.wedge_count(), f = d.face_count();
  r.wedge_indices.assign(d.wedge_indices(), d.wedge_indices() + f * 3);
  r.wedge_vertices.assign(d.wedge_vertices(), d.wedge_vertices() + w);
  if (d.face_materials()) r.materials.assign(d.face_materials(), d.face_materials() + f);
  if (d.texcoord_set_count()) r.texcoords.assign(d.texcoords(0), d.texcoords(0) + w * 2);
  if (d.normals()) r.normals.assign(d.normals(), d.normals() + w * 3);
  if (d.colors()) r.colors.assign(d.colors(), d.colors() + w * d.color_components());
  return r;
}

TEST(AttrRoundTrip, SeamedGridLossless) {
  const pmz::IndexedMesh mesh = pmz_test::seamed_grid(12, 5);
  pmz::WriteOptions opt;
  opt.position_bits = 0;
  opt.texcoord_bits = opt.normal_bits = opt.color_bits = 0;
  Encoded e;
  encode(mesh, opt, e);
  pmz::Decoder d;
  ASSERT_EQ(d.feed(e.bytes.data(), e.bytes.size()), pmz::Status::ok) << d.error_message();
  ASSERT_EQ(d.finish(), pmz::Status::ok);
  EXPECT_EQ(d.info().flags, 1u);
  ASSERT_EQ(d.material_count(), 2u);
  EXPECT_EQ(d.material(0)->name, "left");
  EXPECT_EQ(d.material(1)->name, "right");
  EXPECT_EQ(d.material(2), nullptr);
  expect_consistent(d);
  d.refine();
  expect_consistent(d);
  expect_full(d, e, 0, 0, 0);
}

TEST(AttrRoundTrip, SeamedGridQuantizedEveryLevel) {
  const pmz::IndexedMesh mesh = pmz_test::seamed_grid(16, 7);
  Encoded e;
  encode(mesh, {}, e);
  pmz::Decoder d;
  ASSERT_EQ(d.feed(e.bytes.data(), e.bytes.size()), pmz::Status::ok) << d.error_message();
  ASSERT_EQ(d.finish(), pmz::Status::ok);
  // Every level once while refining, then down and up again: the same arrays.
  std::vector<Arrays> levels{arrays(d)};
  expect_consistent(d);
  while (d.refine(1) == 1) {
    expect_consistent(d);
    levels.push_back(arrays(d));
  }
  // Texture coordinates over a 1.0 extent (v) at 12 bits, colours at 8 bits over [0, 1], normals
  // at 10 bits octahedral (a step of 2/1023 in x and y, under 0.005 on the sphere).
  expect_full(d, e, 1.f / 4095 * 0.51f, 0.005f, 1.f / 255 * 0.51f);
  for (size_t l = levels.size() - 1; l-- > 0;) {
    ASSERT_EQ(d.coarsen(1), 1u);
    ASSERT_TRUE(arrays(d) == levels[l]) << "level " << l << " after coarsening";
  }
  d.set_split_target(levels.size() - 1);
  ASSERT_TRUE(arrays(d) == levels.back());
  // Sliced feeding: the same full mesh.
  pmz::Decoder sliced;
  for (size_t i = 0; i < e.bytes.size(); i += 7)
    ASSERT_EQ(sliced.feed(e.bytes.data() + i, std::min<size_t>(7, e.bytes.size() - i)),
              pmz::Status::ok);
  ASSERT_EQ(sliced.finish(), pmz::Status::ok);
  sliced.refine();
  ASSERT_TRUE(arrays(sliced) == levels.back());
}

// The largest extent of texture coordinate set s (the quantization range).
float texcoord_extent(const pmz::MeshAttributes& a, uint32_t s) {
  float lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (size_t i = 0; i < a.texcoords[s].size(); ++i) {
    lo[i % 2] = std::min(lo[i % 2], a.texcoords[s][i]);
    hi[i % 2] = std::max(hi[i % 2], a.texcoords[s][i]);
  }
  return std::max(hi[0] - lo[0], hi[1] - lo[1]);
}

// A UV sphere (the geometric normal prediction's case, spec/format.md 14.3) with a texture seam
// down one meridian and a normal crease at the equator: the northern faces have smooth radial
// normals, the southern ones the flat (0, 0, -1), so equator vertices carry up to four wedges.
TEST(AttrRoundTrip, CreasedUvSphere) {
  const uint32_t rings = 24, segments = 32, equator = rings / 2;
  pmz::IndexedMesh m;
  pmz::MeshAttributes& a = m.attributes;
  a.texcoords.resize(1);
  for (uint32_t r = 1; r < rings; ++r)
    for (uint32_t j = 0; j < segments; ++j) {
      const double t = M_PI * r / rings, f = 2 * M_PI * j / segments;
      m.positions.insert(m.positions.end(), {float(std::sin(t) * std::cos(f)),
                                             float(std::sin(t) * std::sin(f)), float(std::cos(t))});
    }
  const uint32_t north = (rings - 1) * segments, south = north + 1;
  m.positions.insert(m.positions.end(), {0.f, 0.f, 1.f, 0.f, 0.f, -1.f});
  std::map<std::array<uint32_t, 3>, uint32_t> wedges;  // (vertex, u = 1 at the seam, south)
  const auto corner = [&](uint32_t r, uint32_t j, bool wrap, bool below) {
    const uint32_t v = r == 0 ? north : r == rings ? south : (r - 1) * segments + j % segments;
    const bool seam = wrap && j == segments;
    auto [it, fresh] = wedges.try_emplace({v, seam, below}, a.wedge_count());
    if (fresh) {
      a.wedge_vertices.push_back(v);
      a.texcoords[0].insert(a.texcoords[0].end(), {float(j) / segments, float(r) / rings});
      const float* p = &m.positions[size_t(v) * 3];
      if (below)
        a.normals.insert(a.normals.end(), {0.f, 0.f, -1.f});
      else
        a.normals.insert(a.normals.end(), {p[0], p[1], p[2]});
    }
    m.indices.push_back(v);
    a.corner_wedges.push_back(it->second);
  };
  for (uint32_t r = 0; r < rings; ++r)
    for (uint32_t j = 0; j < segments; ++j) {
      const bool below = r >= equator, wrap = j + 1 == segments;
      const uint32_t q[4][2] = {{r, j}, {r + 1, j}, {r + 1, j + 1}, {r, j + 1}};
      for (const auto& t : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
        if ((r == 0 && t[2] == 3) || (r + 1 == rings && t[1] == 1)) continue;  // pole fans
        for (int k : t) corner(q[k][0], q[k][1], wrap, below);
      }
    }
  ASSERT_GT(a.wedge_count(), m.positions.size() / 3 + segments);  // the seam and the crease
  for (bool lossless : {true, false}) {
    SCOPED_TRACE(lossless ? "lossless" : "quantized");
    Encoded e;
    pmz::Decoder d;
    ASSERT_NO_FATAL_FAILURE(encode_and_decode(m, lossless, e, d));
    expect_consistent(d);
    if (lossless)
      expect_full(d, e, 0, 0, 0);
    else
      expect_full(d, e, 1.f / 4095 * 0.51f, 0.005f, 0);
  }
}

// Textured samples from Debian's assimp-testmodels (corpus-assimp, when fetched): an OBJ with
// four materials and a glTF with one, lossless and with the default quantization.
TEST(AttrRoundTrip, AssimpSamples) {
  const std::string dir = std::string(PMZ_SOURCE_DIR) + "/corpus-assimp/";
  const char* files[] = {"OBJ/spider.obj", "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb",
                         "OBJ/cube_with_vertexcolors.obj"};
  int tested = 0;
  for (const char* name : files) {
    pmz::IndexedMesh mesh;
    pmz::MeshRepairStats stats;
    std::string error;
    if (!pmz::read_mesh(dir + name, mesh, stats, error)) continue;
    ASSERT_FALSE(mesh.attributes.empty()) << name;
    ++tested;
    for (bool lossless : {true, false}) {
      SCOPED_TRACE(std::string(name) + (lossless ? " lossless" : " quantized"));
      Encoded e;
      pmz::Decoder d;
      ASSERT_NO_FATAL_FAILURE(encode_and_decode(mesh, lossless, e, d));
      ASSERT_EQ(d.material_count(), mesh.attributes.materials.size());
      for (uint32_t m = 0; m < d.material_count(); ++m) {
        EXPECT_EQ(d.material(m)->name, mesh.attributes.materials[m].name);
        EXPECT_EQ(d.material(m)->base_color_texture,
                  mesh.attributes.materials[m].base_color_texture);
      }
      const float tex = mesh.attributes.texcoords.empty()
                            ? 0
                            : texcoord_extent(mesh.attributes, 0) / 4095 * 0.51f;
      if (lossless)
        expect_full(d, e, 0, 0, 0);
      else
        expect_full(d, e, tex, 0.005f, 1.f / 255 * 0.51f);
    }
  }
  if (!tested) GTEST_SKIP() << "corpus-assimp not fetched (scripts/fetch_corpus.sh)";
}

// The change report covers the wedges: from a level of a few hundred faces, refining, coarsening
// and refining again a few splits at a time, every face below face_begin that is not listed keeps
// its wedge indices, and the wedges below wedge_begin keep their vertex and values.
TEST(AttrRoundTrip, ChangesCoverWedges) {
  const pmz::IndexedMesh mesh = pmz_test::seamed_grid(16, 7);
  Encoded e;
  encode(mesh, {}, e);
  pmz::Decoder d;
  ASSERT_EQ(d.feed(e.bytes.data(), e.bytes.size()), pmz::Status::ok);
  const uint64_t all = d.splits_available();
  ASSERT_GT(all, 200u);
  d.refine(all / 2);
  uint64_t unlisted = 0, rewritten = 0;  // faces checked unchanged; listed faces that changed
  auto step = [&](bool up) {
    d.clear_changes();
    const Arrays before = arrays(d);
    const uint32_t wedges = d.wedge_count();
    ASSERT_EQ(up ? d.refine(3) : d.coarsen(3), 3u);
    const pmz::MeshChanges& c = d.changes();
    ASSERT_FALSE(c.all);
    EXPECT_EQ(c.wedge_begin, std::min(wedges, d.wedge_count()));
    EXPECT_EQ(c.face_begin, std::min<uint32_t>(before.wedge_indices.size() / 3, d.face_count()));
    std::vector<char> listed(c.face_begin, 0);
    for (uint32_t f : c.modified_faces) {
      ASSERT_LT(f, c.face_begin) << "listed face at or above face_begin";
      listed[f] = 1;
    }
    for (uint32_t f = 0; f < c.face_begin; ++f) {
      const bool same = std::equal(d.wedge_indices() + f * 3, d.wedge_indices() + f * 3 + 3,
                                   before.wedge_indices.begin() + f * 3);
      if (listed[f]) {
        rewritten += !same;
        continue;
      }
      ++unlisted;
      ASSERT_TRUE(same) << "face " << f << " changed its wedges, not listed ("
                        << (up ? "refining" : "coarsening") << " at level " << d.splits_applied()
                        << ")";
    }
    const Arrays after = arrays(d);
    for (uint32_t w = 0; w < c.wedge_begin; ++w) {
      ASSERT_EQ(after.wedge_vertices[w], before.wedge_vertices[w]) << "wedge " << w;
      for (int x = 0; x < 2; ++x)
        ASSERT_EQ(after.texcoords[w * 2 + x], before.texcoords[w * 2 + x]) << "wedge " << w;
      for (int x = 0; x < 3; ++x) {
        ASSERT_EQ(after.normals[w * 3 + x], before.normals[w * 3 + x]) << "wedge " << w;
        ASSERT_EQ(after.colors[w * 3 + x], before.colors[w * 3 + x]) << "wedge " << w;
      }
    }
  };
  // First applications, undoing, then re-applying what was undone.
  for (bool up : {true, false, true})
    for (int i = 0; i < 20; ++i) ASSERT_NO_FATAL_FAILURE(step(up));
  // The assertions above ran: hundreds of faces per step, and splits that rewrote the wedges of
  // older faces (listed).
  EXPECT_GT(unlisted, 60u * 200u);
  EXPECT_GT(rewritten, 60u);
}

// A flat (n x n)-quad grid over the unit square in three charts (texture seams down columns n / 3
// and 2n / 3): chart c maps position (x, y) to a scaled, rotated and shifted copy, a similarity,
// so each face's map from positions to texture coordinates is the same across its chart. With
// `constant`, every corner of chart c takes one value instead (the same wedges).
pmz::IndexedMesh three_chart_grid(uint32_t n, bool constant) {
  pmz::IndexedMesh m;
  pmz::MeshAttributes& a = m.attributes;
  a.texcoords.resize(1);
  const double scale[3] = {0.9, 0.5, 0.7}, angle[3] = {0.0, 0.6, -1.1};
  const double shift[3][2] = {{0.05, 0.05}, {0.45, 0.2}, {0.2, 0.55}};
  auto chart_of = [&](uint32_t i) { return i * 3 < n ? 0u : i * 3 < 2 * n ? 1u : 2u; };
  std::vector<uint32_t> wedge((n + 1) * (n + 1) * 3, ~0u);  // [vertex * 3 + chart]
  auto corner = [&](uint32_t i, uint32_t j, uint32_t c) {
    const uint32_t v = j * (n + 1) + i;
    uint32_t& w = wedge[v * 3 + c];
    if (w == ~0u) {
      w = a.wedge_count();
      a.wedge_vertices.push_back(v);
      const double x = double(i) / n, y = double(j) / n;
      const double cs = std::cos(angle[c]), sn = std::sin(angle[c]);
      const double u = constant ? 0.3 * c : shift[c][0] + 0.5 * scale[c] * (cs * x - sn * y);
      const double t = constant ? 0.2 + 0.3 * c : shift[c][1] + 0.5 * scale[c] * (sn * x + cs * y);
      a.texcoords[0].insert(a.texcoords[0].end(), {float(u), float(t)});
    }
    m.indices.push_back(v);
    a.corner_wedges.push_back(w);
  };
  for (uint32_t j = 0; j <= n; ++j)
    for (uint32_t i = 0; i <= n; ++i)
      m.positions.insert(m.positions.end(), {float(i) / float(n), float(j) / float(n), 0.f});
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t c = chart_of(i);
      for (const auto& t :
           {std::array<uint32_t, 6>{0, 0, 1, 0, 1, 1}, std::array<uint32_t, 6>{0, 0, 1, 1, 0, 1}})
        for (int k = 0; k < 3; ++k) corner(i + t[2 * k], j + t[2 * k + 1], c);
    }
  return m;
}

// Texture coordinates on a seamed mesh, chart by chart: every decoded corner within half a
// quantization step of the input's, in each of the three charts; and the face-map prediction
// (spec/format.md section 14.3) nearly free on charts it predicts exactly: the attribute bytes
// beyond those of the same wedges with constant values (the same collapses: the engine ignores
// the attributes here, so the references cost the same) stay under 5 bits per wedge, two
// components within a step or so of their prediction (measured: 2.6). Without the face maps,
// the neighbour's values as the prediction, it was 11.2; with the map's quarter turn the wrong
// way round, 12.1.
TEST(AttrRoundTrip, TexcoordsChartByChart) {
  const uint32_t n = 24;
  pmz::SimplifyOptions geometry;
  geometry.attributes = pmz::AttributeMode::geometry_only;
  uint64_t attribute_bytes[2] = {0, 0};
  for (bool constant : {false, true}) {
    const pmz::IndexedMesh mesh = three_chart_grid(n, constant);
    pmz::CollapseSequence seq;
    std::string error;
    ASSERT_TRUE(pmz::simplify(mesh, geometry, seq, error)) << error;
    std::vector<uint8_t> bytes;
    pmz::WriteStats stats;
    ASSERT_TRUE(pmz::write_pmz(seq, {}, bytes, error, &stats)) << error;
    attribute_bytes[constant] = stats.attribute_bytes;
    if (constant) continue;
    const std::vector<uint32_t> order = pmz::decoded_vertex_order(seq, {});
    pmz::Decoder d;
    ASSERT_EQ(d.feed(bytes.data(), bytes.size()), pmz::Status::ok) << d.error_message();
    d.refine();
    ASSERT_EQ(d.face_count(), mesh.face_count());
    const float step = texcoord_extent(mesh.attributes, 0) / 4095;
    // Input faces by their corners (input ids), to find each decoded face's input slot.
    std::map<Face, uint32_t> input_face;
    for (uint32_t f = 0; f < mesh.face_count(); ++f)
      input_face[canonical(mesh.indices[f * 3], mesh.indices[f * 3 + 1], mesh.indices[f * 3 + 2])] =
          f;
    uint32_t corners[3] = {0, 0, 0};
    for (uint32_t f = 0; f < d.face_count(); ++f) {
      uint32_t t[3];
      for (int k = 0; k < 3; ++k) t[k] = order[d.indices()[f * 3 + k]];
      const auto it = input_face.find(canonical(t[0], t[1], t[2]));
      ASSERT_NE(it, input_face.end()) << "face " << f;
      const uint32_t slot = it->second, column = *std::min_element(t, t + 3) % (n + 1);
      const uint32_t chart = column * 3 < n ? 0 : column * 3 < 2 * n ? 1 : 2;
      for (int k = 0; k < 3; ++k) {
        int j = 0;
        while (mesh.indices[slot * 3 + j] != t[k]) ++j;
        const float* want =
            &mesh.attributes.texcoords[0][mesh.attributes.corner_wedges[slot * 3 + j] * 2];
        const float* got = &d.texcoords(0)[d.wedge_indices()[f * 3 + k] * 2];
        for (int x = 0; x < 2; ++x)
          ASSERT_LE(std::fabs(got[x] - want[x]), 0.51f * step)
              << "chart " << chart << ", face " << f << " corner " << k << ": " << got[x] << " for "
              << want[x];
        ++corners[chart];
      }
    }
    for (uint32_t c = 0; c < 3; ++c) EXPECT_GT(corners[c], 3 * n * n / 4) << "chart " << c;
  }
  const pmz::IndexedMesh mesh = three_chart_grid(n, false);
  const double bits_per_wedge =
      8.0 * double(attribute_bytes[0] - attribute_bytes[1]) / mesh.attributes.wedge_count();
  EXPECT_LT(bits_per_wedge, 5.0) << attribute_bytes[0] << " bytes against " << attribute_bytes[1];
}

TEST(AttrRoundTrip, NoAttributesNoWedges) {
  pmz::IndexedMesh mesh = pmz_test::seamed_grid(6, 2);
  mesh.attributes = {};
  Encoded e;
  encode(mesh, {}, e);
  pmz::Decoder d;
  ASSERT_EQ(d.feed(e.bytes.data(), e.bytes.size()), pmz::Status::ok);
  d.refine();
  EXPECT_EQ(d.info().flags, 0u);
  EXPECT_EQ(d.wedge_count(), 0u);
  EXPECT_EQ(d.wedge_indices(), nullptr);
  EXPECT_EQ(d.texcoords(0), nullptr);
  EXPECT_EQ(d.face_materials(), nullptr);
  EXPECT_EQ(d.material_count(), 0u);
}

}  // namespace
