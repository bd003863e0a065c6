// SPDX-License-Identifier: MIT
// Attribute-aware simplification (spec/algorithm.md section 7): material boundaries (and in
// the strict mode, seams) are discontinuity curves, the attribute term measures what a collapse
// does to the field and prices a seam in the default mode, and a mesh without attributes (or
// AttributeMode::geometry_only) collapses exactly as before.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "../../encoder/src/attr_simplify.hpp"
#include "../../encoder/src/metric.hpp"
#include "pmz/simplify.hpp"

namespace {

// An n x n grid on [0,1]^2 with a gentle bump (so collapses have different costs), two texture
// charts split at x = 0.5 (the column's vertices have two wedges: u = x on the left, x + 1 on
// the right) and two materials split at y = 0.5. The seams cross at the centre.
pmz::IndexedMesh crossing_seams_grid(int n, float bump = 0.05f) {
  pmz::IndexedMesh m;
  auto id = [&](int i, int j) { return uint32_t(j * (n + 1) + i); };
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const float x = float(i) / n, y = float(j) / n;
      m.positions.insert(m.positions.end(),
                         {x, y, bump * std::sin(7.f * x + 1.f) * std::cos(5.f * y + 0.5f)});
    }
  pmz::MeshAttributes& a = m.attributes;
  a.texcoords.resize(1);
  // Wedge of (i, j) in chart c: one per vertex for its own chart, plus a right-chart wedge for
  // the seam column, appended after.
  std::vector<uint32_t> right_wedge(size_t(n + 1) * (n + 1), 0);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const float x = float(i) / n, y = float(j) / n;
      a.wedge_vertices.push_back(id(i, j));
      a.texcoords[0].insert(a.texcoords[0].end(), {2 * i > n ? x + 1 : x, y});
    }
  for (int j = 0; j <= n; ++j) {
    right_wedge[id(n / 2, j)] = a.wedge_count();
    a.wedge_vertices.push_back(id(n / 2, j));
    a.texcoords[0].insert(a.texcoords[0].end(), {0.5f + 1, float(j) / n});
  }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t q[4] = {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)};
      const bool right = 2 * i >= n;
      const uint32_t material = 2 * j >= n;
      const std::array<std::array<uint32_t, 3>, 2> triangles = {
          {{q[0], q[1], q[2]}, {q[0], q[2], q[3]}}};
      for (const auto& t : triangles) {
        for (int k = 0; k < 3; ++k) {
          m.indices.push_back(t[k]);
          const bool on_seam = int(t[k] % (n + 1)) == n / 2;
          a.corner_wedges.push_back(right && on_seam ? right_wedge[t[k]] : t[k]);
        }
        a.face_materials.push_back(material);
      }
    }
  a.materials.resize(2);
  return m;
}

// The edges of the welded mesh (faces as position indices) that only one face holds.
std::vector<std::array<uint32_t, 2>> boundary_edges(const pmz::IndexedMesh& m) {
  std::map<std::array<uint32_t, 2>, int> count;
  for (uint32_t f = 0; f < m.face_count(); ++f)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = m.indices[f * 3 + k], b = m.indices[f * 3 + (k + 1) % 3];
      ++count[{std::min(a, b), std::max(a, b)}];
    }
  std::vector<std::array<uint32_t, 2>> r;
  for (const auto& [e, c] : count)
    if (c == 1) r.push_back(e);
  return r;
}

