// SPDX-License-Identifier: MIT
// The streaming decoder's state (Decoder::Impl), shared by its sources: decoder.cpp, the
// refinement loop (first applications, re-applying and undoing splits: per split work);
// decoder_stream.cpp, the framing and the chunks (per chunk); decoder_view.cpp, decoding for a
// view (per node and per frame). The WebAssembly build optimizes only the first for speed, the
// others for size (scripts/web.sh).
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <deque>
#include <limits>
#include <new>
#include <span>
#include <type_traits>

#include "attribute_stream.hpp"
#include "pmz/base_codec.hpp"
#include "pmz/decoder.hpp"
#include "pmz/fan_wedge.hpp"
#include "pmz/format.hpp"
#include "pmz/node_table.hpp"
#include "pmz/progressive_mesh.hpp"
#include "pmz/speed_level.hpp"
#include "pmz/split_chunk.hpp"
#include "pmz/vertex_choice.hpp"
#include "pmz/wasm_hints.hpp"

// noclone is GCC's: clang has no such attribute and warns (-Wunknown-attributes).
#if defined(__clang__)
#define PMZ_OUT_OF_LINE [[gnu::noinline]]
#else
#define PMZ_OUT_OF_LINE [[gnu::noinline, gnu::noclone]]
#endif

// Chunk framing, the once-per-chunk and the error paths: PMZ_SMALL_IN_WASM (range_coder.hpp),
// e.g. the base mesh decoder inlined into parse by the WebAssembly build's LTO.
#if defined(__wasm__)
#define PMZ_COLD [[gnu::cold, clang::minsize]]
#else
#define PMZ_COLD [[gnu::cold]]
#endif

namespace pmz {

constexpr uint8_t kHasLeft = 1, kHasRight = 2;

// Where the stream is: waiting for HEAD, then BASE, then taking SPLT chunks until END
// (complete); failed after the first error (the mesh stays usable at its last good level).
enum class Stage : uint8_t { header, base, splits, complete, failed };

struct Decoder::Impl {
  DecoderLimits limits;
  Stage stage = Stage::header;
  Status status = Status::ok;  // the first error once stage is failed
  std::string message;
  StreamInfo info;
  Quantizer quant;  // HEAD's

  // Framing: chunks out of whatever slices arrive.
  struct Input {
    uint64_t consumed = 0;         // bytes fed
    std::vector<uint8_t> pending;  // bytes of an incomplete signature or chunk
    bool signature_done = false;
    uint64_t chunk_index = 0, chunk_offset = 0;
    uint64_t chunk_bytes = 0;  // of the chunk being interpreted, header included
    uint64_t parse_base = 0;   // stream offset of the buffer parse() is looking at
  } input;

  // What was decoded, kept to move between levels without re-reading bytes.
  // Available splits: v once its group was decoded (kNoCorner before). From the first application
  // on (below frontier.decoded), a and b are what re-applying needs (ProgressiveMesh::resplit): the
  // sector hint and the sector count (and sides[i] its sides); before, only transiently, the
  // decoded wedge ranks.
  struct Split {
    uint32_t v, a, b;
  };
  // Buffers sized by split counts grow to the header's total_splits at once when that is at
  // most kHeaderTrust times what the decoded input holds (so a lying header cannot make the
  // decoder reserve more than a bounded multiple of its input).
  static constexpr uint64_t kHeaderTrust = 16;
  // Whether buffers holding `splits` splits may grow to the header's count at once (above):
  // in a stream with nodes, not up to the end of node 0, where a view-dependent client leaves
  // file order to hold only the ids of the nodes it applies (WebAssembly memory, once grown, is
  // never given back).
  bool header_trusted(uint64_t splits) const {
    return info.total_splits <= kHeaderTrust * splits &&
           (!(info.flags & kFlagNodes) || (nodes.present && splits > nodes.first_split[1]));
  }
  struct Record {
    BigVector<Split> splits;
    BigVector<uint8_t> sides;   // per split below frontier.decoded: kHasLeft | kHasRight
    uint64_t available = 0;     // splits of the chunks arrived (splits.size())
    BigVector<int32_t> coords;  // 3 per computed vertex (computed >= vertex_count)
    BigVector<float> positions;
    BigVector<uint32_t> parents;
    // Per split below frontier.decoded, in order: its sector's fan entries
    // (ProgressiveMesh::sector_corners(), splits[i].b of them), so that re-applying a split
    // reads them from here instead of walking the fan along opposite.
    BigVector<uint32_t> sector_corners;
  } record;

