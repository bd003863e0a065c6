// SPDX-License-Identifier: MIT
// Streams in nodes (spec/format.md section 15): a sequence simplified in levels of cells is
// written node by node behind a node table; the decoder gives back the input, whatever the
// slicing, and refuses a table that does not match the nodes' bytes, faces or cells.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "pmz/coding.hpp"
#include "pmz/decoder.hpp"
#include "pmz/format.hpp"
#include "pmz/node_table.hpp"
#include "pmz/simplify.hpp"
#include "pmz/writer.hpp"
#include "seamed_grid.hpp"
#include "simplify_test_meshes.hpp"
#include "view_select.hpp"  // (decoder/src: the selection's own test of a node against a view)

namespace {

using pmz::IndexedMesh;

IndexedMesh bumpy_sphere(int levels) {
  IndexedMesh m = pmz_test::icosphere(levels);
  for (size_t i = 0; i < m.positions.size(); i += 3) {
    float* p = &m.positions[i];
    const double r =
        1 + 0.08 * std::sin(5 * p[0]) * std::cos(4 * p[1]) + 0.03 * std::sin(17 * p[2] + 3 * p[0]);
    for (int a = 0; a < 3; ++a) p[a] = float(p[a] * r);
  }
  return m;
}

pmz::CollapseSequence clustered(const IndexedMesh& mesh, uint32_t cell_vertices) {
  pmz::SimplifyOptions o;
  o.clusters.vertices = cell_vertices;
  o.clusters.position_bits = 14;
  pmz::CollapseSequence seq;
  std::string error;
  EXPECT_TRUE(pmz::simplify(mesh, o, seq, error)) << error;
  return seq;
}

std::vector<uint8_t> write(const pmz::CollapseSequence& seq) {
  std::vector<uint8_t> bytes;
  std::string error;
  EXPECT_TRUE(pmz::write_pmz(seq, pmz::WriteOptions{}, bytes, error)) << error;
  return bytes;
}

struct Decoded {
  pmz::Status status;
  std::string message;
  uint64_t nodes = 0, splits = 0;
  std::vector<uint32_t> indices;
  std::vector<float> positions;
};

Decoded decode(const std::vector<uint8_t>& bytes, size_t slice = 0) {
  pmz::Decoder d;
  if (slice == 0) slice = bytes.size();
  for (size_t at = 0; at < bytes.size(); at += slice)
    d.feed(bytes.data() + at, std::min(slice, bytes.size() - at));
  d.finish();
  Decoded out;
  out.splits = d.refine();
  out.status = d.status();
  out.message = d.error_message();
  out.nodes = d.info().nodes;
  out.indices.assign(d.indices(), d.indices() + size_t(d.face_count()) * 3);
  out.positions.assign(d.positions(), d.positions() + size_t(d.vertex_count()) * 3);
  return out;
}

// The input's faces in decoded vertex ids, each rotated to start at its smallest id, sorted.
std::vector<std::array<uint32_t, 3>> face_set(const uint32_t* indices, size_t faces,
                                              const std::vector<uint32_t>* rename = nullptr) {
  std::vector<std::array<uint32_t, 3>> out;
  for (size_t f = 0; f < faces; ++f) {
    std::array<uint32_t, 3> t = {indices[f * 3], indices[f * 3 + 1], indices[f * 3 + 2]};
    if (rename)
      for (uint32_t& x : t) x = (*rename)[x];
    while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
    out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The NODE chunk of a stream: where it starts, its size with the header, and its table.
struct NodeChunk {
  size_t at = 0, size = 0;
  pmz::NodeTable table;
};

NodeChunk find_node_chunk(const std::vector<uint8_t>& bytes, uint64_t total_splits) {
  NodeChunk out;
  size_t at = 8;
  while (at < bytes.size()) {
    pmz::ChunkFrame f;
    EXPECT_EQ(pmz::parse_chunk_frame(bytes.data() + at, bytes.size() - at, f),
              pmz::FrameStatus::ok);
    const size_t size = f.header_size + size_t(f.payload_size);
    if (f.type == pmz::kChunkNodes) {
      std::string error;
      out.at = at;
      out.size = size;
      EXPECT_TRUE(pmz::read_node_table(bytes.data() + at + f.header_size, size_t(f.payload_size),
                                       total_splits, 1u << 20, false, true, out.table, error))
          << error;
      return out;
    }
    at += size;
  }
  ADD_FAILURE() << "no NODE chunk";
  return out;
}

// The stream with its NODE chunk replaced by `table`'s.
std::vector<uint8_t> with_table(const std::vector<uint8_t>& bytes, const NodeChunk& c,
                                const pmz::NodeTable& table) {
  std::vector<uint8_t> payload, chunk;
  pmz::write_node_table(payload, table);
  pmz::append_chunk(chunk, pmz::kChunkNodes, payload);
  std::vector<uint8_t> out(bytes.begin(), bytes.begin() + ptrdiff_t(c.at));
  out.insert(out.end(), chunk.begin(), chunk.end());
  out.insert(out.end(), bytes.begin() + ptrdiff_t(c.at + c.size), bytes.end());
  return out;
}

class NodeStream : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    mesh_ = new IndexedMesh(bumpy_sphere(5));
    seq_ = new pmz::CollapseSequence(clustered(*mesh_, 200));
    bytes_ = new std::vector<uint8_t>(write(*seq_));
  }
  static void TearDownTestSuite() {
    delete bytes_;
    delete seq_;
    delete mesh_;
  }
  static IndexedMesh* mesh_;
  static pmz::CollapseSequence* seq_;
  static std::vector<uint8_t>* bytes_;
};
IndexedMesh* NodeStream::mesh_ = nullptr;
pmz::CollapseSequence* NodeStream::seq_ = nullptr;
std::vector<uint8_t>* NodeStream::bytes_ = nullptr;

TEST_F(NodeStream, DecodesToTheInputMeshInEverySlicing) {
  const Decoded whole = decode(*bytes_);
  ASSERT_EQ(whole.status, pmz::Status::ok) << whole.message;
  EXPECT_GT(whole.nodes, 8u);  // levels of cells, not one node
  EXPECT_EQ(whole.splits, seq_->collapses.size());
  // The decoded faces are the input's, vertex for vertex.
  const std::vector<uint32_t> order = pmz::decoded_vertex_order(*seq_, pmz::WriteOptions{});
  ASSERT_EQ(order.size(), mesh_->vertex_count());
  EXPECT_EQ(face_set(whole.indices.data(), whole.indices.size() / 3, &order),
            face_set(mesh_->indices.data(), mesh_->face_count()));
  for (size_t slice : {1, 7, 997}) {
    const Decoded sliced = decode(*bytes_, slice);
    EXPECT_EQ(sliced.status, pmz::Status::ok) << slice;
    EXPECT_EQ(sliced.indices, whole.indices) << slice;
    EXPECT_EQ(sliced.positions, whole.positions) << slice;
  }
}

TEST_F(NodeStream, TheTableMatchesTheNodesAndEveryPrefixOfNodesIsAMesh) {
  const uint64_t total = seq_->collapses.size();
  const NodeChunk c = find_node_chunk(*bytes_, total);
  const pmz::NodeTable& t = c.table;
  ASSERT_GT(t.levels.size(), 2u);
  EXPECT_EQ(t.levels.back().side, 0);  // the last level is the whole mesh
  uint64_t bytes = 0;
  for (const pmz::NodeEntry& n : t.nodes) bytes += n.bytes;
  // The first node's chunks, the NODE chunk, the other nodes' chunks, END (an empty chunk: 6
  // bytes): the nodes' bytes are everything after BASE but the NODE chunk and END.
  const size_t base_end = c.at - size_t(t.nodes[0].bytes);
  EXPECT_EQ(base_end + c.size + bytes + 6, bytes_->size());
  EXPECT_EQ(t.levels[t.nodes[0].level].side, 0);  // the first node is on the whole mesh
  // Parents come first, and a parent's error bound covers its children's.
  const pmz::NodeIndex index(t);
  for (uint32_t k = 0; k < t.nodes.size(); ++k)
    for (uint32_t p : index.parents(k)) {
      EXPECT_LT(p, k);
      EXPECT_GE(t.nodes[p].error, t.nodes[k].error);
    }
  // Refined node by node, the faces grow by each node's count; coarsened to the base and
  // refined again, the mesh is the same.
  pmz::Decoder d;
  ASSERT_EQ(d.feed(bytes_->data(), bytes_->size()), pmz::Status::ok);
  for (const pmz::NodeEntry& n : t.nodes) {
    const uint32_t faces = d.face_count();
    ASSERT_EQ(d.refine(n.splits), n.splits);
    EXPECT_EQ(d.face_count(), faces + n.faces);
  }
  const std::vector<uint32_t> full(d.indices(), d.indices() + size_t(d.face_count()) * 3);
  d.coarsen(total);
  EXPECT_EQ(d.splits_applied(), 0u);
  d.refine();
  EXPECT_EQ(std::vector<uint32_t>(d.indices(), d.indices() + size_t(d.face_count()) * 3), full);
  EXPECT_EQ(d.status(), pmz::Status::ok);
}

// A table that disagrees with the nodes is refused as corrupt, and the splits before the
// disagreement stay applied.
TEST_F(NodeStream, ATableThatDisagreesWithTheNodesIsRefused) {
  const uint64_t total = seq_->collapses.size();
  const NodeChunk c = find_node_chunk(*bytes_, total);
  const size_t last = c.table.nodes.size() - 1;
  auto expect_refused = [&](const pmz::NodeTable& t, const std::string& why) {
    const Decoded d = decode(with_table(*bytes_, c, t));
    EXPECT_EQ(d.status, pmz::Status::corrupt) << why;
    EXPECT_NE(d.message.find(why), std::string::npos) << d.message;
    EXPECT_LT(d.splits, total) << why;
  };
  {
    pmz::NodeTable t = c.table;
    t.nodes[1].bytes += 1;
    expect_refused(t, "shorter than its table entry");
  }
  {
    pmz::NodeTable t = c.table;
    t.nodes[1].bytes -= 1;
    expect_refused(t, "longer than its table entry");
  }
  {
    pmz::NodeTable t = c.table;
    t.nodes[1].faces -= 1;
    expect_refused(t, "added other faces");
  }
  {
    pmz::NodeTable t = c.table;
    t.nodes[last].faces -= 1;
    expect_refused(t, "added other faces");
  }
  {  // a leaf node given another cell (one without a node): its splits find no vertex there
    pmz::NodeTable t = c.table;
    t.nodes[last].cell[0] += 1000;
    expect_refused(t, "split ");
  }
  {  // the split counts moved between two nodes
    pmz::NodeTable t = c.table;
    t.nodes[1].splits -= 1;
    t.nodes[2].splits += 1;
    const Decoded d = decode(with_table(*bytes_, c, t));
    EXPECT_EQ(d.status, pmz::Status::corrupt);
  }
}

// Everything a caller sees of a decoder, after each step of a refine / coarsen schedule.
struct Seen {
  pmz::Status status;
  std::string message;
  std::vector<uint64_t> steps;  // per step: its result, splits applied, faces, change report
  std::vector<uint32_t> indices, parents, modified, wedges;
  std::vector<float> positions;
  bool operator==(const Seen&) const = default;
};

// Which parts of two decodes differ (for the failure message).
std::string differences(const Seen& a, const Seen& b) {
  std::string out;
  if (a.status != b.status || a.message != b.message)
    out += " status: '" + a.message + "' vs '" + b.message + "'";
  if (a.steps != b.steps) {
    size_t i = 0;
    while (i < a.steps.size() && i < b.steps.size() && a.steps[i] == b.steps[i]) ++i;
    out += " steps from " + std::to_string(i) + ": " +
           (i < a.steps.size() ? std::to_string(a.steps[i]) : "-") + " vs " +
           (i < b.steps.size() ? std::to_string(b.steps[i]) : "-");
  }
  if (a.indices != b.indices) out += " indices";
  if (a.positions != b.positions) out += " positions";
  if (a.parents != b.parents) out += " parents";
  if (a.modified != b.modified) out += " modified faces";
  if (a.wedges != b.wedges) out += " wedges";
  return out;
}

// targets: face targets gone to (ascending) before refining to the end.
Seen decode_with(const std::vector<uint8_t>& bytes, uint32_t threads, size_t slice,
                 bool refine_while_feeding, const std::vector<uint64_t>& targets = {}) {
  pmz::Decoder d;
  d.set_threads(threads);
  Seen out;
  auto look = [&] {
    const pmz::MeshChanges& c = d.changes();
    out.steps.insert(out.steps.end(), {d.splits_applied(), d.face_count(), c.vertex_begin,
                                       c.face_begin, c.wedge_begin, c.all ? 1u : 0u});
    out.modified.insert(out.modified.end(), c.modified_faces.begin(), c.modified_faces.end());
    d.clear_changes();
  };
  for (size_t at = 0; at < bytes.size(); at += slice) {
    d.feed(bytes.data() + at, std::min(slice, bytes.size() - at));
    if (refine_while_feeding) {
      out.steps.push_back(d.refine(d.splits_available() / 3));
      look();
    }
  }
  d.finish();
  for (uint64_t faces : targets) {
    d.set_face_target(faces);
    look();
  }
  out.steps.push_back(d.refine());
  look();
  d.set_face_target(d.face_count() / 2);
  look();
  out.steps.push_back(d.coarsen(d.splits_applied() / 3));
  look();
  out.steps.push_back(d.refine());
  look();
  out.status = d.status();
  out.message = d.error_message();
  out.indices.assign(d.indices(), d.indices() + size_t(d.face_count()) * 3);
  out.positions.assign(d.positions(), d.positions() + size_t(d.vertex_count()) * 3);
  out.parents.assign(d.split_parents(), d.split_parents() + d.vertex_count());
  if (d.wedge_count()) {
    out.wedges.assign(d.wedge_indices(), d.wedge_indices() + size_t(d.face_count()) * 3);
    out.wedges.insert(out.wedges.end(), d.wedge_vertices(), d.wedge_vertices() + d.wedge_count());
  }
  return out;
}

// The nodes of a level decode on several threads: the same mesh, ids, change reports and errors
// as on one, however the bytes arrive and whatever the refinement schedule.
void expect_same_on_threads(const std::vector<uint8_t>& bytes,
                            const std::vector<uint64_t>& targets = {}) {
  for (bool feeding : {false, true})
    for (size_t slice : {bytes.size(), size_t(997), size_t(61)}) {
      const Seen one = decode_with(bytes, 1, slice, feeding, targets);
      for (uint32_t threads : {2u, 3u, 8u})
        EXPECT_EQ(differences(one, decode_with(bytes, threads, slice, feeding, targets)), "")
            << threads << " threads, slices of " << slice << (feeding ? ", refining" : "");
    }
}

TEST_F(NodeStream, ThreadsChangeNothing) {
  expect_same_on_threads(*bytes_);
  {  // refined from the base mesh to face targets that end inside nodes
    pmz::Decoder probe;
    probe.feed(bytes_->data(), bytes_->size());
    const uint64_t full = probe.info().full_faces;
    expect_same_on_threads(*bytes_, {full / 7, full / 3 + 1, full / 2 + 2});
  }
  EXPECT_EQ(decode_with(*bytes_, 2, bytes_->size(), false).status, pmz::Status::ok);
  // Damaged tables and nodes: the same errors at the same splits.
  const uint64_t total = seq_->collapses.size();
  const NodeChunk c = find_node_chunk(*bytes_, total);
  for (size_t k : {size_t(1), size_t(2), c.table.nodes.size() / 2, c.table.nodes.size() - 1}) {
    pmz::NodeTable t = c.table;
    t.nodes[k].faces += 1;
    expect_same_on_threads(with_table(*bytes_, c, t));
    t.nodes[k].faces -= 2;  // a node that adds more faces than its entry
    expect_same_on_threads(with_table(*bytes_, c, t));
    t.nodes[k].faces += 1;  // (back, and one node's cell moved)
    t.nodes[k].cell[0] += 1000;
    expect_same_on_threads(with_table(*bytes_, c, t));
    // Moved to a free cell next to its level's others: its first split leaves the cell (for
    // node 1, the first split of the first parallel batch).
    t = c.table;
    int64_t free_x = t.nodes[k].cell[0];
    for (const pmz::NodeEntry& e : t.nodes)
      if (e.level == t.nodes[k].level) free_x = std::max(free_x, e.cell[0] + 1);
    t.nodes[k].cell[0] = free_x;
    const std::vector<uint8_t> moved = with_table(*bytes_, c, t);
    EXPECT_EQ(decode_with(moved, 1, moved.size(), false).status, pmz::Status::corrupt) << k;
    expect_same_on_threads(moved);
  }
  // A bit flipped in a late chunk: its checksum stops the stream there.
  std::vector<uint8_t> flipped = *bytes_;
  const size_t at = flipped.size() - flipped.size() / 5;
  flipped[at] ^= 0x10;
  const Seen one = decode_with(flipped, 1, flipped.size(), false);
  EXPECT_TRUE(decode_with(flipped, 2, flipped.size(), false) == one);
}

// With attributes every node states the wedges it adds, and the decoder holds it to them.
// ---- view-dependent decoding (Decoder::update_view, feed_node) ----

// A camera on the sphere's axis through `dir` at `distance` from its centre, looking at it.
pmz::View view_from(const float dir[3], float distance, float pixel_error) {
  const float eye[3] = {dir[0] * distance, dir[1] * distance, dir[2] * distance};
  const float target[3] = {0, 0, 0};
  return pmz::look_at(eye, target, 1.0f, 800, 600, 1e-3f, pixel_error);
}

// The mesh is closed and crack-free: every directed edge of its faces once, and its opposite
// too; the vertices of its faces hold the whole stream's positions for their ids (ids are the
// table's; but for ids in [own_begin, own_end)), none unused id referenced.
void expect_closed(const pmz::Decoder& d, const std::vector<float>& positions,
                   const std::string& what, uint64_t own_begin = 0, uint64_t own_end = 0) {
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  const uint32_t* ix = d.indices();
  size_t faces = 0;
  for (size_t f = 0; f < d.face_count(); ++f) {
    const uint32_t* t = ix + f * 3;
    if (t[0] == t[1] && t[1] == t[2]) continue;  // (a node not applied)
    ++faces;
    for (int c = 0; c < 3; ++c) {
      edges.push_back({t[c], t[(c + 1) % 3]});
      ASSERT_LT(t[c], d.vertex_count()) << what;
      if (t[c] < own_begin || t[c] >= own_end) {
        EXPECT_EQ(std::vector<float>(d.positions() + t[c] * 3, d.positions() + t[c] * 3 + 3),
                  std::vector<float>(&positions[t[c] * 3], &positions[t[c] * 3 + 3]))
            << what << ": vertex " << t[c];
      }
    }
  }
  std::sort(edges.begin(), edges.end());
  EXPECT_EQ(std::adjacent_find(edges.begin(), edges.end()), edges.end()) << what;
  size_t open = 0;
  for (const auto& [a, b] : edges)
    open += !std::binary_search(edges.begin(), edges.end(), std::pair(b, a));
  EXPECT_EQ(open, 0u) << what << ": " << faces << " faces";
}

// Feeds the stream in order up to its node table (inclusive), as a client reading by ranges.
void feed_to_table(pmz::Decoder& d, const std::vector<uint8_t>& bytes, const NodeChunk& c) {
  ASSERT_EQ(d.feed(bytes.data(), c.at + c.size), pmz::Status::ok) << d.error_message();
  ASSERT_GT(d.info().nodes, 1u);
}

// Node k's bytes as node_range() places them.
std::vector<uint8_t> node_bytes(const pmz::Decoder& d, const std::vector<uint8_t>& bytes,
                                uint32_t k) {
  uint64_t offset = 0, size = 0;
  EXPECT_TRUE(d.node_range(k, offset, size)) << k;
  EXPECT_LE(offset + size, bytes.size());
  return {bytes.begin() + ptrdiff_t(offset), bytes.begin() + ptrdiff_t(offset + size)};
}

// The whole stream decoded in order, its NODE chunk, and a decoder fed up to it.
struct ViewStart {
  Decoded whole;
  NodeChunk c;
  pmz::Decoder d;
  ViewStart(const std::vector<uint8_t>& bytes, uint64_t splits)
      : whole(decode(bytes)), c(find_node_chunk(bytes, splits)) {
    feed_to_table(d, bytes, c);
  }
};

// A view of every node (each one's error spans more than -1 pixel, none culled by its cone).
pmz::View every_node() {
  const float dir[3] = {0, 0, 1};
  pmz::View v = view_from(dir, 20, -1);
  v.cull_facing_away = false;
  return v;
}

TEST_F(NodeStream, AViewOfEveryNodeInAnyOrderIsTheWholeStream) {
  ViewStart v(*bytes_, seq_->collapses.size());
  auto& [whole, c, d] = v;
  const pmz::View all = every_node();
  d.update_view(all);
  EXPECT_FALSE(d.view_complete());
  std::vector<uint32_t> fetch = d.nodes_to_fetch();
  EXPECT_EQ(fetch.size(), c.table.nodes.size() - 1);
  // The node ranges tile the stream from the table's end to the END chunk.
  uint64_t end = c.at + c.size;
  for (uint32_t k = 1; k < c.table.nodes.size(); ++k) {
    uint64_t offset = 0, size = 0;
    ASSERT_TRUE(d.node_range(k, offset, size));
    EXPECT_EQ(offset, end) << k;
    end = offset + size;
  }
  EXPECT_EQ(end + 6, bytes_->size());  // (END: type, payload size 0, crc)
  EXPECT_FALSE(d.node_range(0, end, end));
  // Fed in reverse: each node is applied once its parents are.
  std::reverse(fetch.begin(), fetch.end());
  for (uint32_t k : fetch) {
    const std::vector<uint8_t> b = node_bytes(d, *bytes_, k);
    ASSERT_EQ(d.feed_node(k, b.data(), b.size()), pmz::Status::ok) << d.error_message();
    d.update_view(all, 50);  // (small budgets: a node or so per call)
  }
  while (!d.view_complete() && d.update_view(all, 50)) {
  }
  ASSERT_TRUE(d.view_complete());
  ASSERT_EQ(d.status(), pmz::Status::ok) << d.error_message();
  EXPECT_EQ(d.nodes_applied(), c.table.nodes.size());
  EXPECT_EQ(d.splits_applied(), seq_->collapses.size());
  EXPECT_EQ(std::vector<uint32_t>(d.indices(), d.indices() + size_t(d.face_count()) * 3),
            whole.indices);
  EXPECT_EQ(std::vector<float>(d.positions(), d.positions() + size_t(d.vertex_count()) * 3),
            whole.positions);
  // The level of detail calls leave a view's mesh alone.
  EXPECT_EQ(d.coarsen(10), 0u);
  EXPECT_EQ(d.refine(), 0u);
}

TEST_F(NodeStream, ViewsComeAndGoWithoutCracks) {
  ViewStart v(*bytes_, seq_->collapses.size());
  auto& [whole, c, d] = v;
  // Close views from six sides at several errors, then far: nodes come and go.
  const float dirs[6][3] = {{1, 0, 0},  {0, 1, 0},        {0, 0, 1},
                            {-1, 0, 0}, {0, -0.6f, 0.8f}, {0.6f, 0, -0.8f}};
  uint64_t undone = 0, mixed = 0;
  for (int round = 0; round < 12; ++round) {
    const pmz::View v =
        view_from(dirs[round % 6], round < 6 ? 1.6f : 3.0f, round % 3 ? 0.5f : 4.0f);
    const uint32_t before = d.nodes_applied();
    for (int step = 0; step < 1000 && d.status() == pmz::Status::ok; ++step) {
      d.update_view(v, 300);
      if (d.view_complete()) break;
      for (uint32_t k : d.nodes_to_fetch()) {
        const std::vector<uint8_t> b = node_bytes(d, *bytes_, k);
        ASSERT_EQ(d.feed_node(k, b.data(), b.size()), pmz::Status::ok) << d.error_message();
      }
    }
    ASSERT_TRUE(d.view_complete()) << round;
    ASSERT_EQ(d.status(), pmz::Status::ok) << d.error_message();
    if (d.nodes_applied() < before) ++undone;
    if (d.nodes_applied() > 1 && d.nodes_applied() < c.table.nodes.size()) ++mixed;
    expect_closed(d, whole.positions, "round " + std::to_string(round));
  }
  EXPECT_GT(undone, 0u);  // views that needed fewer nodes than the one before
  EXPECT_GT(mixed, 3u);   // meshes of nodes of several levels, some not applied
  // And back to every node: the whole stream, after all that undoing and re-applying.
  while (!d.view_complete() || d.nodes_applied() < c.table.nodes.size()) {
    d.update_view(every_node());
    for (uint32_t k : d.nodes_to_fetch()) {
      const std::vector<uint8_t> b = node_bytes(d, *bytes_, k);
      ASSERT_EQ(d.feed_node(k, b.data(), b.size()), pmz::Status::ok);
    }
  }
  EXPECT_EQ(std::vector<uint32_t>(d.indices(), d.indices() + size_t(d.face_count()) * 3),
            whole.indices);
}

TEST_F(NodeStream, AViewTakesTheRestOfTheStreamInOrderToo) {
  ViewStart v(*bytes_, seq_->collapses.size());
  auto& [whole, c, d] = v;
  const pmz::View all = every_node();
  d.update_view(all);
  // Some nodes by range, the whole rest of the stream in order in small slices (those nodes'
  // chunks are then skipped), refining as it arrives.
  const std::vector<uint32_t> fetch = d.nodes_to_fetch();
  for (size_t i = 0; i < fetch.size(); i += 3) {
    const std::vector<uint8_t> b = node_bytes(d, *bytes_, fetch[i]);
    ASSERT_EQ(d.feed_node(fetch[i], b.data(), b.size()), pmz::Status::ok);
  }
  for (size_t at = c.at + c.size; at < bytes_->size(); at += 997) {
    ASSERT_EQ(d.feed(bytes_->data() + at, std::min<size_t>(997, bytes_->size() - at)),
              pmz::Status::ok)
        << d.error_message();
    d.update_view(all, 200);
  }
  EXPECT_EQ(d.finish(), pmz::Status::ok);
  d.update_view(all);
  EXPECT_TRUE(d.view_complete());
  EXPECT_EQ(std::vector<uint32_t>(d.indices(), d.indices() + size_t(d.face_count()) * 3),
            whole.indices);
}

// A coarse view holds the ids of coarse nodes only; the nodes after them that then arrive in
// order (a server that ignores Range) wait, outside the mesh arrays, until a view takes them.
TEST_F(NodeStream, NodesArrivingInOrderPastTheIdsAViewHoldsWait) {
  ViewStart v(*bytes_, seq_->collapses.size());
  auto& [whole, c, d] = v;
  const float dir[3] = {0, 0, 1};
  const pmz::View coarse = view_from(dir, 20, 30);
  d.update_view(coarse);
  for (uint32_t k : std::vector<uint32_t>(d.nodes_to_fetch())) {
    const std::vector<uint8_t> b = node_bytes(d, *bytes_, k);
    ASSERT_EQ(d.feed_node(k, b.data(), b.size()), pmz::Status::ok) << d.error_message();
  }
  d.update_view(coarse);
  ASSERT_TRUE(d.view_complete());
  ASSERT_LT(d.vertex_count() * 3, whole.positions.size());  // the last nodes' ids not held
  for (size_t at = c.at + c.size; at < bytes_->size(); at += 997)
    ASSERT_EQ(d.feed(bytes_->data() + at, std::min<size_t>(997, bytes_->size() - at)),
              pmz::Status::ok)
        << d.error_message();
  EXPECT_EQ(d.finish(), pmz::Status::ok);
  d.update_view(every_node());
  EXPECT_TRUE(d.view_complete());
  EXPECT_EQ(std::vector<uint32_t>(d.indices(), d.indices() + size_t(d.face_count()) * 3),
            whole.indices);
}

TEST_F(NodeStream, AViewReportsTheFacesItChanges) {
  const NodeChunk c = find_node_chunk(*bytes_, seq_->collapses.size());
  pmz::Decoder d;
  feed_to_table(d, *bytes_, c);
  for (uint32_t k = 1; k < c.table.nodes.size(); ++k) {
    const std::vector<uint8_t> b = node_bytes(d, *bytes_, k);
    ASSERT_EQ(d.feed_node(k, b.data(), b.size()), pmz::Status::ok);
  }
  const float near_dir[3] = {1, 0, 0}, far_dir[3] = {0, 0, 1};
  std::vector<uint32_t> seen(d.indices(), d.indices() + size_t(d.face_count()) * 3);
  d.clear_changes();
  for (const pmz::View& v : {view_from(near_dir, 1.6f, 0.5f), view_from(far_dir, 1.6f, 0.5f),
                             view_from(far_dir, 6, 2)}) {
    ASSERT_GT(d.update_view(v), 0u);
    const pmz::MeshChanges& ch = d.changes();
    if (ch.all) {
      seen.assign(d.indices(), d.indices() + size_t(d.face_count()) * 3);
      d.clear_changes();
      continue;
    }
    std::vector<uint8_t> listed(d.face_count(), 0), used(d.vertex_count(), 0);
    for (uint32_t f : ch.modified_faces) listed[f] = 1;
    for (uint32_t x : seen) used[x] = 1;
    size_t changed = 0;
    for (uint32_t f = 0; f < d.face_count(); ++f)
      if (f * 3 >= seen.size() ||
          !std::equal(&seen[f * 3], &seen[f * 3 + 3], d.indices() + f * 3)) {
        ++changed;
        EXPECT_TRUE(f >= ch.face_begin || listed[f]) << "face " << f << " changed unreported";
        for (int a = 0; a < 3; ++a)  // a vertex new to the faces: among the new vertices
          EXPECT_TRUE(used[d.indices()[f * 3 + a]] || d.indices()[f * 3 + a] >= ch.vertex_begin);
      }
    EXPECT_GT(changed, 0u);
    seen.assign(d.indices(), d.indices() + size_t(d.face_count()) * 3);
    d.clear_changes();
  }
}

// The mesh arrays hold the ids up to the last node in file order applied: a view of coarse
// nodes holds fewer than the stream's, they grow (reported as new) for finer ones, and the view
// of every node holds them all.
TEST_F(NodeStream, AViewHoldsTheIdsOfTheNodesItApplied) {
  ViewStart v(*bytes_, seq_->collapses.size());
  auto& [whole, c, d] = v;
  const float dir[3] = {0, 0, 1};
  const pmz::View coarse = view_from(dir, 6, 2);
  for (int step = 0; step < 100 && !d.view_complete(); ++step) {
    d.update_view(coarse);
    for (uint32_t k : d.nodes_to_fetch()) {
      const std::vector<uint8_t> b = node_bytes(d, *bytes_, k);
      ASSERT_EQ(d.feed_node(k, b.data(), b.size()), pmz::Status::ok) << d.error_message();
    }
  }
  ASSERT_TRUE(d.view_complete());
  ASSERT_LT(d.nodes_applied(), c.table.nodes.size());
  // Through the last node applied: the faces of the nodes up to it, in file order.
  uint64_t faces = whole.indices.size() / 3, vertices = whole.positions.size() / 3;
  for (size_t k = c.table.nodes.size(); k-- > 1 && faces > d.face_count();) {
    faces -= c.table.nodes[k].faces;
    vertices -= c.table.nodes[k].splits;
  }
  EXPECT_EQ(d.face_count(), faces);
  EXPECT_EQ(d.vertex_count(), vertices);
  EXPECT_LT(d.face_count(), whole.indices.size() / 3);
  expect_closed(d, whole.positions, "coarse");
  const uint32_t held = d.face_count(), held_vertices = d.vertex_count();
  d.clear_changes();
  while (!d.view_complete() || d.nodes_applied() < c.table.nodes.size()) {
    d.update_view(every_node());
    for (uint32_t k : d.nodes_to_fetch()) {
      const std::vector<uint8_t> b = node_bytes(d, *bytes_, k);
      ASSERT_EQ(d.feed_node(k, b.data(), b.size()), pmz::Status::ok) << d.error_message();
    }
  }
  EXPECT_LE(d.changes().face_begin, held);
  EXPECT_LE(d.changes().vertex_begin, held_vertices);
  EXPECT_EQ(std::vector<uint32_t>(d.indices(), d.indices() + size_t(d.face_count()) * 3),
            whole.indices);
}

// The stream as format 13.0 writes it: HEAD's minor version 0, so the cones are bytes after
// the table that a decoder ignores (spec/format.md section 15.1).
std::vector<uint8_t> as_minor_zero(std::vector<uint8_t> bytes) {
  pmz::ChunkFrame f;
  EXPECT_EQ(pmz::parse_chunk_frame(bytes.data() + 8, bytes.size() - 8, f), pmz::FrameStatus::ok);
  EXPECT_EQ(f.type, pmz::kChunkHead);
  bytes[8 + f.header_size + 1] = 0;
  pmz::repair_chunk_crc(bytes.data() + 8, f);
  return bytes;
}

// Every node whose own sphere meets the view, whose error bound spans more than the pixel error
// and whose normal cone does not face away is applied once the view is complete, with its
// parents, even those whose spheres lie outside the frustum, whose errors are smaller on screen
// (a node's cell meets up to eight parents' per coarser level) or which face away. A node facing
// away that no node needs as a parent is not applied; without cones (format 13.0) none is left.
void expect_view_applies_what_it_sees(const std::vector<uint8_t>& bytes, uint64_t splits,
                                      bool cones) {
  ViewStart v(bytes, splits);
  auto& [whole, c, d] = v;
  const std::vector<pmz::NodeEntry>& table = c.table.nodes;
  std::vector<uint64_t> first_face(table.size());
  uint64_t faces = d.info().base_faces;
  for (size_t k = 0; k < table.size(); ++k) {
    first_face[k] = faces;
    faces += table[k].faces;
  }
  const float dirs[4][3] = {{1, 0, 0}, {0, 0.6f, 0.8f}, {-0.8f, 0, -0.6f}, {0, -1, 0}};
  size_t seen = 0, parent_unseen = 0, culled = 0, culled_parent = 0;
  for (int round = 0; round < 8; ++round) {
    const pmz::View view = view_from(dirs[round % 4], 1.2f, round < 4 ? 0 : 0.5f);
    for (int step = 0; step < 1000; ++step) {
      d.update_view(view);
      if (d.view_complete()) break;
      for (uint32_t k : d.nodes_to_fetch()) {
        const std::vector<uint8_t> b = node_bytes(d, bytes, k);
        ASSERT_EQ(d.feed_node(k, b.data(), b.size()), pmz::Status::ok) << d.error_message();
      }
    }
    ASSERT_TRUE(d.view_complete()) << round;
    std::vector<uint8_t> needed(table.size(), 0), away(table.size(), 0);
    for (size_t k = table.size(); k-- > 1;) {
      const float e = pmz::projected_error(view, table[k]);
      away[k] = cones && pmz::faces_away(view, table[k]);
      const bool sees = e > view.pixel_error || (view.pixel_error <= 0 && e >= 0);
      culled_parent += sees && away[k] && needed[k];
      needed[k] = needed[k] || (sees && !away[k]);
      culled += sees && away[k] && !needed[k];
      seen += needed[k] && e >= 0;
      if (!needed[k]) continue;
      for (uint32_t p : pmz::NodeIndex(c.table).parents(uint32_t(k))) {
        parent_unseen += !needed[p] && pmz::projected_error(view, table[p]) < 0;
        needed[p] = 1;
      }
    }
    for (size_t k = 1; k < table.size(); ++k) {
      const uint32_t* t = d.indices() + first_face[k] * 3;
      const bool applied = first_face[k] < d.face_count() && !(t[0] == t[1] && t[1] == t[2]);
      EXPECT_EQ(applied, bool(needed[k])) << "round " << round << ", node " << k;
    }
    expect_closed(d, whole.positions, "round " + std::to_string(round));
  }
  EXPECT_GT(seen, 0u);
  EXPECT_GT(parent_unseen, 0u);  // (the cases this is about did occur)
  if (cones) {
    EXPECT_GT(culled, 0u);
    EXPECT_GT(culled_parent, 0u);
  }
}

TEST_F(NodeStream, AViewAppliesEveryNodeItSeesWithItsParents) {
  expect_view_applies_what_it_sees(*bytes_, seq_->collapses.size(), true);
}

TEST_F(NodeStream, AStreamWithoutConesSelectsByFrustumAndErrorAlone) {
  const std::vector<uint8_t> old = as_minor_zero(*bytes_);
  pmz::Decoder d;
  d.feed(old.data(), old.size());
  EXPECT_EQ(d.info().version_minor, 0u);
  expect_view_applies_what_it_sees(old, seq_->collapses.size(), false);
}

// Every cone holds the normals of its node's faces (spec/format.md section 15.5): the faces with
// a corner among the node's vertices, right after its last split in file order and in the full
// mesh, at the decoded positions; and most nodes of a smooth surface have a cone.
TEST_F(NodeStream, EveryConeHoldsItsNodesFaces) {
  const NodeChunk c = find_node_chunk(*bytes_, seq_->collapses.size());
  ASSERT_TRUE(c.table.cones);
  pmz::Decoder d;
  ASSERT_EQ(d.feed(bytes_->data(), bytes_->size()), pmz::Status::ok);
  d.finish();
  const std::vector<pmz::NodeEntry>& table = c.table.nodes;
  std::vector<uint64_t> first_split(table.size() + 1, 0);
  for (size_t k = 0; k < table.size(); ++k) first_split[k + 1] = first_split[k] + table[k].splits;
  size_t with_cone = 0, checked = 0;
  auto check = [&](size_t k, const char* when) {
    const pmz::NodeEntry& n = table[k];
    if (!n.has_cone()) return;
    double axis[3], len = 0;
    for (int a = 0; a < 3; ++a) len += double(n.cone_axis[a]) * n.cone_axis[a];
    for (int a = 0; a < 3; ++a) axis[a] = n.cone_axis[a] / std::sqrt(len);
    const double least = std::sqrt(1 - (n.cone_cutoff / 127.0) * (n.cone_cutoff / 127.0));
    const uint32_t first = d.info().base_vertices + uint32_t(first_split[k]);
    const uint32_t end = first + uint32_t(n.splits);
    const float* p = d.positions();
    for (uint32_t f = 0; f < d.face_count(); ++f) {
      const uint32_t* t = d.indices() + size_t(f) * 3;
      if (!((t[0] >= first && t[0] < end) || (t[1] >= first && t[1] < end) ||
            (t[2] >= first && t[2] < end)))
        continue;
      double e[2][3], nrm[3];
      for (int a = 0; a < 3; ++a) {
        e[0][a] = double(p[t[1] * 3 + a]) - p[t[0] * 3 + a];
        e[1][a] = double(p[t[2] * 3 + a]) - p[t[0] * 3 + a];
      }
      for (int a = 0; a < 3; ++a)
        nrm[a] = e[0][(a + 1) % 3] * e[1][(a + 2) % 3] - e[0][(a + 2) % 3] * e[1][(a + 1) % 3];
      const double l = std::sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
      if (!(l > 0)) continue;
      EXPECT_GE((nrm[0] * axis[0] + nrm[1] * axis[1] + nrm[2] * axis[2]) / l, least - 1e-9)
          << when << ", node " << k << ", face " << f;
      ++checked;
    }
  };
  for (size_t k = 0; k < table.size(); ++k) {
    d.refine(first_split[k + 1] - d.splits_applied());
    ASSERT_EQ(d.splits_applied(), first_split[k + 1]);
    check(k, "as the node leaves them");
    with_cone += table[k].has_cone();
  }
  for (size_t k = 0; k < table.size(); ++k) check(k, "in the full mesh");
  EXPECT_GT(with_cone, table.size() / 2);
  EXPECT_GT(checked, size_t(d.face_count()));
}

// The faces drawn: those of the nodes applied (the others' are degenerate).
uint64_t drawn_faces(const pmz::Decoder& d) {
  uint64_t n = 0;
  for (size_t f = 0; f < d.face_count(); ++f) {
    const uint32_t* t = d.indices() + f * 3;
    n += !(t[0] == t[1] && t[1] == t[2]);
  }
  return n;
}

// update_view() until the view is complete, feeding what nodes_to_fetch() lists; the nodes
// fetched.
std::vector<uint32_t> settle(pmz::Decoder& d, const std::vector<uint8_t>& bytes,
                             const pmz::View& view) {
  std::vector<uint32_t> fetched;
  for (int step = 0; step < 1000 && d.status() == pmz::Status::ok; ++step) {
    d.update_view(view);
    if (d.view_complete()) break;
    for (uint32_t k : d.nodes_to_fetch()) {
      const std::vector<uint8_t> b = node_bytes(d, bytes, k);
      EXPECT_EQ(d.feed_node(k, b.data(), b.size()), pmz::Status::ok) << d.error_message();
      fetched.push_back(k);
    }
  }
  EXPECT_TRUE(d.view_complete());
  EXPECT_EQ(d.status(), pmz::Status::ok) << d.error_message();
  return fetched;
}

// A face budget (set_view_face_budget): the nodes a view applies keep the faces within it, are
// closed under parents and are among those the view needs without it; each node the view sees
// that is left out would have brought the faces past the budget with its parents not applied;
// only nodes the budget admits are fetched; a lower budget undoes nodes; 0 is no budget.
TEST_F(NodeStream, AFaceBudgetBoundsTheFacesAViewApplies) {
  ViewStart v(*bytes_, seq_->collapses.size());
  auto& [whole, c, d] = v;
  const std::vector<pmz::NodeEntry>& table = c.table.nodes;
  const pmz::NodeIndex index(c.table);
  std::vector<uint64_t> first_face(table.size());
  uint64_t faces = d.info().base_faces;
  for (size_t k = 0; k < table.size(); ++k) {
    first_face[k] = faces;
    faces += table[k].faces;
  }
  const auto applied = [&](const pmz::Decoder& x) {
    std::vector<uint8_t> out(table.size(), 0);
    out[0] = 1;
    for (size_t k = 1; k < table.size(); ++k) {
      const uint32_t* t = x.indices() + first_face[k] * 3;
      out[k] = first_face[k] < x.face_count() && !(t[0] == t[1] && t[1] == t[2]);
    }
    return out;
  };
  // The views without a budget, on a decoder whose budget was set and then set to 0.
  const float dirs[4][3] = {{1, 0, 0}, {0, 0.6f, 0.8f}, {-0.8f, 0, -0.6f}, {0, -1, 0}};
  std::vector<pmz::View> views;
  for (int round = 0; round < 4; ++round)
    views.push_back(view_from(dirs[round], 1.2f, round % 2 ? 0.5f : 0));
  pmz::Decoder free;
  feed_to_table(free, *bytes_, c);
  free.set_view_face_budget(100);
  free.set_view_face_budget(0);
  std::vector<std::vector<uint8_t>> wanted;
  uint64_t least = UINT64_MAX;
  for (const pmz::View& view : views) {
    settle(free, *bytes_, view);
    wanted.push_back(applied(free));
    least = std::min(least, drawn_faces(free));
  }
  const uint64_t budget = least * 6 / 10;
  ASSERT_GT(budget, d.info().base_faces + table[0].faces);
  d.set_view_face_budget(budget);
  size_t left_out = 0;
  for (int round = 0; round < 8; ++round) {
    const pmz::View& view = views[round % 4];
    const std::vector<uint32_t> fetched = settle(d, *bytes_, view);
    const std::vector<uint8_t> now = applied(d);
    const std::string what = "round " + std::to_string(round);
    uint64_t sum = d.info().base_faces;
    for (size_t k = 0; k < table.size(); ++k) {
      if (!now[k]) continue;
      sum += table[k].faces;
      EXPECT_TRUE(wanted[round % 4][k]) << what << ": node " << k << " is not needed";
      for (uint32_t p : index.parents(uint32_t(k)))
        EXPECT_TRUE(now[p]) << what << ": node " << k << " without its parent " << p;
    }
    EXPECT_EQ(drawn_faces(d), sum) << what;
    EXPECT_LE(sum, budget) << what;
    EXPECT_GT(sum, d.info().base_faces + table[0].faces) << what;
    for (uint32_t k : fetched) EXPECT_TRUE(now[k]) << what << ": node " << k << " fetched, unused";
    for (size_t k = 1; k < table.size(); ++k) {  // (a parent only is taken with a child)
      const float e = pmz::projected_error(view, table[k]);
      const bool seen = (e > view.pixel_error || (view.pixel_error <= 0 && e >= 0)) &&
                        !pmz::faces_away(view, table[k]);  // (its cone facing away: not seen)
      if (!seen || now[k]) continue;
      ++left_out;
      std::vector<uint8_t> taken = now;  // k with its parents not applied
      std::vector<uint32_t> stack = {uint32_t(k)};
      uint64_t more = 0;
      taken[k] = 1;
      while (!stack.empty()) {
        const uint32_t x = stack.back();
        stack.pop_back();
        more += table[x].faces;
        for (uint32_t p : index.parents(x))
          if (!taken[p]) stack.push_back(p), taken[p] = 1;
      }
      EXPECT_GT(sum + more, budget) << what << ": node " << k << " fits, left out";
    }
    expect_closed(d, whole.positions, what);
  }
  EXPECT_GT(left_out, 0u);  // (the budget did leave nodes out)
  // A lower budget undoes nodes; one below node 0's faces leaves node 0 alone.
  const std::vector<uint8_t> before = applied(d);
  d.set_view_face_budget(budget / 2);
  EXPECT_GT(d.update_view(views[3]), 0u);
  EXPECT_LE(drawn_faces(d), budget / 2);
  const std::vector<uint8_t> lower = applied(d);
  size_t undone = 0;
  for (size_t k = 1; k < table.size(); ++k) undone += before[k] && !lower[k];
  EXPECT_GT(undone, 0u);
  settle(d, *bytes_, views[3]);
  EXPECT_LE(drawn_faces(d), budget / 2);
  expect_closed(d, whole.positions, "half the budget");
  d.set_view_face_budget(1);
  d.update_view(views[3]);
  EXPECT_TRUE(d.view_complete());
  EXPECT_TRUE(d.nodes_to_fetch().empty());
  EXPECT_EQ(d.nodes_applied(), 1u);
  // No budget again: the view's nodes without one, the free decoder's faces.
  d.set_view_face_budget(0);
  settle(d, *bytes_, views[3]);
  EXPECT_EQ(applied(d), wanted[3]);
  const auto drawn = [](const pmz::Decoder& x) {
    std::vector<std::array<uint32_t, 4>> out;
    for (uint32_t f = 0; f < x.face_count(); ++f) {
      const uint32_t* t = x.indices() + size_t(f) * 3;
      if (!(t[0] == t[1] && t[1] == t[2])) out.push_back({f, t[0], t[1], t[2]});
    }
    return out;
  };
  EXPECT_EQ(drawn(d), drawn(free));
}

TEST_F(NodeStream, ANodesBytesAreChecked) {
  const NodeChunk c = find_node_chunk(*bytes_, seq_->collapses.size());
  const uint32_t last = uint32_t(c.table.nodes.size() - 1);
  auto fresh = [&](pmz::Decoder& d) { feed_to_table(d, *bytes_, c); };
  {  // another node's bytes
    pmz::Decoder d;
    fresh(d);
    const std::vector<uint8_t> b = node_bytes(d, *bytes_, 1);
    EXPECT_NE(d.feed_node(last, b.data(), b.size()), pmz::Status::ok);
    EXPECT_NE(d.error_message().find("node " + std::to_string(last)), std::string::npos)
        << d.error_message();
    EXPECT_GT(d.face_count(), 0u);  // the mesh stays (node 0's)
  }
  {  // cut short, a byte changed, no such node
    pmz::Decoder d1, d2, d3;
    fresh(d1);
    fresh(d2);
    fresh(d3);
    std::vector<uint8_t> b = node_bytes(d1, *bytes_, 2);
    EXPECT_EQ(d1.feed_node(2, b.data(), b.size() - 1), pmz::Status::corrupt);
    b[b.size() / 2] ^= 0x20;
    EXPECT_EQ(d2.feed_node(2, b.data(), b.size()), pmz::Status::bad_checksum);
    EXPECT_EQ(d3.feed_node(last + 1, b.data(), b.size()), pmz::Status::corrupt);
    for (pmz::Decoder* d : {&d1, &d2, &d3}) {
      EXPECT_EQ(d->update_view(every_node()), 0u);
      EXPECT_FALSE(d->view_complete());
    }
  }
  {  // damage past the checksums (repaired): found as the node is first applied, part way
     // through its splits (those it applied are taken back and its faces left degenerate), or
     // in a descendant
    const Decoded whole = decode(*bytes_);
    int refused = 0;
    for (uint32_t k = 1; k <= last; ++k) {
      pmz::Decoder d;
      fresh(d);
      std::vector<uint8_t> b = node_bytes(d, *bytes_, k);
      pmz::ChunkFrame f;
      ASSERT_EQ(pmz::parse_chunk_frame(b.data(), b.size(), f), pmz::FrameStatus::ok);
      b[f.header_size + size_t(f.payload_size) * 3 / 4] ^= 0x5a;
      pmz::repair_chunk_crc(b.data(), f);
      d.update_view(every_node());
      if (d.feed_node(k, b.data(), b.size()) != pmz::Status::ok) continue;  // (its tables)
      for (int round = 0; round < 50 && !d.view_complete() && d.status() == pmz::Status::ok;
           ++round) {
        for (uint32_t j : d.nodes_to_fetch()) {
          const std::vector<uint8_t> other = node_bytes(d, *bytes_, j);
          d.feed_node(j, other.data(), other.size());
        }
        d.update_view(every_node(), 200);
      }
      if (d.status() == pmz::Status::ok) continue;  // (a change that decodes)
      ++refused;
      // A change that keeps every rule in node k (a residual) gives its own vertices other
      // positions and is found, if at all, in a descendant, which alone is taken back.
      uint64_t own = d.info().base_vertices;
      for (uint32_t j = 0; j < k; ++j) own += c.table.nodes[j].splits;
      expect_closed(d, whole.positions, "node " + std::to_string(k) + " damaged", own,
                    own + c.table.nodes[k].splits);
    }
    EXPECT_GT(refused, 0);
  }
}

TEST(NodeStreamAttributes, WedgesPerNodeAreChecked) {
  const IndexedMesh mesh = pmz_test::seamed_grid(60, 23);
  const pmz::CollapseSequence seq = clustered(mesh, 150);
  const std::vector<uint8_t> bytes = write(seq);
  const Decoded whole = decode(bytes);
  ASSERT_EQ(whole.status, pmz::Status::ok) << whole.message;
  EXPECT_GT(whole.nodes, 4u);
  EXPECT_EQ(whole.splits, seq.collapses.size());
  expect_same_on_threads(bytes);  // (attributes: decoded on one thread whatever the count)
  // The table, read with the attribute fields: the wedges it states add up to the full count.
  NodeChunk c;
  size_t at = 8;
  while (at < bytes.size() && !c.size) {
    pmz::ChunkFrame f;
    ASSERT_EQ(pmz::parse_chunk_frame(bytes.data() + at, bytes.size() - at, f),
              pmz::FrameStatus::ok);
    if (f.type == pmz::kChunkNodes) {
      std::string error;
      ASSERT_TRUE(pmz::read_node_table(bytes.data() + at + f.header_size, size_t(f.payload_size),
                                       seq.collapses.size(), 1u << 20, true, true, c.table, error))
          << error;
      c.at = at;
      c.size = f.header_size + size_t(f.payload_size);
    }
    at += f.header_size + size_t(f.payload_size);
  }
  ASSERT_TRUE(c.size);
  pmz::Decoder d;
  ASSERT_EQ(d.feed(bytes.data(), bytes.size()), pmz::Status::ok);
  const uint32_t base_wedges = [&] {
    d.refine(0);
    return d.wedge_count();
  }();
  uint64_t wedges = 0;
  for (const pmz::NodeEntry& n : c.table.nodes) wedges += n.wedges;
  d.refine();
  EXPECT_EQ(base_wedges + wedges, d.wedge_count());
  pmz::NodeTable t = c.table;
  t.nodes[1].wedges += 1;
  const Decoded bad = decode(with_table(bytes, c, t));
  EXPECT_EQ(bad.status, pmz::Status::corrupt);
  EXPECT_NE(bad.message.find("faces or wedges"), std::string::npos) << bad.message;
}

// A reader in file order shows every split whose chunk arrived: the bytes that arrived but do
// not show yet (the SPLT and ATTR chunks not complete) stay within the larger of 2 KB and 3% of
// the bytes so far, and the first splits show after a few hundred bytes.
TEST(StreamingLag, ChunksStayWithinTheLagBound) {
  for (const bool nodes : {false, true}) {
    const IndexedMesh mesh = bumpy_sphere(6);
    pmz::CollapseSequence seq;
    if (nodes) {
      seq = clustered(mesh, 400);
    } else {
      std::string error;
      ASSERT_TRUE(pmz::simplify(mesh, pmz::SimplifyOptions{}, seq, error)) << error;
    }
    const std::vector<uint8_t> bytes = write(seq);
    size_t at = 8, shown = 0, first = 0, chunks = 0;
    while (at < bytes.size()) {
      pmz::ChunkFrame f;
      ASSERT_EQ(pmz::parse_chunk_frame(bytes.data() + at, bytes.size() - at, f),
                pmz::FrameStatus::ok);
      const size_t end = at + f.header_size + size_t(f.payload_size);
      // A SPLT chunk shows with its ATTR chunk (none here); HEAD, BASE and NODE carry no split.
      if (f.type == pmz::kChunkSplits) {
        const size_t lag = end - 1 - std::max(shown, at);
        EXPECT_LE(double(lag), std::max(2048.0, 0.03 * double(end - 1))) << "chunk at " << at;
        if (!first) first = end;
        shown = end;
        ++chunks;
      } else if (f.type != pmz::kChunkEnd) {
        shown = end;  // (nothing in it waits to show)
      }
      at = end;
    }
    EXPECT_LE(first, 600u) << nodes;
    EXPECT_GT(chunks, 10u) << nodes;
    const Decoded d = decode(bytes);
    EXPECT_EQ(d.status, pmz::Status::ok) << d.message;
    EXPECT_EQ(d.splits, seq.collapses.size());
  }
}

TEST(NodeTable, ReadBackAndRefusedWhenMalformed) {
  pmz::NodeTable t;
  t.levels = {{4, {-3, 0, 5}}, {8, {-1, 2, 7}}, {0, {0, 0, 0}}};
  auto node = [](uint32_t level, int64_t x, int64_t y, int64_t z, uint64_t splits) {
    pmz::NodeEntry n;
    n.level = level;
    n.cell[0] = x, n.cell[1] = y, n.cell[2] = z;
    n.splits = splits;
    n.faces = splits * 2;
    n.bytes = 10 + splits;
    n.center[0] = 1.5f;
    n.radius = 2;
    n.error = 0.25f;
    return n;
  };
  t.nodes = {node(2, 0, 0, 0, 5), node(1, 0, 0, 0, 3), node(1, -1, 0, 0, 2), node(0, 0, 0, 0, 4)};
  std::vector<uint8_t> payload;
  pmz::write_node_table(payload, t);
  pmz::NodeTable back;
  std::string error;
  ASSERT_TRUE(
      pmz::read_node_table(payload.data(), payload.size(), 14, 100, false, false, back, error))
      << error;
  ASSERT_EQ(back.nodes.size(), 4u);
  EXPECT_EQ(back.levels[1].origin[0], -1);
  EXPECT_EQ(back.nodes[2].cell[0], -1);
  EXPECT_EQ(back.nodes[3].bytes, 14u);
  EXPECT_EQ(pmz::NodeIndex(back).parents(3), (std::vector<uint32_t>{0, 1, 2}));
  // Every prefix is refused, and so is a table whose counts do not add up to HEAD's.
  for (size_t n = 0; n < payload.size(); ++n)
    EXPECT_FALSE(pmz::read_node_table(payload.data(), n, 14, 100, false, false, back, error)) << n;
  EXPECT_FALSE(
      pmz::read_node_table(payload.data(), payload.size(), 15, 100, false, false, back, error));
  EXPECT_FALSE(
      pmz::read_node_table(payload.data(), payload.size(), 13, 100, false, false, back, error));
  auto refused = [&](pmz::NodeTable bad, const std::string& why) {
    std::vector<uint8_t> p;
    pmz::write_node_table(p, bad);
    EXPECT_FALSE(pmz::read_node_table(p.data(), p.size(), 14, 100, false, false, back, error))
        << why;
    EXPECT_NE(error.find(why), std::string::npos) << error;
  };
  pmz::NodeTable bad = t;
  std::swap(bad.nodes[0], bad.nodes[3]);  // a leaf before its parents
  refused(bad, "before one of its parents");
  bad = t;
  bad.nodes[2].cell[0] = 0;  // two nodes in one cell
  refused(bad, "two nodes");
  bad = t;
  bad.levels[1].side = 2;  // cells smaller than the level below's
  refused(bad, "smaller");
  bad = t;
  bad.levels[0].side = 0;  // a level without cells that is not the last
  refused(bad, "without cells");
  bad = t;
  bad.nodes[1].error = NAN;
  refused(bad, "finite");
  bad = t;
  bad.nodes[3].faces = 9;
  refused(bad, "two per split");
}

// faces_away (spec/format.md section 15.5's test): a cone facing the eye's way, a cone across
// the view, an eye inside the sphere and no cone are not culled; the cutoff's limit is where the
// text puts it; and whenever a node is culled, every normal of its cone makes a dot product >= 0
// with every point of its sphere as seen from the eye (sampled).
TEST(ViewSelect, ANodeFacesAwayOnlyWhenItsWholeSphereDoes) {
  const float eye[3] = {0, 0, 10}, target[3] = {0, 0, 0};
  const pmz::View view = pmz::look_at(eye, target, 1.0f, 800, 600, 1e-3f, 1);
  pmz::NodeEntry n;
  n.radius = 1;
  n.cone_axis[2] = -127;  // normals along -z: away from the eye
  n.cone_cutoff = 0;
  EXPECT_TRUE(pmz::faces_away(view, n));
  n.cone_axis[2] = 127;
  EXPECT_FALSE(pmz::faces_away(view, n));
  n.cone_axis[2] = 0;
  n.cone_axis[0] = 127;  // edge-on at the centre, towards the eye at some points of the sphere
  EXPECT_FALSE(pmz::faces_away(view, n));
  n.cone_axis[0] = 0;
  n.cone_axis[2] = -127;
  n.cone_cutoff = 114;  // 10 >= s 10 + 1 while s <= 0.9 = 114.3 / 127
  EXPECT_TRUE(pmz::faces_away(view, n));
  n.cone_cutoff = 115;
  EXPECT_FALSE(pmz::faces_away(view, n));
  n.cone_cutoff = 0;
  n.radius = 20;  // the eye inside the sphere
  EXPECT_FALSE(pmz::faces_away(view, n));
  n.radius = 1;
  n.cone_cutoff = 255;  // no cone
  EXPECT_FALSE(pmz::faces_away(view, n));
  std::mt19937 rng(7);
  auto uniform = [&](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  size_t culled = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    pmz::NodeEntry m;
    for (int a = 0; a < 3; ++a) {
      m.center[a] = float(uniform(-3, 3));
      m.cone_axis[a] = int8_t(std::lround(uniform(-127, 127)));
    }
    m.radius = float(uniform(0, 1.5));
    m.cone_cutoff = uint8_t(std::lround(uniform(0, 127)));
    if (!m.has_cone() || !pmz::faces_away(view, m)) continue;
    ++culled;
    double a[3], len = 0;
    for (int k = 0; k < 3; ++k) len += double(m.cone_axis[k]) * m.cone_axis[k];
    for (int k = 0; k < 3; ++k) a[k] = m.cone_axis[k] / std::sqrt(len);
    const double t = std::asin(m.cone_cutoff / 127.0);
    for (int sample = 0; sample < 50; ++sample) {
      // A unit normal within the cone (at its rim every other time), a point in the sphere.
      double w[3], wa = 0, wl = 0, p[3], dot = 0;
      for (int k = 0; k < 3; ++k) w[k] = uniform(-1, 1), wa += w[k] * a[k];
      for (int k = 0; k < 3; ++k) w[k] -= wa * a[k], wl += w[k] * w[k];
      if (!(wl > 1e-12)) continue;
      const double phi = sample % 2 ? t : uniform(0, t);
      for (int k = 0; k < 3; ++k) {
        p[k] = m.center[k] + m.radius * uniform(-1, 1) / std::sqrt(3.0);
        dot += (std::cos(phi) * a[k] + std::sin(phi) * w[k] / std::sqrt(wl)) * (p[k] - eye[k]);
      }
      EXPECT_GE(dot, -1e-6) << trial;
    }
  }
  EXPECT_GT(culled, 100u);
}

// Format 13.1's cones follow the last node (spec/format.md section 15.1): read back as written,
// a table cut inside them refused, bytes after them ignored; read as 13.0 (cones = false), they
// are such bytes and no node has a cone.
TEST(NodeTable, ConesReadBackAndAShortBlockIsRefused) {
  pmz::NodeTable t;
  t.levels = {{4, {0, 0, 0}}, {0, {0, 0, 0}}};
  t.cones = true;
  for (int k = 0; k < 3; ++k) {
    pmz::NodeEntry n;
    n.level = k == 0 ? 1 : 0;
    n.cell[0] = k;
    n.splits = 2;
    n.bytes = 9;
    n.cone_axis[0] = int8_t(-127 + k);
    n.cone_axis[2] = int8_t(5 * k);
    n.cone_cutoff = uint8_t(k == 2 ? 255 : 40 + k);
    t.nodes.push_back(n);
  }
  std::vector<uint8_t> payload;
  pmz::write_node_table(payload, t);
  std::vector<uint8_t> without;
  t.cones = false;
  pmz::write_node_table(without, t);
  ASSERT_EQ(payload.size(), without.size() + 12);
  pmz::NodeTable back;
  std::string error;
  ASSERT_TRUE(
      pmz::read_node_table(payload.data(), payload.size(), 6, 100, false, true, back, error))
      << error;
  ASSERT_TRUE(back.cones);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(back.nodes[k].cone_axis[0], -127 + k);
    EXPECT_EQ(back.nodes[k].cone_axis[1], 0);
    EXPECT_EQ(back.nodes[k].cone_axis[2], 5 * k);
    EXPECT_EQ(back.nodes[k].cone_cutoff, k == 2 ? 255 : 40 + k);
    EXPECT_EQ(back.nodes[k].has_cone(), k < 2);
  }
  for (size_t n = without.size(); n < payload.size(); ++n) {
    EXPECT_FALSE(pmz::read_node_table(payload.data(), n, 6, 100, false, true, back, error)) << n;
    EXPECT_NE(error.find("cones end early"), std::string::npos) << error;
  }
  payload.push_back(7);  // (a later minor's field)
  EXPECT_TRUE(
      pmz::read_node_table(payload.data(), payload.size(), 6, 100, false, true, back, error));
  ASSERT_TRUE(
      pmz::read_node_table(payload.data(), payload.size(), 6, 100, false, false, back, error));
  EXPECT_FALSE(back.cones);
  for (const pmz::NodeEntry& n : back.nodes) EXPECT_FALSE(n.has_cone());
}

}  // namespace