// Strict mode: seams are kept like material boundaries.
TEST(AttributeSimplify, SeamsAreKeptAndTheirCornersStay) {
  const int n = 24;
  const pmz::IndexedMesh mesh = crossing_seams_grid(n);
  {
    const pmz::AttributeMode mode = pmz::AttributeMode::seams;
    pmz::SimplifyOptions options;
    options.attributes = mode;
    options.target_faces = 60;
    pmz::CollapseSequence seq;
    std::string error;
    ASSERT_TRUE(pmz::simplify(mesh, options, seq, error)) << error;
    // Far enough to have moved seam vertices many times.
    EXPECT_LT(seq.base_indices.size() / 3, 200u);
    auto column = [&](uint32_t v) { return int(v % (n + 1)); };
    auto row = [&](uint32_t v) { return int(v / (n + 1)); };
    uint64_t along_seams = 0;
    for (const pmz::HalfEdgeCollapse& c : seq.collapses) {
      const bool vertical = column(c.u) == n / 2, horizontal = row(c.u) == n / 2;
      // The seam corners (the crossing and the four ends on the boundary) never move.
      EXPECT_FALSE(vertical && horizontal) << "the seam crossing moved";
      EXPECT_FALSE(vertical && (row(c.u) == 0 || row(c.u) == n)) << "a seam end moved";
      EXPECT_FALSE(horizontal && (column(c.u) == 0 || column(c.u) == n)) << "a seam end moved";
      // A seam vertex moves along its seam only.
      if (vertical) {
        EXPECT_EQ(column(c.v), n / 2) << c.u << " -> " << c.v << " left the seam";
      }
      if (horizontal) {
        EXPECT_EQ(row(c.v), n / 2) << c.u << " -> " << c.v << " left the seam";
      }
      along_seams += vertical || horizontal;
    }
    EXPECT_GT(along_seams, uint64_t(n));  // seams are simplified, not frozen
    // The result (mesh_after replays the collapse rule): no face straddles a seam. Each face
    // lies in one chart (left: u <= 0.5, right: u >= 1.5) and its material is its side's.
    const pmz::IndexedMesh result = pmz::mesh_after(seq, seq.collapses.size());
    const pmz::MeshAttributes& a = result.attributes;
    ASSERT_EQ(a.corner_wedges.size(), result.indices.size());
    ASSERT_EQ(a.face_materials.size(), result.face_count());
    for (uint32_t f = 0; f < result.face_count(); ++f) {
      float cx = 0, cy = 0;
      int right = 0;
      for (int k = 0; k < 3; ++k) {
        cx += result.positions[size_t(result.indices[f * 3 + k]) * 3] / 3;
        cy += result.positions[size_t(result.indices[f * 3 + k]) * 3 + 1] / 3;
        right += a.texcoords[0][size_t(a.corner_wedges[f * 3 + k]) * 2] > 1;
      }
      EXPECT_EQ(right, cx > 0.5f ? 3 : 0) << "face " << f << " straddles the texture seam";
      EXPECT_EQ(a.face_materials[f], cy > 0.5f ? 1u : 0u) << "face " << f;
    }
  }
}