  // The first-application frontier: splits below `decoded` have their symbols decoded; the
  // symbols of the others wait in their chunk readers, decoded with contexts from the mesh.
  struct Frontier {
    ProgressiveMesh* mesh = nullptr;  // level.mesh, or a worker's view of it
    // The node being applied (a stream with nodes): its cell's box, whether it has a cell, and
    // (a worker's) the face count its table entry ends at.
    CellBox box;
    bool cells = false;
    uint64_t face_end = 0;
    // A worker's: its splits' sector corners and ring sizes, in order, and how it stopped.
    BigVector<uint32_t> sectors;
    std::vector<uint32_t> rings;
    Status status = Status::ok;
    std::string message;
    bool paused = false;  // before split `decoded`, whose faces would pass face_end
    ProgressiveMesh view;
    FanPrefetcher fans;  // (a worker's: the serial decoder's is level.fans)
    // Chunks whose wedge and residual symbols are not all decoded yet, oldest first; the front
    // one starts at split lazy_first.
    std::deque<SplitChunkReader> lazy;
    std::unique_ptr<SplitModels>
        models;  // the file's context models (spec/format.md section 8: carried across chunks)
    uint64_t lazy_first = 0, decoded = 0;
    WedgeScratch wedge_scratch;
    uint32_t wedge_scratch_ring = 0;  // wedge_scratch has room for rings up to this size
    VertexChoice choice;              // degrees and neighbourhoods at the frontier
    std::vector<uint32_t> group_vs;
    uint64_t group_first = 0;  // the first split of the group being found
    bool choice_ok = false;    // its scan can continue (else splits without a vertex are refused)
    uint64_t ring_work = 0;    // sum of ring sizes over first applications
    // The ring-work bound allows kRingWorkPerSplit per first application: split i is the
    // (i + 1 + ring_shift)-th (a view's node worker: its node's place among the splits the view
    // first applied, in whatever order the view took the nodes; otherwise 0, file order).
    int64_t ring_shift = 0;
    // Bounding box of the coordinates, its largest side as wedge_scratch.extent (64-bit scores
    // unchecked).
    int32_t box_lo[3] = {INT32_MAX, INT32_MAX, INT32_MAX},
            box_hi[3] = {INT32_MIN, INT32_MIN, INT32_MIN};
    void grow_box(const int32_t* c) {
      bool grew = false;
      for (int a = 0; a < 3; ++a) {
        if (c[a] < box_lo[a]) box_lo[a] = c[a], grew = true;
        if (c[a] > box_hi[a]) box_hi[a] = c[a], grew = true;
      }
      if (!grew) return;
      uint64_t extent = 0;
      for (int a = 0; a < 3; ++a)
        extent = std::max<uint64_t>(extent, uint64_t(int64_t(box_hi[a]) - box_lo[a]));
      wedge_scratch.extent = extent;
    }
    // Continues the scan of the group being found (lazy.front()'s) until `upto` of its vertices
    // are known (within what the lag allows: the caller applied enough of its splits), into
    // splits[].v; a failure leaves the splits without a vertex, refused when reached.
    // A group the front chunk's end cuts: its vertices are found ahead, those of splits in
    // chunks yet to come kept in `ahead` until their chunk arrives.
    void find_vertices(uint32_t upto, BigVector<Split>& splits) {
      if (!choice_ok) return;
      const uint32_t before = choice.found();
      group_vs.clear();
      choice_ok = lazy.front().find(choice, nullptr, upto, group_vs);
      for (size_t i = 0; i < group_vs.size(); ++i) {
        const uint64_t at = group_first + before + i;
        if (at < splits.size())
          splits[at].v = group_vs[i];
        else
          ahead.push_back(group_vs[i]);
      }
    }
    std::vector<uint32_t> ahead;  // (at most kChoiceLag + 1)
    OpenGroup open;               // the group the last chunk arrived cuts
  } frontier;
  static constexpr uint64_t kRingWorkPerSplit = 64, kRingWorkSlack = 1u << 22;

  // The current level: the mesh, how many splits it has applied, what changed since the
  // caller last looked, and the prefetcher of the refinement loop.
  struct Level {
    ProgressiveMesh mesh;
    uint64_t applied = 0;
    uint64_t sector_end = 0;    // record.sector_corners of the splits below `applied`
    uint64_t listed_ahead = 0;  // record.sector_corners prefetched up to here (re-applying)
    MeshChanges changes;
    FanPrefetcher fans;
  } level;

