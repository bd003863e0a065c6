// SPDX-License-Identifier: MIT
// Polygon soup -> manifold-with-boundary triangle mesh without losing a face.
//
// 1. Each face is cleaned (consecutive repeated corners removed; a polygon pinched at a repeated
//    vertex is split into its loops) and triangulated by ear clipping in its best-fit plane.
//    Faces with fewer than three distinct corners are the only ones dropped (counted).
// 2. Faces on each undirected edge are glued in pairs: a manifold edge (two faces, opposite
//    directions) is glued; on a non-manifold edge (3+ faces, or two in the same direction) each
//    face is glued to the earliest unglued face running the other way, in input order, and the
//    rest become boundary. This keeps both sheets of double-sided geometry intact.
// 3. Corners around each vertex joined by glued edges form fans (each corner has two edges, so a
//    fan is a path or a cycle); each fan gets its own vertex. The fan with the vertex's first
//    corner keeps the input id; other fans get copies appended after the input vertices.
// 4. Two unglued faces can still land on the same (copied) edge when they are fan-connected at
//    both ends; such a face is detached at one corner and step 3 is redone until every edge has
//    at most two faces of opposite orientation. Each pass removes glue, so this terminates.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>
#include <utility>
#include <vector>

#include "pmz/mesh.hpp"
#include "pmz/progressive_mesh.hpp"  // next_corner, prev_corner