// The default mode prices texture seams: where the target is reachable along them (the seam's
// uv jump is a whole chart, 24 edges' change) none is crossed; material boundaries stay strict;
// asked for as few faces as legal collapses allow, it goes below the strict mode (locked seam
// corners no longer hold the base mesh up); every level is crack-free (the welded mesh's
// boundary edges all lie on the grid's border).
TEST(AttributeSimplify, PricedSeamsHoldWhereAffordable) {
  const int n = 24;
  const pmz::IndexedMesh mesh = crossing_seams_grid(n);
  auto run = [&](pmz::AttributeMode mode, uint64_t target) {
    pmz::SimplifyOptions options;
    options.attributes = mode;
    options.target_faces = target;
    pmz::CollapseSequence seq;
    std::string error;
    EXPECT_TRUE(pmz::simplify(mesh, options, seq, error)) << error;
    return seq;
  };
  auto centroid = [](const pmz::IndexedMesh& r, uint32_t f, int axis) {
    float c = 0;
    for (int k = 0; k < 3; ++k) c += r.positions[size_t(r.indices[f * 3 + k]) * 3 + axis] / 3;
    return c;
  };
  const pmz::CollapseSequence priced = run(pmz::AttributeMode::full, 200);
  const pmz::IndexedMesh result = pmz::mesh_after(priced, priced.collapses.size());
  ASSERT_LE(result.face_count(), 200u);
  const pmz::MeshAttributes& a = result.attributes;
  for (uint32_t f = 0; f < result.face_count(); ++f) {
    int right = 0;
    for (int k = 0; k < 3; ++k) right += a.texcoords[0][size_t(a.corner_wedges[f * 3 + k]) * 2] > 1;
    EXPECT_EQ(right, centroid(result, f, 0) > 0.5f ? 3 : 0) << "face " << f << " straddles";
    EXPECT_EQ(a.face_materials[f], centroid(result, f, 1) > 0.5f ? 1u : 0u) << "face " << f;
  }
  const pmz::CollapseSequence strict_all = run(pmz::AttributeMode::seams, 0);
  const pmz::CollapseSequence priced_all = run(pmz::AttributeMode::full, 0);
  EXPECT_LT(priced_all.base_indices.size(), strict_all.base_indices.size());
  // The grid is a disc: at every level the welded mesh's boundary edges form one loop (a crack
  // would open a second one).
  const size_t count = priced_all.collapses.size();
  for (size_t k : {count / 4, count / 2, count * 3 / 4, count}) {
    const auto edges = boundary_edges(pmz::mesh_after(priced_all, k));
    std::map<uint32_t, std::vector<uint32_t>> around;
    for (const auto& e : edges) around[e[0]].push_back(e[1]), around[e[1]].push_back(e[0]);
    for (const auto& [x, next] : around) ASSERT_EQ(next.size(), 2u) << "level " << k;
    size_t length = 1;  // edges walked from edges[0][0]; the loop closes back there
    for (uint32_t prev = edges[0][0], x = edges[0][1]; x != edges[0][0] && length <= edges.size();
         ++length) {
      const uint32_t step = around[x][0] == prev ? around[x][1] : around[x][0];
      prev = x, x = step;
    }
    EXPECT_EQ(length, edges.size()) << "level " << k << ": more than one boundary loop";
  }
}

// Without attributes, or with AttributeMode::geometry_only, the collapses are the same bits.
TEST(AttributeSimplify, GeometryOnlyIsTheGeometryRun) {
  const pmz::IndexedMesh seamed = crossing_seams_grid(20);
  pmz::IndexedMesh plain;
  plain.positions = seamed.positions;
  plain.indices = seamed.indices;
  pmz::SimplifyOptions geometry;
  geometry.attributes = pmz::AttributeMode::geometry_only;
  pmz::CollapseSequence a, b, c;
  std::string error;
  ASSERT_TRUE(pmz::simplify(seamed, geometry, a, error)) << error;
  ASSERT_TRUE(pmz::simplify(plain, pmz::SimplifyOptions{}, b, error)) << error;
  ASSERT_TRUE(pmz::simplify(plain, geometry, c, error)) << error;
  ASSERT_EQ(a.collapses.size(), b.collapses.size());
  ASSERT_EQ(b.collapses.size(), c.collapses.size());
  for (size_t i = 0; i < a.collapses.size(); ++i) {
    EXPECT_EQ(a.collapses[i].u, b.collapses[i].u);
    EXPECT_EQ(a.collapses[i].v, b.collapses[i].v);
    EXPECT_EQ(a.collapses[i].cost, b.collapses[i].cost);
    EXPECT_EQ(c.collapses[i].u, b.collapses[i].u);
    EXPECT_EQ(c.collapses[i].v, b.collapses[i].v);
  }
  EXPECT_EQ(a.base_indices, b.base_indices);
}