  // Attributes (spec/format.md section 14): null for a stream without them, so their cost there is
  // one branch per split. base_geometry: BASE decoded, its ATTR chunk awaited (stage stays base);
  // attr_awaited: the last SPLT chunk's ATTR chunk has not arrived (its splits are not
  // available yet).
  std::unique_ptr<AttributeStream> attrs;
  double* attribute_bits = nullptr;  // Decoder::count_attribute_bits()
  bool base_geometry = false, attr_awaited = false;
  std::unique_ptr<std::pair<ProgressiveMesh, std::vector<int32_t>>> pending_base;  // its coords
  std::vector<MaterialInfo> materials;

  // A stream in nodes (HEAD flag bit 1, spec/format.md section 15): the table; where the
  // arriving chunks are (node, its splits and bytes so far) and each node's models, made when
  // its first chunk arrives and dropped once its splits are decoded; where the first
  // applications are (the node applied last, its start) and the candidates of the level binned
  // last.
  struct Nodes {
    bool present = false;
    NodeTable table;
    std::vector<uint64_t> first_split;  // per node
    size_t arriving = 0;
    uint64_t arrived_splits = 0, arrived_bytes = 0;
    std::vector<std::unique_ptr<SplitModels>> models;  // per node
    // The models the first node left (its split and attribute models): every later node's
    // start.
    std::unique_ptr<SplitModels> first_models;
    // A node after the first has its models made as its first application starts (node_models);
    // until then its chunks' groups are decoded with the group models of `arrival` (those of
    // the node arriving). spare: the models of a node done, for one to come (memory already
    // touched).
    std::unique_ptr<SplitModels> arrival, spare;
    std::unique_ptr<AttributeModels> first_attribute_models;
    size_t applying = 0;  // nodes whose first application started
    uint64_t start_faces = 0, start_wedges = 0;
    CellBins bins;
    int64_t bins_level = -1;
  } nodes;
  PMZ_COLD Status node_chunk(const uint8_t* p, size_t n);
  PMZ_COLD std::unique_ptr<SplitModels> first_models_copy();
  PMZ_COLD SplitModels& node_models(size_t k, std::deque<SplitChunkReader>& readers);
  // Models done with: kept for a node to come.
  void spare_models(std::unique_ptr<SplitModels>& m) noexcept {
    if (m) nodes.spare = std::move(m);
  }
  void drop_models(size_t k) noexcept { spare_models(nodes.models[k]); }
  PMZ_COLD Status node_arrived(uint64_t bytes, bool attributes_done);
  PMZ_COLD bool start_node();
  // The faces and wedges node k (the one applied last) added are its table entry's.
  bool node_counts_match(size_t k) const {
    const NodeEntry& e = nodes.table.nodes[k];
    return level.mesh.face_count() - nodes.start_faces == e.faces &&
           (!attrs || attrs->state.wedge_count - nodes.start_wedges == e.wedges);
  }