namespace pmz {

namespace {

constexpr uint32_t kNone = 0xFFFFFFFFu;
constexpr size_t kMaxEarClipCorners = 64;  // beyond this, a fan (ear clipping is quadratic)

// Loops hold input corners (indices into PolygonSoup::corners, so attributes stay with them);
// `vertex` maps a corner to its vertex id.

// Removes cyclically consecutive repeats in place (a b b c a -> a b c), keeping the first corner.
void remove_consecutive_repeats(std::vector<uint32_t>& loop, const std::vector<uint32_t>& vertex) {
  size_t n = 0;
  for (uint32_t c : loop)
    if (n == 0 || vertex[loop[n - 1]] != vertex[c]) loop[n++] = c;
  while (n > 1 && vertex[loop[n - 1]] == vertex[loop[0]]) --n;
  loop.resize(n);
}

// Position j of the first corner whose vertex already occurred at an earlier position i.
bool find_repeat(const std::vector<uint32_t>& loop, const std::vector<uint32_t>& vertex,
                 std::vector<uint32_t>& sorted, std::unordered_map<uint32_t, uint32_t>& seen,
                 size_t& i, size_t& j) {
  sorted.resize(loop.size());
  for (size_t k = 0; k < loop.size(); ++k) sorted[k] = vertex[loop[k]];
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end()) return false;
  seen.clear();
  for (j = 0; j < loop.size(); ++j) {
    auto [it, fresh] = seen.emplace(vertex[loop[j]], uint32_t(j));
    if (!fresh) {
      i = it->second;
      return true;
    }
  }
  return false;
}

// Triangulates a simple loop of corners at distinct vertices into n-2 triangles (of corners)
// with its winding.
void triangulate_loop(const std::vector<uint32_t>& loop, const std::vector<uint32_t>& vertex,
                      const std::vector<float>& pos, std::vector<uint32_t>& tris) {
  const size_t n = loop.size();
  if (n == 3 || n > kMaxEarClipCorners) {
    for (size_t k = 1; k + 1 < n; ++k) tris.insert(tris.end(), {loop[0], loop[k], loop[k + 1]});
    return;
  }
  // Newell normal; project on the plane of its two minor axes, counter-clockwise.
  double normal[3] = {0, 0, 0};
  for (size_t k = 0; k < n; ++k) {
    const float* a = &pos[size_t(vertex[loop[k]]) * 3];
    const float* b = &pos[size_t(vertex[loop[(k + 1) % n]]) * 3];
    for (int d = 0; d < 3; ++d)
      normal[d] +=
          (double(a[(d + 1) % 3]) - b[(d + 1) % 3]) * (double(a[(d + 2) % 3]) + b[(d + 2) % 3]);
  }
  int axis = 0;
  for (int d = 1; d < 3; ++d)
    if (std::fabs(normal[d]) > std::fabs(normal[axis])) axis = d;
  int u = (axis + 1) % 3, w = (axis + 2) % 3;
  if (normal[axis] < 0) std::swap(u, w);
  double x[kMaxEarClipCorners], y[kMaxEarClipCorners];
  uint8_t next[kMaxEarClipCorners], prev[kMaxEarClipCorners];
  for (size_t k = 0; k < n; ++k) {
    x[k] = pos[size_t(vertex[loop[k]]) * 3 + u];
    y[k] = pos[size_t(vertex[loop[k]]) * 3 + w];
    next[k] = uint8_t((k + 1) % n);
    prev[k] = uint8_t((k + n - 1) % n);
  }
  auto cross = [&](size_t a, size_t b, size_t c) {
    return (x[b] - x[a]) * (y[c] - y[a]) - (y[b] - y[a]) * (x[c] - x[a]);
  };
  auto is_ear = [&](size_t b) {
    size_t a = prev[b], c = next[b];
    if (!(cross(a, b, c) > 0)) return false;
    for (size_t v = next[c]; v != a; v = next[v])  // a vertex inside or on the ear blocks it
      if (cross(a, b, v) >= 0 && cross(b, c, v) >= 0 && cross(c, a, v) >= 0) return false;
    return true;
  };
  size_t b = 1;  // starting at corner 1 turns a convex polygon into the usual fan from corner 0
  for (size_t left = n; left > 3; --left) {
    size_t tries = 0;
    while (tries < left && !is_ear(b)) b = next[b], ++tries;
    // No ear (self-intersecting or degenerate loop): clip the current corner anyway.
    tris.insert(tris.end(), {loop[prev[b]], loop[b], loop[next[b]]});
    next[prev[b]] = next[b];
    prev[next[b]] = prev[b];
    b = next[b];
  }
  tris.insert(tris.end(), {loop[prev[b]], loop[b], loop[next[b]]});
}

uint64_t edge_key(uint32_t a, uint32_t b) {
  return a < b ? uint64_t(a) << 32 | b : uint64_t(b) << 32 | a;
}

// The half-edges of `tris` (vertex ids below `vertices`) ordered by their undirected edge's key
// (edge_key), ties in input order: a counting sort by the smaller vertex, then each vertex's few
// half-edges sorted by the larger one. 4 bytes a half-edge and 4 a vertex (pairs of a 64-bit key
// and a half-edge took 16 bytes a half-edge).
void sort_edges(const std::vector<uint32_t>& tris, uint32_t vertices,
                std::vector<uint32_t>& edges) {
  const uint32_t n = uint32_t(tris.size());
  auto low = [&](uint32_t h) { return std::min(tris[h], tris[next_corner(h)]); };
  auto high = [&](uint32_t h) { return std::max(tris[h], tris[next_corner(h)]); };
  std::vector<uint32_t> end(size_t(vertices) + 1, 0);  // then: where each vertex's run ends
  for (uint32_t h = 0; h < n; ++h) ++end[low(h) + 1];
  for (uint32_t v = 0; v < vertices; ++v) end[v + 1] += end[v];
  edges.resize(n);
  for (uint32_t h = 0; h < n; ++h) edges[end[low(h)]++] = h;
  for (uint32_t v = 0, begin = 0; v < vertices; begin = end[v++])
    if (end[v] - begin > 1)
      std::sort(edges.begin() + begin, edges.begin() + end[v], [&](uint32_t a, uint32_t b) {
        const uint32_t x = high(a), y = high(b);
        return x < y || (x == y && a < b);
      });
}

struct UnionFind {
  std::vector<uint32_t> parent;
  void reset(size_t n) {
    parent.resize(n);
    for (uint32_t i = 0; i < n; ++i) parent[i] = i;
  }
  uint32_t find(uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// Wedges: per output vertex, one per distinct combination of its corners' attribute values
// (compared bitwise, so equal values from different file entries share a wedge).
void build_wedges(const SoupAttributes& in, const std::vector<uint32_t>& source,
                  const std::vector<uint32_t>& face_source, IndexedMesh& out) {
  MeshAttributes& a = out.attributes;
  a = MeshAttributes();
  a.materials = in.materials;
  a.material_library = in.material_library;
  if (!in.face_materials.empty()) {
    a.face_materials.resize(face_source.size());
    for (size_t f = 0; f < face_source.size(); ++f)
      a.face_materials[f] = in.face_materials[face_source[f]];
  }
  const size_t sets = in.texcoords.size();
  const bool normals = !in.corner_normals.empty(), colors = !in.corner_colors.empty();
  if (sets == 0 && !normals && !colors) return;
  a.texcoords.resize(sets);
  a.color_components = colors ? in.color_components : 0;
  // The wedge's values in one row: u v per set, normal xyz, colour.
  const size_t width = sets * 2 + (normals ? 3 : 0) + a.color_components;
  std::vector<float> row(width), rows;
  auto fill = [&](uint32_t c) {
    float* r = row.data();
    auto put = [&](const std::vector<float>& pool, uint32_t index, size_t n) {
      for (size_t k = 0; k < n; ++k) *r++ = index == kNoAttribute ? 0.0f : pool[index * n + k];
    };
    // A set no corner names (its corner list empty) reads as zeros, like a missing value.
    for (size_t s = 0; s < sets; ++s)
      put(in.texcoords[s],
          in.corner_texcoords[s].empty() ? kNoAttribute : in.corner_texcoords[s][c], 2);
    if (normals) put(in.normals, in.corner_normals[c], 3);
    if (colors) put(in.colors, in.corner_colors[c], a.color_components);
  };
  std::vector<uint32_t> first(out.vertex_count(), kNoAttribute), next;
  a.corner_wedges.resize(source.size());
  for (size_t c = 0; c < source.size(); ++c) {
    fill(source[c]);
    uint32_t v = out.indices[c], w = first[v];
    while (w != kNoAttribute && std::memcmp(&rows[w * width], row.data(), width * 4) != 0)
      w = next[w];
    if (w == kNoAttribute) {
      w = uint32_t(a.wedge_vertices.size());
      a.wedge_vertices.push_back(v);
      next.push_back(first[v]);
      first[v] = w;
      rows.insert(rows.end(), row.begin(), row.end());
    }
    a.corner_wedges[c] = w;
  }
  const size_t wedges = a.wedge_vertices.size();
  for (size_t s = 0; s < sets; ++s) a.texcoords[s].resize(wedges * 2);
  a.normals.resize(normals ? wedges * 3 : 0);
  a.colors.resize(wedges * a.color_components);
  for (size_t w = 0; w < wedges; ++w) {
    const float* r = &rows[w * width];
    for (size_t s = 0; s < sets; ++s, r += 2) std::copy(r, r + 2, &a.texcoords[s][w * 2]);
    if (normals) std::copy(r, r + 3, &a.normals[w * 3]), r += 3;
    std::copy(r, r + a.color_components, a.colors.data() + w * a.color_components);
  }
}

}  // namespace

std::string MeshAttributes::describe() const {
  std::string s;
  auto add = [&](const std::string& part) { s += (s.empty() ? "" : ", ") + part; };
  if (texcoords.size() == 1) add("texture coordinates");
  if (texcoords.size() > 1) add(std::to_string(texcoords.size()) + " texture coordinate sets");
  if (!normals.empty()) add("normals");
  if (color_components) add(color_components == 4 ? "RGBA colours" : "RGB colours");
  if (!materials.empty())
    add(std::to_string(materials.size()) + (materials.size() == 1 ? " material" : " materials"));
  else if (!face_materials.empty())
    add("material ids");
  return s;
}

std::string MeshRepairStats::summary() const {
  std::string s;
  auto add = [&](uint64_t n, const char* verb, const char* one, const char* many) {
    if (!n) return;
    if (!s.empty()) s += "; ";
    s += std::string(verb) + " " + std::to_string(n) + " " + (n == 1 ? one : many);
  };
  if (polygons_triangulated)
    s = "triangulated " + std::to_string(polygons_triangulated) +
        (polygons_triangulated == 1 ? " polygon" : " polygons") + " into " +
        std::to_string(triangles_from_polygons) +
        (triangles_from_polygons == 1 ? " triangle" : " triangles");
  add(welded_vertices, "welded", "vertex with an equal position (attribute seam)",
      "vertices with equal positions (attribute seams)");
  add(degenerate_faces_dropped, "dropped", "degenerate face (repeated vertex)",
      "degenerate faces (repeated vertex)");
  add(repeated_corners_removed, "removed repeated corners from", "face", "faces");
  add(duplicate_faces, "kept", "duplicate face", "duplicate faces");
  add(nonmanifold_edges, "cut", "non-manifold edge", "non-manifold edges");
  add(nonmanifold_vertices, "split", "non-manifold vertex", "non-manifold vertices");
  add(vertices_added, "appended", "vertex copy", "vertex copies");
  add(isolated_vertices, "kept", "isolated vertex", "isolated vertices");
  return s;
}

namespace {

// `owned`: the soup itself when the caller hands it over, whose arrays are then freed as soon as
// nothing reads them (its positions become the mesh's).
void repair(const PolygonSoup& soup, PolygonSoup* owned, IndexedMesh& out, MeshRepairStats& stats) {
  stats = MeshRepairStats();
  stats.input_faces = soup.face_count();
  const uint32_t input_vertices = soup.vertex_count();

  // 1. Clean and triangulate, keeping face order. source[c]: the input corner of corner c.
  std::vector<uint32_t> source, face_source;
  source.reserve(soup.corners.size());
  std::vector<uint32_t> loop, rest, sorted;
  std::unordered_map<uint32_t, uint32_t> seen;
  for (uint32_t f = 0; f < soup.face_count(); ++f) {
    uint32_t begin = soup.face_offsets[f], end = soup.face_offsets[f + 1];
    rest.resize(end - begin);
    for (uint32_t c = begin; c < end; ++c) rest[c - begin] = c;
    size_t before = source.size();
    bool repeats = false;
    for (;;) {
      size_t n = rest.size();
      remove_consecutive_repeats(rest, soup.corners);
      repeats |= rest.size() != n;
      size_t i, j;
      if (!find_repeat(rest, soup.corners, sorted, seen, i, j)) break;
      // rest[i..j) is a simple loop; the remainder keeps rest[i] once.
      repeats = true;
      loop.assign(rest.begin() + i, rest.begin() + j);
      if (loop.size() >= 3) triangulate_loop(loop, soup.corners, soup.positions, source);
      rest.erase(rest.begin() + i + 1, rest.begin() + j + 1);
    }
    if (rest.size() >= 3) triangulate_loop(rest, soup.corners, soup.positions, source);
    if (source.size() == before)
      ++stats.degenerate_faces_dropped;
    else if (repeats)
      ++stats.repeated_corners_removed;
    if (end - begin > 3) {
      ++stats.polygons_triangulated;
      stats.triangles_from_polygons += (source.size() - before) / 3;
    }
    face_source.resize(source.size() / 3, f);
  }
  const uint32_t corner_count = uint32_t(source.size());
  std::vector<uint32_t> tris(corner_count);
  for (uint32_t c = 0; c < corner_count; ++c) tris[c] = soup.corners[source[c]];
  // The input corners and faces are read again only for attributes and materials.
  const SoupAttributes& attrs = soup.attributes;
  if (attrs.texcoords.empty() && attrs.corner_normals.empty() && attrs.corner_colors.empty() &&
      attrs.face_materials.empty())
    source = std::vector<uint32_t>(), face_source = std::vector<uint32_t>();
  if (owned)
    owned->corners = std::vector<uint32_t>(), owned->face_offsets = std::vector<uint32_t>();

  // 2. Glue faces in pairs along each edge.
  std::vector<uint32_t> mate(corner_count, kNone);
  std::vector<uint32_t> edges;
  sort_edges(tris, input_vertices, edges);
  auto key = [&](uint32_t h) { return edge_key(tris[h], tris[next_corner(h)]); };
  auto forward = [&](uint32_t h) { return tris[h] < tris[next_corner(h)]; };
  std::vector<uint32_t> open[2];  // unglued half-edges of the current edge, by direction
  for (size_t g = 0; g < edges.size();) {
    const uint64_t group = key(edges[g]);
    size_t e = g + 1;
    while (e < edges.size() && key(edges[e]) == group) ++e;
    // Duplicate triangles (same vertex set) are kept; the gluing separates them. Counted once,
    // in the group of the face's smallest edge: a later face whose third vertex matches.
    for (size_t k = g + 1; k < e; ++k) {
      uint32_t h = edges[k], t = h - h % 3;
      uint64_t smallest =
          std::min({edge_key(tris[t], tris[t + 1]), edge_key(tris[t + 1], tris[t + 2]),
                    edge_key(tris[t + 2], tris[t])});
      if (smallest != group) continue;
      uint32_t apex = tris[prev_corner(h)];
      for (size_t j = g; j < k; ++j)
        if (tris[prev_corner(edges[j])] == apex) {
          ++stats.duplicate_faces;
          break;
        }
    }
    if (e - g == 2 && forward(edges[g]) != forward(edges[g + 1])) {
      mate[edges[g]] = edges[g + 1];
      mate[edges[g + 1]] = edges[g];
    } else if (e - g >= 2) {
      ++stats.nonmanifold_edges;
      size_t head[2] = {0, 0};
      open[0].clear(), open[1].clear();
      for (size_t k = g; k < e; ++k) {
        uint32_t h = edges[k];
        int d = forward(h), o = 1 - d;
        if (head[o] < open[o].size()) {
          uint32_t m = open[o][head[o]++];
          mate[h] = m, mate[m] = h;
        } else {
          open[d].push_back(h);
        }
      }
    }
    g = e;
  }
  edges = std::vector<uint32_t>();

  // 3 + 4. One vertex per fan; detach faces that still share an edge beyond a manifold pair.
  // A fan's root is its first corner (unite keeps the smaller root), so corner c meets its fan
  // first when c is the root, and later corners take the vertex the root got.
  UnionFind fans;
  std::vector<uint32_t> copy_source;
  std::vector<uint8_t> claimed;
  out.indices.resize(corner_count);
  for (;;) {
    fans.reset(corner_count);
    for (uint32_t h = 0; h < corner_count; ++h)
      if (mate[h] != kNone && h < mate[h]) {
        fans.unite(h, next_corner(mate[h]));  // the corners at h's start vertex
        fans.unite(next_corner(h), mate[h]);  // the corners at h's end vertex
      }
    claimed.assign(input_vertices, 0);
    copy_source.clear();
    for (uint32_t c = 0; c < corner_count; ++c) {
      uint32_t root = fans.find(c);
      if (root != c) {
        out.indices[c] = out.indices[root];
        continue;
      }
      uint32_t v = tris[c];
      if (!claimed[v]) {
        claimed[v] = 1;
        out.indices[c] = v;
      } else {
        out.indices[c] = input_vertices + uint32_t(copy_source.size());
        copy_source.push_back(v);
      }
    }
    // Without a non-manifold edge every edge group was glued or single: nothing to detach.
    if (stats.nonmanifold_edges == 0) break;
    sort_edges(out.indices, input_vertices + uint32_t(copy_source.size()), edges);
    auto key_out = [&](uint32_t h) {
      return edge_key(out.indices[h], out.indices[next_corner(h)]);
    };
    auto forward_out = [&](uint32_t h) { return out.indices[h] < out.indices[next_corner(h)]; };
    bool detached = false;
    for (size_t g = 0; g < edges.size();) {
      const uint64_t group = key_out(edges[g]);
      size_t e = g + 1;
      while (e < edges.size() && key_out(edges[e]) == group) ++e;
      if (e - g > 2 || (e - g == 2 && forward_out(edges[g]) == forward_out(edges[g + 1]))) {
        // Keep a glued pair if the group has one (else the first face); detach the others at
        // their start corner, which then forms a fan of its own.
        uint32_t keep = edges[g];
        for (size_t k = g; k < e; ++k) {
          uint32_t m = mate[edges[k]];
          if (m != kNone && key_out(m) == group) {
            keep = edges[k];
            break;
          }
        }
        for (size_t k = g; k < e; ++k) {
          uint32_t h = edges[k];
          if (h == keep || h == mate[keep]) continue;
          for (uint32_t x : {h, prev_corner(h)})
            if (mate[x] != kNone) mate[mate[x]] = kNone, mate[x] = kNone, detached = true;
        }
      }
      g = e;
    }
    if (!detached) break;
  }
  edges = std::vector<uint32_t>();
  fans.parent = std::vector<uint32_t>();
  mate = std::vector<uint32_t>();

  if (owned)
    out.positions = std::move(owned->positions);
  else
    out.positions.assign(soup.positions.begin(), soup.positions.end());
  out.positions.reserve(out.positions.size() + copy_source.size() * 3);
  for (uint32_t v : copy_source)
    for (int k = 0; k < 3; ++k) out.positions.push_back(out.positions[size_t(v) * 3 + k]);
  stats.vertices_added = copy_source.size();
  std::vector<uint8_t> split(input_vertices, 0);
  for (uint32_t v : copy_source) stats.nonmanifold_vertices += !split[v], split[v] = 1;
  std::vector<uint8_t> used(input_vertices, 0);
  for (uint32_t v : tris) used[v] = 1;
  stats.isolated_vertices = uint64_t(std::count(used.begin(), used.end(), 0));
  stats.welded_vertices = soup.welded_vertices;
  build_wedges(soup.attributes, source, face_source, out);
}

}  // namespace

void repair_mesh(const PolygonSoup& soup, IndexedMesh& out, MeshRepairStats& stats) {
  repair(soup, nullptr, out, stats);
}

void repair_mesh(PolygonSoup&& soup, IndexedMesh& out, MeshRepairStats& stats) {
  repair(soup, &soup, out, stats);
  soup = PolygonSoup();
}

}  // namespace pmz