// The attribute term: zero where the field is linear, positive where a collapse distorts it;
// a seam vertex's move off its seam is forbidden (infinite) in the strict mode and costs the
// chart's jump in the default one.
TEST(AttributeSimplify, AttributeTermMeasuresTheFieldsDistortion) {
  const int n = 8;
  pmz::IndexedMesh flat = crossing_seams_grid(n, 0.f);  // texture coordinates linear in each chart
  flat.attributes.face_materials.clear();
  flat.attributes.materials.clear();
  const uint32_t u = 2 * (n + 1) + 2, v = u + 1;  // interior, left chart, off the seam
  auto cost = [&](const pmz::IndexedMesh& m, pmz::AttributeMode mode, uint32_t a, uint32_t b) {
    pmz::SimplifyOptions options;
    options.attributes = mode;
    return pmz::detail::initial_collapse_cost(m, options, a, b);
  };
  // Flat: the geometric cost is zero, and so is the attribute term of a linear field.
  EXPECT_EQ(cost(flat, pmz::AttributeMode::geometry_only, u, v), 0.f);
  EXPECT_LT(cost(flat, pmz::AttributeMode::full, u, v), 1e-9f);
  // u's texture coordinate pushed off the linear field by a quarter of an edge's change:
  // collapsing u costs, in proportion to the square of the push.
  pmz::IndexedMesh bent = flat;
  bent.attributes.texcoords[0][size_t(u) * 2 + 1] += 0.25f / n;
  const float bent_cost = cost(bent, pmz::AttributeMode::full, u, v);
  EXPECT_GT(bent_cost, 1e-3f);
  bent.attributes.texcoords[0][size_t(u) * 2 + 1] += 0.25f / n;  // twice the push
  EXPECT_NEAR(cost(bent, pmz::AttributeMode::full, u, v) / bent_cost, 4.f, 0.05f);
  EXPECT_EQ(cost(bent, pmz::AttributeMode::seams, u, v),
            cost(bent, pmz::AttributeMode::full, u, v));
  // A seam vertex: along the seam free; off it forbidden (strict) or priced by the jump (the
  // left faces' corner at u takes the right chart's texture coordinate, one uv unit = n edges'
  // change away), far above the quarter-edge push.
  const uint32_t s = 3 * (n + 1) + n / 2;
  EXPECT_LT(cost(flat, pmz::AttributeMode::full, s, s + (n + 1)), 1e-9f);
  EXPECT_LT(cost(flat, pmz::AttributeMode::seams, s, s + (n + 1)), 1e-9f);
  const float crossing = cost(flat, pmz::AttributeMode::full, s, s + 1);
  EXPECT_TRUE(std::isfinite(crossing));
  EXPECT_GT(crossing, 100 * bent_cost);
  EXPECT_TRUE(std::isinf(cost(flat, pmz::AttributeMode::seams, s, s + 1)));
  EXPECT_TRUE(std::isinf(cost(flat, pmz::AttributeMode::seams, s, s - 1)));
  EXPECT_EQ(cost(flat, pmz::AttributeMode::geometry_only, s, s + 1), 0.f);
  // Without the term (weight 0) nothing prices a seam: it is locked in the default mode too.
  pmz::SimplifyOptions unweighted;
  unweighted.params.attribute_weight = 0;
  EXPECT_TRUE(std::isinf(pmz::detail::initial_collapse_cost(flat, unweighted, s, s + 1)));
}