  // View-dependent decoding (Decoder::update_view): once node 0 is applied, nodes are applied
  // and undone one at a time at the ids the table fixes (spec/format.md section 15.4: only some
  // nodes, each after its parents). `on`: the mesh arrays hold every id (those of nodes not
  // applied: unused vertices, degenerate faces) and the serial refine and coarsen stop.
  // `in_order`: refined past node 0 before (or a stream this does not cover): update_view
  // refines in file order.
  struct Selection {
    enum Arrival : uint8_t { none, partial, whole };  // partial: being fed in order
    bool on = false, in_order = false;
    uint64_t nodes_start = 0;  // stream offset of node 1's bytes (the NODE chunk's end)
    std::vector<uint64_t> offset, first_face;  // per node: its bytes' offset, its first face
    std::vector<std::vector<uint32_t>> parents, children;
    std::vector<uint8_t> arrival, decoded, applied;
    std::vector<std::deque<SplitChunkReader>> readers;  // per node, until first applied
    std::vector<std::vector<uint32_t>> sectors;  // per decoded node: its splits' sector corners
    std::vector<CellBins> bins;                  // per level: BASE's and node 0's vertices by cell
    std::vector<float> priority;  // per node: pixels its error spans in the last view
    std::vector<uint32_t> fetch;  // see Decoder::nodes_to_fetch
    uint64_t available = 0, applied_splits = 0, ring_work = 0;
    uint64_t first_applied = 0;  // splits a view first-applied (the ring-work bound's count)
    uint32_t applied_nodes = 0;
    uint32_t id_nodes = 0;     // the mesh arrays hold the ids of nodes [0, id_nodes)
    uint64_t face_budget = 0;  // see Decoder::set_view_face_budget (0: none)
    bool complete = false;
    ProgressiveMesh walker;  // re-applies and undoes nodes (attached; keeps its ring scratch)
  } sel;
  uint32_t node_first_vertex(size_t k) const {
    return uint32_t(info.base_vertices + nodes.first_split[k]);
  }
  PMZ_COLD bool enter_selection();
  PMZ_COLD bool cover_node_ids(uint32_t k);
  PMZ_COLD std::vector<uint32_t> cell_list(uint32_t k);
  PMZ_COLD bool first_apply_node(uint32_t k);
  PMZ_COLD void reapply_node(uint32_t k);
  PMZ_COLD void undo_node(uint32_t k);
  PMZ_COLD void clear_node_faces(uint32_t k);
  PMZ_COLD Status node_bytes(uint32_t k, const uint8_t* p, size_t n);
  PMZ_COLD bool selection(uint64_t budget, uint64_t& n);
  PMZ_COLD uint64_t update_view(const View& v, uint64_t budget);
  PMZ_COLD void within_face_budget(std::vector<uint8_t>& want, const std::vector<uint32_t>& order);

