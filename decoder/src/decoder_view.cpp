// SPDX-License-Identifier: MIT
// Decoding for a view (Decoder::update_view): nodes of a stream's table applied and undone one at
// a time, fetched by byte ranges (per node and per frame; the state: decoder_impl.hpp).
#include <queue>

#include "decoder_impl.hpp"
#include "view_select.hpp"

namespace pmz {

// Node 0 is applied and nothing after it: the chunks that arrived in order go to their nodes'
// readers, and the nodes' parents and cells are set up. The mesh arrays grow as a view wants
// nodes (cover_node_ids): a view of a large stream that needs its coarse nodes only, which come
// first in file order, holds their ids only.
bool Decoder::Impl::enter_selection() {
  const std::vector<NodeEntry>& table = nodes.table.nodes;
  const size_t total = table.size();
  if (!node_counts_match(0))
    return refuse(Status::corrupt, "node 0 added other faces or wedges than its table entry");
  PMZ_TRY {
    sel.parents.assign(total, {});
    sel.children.assign(total, {});
    const NodeIndex index(nodes.table);
    for (uint32_t k = 1; k < total; ++k) {
      sel.parents[k] = index.parents(k);
      for (uint32_t p : sel.parents[k]) sel.children[p].push_back(k);
    }
    sel.decoded.assign(total, 0);
    sel.applied.assign(total, 0);
    sel.sectors.assign(total, {});
    sel.priority.assign(total, 0);
    sel.decoded[0] = sel.applied[0] = 1;
    sel.bins.assign(nodes.table.levels.size(), {});
    for (uint32_t l = 0; l < nodes.table.levels.size(); ++l)
      if (nodes.table.levels[l].side > 0)
        sel.bins[l].build(nodes.table, l, record.coords.data(), node_first_vertex(1));
  }
  PMZ_CATCH_BAD_ALLOC {
    fail(Status::out_of_memory, "allocation failed for the node graph");
    return false;
  }
  // The chunks that arrived in order, node after node from node 1 on.
  sel.available = nodes.first_split[1];
  for (size_t k = 1; k < total && !frontier.lazy.empty(); ++k) {
    for (uint64_t got = 0; got < table[k].splits && !frontier.lazy.empty();
         frontier.lazy.pop_front()) {
      got += frontier.lazy.front().split_count();
      sel.readers[k].push_back(std::move(frontier.lazy.front()));
    }
    sel.arrival[k] = k < nodes.arriving ? Selection::whole : Selection::partial;
    if (k < nodes.arriving) sel.available += table[k].splits;
  }
  sel.id_nodes = 1;
  nodes.first_models = std::move(nodes.models[0]);
  sel.applied_nodes = 1;
  sel.on = true;
  level.changes.all = true;
  return true;
}

// The mesh arrays through node k's ids (those of the nodes before it in file order unused:
// degenerate faces), grown by half again at least so that a camera moving in small steps does
// not copy them each time. False when that fails (the mesh is as it was).
bool Decoder::Impl::cover_node_ids(uint32_t k) {
  if (k < sel.id_nodes) return true;
  const std::vector<NodeEntry>& table = nodes.table.nodes;
  const uint64_t splits = nodes.first_split[k] + table[k].splits;
  const uint64_t nv = node_first_vertex(k) + table[k].splits;
  const uint64_t nf = sel.first_face[k] + table[k].faces;
  const uint64_t f0 = level.mesh.face_count(), v0 = level.mesh.vertex_count();
  auto room = [](auto& v, uint64_t n, uint64_t full) {
    if (n > v.capacity())
      v.reserve(size_t(std::min(full, std::max<uint64_t>(n, v.capacity() + v.capacity() / 2))));
  };
  PMZ_TRY {
    room(level.mesh.corner_vertex, nf * 3, info.full_faces * 3);
    room(level.mesh.opposite, nf * 3, info.full_faces * 3);
    room(level.mesh.vertex_corner, nv, info.full_vertices);
    room(record.coords, nv * 3, info.full_vertices * 3);
    room(record.positions, nv * 3, info.full_vertices * 3);
    room(record.parents, nv, info.full_vertices);
    room(record.sides, splits, info.total_splits);
    room(record.splits, splits, info.total_splits);
    frontier.choice.reserve_vertices(level.mesh.vertex_corner.capacity());
  }
  PMZ_CATCH_BAD_ALLOC {
    fail(Status::out_of_memory, "allocation failed for node " + PMZ_DECIMAL(k) + "'s ids");
    return false;
  }
  level.mesh.corner_vertex.resize(nf * 3, 0);
  level.mesh.opposite.resize(nf * 3, kNoCorner);
  level.mesh.vertex_corner.resize(nv, kNoCorner);
  record.coords.resize(nv * 3);
  record.positions.resize(nv * 3);
  record.parents.resize(nv, 0xFFFFFFFFu);
  record.sides.resize(splits);
  record.splits.resize(splits, {kNoCorner, kNoRank, kNoRank});
  frontier.choice.resize_vertices(nv);
  level.changes.face_begin = std::min(level.changes.face_begin, uint32_t(f0));
  level.changes.vertex_begin = std::min(level.changes.vertex_begin, uint32_t(v0));
  sel.id_nodes = k + 1;
  return true;
}

// The candidates of node k (spec/format.md section 15.4): the vertices of BASE, node 0 and its
// other parents (all applied) that lie in its cell, ascending.
std::vector<uint32_t> Decoder::Impl::cell_list(uint32_t k) {
  const NodeEntry& e = nodes.table.nodes[k];
  const std::span<const uint32_t> binned = sel.bins[e.level].bin(k);
  std::vector<uint32_t> out(binned.begin(), binned.end());
  const CellBox box(nodes.table.levels[e.level], e.cell);
  for (uint32_t p : sel.parents[k]) {
    if (p == 0) continue;  // (binned)
    for (uint32_t x = node_first_vertex(p), end = x + uint32_t(nodes.table.nodes[p].splits);
         x < end; ++x)
      if (box.contains(&record.coords[size_t(x) * 3])) out.push_back(x);
  }
  return out;
}

// The first application of node k's splits, on a worker's view of the mesh at its ids; what
// re-applying them needs is kept. A failure leaves none of them applied and fails the stream.
bool Decoder::Impl::first_apply_node(uint32_t k) {
  const NodeEntry& e = nodes.table.nodes[k];
  const uint64_t first = nodes.first_split[k], last = first + e.splits;
  if (!cover_node_ids(k)) return false;
  auto owned = std::make_unique<Frontier>();
  Frontier& w = *owned;
  start_worker(w, k, node_first_vertex(k), sel.first_face[k],
               frontier.choice.take_epochs(e.splits + 1), cell_list(k), sel.ring_work);
  w.ring_shift = int64_t(sel.first_applied) - int64_t(first);
  w.lazy = std::move(sel.readers[k]);
  node_models(k, w.lazy);
  first_apply_worker(w, last);
  if (w.decoded != last || w.view.face_count() != w.face_end) {
    undo_worker(w, first);
    clear_node_faces(k);
    std::string what = w.message;
    Status st = w.status;
    if (st == Status::ok) {
      st = Status::corrupt;
      what = "node " + PMZ_DECIMAL(k) + " added other faces or wedges than its table entry";
    }
    fail(st, what);
    return false;
  }
  sel.ring_work = w.ring_work;
  sel.first_applied += e.splits;
  sel.sectors[k].assign(w.sectors.begin(), w.sectors.end());
  sel.decoded[k] = 1;
  drop_models(k);
  uint64_t corners = 0;
  for (uint64_t t = first; t < last; ++t) {
    note_rewritten<3>({w.sectors.data() + corners, record.splits[t].b}, level.mesh.face_count());
    corners += record.splits[t].b;
  }
  return true;
}

// Node k again (decoded before, its parents applied, its children not): from its sector lists.
void Decoder::Impl::reapply_node(uint32_t k) {
  const uint64_t first = nodes.first_split[k], last = first + nodes.table.nodes[k].splits;
  sel.walker.attach(level.mesh, node_first_vertex(k), uint32_t(sel.first_face[k]));
  const uint32_t* sector = sel.sectors[k].data();
  for (uint64_t t = first; t < last; ++t) {
    const Split& x = record.splits[t];
    const uint8_t side = record.sides[t];
    sel.walker.resplit_listed(x.v, sector, x.b, x.a, side & kHasLeft, side & kHasRight);
    sector += x.b;
    note_rewritten(sel.walker.sector_faces(), level.mesh.face_count());
  }
}

// Takes node k's splits back (its children not applied): the last first. Its faces become
// degenerate.
void Decoder::Impl::undo_node(uint32_t k) {
  const NodeEntry& e = nodes.table.nodes[k];
  const uint64_t first = nodes.first_split[k], last = first + e.splits;
  sel.walker.attach(level.mesh, uint32_t(node_first_vertex(k) + e.splits),
                    uint32_t(sel.first_face[k] + e.faces));
  for (uint64_t t = last; t-- > first;) {
    const Split& x = record.splits[t];
    const uint8_t side = record.sides[t];
    sel.walker.undo_resplit(x.v, x.a, x.b, side & kHasLeft, side & kHasRight);
    note_rewritten(sel.walker.sector_faces(), level.mesh.face_count());
  }
  clear_node_faces(k);
}

// Node k's face numbers, not applied: degenerate faces (0, 0, 0), reported as changed.
void Decoder::Impl::clear_node_faces(uint32_t k) {
  const NodeEntry& e = nodes.table.nodes[k];
  note_face_range(sel.first_face[k], e.faces);
  const size_t c0 = size_t(sel.first_face[k]) * 3, c1 = c0 + size_t(e.faces) * 3;
  std::fill(level.mesh.corner_vertex.begin() + ptrdiff_t(c0),
            level.mesh.corner_vertex.begin() + ptrdiff_t(c1), 0u);
  std::fill(level.mesh.opposite.begin() + ptrdiff_t(c0),
            level.mesh.opposite.begin() + ptrdiff_t(c1), kNoCorner);
}

// Node k's bytes from a range (Decoder::feed_node): its chunks, checked against its entry.
Status Decoder::Impl::node_bytes(uint32_t k, const uint8_t* p, size_t n) {
  const NodeEntry& e = nodes.table.nodes[k];
  input.chunk_offset = sel.offset[k];
  auto bad = [&](Status st, const std::string& why) {
    return fail(st, "node " + PMZ_DECIMAL(k) + ": " + why);
  };
  if (n != e.bytes)
    return bad(Status::corrupt,
               PMZ_DECIMAL(n) + " bytes where its table entry has " + PMZ_DECIMAL(e.bytes));
  auto models = std::make_unique<SplitModels>();
  models->speed = info.level == kLevelSpeed;
  std::deque<SplitChunkReader> readers;
  OpenGroup open;
  uint64_t got = 0;
  for (size_t at = 0; at < n;) {
    input.chunk_offset = sel.offset[k] + at;
    ChunkFrame f;
    if (parse_chunk_frame(p + at, n - at, f) != FrameStatus::ok ||
        f.payload_size > n - at - f.header_size)
      return bad(Status::corrupt, "a chunk runs past its bytes");
    const uint8_t* payload = p + at + f.header_size;
    if (chunk_crc(p + at, f, payload) != f.crc)
      return bad(Status::bad_checksum, "chunk checksum mismatch");
    if (f.type != kChunkSplits) return bad(Status::corrupt, "a chunk other than SPLT");
    SplitChunkReader r;
    std::string err;
    if (!r.open(payload, size_t(f.payload_size), e.splits - got, *models, err, open))
      return bad(Status::corrupt, err);
    open = r.open_group();
    got += r.split_count();
    readers.push_back(std::move(r));
    at += f.header_size + size_t(f.payload_size);
  }
  if (got != e.splits) return bad(Status::corrupt, "fewer splits than its table entry");
  const uint64_t first = nodes.first_split[k];
  // (Those past the arrays' end: cover_node_ids fills them so.)
  const uint64_t held = std::min<uint64_t>(record.splits.size(), first + e.splits);
  if (first < held)
    std::fill(record.splits.begin() + ptrdiff_t(first), record.splits.begin() + ptrdiff_t(held),
              Split{kNoCorner, kNoRank, kNoRank});
  sel.readers[k] = std::move(readers);
  nodes.models[k] = std::move(models);
  sel.arrival[k] = Selection::whole;
  sel.available += e.splits;
  return Status::ok;
}

// The nodes the face budget admits (Decoder::set_view_face_budget) of those a view wants: the
// ones it sees (want 2) in `order`, each with its parents not yet taken, while the faces stay
// within the budget. want keeps those taken (1).
void Decoder::Impl::within_face_budget(std::vector<uint8_t>& want,
                                       const std::vector<uint32_t>& order) {
  const std::vector<NodeEntry>& table = nodes.table.nodes;
  std::vector<uint8_t> taken(want.size(), 0);
  std::vector<uint32_t> group;
  taken[0] = 1;
  uint64_t faces = info.base_faces + table[0].faces;
  for (uint32_t k : order) {
    if (want[k] != 2 || taken[k] || faces + table[k].faces > sel.face_budget) continue;
    group.assign(1, k);  // k and its ancestors not taken (marked while the group is open)
    taken[k] = 1;
    uint64_t more = 0;
    for (size_t i = 0; i < group.size(); ++i) {
      more += table[group[i]].faces;
      for (uint32_t p : sel.parents[group[i]])
        if (!taken[p]) taken[p] = 1, group.push_back(p);
    }
    if (faces + more <= sel.face_budget)
      faces += more;
    else
      for (uint32_t x : group) taken[x] = 0;
  }
  want.swap(taken);
}

// Whether nodes are applied one by one (see Selection): entered once node 0 is applied (refined
// first, within budget; n counts those splits).
bool Decoder::Impl::selection(uint64_t budget, uint64_t& n) {
  if (sel.on) return true;
  if (sel.in_order || stage == Stage::failed) return false;
  if (!(info.flags & kFlagNodes) || attrs ||
      (nodes.present && frontier.decoded > nodes.first_split[1])) {
    sel.in_order = true;
    return false;
  }
  if (!nodes.present) return false;
  n += refine(std::min(budget, nodes.first_split[1] - level.applied), UINT64_MAX);
  return level.applied == nodes.first_split[1] && enter_selection();
}

uint64_t Decoder::Impl::update_view(const View& v, uint64_t budget) {
  sel.fetch.clear();
  sel.complete = false;
  if (stage == Stage::failed || !info.base_done) return 0;
  uint64_t n = 0;
  if (!selection(budget, n)) {
    if (sel.on || stage == Stage::failed) return n;
    n += refine(budget - std::min(budget, n), UINT64_MAX);  // (before the table: node 0)
    sel.complete = sel.in_order && info.complete && level.applied == info.total_splits;
    return n;
  }
  const std::vector<NodeEntry>& table = nodes.table.nodes;
  const size_t total = table.size();
  std::vector<uint8_t> want(total, 0);
  want[0] = 1;
  // The nodes the view sees in enough detail and not facing away (spec/format.md section 15.5), and
  // their parents whatever their own spheres, errors and cones (a node's cell meets up to eight
  // parents' on each coarser level; the parents come first in file order, so one pass from the
  // last node up reaches every ancestor).
  for (size_t k = total; k-- > 1;) {
    sel.priority[k] = projected_error(v, table[k]);
    if ((sel.priority[k] > v.pixel_error || (v.pixel_error <= 0 && sel.priority[k] >= 0)) &&
        !(v.cull_facing_away && faces_away(v, table[k])))
      want[k] = 2;  // (seen; 1: a parent only)
    if (want[k])
      for (uint32_t p : sel.parents[k]) want[p] = 1;
  }
  PMZ_TRY {
    // The nodes it wants, the largest projected error first (file order among equals): the
    // order the face budget takes them in and, level by level, the order to fetch them in.
    std::vector<uint32_t> order;
    std::priority_queue<std::pair<float, uint32_t>> heap;
    for (uint32_t k = 1; k < total; ++k)
      if (want[k]) heap.push({sel.priority[k], ~k});
    for (; !heap.empty(); heap.pop()) order.push_back(~heap.top().second);
    if (sel.face_budget) within_face_budget(want, order);
    // Room for the ids of every node the view wants at once: grown node by node, the arrays'
    // old copies would add up (WebAssembly memory keeps its high-water mark).
    for (size_t k = total; k-- > 1;)
      if (want[k]) {
        if (!cover_node_ids(uint32_t(k))) return n;
        break;
      }
    // What the view no longer needs, children first (they follow their parents in file order).
    for (size_t k = total; k-- > 1 && n < budget;)
      if (sel.applied[k] && !want[k]) {
        undo_node(uint32_t(k));
        sel.applied[k] = 0;
        sel.applied_splits -= table[k].splits;
        --sel.applied_nodes;
        n += table[k].splits;
      }
    // What it needs, ready (arrived, parents applied), the largest projected error first.
    auto ready = [&](uint32_t k) {
      if (!want[k] || sel.applied[k] || (!sel.decoded[k] && sel.arrival[k] != Selection::whole))
        return false;
      for (uint32_t p : sel.parents[k])
        if (!sel.applied[p]) return false;
      return true;
    };
    for (uint32_t k = 1; k < total; ++k)
      if (ready(k)) heap.push({sel.priority[k], k});
    while (!heap.empty() && n < budget) {
      const uint32_t k = heap.top().second;
      heap.pop();
      if (sel.applied[k]) continue;
      level.changes.vertex_begin = std::min(level.changes.vertex_begin, node_first_vertex(k));
      if (sel.decoded[k])
        reapply_node(k);
      else if (!first_apply_node(k))
        return n;
      note_face_range(sel.first_face[k], table[k].faces);
      sel.applied[k] = 1;
      sel.applied_splits += table[k].splits;
      ++sel.applied_nodes;
      n += table[k].splits;
      for (uint32_t c : sel.children[k])
        if (ready(c)) heap.push({sel.priority[c], c});
    }
    sel.complete = true;
    for (uint32_t l = uint32_t(nodes.table.levels.size()); l-- > 0;)  // (parents' levels first)
      for (uint32_t k : order) {
        if (table[k].level != l || !want[k] || sel.applied[k]) continue;
        sel.complete = false;
        if (!sel.decoded[k] && sel.arrival[k] != Selection::whole) sel.fetch.push_back(k);
      }
  }
  PMZ_CATCH_BAD_ALLOC { fail(Status::out_of_memory, "allocation failed while refining"); }
  return n;
}

bool Decoder::node_range(uint32_t k, uint64_t& offset, uint64_t& size) const {
  const Impl& d = *impl_;
  if (!d.nodes.present || k == 0 || k >= d.nodes.table.nodes.size()) return false;
  offset = d.sel.offset[k];
  size = d.nodes.table.nodes[k].bytes;
  return true;
}

Status Decoder::feed_node(uint32_t k, const void* data, size_t size) {
  Impl& d = *impl_;
  if (d.stage == Stage::failed) return d.status;
  if (!d.nodes.present || k == 0 || k >= d.nodes.table.nodes.size())
    return d.fail(Status::corrupt, "feed_node: no node " + PMZ_DECIMAL(k) + " in the table");
  if (d.sel.arrival[k] == Impl::Selection::whole || (d.sel.on && d.sel.decoded[k])) return d.status;
  uint64_t refined = 0;  // (node 0 first: its splits all arrived with the table)
  if (!d.selection(UINT64_MAX, refined)) return d.status;  // in file order: bytes by feed()
  PMZ_TRY { return d.node_bytes(k, static_cast<const uint8_t*>(data), size); }
  PMZ_CATCH_BAD_ALLOC { return d.fail(Status::out_of_memory, "allocation failed"); }
}

uint64_t Decoder::update_view(const View& view, uint64_t max_splits) {
  return impl_->update_view(view, max_splits);
}
void Decoder::set_view_face_budget(uint64_t faces) { impl_->sel.face_budget = faces; }
bool Decoder::view_complete() const { return impl_->sel.complete; }
const std::vector<uint32_t>& Decoder::nodes_to_fetch() const { return impl_->sel.fetch; }
uint32_t Decoder::nodes_applied() const {
  const Impl& d = *impl_;
  if (d.sel.on) return d.sel.applied_nodes;
  uint32_t n = 0;  // in file order: the nodes whose splits are all applied
  for (size_t k = 0; k < d.nodes.first_split.size(); ++k)
    n += d.level.applied >= d.nodes.first_split[k] + d.nodes.table.nodes[k].splits;
  return n;
}

}  // namespace pmz