// A normal-only crease (texture continuous, normals differ across a column): the default mode
// prices crossing it by the normal jump (the square of the chord between the two normals); the
// strict mode forbids it.
TEST(AttributeSimplify, NormalCreaseIsPricedByTheNormalJump) {
  const int n = 8;
  const uint32_t s = 3 * (n + 1) + n / 2;  // on the crease column
  auto creased = [&](float angle) {
    pmz::IndexedMesh m = crossing_seams_grid(n, 0.f);
    pmz::MeshAttributes& a = m.attributes;
    a.face_materials.clear();
    a.materials.clear();
    for (uint32_t w = 0; w < a.wedge_count(); ++w) {
      float& tu = a.texcoords[0][size_t(w) * 2];
      const bool right = tu > 1;
      if (right) tu -= 1;  // one chart: the texture is continuous across the column
      const float t = right ? angle : 0.f;
      a.normals.insert(a.normals.end(), {std::sin(t), 0.f, std::cos(t)});
    }
    return m;
  };
  auto cost = [&](const pmz::IndexedMesh& m, pmz::AttributeMode mode, uint32_t a, uint32_t b) {
    pmz::SimplifyOptions options;
    options.attributes = mode;
    return pmz::detail::initial_collapse_cost(m, options, a, b);
  };
  // Moving off the crease also costs its seam planes, the same at every angle: measured at a
  // negligible angle and taken off.
  const float angle = 0.5f, tiny = 1e-3f;
  const pmz::IndexedMesh once = creased(angle), twice = creased(2 * angle);
  const float c0 = cost(creased(tiny), pmz::AttributeMode::full, s, s + 1);
  const float c1 = cost(once, pmz::AttributeMode::full, s, s + 1);
  const float c2 = cost(twice, pmz::AttributeMode::full, s, s + 1);
  ASSERT_GT(c1, c0);
  auto chord2 = [](double t) { return 4 * std::sin(t / 2) * std::sin(t / 2); };
  EXPECT_NEAR((c2 - c0) / (c1 - c0),
              (chord2(2 * angle) - chord2(tiny)) / (chord2(angle) - chord2(tiny)), 0.01);
  EXPECT_LT(cost(once, pmz::AttributeMode::full, s, s + (n + 1)), 1e-9f);  // along: free
  EXPECT_TRUE(std::isinf(cost(once, pmz::AttributeMode::seams, s, s + 1)));
}

// A corner that takes the far side of a seam is wrong however far the jump: its deviation
// counts at most kJumpCap times its face's own largest squared change along an edge. Crossing
// a texture seam costs the same whether the charts lie one or two uv units apart, while a
// jump below the cap still costs less the smaller it is.
TEST(AttributeSimplify, SeamJumpIsCappedByTheFacesExtent) {
  const int n = 8;
  const uint32_t s = 3 * (n + 1) + n / 2;  // on the seam column
  auto apart = [&](float offset) {         // the right chart moved to u = x + offset
    pmz::IndexedMesh m = crossing_seams_grid(n, 0.f);
    m.attributes.face_materials.clear();
    m.attributes.materials.clear();
    for (size_t w = 0; w < m.attributes.wedge_count(); ++w) {
      float& tu = m.attributes.texcoords[0][w * 2];
      if (tu > 1) tu += offset - 1;
    }
    return m;
  };
  auto crossing = [&](const pmz::IndexedMesh& m) {
    return pmz::detail::initial_collapse_cost(m, pmz::SimplifyOptions{}, s, s + 1);
  };
  const float one = crossing(apart(1)), two = crossing(apart(2));
  ASSERT_TRUE(std::isfinite(one));
  EXPECT_EQ(one, two);
  const float small = crossing(apart(0.5f / n)), smaller = crossing(apart(0.25f / n));
  EXPECT_LT(smaller, small);
  EXPECT_LT(small, one);
}

// Seam planes: sliding a seam vertex along its seam leaves both sides' fields as they were
// (free when the seam is straight) but moves where the seam runs; where the seam bends, the
// slide costs the square of the bend's distance, and only in the modes with seams.
TEST(AttributeSimplify, SeamPlanesKeepTheSeamsCourse) {
  const int n = 8;
  const uint32_t s = 3 * (n + 1) + n / 2;  // on the seam column, below the material boundary
  auto bent = [&](float shift) {  // s and its wedges moved by shift in x: the seam bends at s
    pmz::IndexedMesh m = crossing_seams_grid(n, 0.f);  // flat, fields linear in each chart
    m.positions[size_t(s) * 3] += shift;
    for (size_t w = 0; w < m.attributes.wedge_count(); ++w)
      if (m.attributes.wedge_vertices[w] == s) m.attributes.texcoords[0][w * 2] += shift;
    return m;
  };
  auto slide = [&](const pmz::IndexedMesh& m, pmz::AttributeMode mode) {
    pmz::SimplifyOptions options;
    options.attributes = mode;
    return pmz::detail::initial_collapse_cost(m, options, s, s + (n + 1));
  };
  EXPECT_LT(slide(bent(0), pmz::AttributeMode::full), 1e-9f);
  const float d = 0.05f / n;
  const float once = slide(bent(d), pmz::AttributeMode::full);
  const float twice = slide(bent(2 * d), pmz::AttributeMode::full);
  EXPECT_GT(once, 1e-6f);
  EXPECT_NEAR(twice / once, 4.f, 0.2f);
  EXPECT_EQ(slide(bent(d), pmz::AttributeMode::seams), once);
  EXPECT_EQ(slide(bent(d), pmz::AttributeMode::geometry_only), 0.f);
}