  // Error paths and the once-per-file HEAD are cold: kept small, out of the hot code's way
  // (the stripped library has a 200 KB budget).
  PMZ_COLD Status fail(Status s, const std::string& what) {
    stage = Stage::failed;
    status = s;
    message = std::string("pmz: ") + status_name(s) + ": " + what + " (chunk " +
              PMZ_DECIMAL(input.chunk_index) + " at byte " + PMZ_DECIMAL(input.chunk_offset) + ")";
    return s;
  }
  PMZ_SMALL_IN_WASM size_t parse(const uint8_t* p, size_t n);
  PMZ_SMALL_IN_WASM Status chunk(uint8_t type, const uint8_t* p, size_t n);
  PMZ_COLD Status head(const uint8_t* p, size_t n);
  PMZ_COLD Status base(const uint8_t* p, size_t n);  // once per file, like head
  PMZ_SMALL_IN_WASM Status split_chunk(const uint8_t* p, size_t n);
  PMZ_COLD Status attribute_chunk(const uint8_t* p, size_t n);
  PMZ_COLD Status install_base(ProgressiveMesh&& m, std::vector<int32_t>&& coords);
  bool apply();
  PMZ_COLD bool refuse(Status s, const std::string& what);
  // resume: a worker paused before the split (see Frontier::paused) goes on from there.
  bool first_apply(Frontier& f, uint64_t i, bool resume = false);
  void first_apply_worker(Frontier& w, uint64_t last);
  static constexpr const char* kValences = "vertex valences beyond what a mesh needs";
  // Decoding threads (set_threads; 1: serial) and the level-wise parallel first applications.
  uint32_t threads = 1;
  PMZ_COLD uint64_t parallel_nodes(uint64_t max_splits, uint64_t face_target);
  // A worker for node k (a level with cells) whose new vertices and faces start at those numbers,
  // its scan marks from `epoch` on, its candidates `cell`; its readers are the caller's to give.
  void start_worker(Frontier& w, size_t k, uint32_t vertex, uint64_t face, uint32_t epoch,
                    std::vector<uint32_t>&& cell, uint64_t ring_work) {
    const NodeEntry& e = nodes.table.nodes[k];
    w.mesh = &w.view;
    w.view.attach(level.mesh, vertex, uint32_t(face));
    w.choice.attach(frontier.choice, epoch);
    w.choice.begin_node(std::move(cell));
    w.lazy_first = w.decoded = nodes.first_split[k];
    std::copy_n(frontier.box_lo, 3, w.box_lo);
    std::copy_n(frontier.box_hi, 3, w.box_hi);
    w.wedge_scratch.extent = frontier.wedge_scratch.extent;
    w.ring_work = ring_work;
    w.cells = true;
    w.box = CellBox(nodes.table.levels[e.level], e.cell);
    w.face_end = face + e.faces;
    w.group_vs.reserve(kChoiceLag + 2);
  }
  // Undoes a worker's splits from `from` on (the last first).
  void undo_worker(Frontier& w, uint64_t from) {
    for (uint64_t t = w.decoded; t-- > from;)
      w.view.undo_split(record.splits[t].v, record.sides[t] & kHasLeft,
                        record.sides[t] & kHasRight);
  }
  // The mesh, record and vertex choice arrays sized for that many faces, vertices and splits.
  PMZ_COLD void resize_level(uint64_t faces, uint64_t vertices, uint64_t splits) {
    level.mesh.corner_vertex.resize(faces * 3);
    level.mesh.opposite.resize(faces * 3);
    level.mesh.vertex_corner.resize(vertices);
    record.coords.resize(vertices * 3);
    record.positions.resize(vertices * 3);
    record.parents.resize(vertices);
    record.sides.resize(splits);
    frontier.choice.resize_vertices(vertices);
  }
  void undo();
  // Up to max_splits splits, stopping once the mesh has face_target faces / before it would
  // have fewer than face_floor.
  // Not inlined: the public refine / coarsen / set_face_target share one copy of each loop
  // (set_face_target inlining both cost ~4.6 KB of the library's size budget).
  PMZ_OUT_OF_LINE uint64_t refine(uint64_t max_splits, uint64_t face_target);
  PMZ_OUT_OF_LINE uint64_t coarsen(uint64_t max_splits, uint64_t face_floor);
  // Before applying split `applied`: the fans of the next splits (see FanPrefetcher), and
  // further ahead the vertex_corner entries those walks start from. Splits applied before are
  // re-applied from their sector hints: the walks follow only the sectors, and further ahead
  // the hints' faces are prefetched directly.
  void prefetch() {
    constexpr uint64_t kFar = 2 * FanPrefetcher::kWalkers;
    const uint64_t near = level.applied + FanPrefetcher::kWalkers;
    if (near < frontier.decoded) {
      if (level.applied + kFar < frontier.decoded) {
        const Split& f = record.splits[level.applied + kFar];
        if (f.v < level.mesh.vertex_corner.size()) PMZ_PREFETCH(&level.mesh.vertex_corner[f.v]);
        if (f.a < level.mesh.opposite.size()) {     // (the hint: a sector's first face or, for an
          PMZ_PREFETCH(&level.mesh.opposite[f.a]);  // empty sector, the face read instead)
          PMZ_PREFETCH(&level.mesh.corner_vertex[f.a]);
        }
      }
      prefetch_listed();
      return;
    }
    if (level.applied + kFar < record.available) {
      const uint32_t v = record.splits[level.applied + kFar].v;
      if (v < level.mesh.vertex_corner.size()) PMZ_PREFETCH(&level.mesh.vertex_corner[v]);
    }
    // Ring coordinates matter only where positions are still to be predicted (not when
    // re-refining after coarsening: there they cost about 10% on bunny00-loop2).
    const bool predicting =
        record.coords.size() <= (size_t(level.mesh.vertex_count()) + FanPrefetcher::kWalkers) * 3;
    level.fans.step(level.mesh, record.coords.data(), predicting ? record.coords.size() : 0,
                    near < record.available ? record.splits[near].v : kNoCorner,
                    frontier.choice.degrees(), frontier.choice.sums_bytes());
  }
  // Re-applying: the sector faces kListAhead list entries ahead (their corner_vertex and
  // opposite lines), and half as far ahead the faces across a sector's ends, whose links the
  // split rewrites (opposite[next(n)] and opposite[n], read from lines prefetched before).
  static constexpr uint64_t kListAhead = 32;
  void prefetch_listed() {
    const uint32_t* list = record.sector_corners.data();
    const uint64_t size = record.sector_corners.size();
    const uint32_t* opp = level.mesh.opposite.data();
    const uint32_t* cv = level.mesh.corner_vertex.data();
    const size_t corners = level.mesh.opposite.size();
    const uint64_t far = std::min(size, level.sector_end + kListAhead);
    uint64_t at = std::max(level.listed_ahead, level.sector_end);
    for (; at < far; ++at) {
      const uint32_t n = list[at];
      if (n >= corners) continue;
      PMZ_PREFETCH(opp + n);
      PMZ_PREFETCH(cv + n);
      // The faces across: from lines prefetched kListAhead / 2 entries ago.
      const uint64_t back = at - kListAhead / 2;
      if (at >= kListAhead / 2 && back >= level.sector_end) {
        const uint32_t m = list[back];
        if (m < corners) {
          const uint32_t a = opp[m], b = opp[m % 3 == 2 ? m - 2 : m + 1];
          if (a < corners) PMZ_PREFETCH(opp + a);
          if (b < corners) PMZ_PREFETCH(opp + b);
        }
      }
    }
    level.listed_ahead = at;
  }
  // Coarsening: undoing a split rewires the faces across its new faces and repoints
  // vertex_corner of v, vl and vr, all anywhere in the buffers. For the split kUnlinkAhead
  // before the next one undone, whose new faces start at face_count() minus the faces of the
  // splits from it on (`faces`, kept as the window slides), prefetch those entries.
  static constexpr uint64_t kUnlinkAhead = 2 * FanPrefetcher::kWalkers;
  struct UnlinkWindow {
    uint64_t top = 0;    // applied when `faces` was last updated (0: not started)
    uint64_t faces = 0;  // new faces of splits top - 1 - kUnlinkAhead .. top - 1
  };
  static uint32_t new_faces(uint8_t side) {
    return (side & kHasLeft ? 1u : 0u) + (side & kHasRight ? 1u : 0u);
  }
  void prefetch_unlink(UnlinkWindow& w) {
    if (level.applied <= kUnlinkAhead) return;
    const uint64_t j = level.applied - 1 - kUnlinkAhead;
    if (w.top != level.applied + 1) {  // (re)start: sum over the window
      w.faces = 0;
      for (uint64_t t = j; t < level.applied; ++t) w.faces += new_faces(record.sides[t]);
    } else {  // slid by one: split `applied` (just undone) left the window, split j entered it
      w.faces = w.faces - new_faces(record.sides[level.applied]) + new_faces(record.sides[j]);
    }
    w.top = level.applied;
    const uint8_t side = record.sides[j];
    const size_t f0 = 3 * (size_t(level.mesh.face_count()) - w.faces),
                 corners = level.mesh.opposite.size();
    const uint32_t* opp = level.mesh.opposite.data();
    const uint32_t* cv = level.mesh.corner_vertex.data();
    auto near = [&](uint32_t c) {  // a corner across a new face: its link and its face
      if (c < corners) {
        PMZ_PREFETCH(opp + c);
        PMZ_PREFETCH(cv + c);
      }
    };
    auto vertex = [&](uint32_t x) {
      if (x < level.mesh.vertex_corner.size()) PMZ_PREFETCH(&level.mesh.vertex_corner[x]);
    };
    vertex(record.splits[j].v);
    if (f0 + 3 * new_faces(side) > corners) return;
    for (size_t g = f0, e = f0 + 3 * new_faces(side); g < e; g += 3) {
      near(opp[g]);
      near(opp[g + 1]);
      vertex(cv[g + 2]);
    }
  }
  // Never throws: called after the mesh changed, it must not leave a split half counted. Out of
  // memory for the list, it reports everything as changed.
  // (kPer 3: the faces of a list of their corners)
  template <uint32_t kPer = 1>
  void note_rewritten(std::span<const uint32_t> faces, uint64_t face_count) noexcept {
    if (level.changes.all) return;
    PMZ_TRY {
      for (uint32_t f : faces)
        if (f / kPer < level.changes.face_begin) level.changes.modified_faces.push_back(f / kPer);
    }
    PMZ_CATCH_BAD_ALLOC { level.changes.all = true; }
    if (level.changes.all || level.changes.modified_faces.size() > face_count + 64u) {
      level.changes.all = true;
      level.changes.modified_faces.clear();
    }
  }
  // The same for the faces first .. first + count - 1 (a node's, applied or undone).
  void note_face_range(uint64_t first, uint64_t count) noexcept {
    if (!level.changes.all &&
        level.changes.modified_faces.size() + count > level.mesh.face_count() + 64u)
      level.changes.all = true;
    if (level.changes.all) {
      level.changes.modified_faces.clear();
      return;
    }
    PMZ_TRY {
      for (uint64_t f = first; f < first + count; ++f)
        level.changes.modified_faces.push_back(uint32_t(f));
    }
    PMZ_CATCH_BAD_ALLOC {
      level.changes.all = true;
      level.changes.modified_faces.clear();
    }
  }
};

}  // namespace pmz