// The field term follows the current mesh (kFieldDecay = 3): with half the input's faces left,
// a distortion of the field costs an eighth of what it cost at the input, so seams do not
// outgrow geometry late; the seam planes (where a seam runs) stay as they were.
TEST(AttributeSimplify, FieldTermDecaysWithTheFaceCount) {
  using pmz::detail::kNone;
  const int n = 8;
  pmz::IndexedMesh mesh = crossing_seams_grid(n, 0.f);  // flat: the fields alone cost
  mesh.attributes.face_materials.clear();
  mesh.attributes.materials.clear();
  const uint32_t u = 2 * (n + 1) + 2;  // interior, left chart, off the seam
  mesh.attributes.texcoords[0][size_t(u) * 2 + 1] += 0.25f / n;  // off the linear field
  const uint32_t s = 5 * (n + 1) + n / 2;                        // on the seam column
  mesh.positions[size_t(s) * 3] += 0.05f / n;                    // the seam bends at s
  for (size_t w = 0; w < mesh.attributes.wedge_count(); ++w)
    if (mesh.attributes.wedge_vertices[w] == s) mesh.attributes.texcoords[0][w * 2] += 0.05f / n;
  pmz::detail::HalfEdgeMesh m;
  std::string error;
  ASSERT_TRUE(pmz::detail::build_halfedge(mesh, m, error)) << error;
  pmz::detail::AttributeField field;
  field.init(m, mesh.attributes.corner_wedges, {}, mesh.attributes, pmz::AttributeMode::full, 0.5f,
             1.0 / n);
  auto cost = [&](uint32_t a, uint32_t b) {  // a -> b, an interior edge
    uint32_t ha = kNone;
    pmz::detail::for_each_outgoing(m, a, [&](uint32_t h) {
      if (m.dest(h) == b) ha = h;
    });
    EXPECT_NE(ha, kNone);
    return field.cost(m, a, b, ha, m.twin[ha]);
  };
  const float distortion = cost(u, u + 1), slide = cost(s, s + (n + 1));
  ASSERT_GT(distortion, 0.f);
  ASSERT_GT(slide, 0.f);
  // Collapses far from u and s (their corners' wedges are rewritten, the topology is left as
  // it is: only the count of faces matters here) until half the faces are gone.
  const uint32_t far = 1, far_to = 2;  // on the bottom boundary, left chart
  uint32_t ha = kNone;
  pmz::detail::for_each_outgoing(m, far, [&](uint32_t h) {
    if (m.dest(h) == far_to) ha = h;
  });
  ASSERT_NE(ha, kNone);
  ASSERT_EQ(m.twin[ha], kNone);
  std::vector<std::pair<uint32_t, uint32_t>> moved;
  for (uint32_t faces = m.face_count(); faces > m.face_count() / 2; --faces)
    field.collapse(m, far, ha, kNone, moved, true);  // a boundary collapse: one face
  EXPECT_NEAR(cost(u, u + 1) / distortion, 0.125f, 1e-4f);
  EXPECT_NEAR(cost(s, s + (n + 1)) / slide, 1.f, 1e-4f);
}

}  // namespace
