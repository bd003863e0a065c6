// SPDX-License-Identifier: MIT
// The streaming decoder: frames chunks out of whatever slices arrive, decodes which vertices
// split when a chunk arrives (validated before anything is appended), decodes each split's
// wedge and position when it is first applied (their contexts come from the mesh), keeps what
// it decoded, and moves the mesh between levels with the shared ProgressiveMesh core.
#include "pmz/decoder.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <deque>
#include <limits>
#include <new>
#include <queue>
#include <span>
#include <system_error>
#include <thread>
#include <type_traits>

#include "attribute_stream.hpp"
#include "pmz/base_codec.hpp"
#include "pmz/fan_wedge.hpp"
#include "pmz/format.hpp"
#include "pmz/node_table.hpp"
#include "pmz/progressive_mesh.hpp"
#include "pmz/speed_level.hpp"
#include "pmz/split_chunk.hpp"
#include "pmz/vertex_choice.hpp"
#include "pmz/wasm_hints.hpp"
#include "view_select.hpp"

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

uint32_t version() { return PMZ_VERSION_NUMBER; }

const char* status_name(Status s) {
  switch (s) {
    case Status::ok:
      return "ok";
    case Status::bad_magic:
      return "bad magic";
    case Status::bad_version:
      return "unsupported version";
    case Status::bad_checksum:
      return "bad checksum";
    case Status::corrupt:
      return "corrupt stream";
    case Status::limit_exceeded:
      return "limit exceeded";
    case Status::truncated:
      return "truncated stream";
    case Status::out_of_memory:
      return "out of memory";
  }
  return "unknown status";
}

namespace {
constexpr uint8_t kHasLeft = 1, kHasRight = 2;

}  // namespace

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
    std::unique_ptr<AttributeModels> first_attribute_models;
    size_t applying = 0;  // nodes whose first application started
    uint64_t start_faces = 0, start_wedges = 0;
    CellBins bins;
    int64_t bins_level = -1;
  } nodes;
  PMZ_COLD Status node_chunk(const uint8_t* p, size_t n);
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
    uint32_t applied_nodes = 0;
    bool complete = false;
    ProgressiveMesh walker;  // re-applies and undoes nodes (attached; keeps its ring scratch)
  } sel;
  uint32_t node_first_vertex(size_t k) const {
    return uint32_t(info.base_vertices + nodes.first_split[k]);
  }
  PMZ_COLD bool enter_selection();
  PMZ_COLD std::vector<uint32_t> cell_list(uint32_t k);
  PMZ_COLD bool first_apply_node(uint32_t k);
  PMZ_COLD void reapply_node(uint32_t k);
  PMZ_COLD void undo_node(uint32_t k);
  PMZ_COLD void clear_node_faces(uint32_t k);
  PMZ_COLD Status node_bytes(uint32_t k, const uint8_t* p, size_t n);
  PMZ_COLD bool selection(uint64_t budget, uint64_t& n);
  PMZ_COLD uint64_t update_view(const View& v, uint64_t budget);

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

Decoder::Decoder(const DecoderLimits& limits) : impl_(new Impl) {
  impl_->limits = limits;
  impl_->frontier.mesh = &impl_->level.mesh;
  set_threads(0);
}

void Decoder::set_threads(uint32_t n) {
#if defined(__wasm__)
  n = 1;  // (built without threads)
#endif
  impl_->threads = n ? n : std::max(1u, std::thread::hardware_concurrency());
}
Decoder::~Decoder() = default;
Decoder::Decoder(Decoder&&) noexcept = default;
Decoder& Decoder::operator=(Decoder&&) noexcept = default;

// Consumes complete items from p; returns the bytes used (the rest waits for more input).
size_t Decoder::Impl::parse(const uint8_t* p, size_t n) {
  size_t at = 0;
  if (!input.signature_done) {
    size_t k = std::min<size_t>(n, 8);
    if (std::memcmp(p, kSignature, k) != 0) {
      fail(Status::bad_magic, "not a .pmz stream");
      return n;
    }
    if (n < 8) return 0;
    input.signature_done = true;
    at = 8;
  }
  while (stage != Stage::failed) {
    if (stage == Stage::complete)
      return n;  // bytes after END are ignored, framed or not (spec/format.md section 3)
    ChunkFrame f;
    const FrameStatus fs = parse_chunk_frame(p + at, n - at, f);
    input.chunk_offset = input.parse_base + at;
    if (stage == Stage::header && n - at >= 1 && p[at] != kChunkHead) {  // a 6.x or older file?
      const size_t k = std::min<size_t>(n - at, 14);
      if (p[at] == kOldHeadType[0] &&
          std::memcmp(p + at, kOldHeadType, std::min<size_t>(k, 4)) == 0) {
        if (k < 14) break;  // its version bytes (old HEAD payload bytes 0 and 1) are still to come
        fail(Status::bad_version, "format " + PMZ_DECIMAL(p[at + 12]) + "." +
                                      PMZ_DECIMAL(p[at + 13]) + " (this decoder reads format " +
                                      PMZ_DECIMAL(kVersionMajor) + ")");
        return n;
      }
    }
    if (fs == FrameStatus::more) break;  // the frame header continues in the next slice
    if (fs == FrameStatus::malformed) {
      fail(Status::corrupt, "chunk size varint malformed");
      return n;
    }
    // Checked before buffering the payload.
    if (f.payload_size > limits.max_chunk_bytes) {
      fail(Status::limit_exceeded, "chunk of " + PMZ_DECIMAL(f.payload_size) + " bytes");
      return n;
    }
    const size_t size = size_t(f.payload_size);
    if (n - at - f.header_size < size) break;
    const uint8_t* payload = p + at + f.header_size;
    if (chunk_crc(p + at, f, payload) != f.crc) {
      fail(Status::bad_checksum, "chunk checksum mismatch");
      return n;
    }
    input.chunk_bytes = f.header_size + size;
    if (chunk(f.type, payload, size) != Status::ok) return n;
    at += f.header_size + size;
    ++input.chunk_index;
  }
  return at;
}

Status Decoder::Impl::chunk(uint8_t type, const uint8_t* p, size_t n) {
  if (stage == Stage::header && type != kChunkHead)
    return fail(Status::corrupt, "first chunk is not HEAD");
  if (type == kChunkHead) {
    if (stage != Stage::header) return fail(Status::corrupt, "second HEAD chunk");
    return head(p, n);
  }
  if (type == kChunkBase) {
    if (stage != Stage::base || base_geometry) return fail(Status::corrupt, "second BASE chunk");
    return base(p, n);
  }
  if (type == kChunkSplits) {
    if (stage != Stage::splits) return fail(Status::corrupt, "SPLT before BASE");
    if (attr_awaited) return fail(Status::corrupt, "SPLT before the last SPLT's ATTR");
    return split_chunk(p, n);
  }
  if (type == kChunkAttributes && attrs) return attribute_chunk(p, n);
  if (type == kChunkNodes && (info.flags & kFlagNodes)) return node_chunk(p, n);
  if (type == kChunkEnd) {
    const bool all = sel.on ? nodes.arriving == nodes.table.nodes.size()
                            : record.splits.size() == info.total_splits;
    if (stage != Stage::splits || !all || attr_awaited)
      return fail(Status::corrupt, "END before all splits");
    if ((info.flags & kFlagNodes) && !nodes.present)
      return fail(Status::corrupt, "END in a stream with nodes but no NODE chunk");
    info.complete = true;
    stage = Stage::complete;
    return Status::ok;
  }
  return Status::ok;  // unknown chunk type: skipped (forward compatibility)
}

Status Decoder::Impl::head(const uint8_t* p, size_t n) {
  FileHeader h;
  size_t fixed = 0;
  if (!read_head_payload(p, n, h, &fixed)) return fail(Status::corrupt, "HEAD malformed");
  if (h.version_major != kVersionMajor)
    return fail(Status::bad_version, "format version " + PMZ_DECIMAL(h.version_major) + "." +
                                         PMZ_DECIMAL(h.version_minor));
  if (h.position_bits > 30) return fail(Status::corrupt, "position bits above 30");
  if (h.curvature > kMaxCurvature || h.fine_curvature > kMaxCurvature)
    return fail(Status::corrupt, "curvature above 8");
  if (h.level > kMaxLevel) return fail(Status::corrupt, "level above 1");
  if (h.flags & ~kKnownFlags) return fail(Status::corrupt, "unknown HEAD flags");
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(h.bbox_min[a]) || !std::isfinite(h.bbox_max[a]) ||
        h.bbox_min[a] > h.bbox_max[a])
      return fail(Status::corrupt, "bad bounding box");
  if (h.base_faces > h.full_faces || h.full_faces > uint64_t(h.base_faces) + 2ull * h.total_splits)
    return fail(Status::corrupt, "inconsistent counts in HEAD");
  // Vertex ids are uint32 with 0xFFFFFFFF for none, whatever the limits (spec/format.md section 4).
  if (h.full_vertices() > 0xFFFFFFFFu)
    return fail(Status::corrupt,
                PMZ_DECIMAL(h.full_vertices()) + " vertices in HEAD (2^32 or more)");
  if (h.full_vertices() > limits.max_vertices || h.full_faces > limits.max_faces)
    return fail(Status::limit_exceeded, PMZ_DECIMAL(h.full_vertices()) + " vertices, " +
                                            PMZ_DECIMAL(h.full_faces) + " faces");
  if (h.flags & kFlagAttributes) {
    std::string err;
    attrs = std::make_unique<AttributeStream>();
    if (!attrs->head(p + fixed, n - fixed, h.full_faces, err))
      return fail(Status::corrupt, "HEAD attributes: " + err);
    attrs->models->cost.bits = attribute_bits;
    for (const FileMaterial& m : attrs->state.head.materials) {
      MaterialInfo& out = materials.emplace_back();
      out.name = m.name;
      out.base_color_texture = m.base_color_texture;
      out.normal_texture = m.normal_texture;
      std::memcpy(out.base_color, m.base_color, sizeof m.base_color);
    }
  }
  info.header_done = true;
  stage = Stage::base;
  info.version_major = h.version_major;
  info.version_minor = h.version_minor;
  info.flags = h.flags;
  info.position_bits = h.position_bits;
  info.curvature = h.curvature;
  info.fine_curvature = h.fine_curvature;
  info.level = h.level;
  info.base_vertices = h.base_vertices;
  info.base_faces = h.base_faces;
  info.full_vertices = h.full_vertices();
  info.full_faces = h.full_faces;
  info.total_splits = h.total_splits;
  std::memcpy(info.bbox_min, h.bbox_min, sizeof h.bbox_min);
  std::memcpy(info.bbox_max, h.bbox_max, sizeof h.bbox_max);
  quant.init(h.position_bits, h.bbox_min, h.bbox_max);
  return Status::ok;
}

Status Decoder::Impl::base(const uint8_t* p, size_t n) {
  // The payload is the range-coded stream; its counts are HEAD's.
  const uint32_t vn = uint32_t(info.base_vertices), fn = uint32_t(info.base_faces);
  std::string err;
  BaseMesh bm;
  if (const Status s = decode_base(p, n, vn, fn, bm, err); s != Status::ok) return fail(s, err);
  ProgressiveMesh m;
  if (!m.build(vn, bm.faces.data(), fn, err)) return fail(Status::corrupt, "BASE: " + err);
  base_geometry = true;
  if (attrs) {  // drawable once its ATTR chunk arrived
    pending_base = std::make_unique<std::pair<ProgressiveMesh, std::vector<int32_t>>>(
        std::move(m), std::move(bm.coords));
    return Status::ok;
  }
  return install_base(std::move(m), std::move(bm.coords));
}

Status Decoder::Impl::install_base(ProgressiveMesh&& m, std::vector<int32_t>&& coords) {
  const uint32_t vn = uint32_t(info.base_vertices);
  level.mesh = std::move(m);
  [](auto& to, std::vector<int32_t>& from) {  // (a template: the other branch is discarded)
    if constexpr (std::is_same_v<std::remove_reference_t<decltype(to)>, std::vector<int32_t>>)
      to = std::move(from);  // BigVector is std::vector (WebAssembly)
    else
      to.assign(from.begin(), from.end());
  }(record.coords, coords);
  frontier.choice.reset(level.mesh, record.coords.data(), info.position_bits,
                        info.level != kLevelSpeed);
  frontier.group_vs.reserve(kChoiceLag +
                            2);  // find_vertices() adds at most kChoiceLag + 1 at a time
  for (size_t i = 0; i < vn; ++i) frontier.grow_box(&record.coords[i * 3]);
  record.positions.resize(size_t(vn) * 3);
  for (size_t i = 0; i < size_t(vn) * 3; ++i)
    record.positions[i] = quant.dequantize(record.coords[i], int(i % 3));
  record.parents.assign(vn, 0xFFFFFFFFu);
  info.base_done = true;
  stage = Stage::splits;
  level.changes = {};
  level.changes.all = true;
  return Status::ok;
}

Status Decoder::Impl::attribute_chunk(const uint8_t* p, size_t n) {
  if (stage == Stage::base && base_geometry) {  // the base mesh's a-wedges
    std::string err;
    auto& [mesh, coords] = *pending_base;
    std::vector<float> positions(coords.size());
    for (size_t i = 0; i < coords.size(); ++i)
      positions[i] = quant.dequantize(coords[i], int(i % 3));
    if (!attrs->base(p, n, mesh, coords.data(), positions.data(), err))
      return fail(Status::corrupt, err);
    const Status st = install_base(std::move(mesh), std::move(coords));
    pending_base.reset();
    return st;
  }
  if (stage != Stage::splits || !attr_awaited)
    return fail(Status::corrupt, "ATTR chunk without its BASE or SPLT chunk");
  attrs->chunk(p, n);
  attr_awaited = false;
  record.available = record.splits.size();
  if (info.flags & kFlagNodes && !nodes.present) {  // the first node's, before the table
    nodes.arrived_bytes += input.chunk_bytes;
    return Status::ok;
  }
  return nodes.present ? node_arrived(input.chunk_bytes, true) : Status::ok;
}

Status Decoder::Impl::split_chunk(const uint8_t* p, size_t n) {
  std::string err;
  if (sel.on) {  // view-dependent: the chunk goes to its node's readers
    const size_t k = nodes.arriving;
    if (k >= nodes.table.nodes.size())
      return fail(Status::corrupt, "SPLT after every node's splits");
    const NodeEntry& e = nodes.table.nodes[k];
    if (sel.arrival[k] == Selection::whole) {  // arrived by feed_node(): only its bytes count
      nodes.arrived_bytes += input.chunk_bytes;
      if (nodes.arrived_bytes > e.bytes)
        return fail(Status::corrupt, "node " + PMZ_DECIMAL(k) + " longer than its table entry");
      if (nodes.arrived_bytes == e.bytes) {
        ++nodes.arriving;
        nodes.arrived_splits = nodes.arrived_bytes = 0;
        frontier.open = {};  // (a node's groups end with it)
      }
      return Status::ok;
    }
    std::unique_ptr<SplitModels>& models = nodes.models[k];
    if (!models) {
      models = std::make_unique<SplitModels>();
      models->speed = info.level == kLevelSpeed;
    }
    SplitChunkReader r;
    if (!r.open(p, n, e.splits - nodes.arrived_splits, *models, err, frontier.open))
      return fail(Status::corrupt, err);
    frontier.open = r.open_group();
    const uint64_t at = nodes.first_split[k] + nodes.arrived_splits;
    std::fill_n(record.splits.begin() + ptrdiff_t(at), r.split_count(),
                Split{kNoCorner, kNoRank, kNoRank});
    nodes.arrived_splits += r.split_count();
    sel.readers[k].push_back(std::move(r));
    sel.arrival[k] = Selection::partial;
    const Status st = node_arrived(input.chunk_bytes, true);
    if (st == Status::ok && nodes.arriving > k) {
      sel.arrival[k] = Selection::whole;
      sel.available += e.splits;
    }
    return st;
  }
  SplitChunkReader r;
  uint64_t max_splits = info.total_splits - record.splits.size();
  std::unique_ptr<SplitModels>* models = &frontier.models;
  if (nodes.present) {  // the chunk's node: models of its own (spec/format.md section 15.4)
    if (nodes.arriving >= nodes.table.nodes.size())
      return fail(Status::corrupt, "SPLT after every node's splits");
    models = &nodes.models[nodes.arriving];
    max_splits = nodes.table.nodes[nodes.arriving].splits - nodes.arrived_splits;
  }
  if (!*models) {
    *models = std::make_unique<SplitModels>();
    (*models)->speed = info.level == kLevelSpeed;
  }
  if (!r.open(p, n, max_splits, **models, err, frontier.open)) return fail(Status::corrupt, err);
  frontier.open = r.open_group();
  if (nodes.present) nodes.arrived_splits += r.split_count();
  const size_t size = record.splits.size() + r.split_count();
  // As refine() grows the mesh buffers: room for every split of the header once the decoded ones
  // are at least 1 / kHeaderTrust of them, instead of doubling (a copy and page faults each).
  if (size > record.splits.capacity() && info.total_splits <= kHeaderTrust * size) {
    record.splits.reserve(info.total_splits);
  }
  const size_t first = record.splits.size();
  record.splits.resize(size, {kNoCorner, kNoRank, kNoRank});
  // Vertices a group this chunk continues found ahead (spec/format.md section 8).
  const size_t known = std::min(frontier.ahead.size(), size - first);
  for (size_t i = 0; i < known; ++i) record.splits[first + i].v = frontier.ahead[i];
  frontier.ahead.erase(frontier.ahead.begin(), frontier.ahead.begin() + ptrdiff_t(known));
  frontier.lazy.push_back(std::move(r));
  if (attrs)
    attr_awaited = true;  // available with its ATTR chunk
  else
    record.available = record.splits.size();
  if (info.flags & kFlagNodes && !nodes.present) {  // the first node's, before the table
    nodes.arrived_bytes += input.chunk_bytes;
    return Status::ok;
  }
  return nodes.present ? node_arrived(input.chunk_bytes, !attrs) : Status::ok;
}

Status Decoder::Impl::node_chunk(const uint8_t* p, size_t n) {
  if (stage != Stage::splits || nodes.present || attr_awaited)
    return fail(Status::corrupt, "NODE chunk out of place");
  std::string err;
  if (!read_node_table(p, n, info.total_splits, n / 16 + 1, attrs != nullptr, nodes.table, err))
    return fail(Status::corrupt, err);
  // The chunks before it are the first node's, all of them (spec/format.md section 15.1).
  const NodeEntry& first = nodes.table.nodes[0];
  if (record.splits.size() != first.splits || nodes.arrived_bytes != first.bytes ||
      frontier.open.size)
    return fail(Status::corrupt, "NODE chunk not right after the first node's chunks");
  if (nodes.table.nodes.size() < 2) return fail(Status::corrupt, "NODE: a single node");
  if (nodes.table.levels[first.level].side != 0)
    return fail(Status::corrupt, "NODE: the first node has a cell");
  nodes.present = true;
  nodes.arriving = 1;
  nodes.arrived_bytes = 0;
  nodes.applying = 1;  // the first node decodes as a stream without nodes: nothing to start
  nodes.start_faces = info.base_faces;
  nodes.start_wedges = attrs ? attrs->state.head.base_wedges : 0;
  uint64_t at = 0, offset = input.chunk_offset + input.chunk_bytes, face = info.base_faces;
  sel.nodes_start = offset;
  for (size_t k = 0; k < nodes.table.nodes.size(); ++k) {
    const NodeEntry& e = nodes.table.nodes[k];
    nodes.first_split.push_back(at);
    sel.offset.push_back(k ? offset : 0);
    sel.first_face.push_back(face);
    at += e.splits;
    if (k) offset += e.bytes;
    face += e.faces;
  }
  sel.arrival.assign(nodes.table.nodes.size(), Selection::none);
  sel.arrival[0] = Selection::whole;
  sel.readers.resize(nodes.table.nodes.size());
  nodes.models.resize(nodes.table.nodes.size());
  nodes.models[0] = std::move(frontier.models);  // (its readers keep pointing at it)
  info.nodes = nodes.table.nodes.size();
  return Status::ok;
}

// A chunk of node `arriving` (bytes: its size) arrived; attributes_done: its splits' ATTR chunk
// too (or there is none). Once the node's splits and their ATTR chunk are all there, its bytes
// must be the table's.
Status Decoder::Impl::node_arrived(uint64_t bytes, bool attributes_done) {
  nodes.arrived_bytes += bytes;
  const NodeEntry& e = nodes.table.nodes[nodes.arriving];
  if (nodes.arrived_bytes > e.bytes)
    return fail(Status::corrupt,
                "node " + PMZ_DECIMAL(nodes.arriving) + " longer than its table entry");
  if (!attributes_done || nodes.arrived_splits < e.splits) return Status::ok;
  if (nodes.arrived_bytes != e.bytes)
    return fail(Status::corrupt,
                "node " + PMZ_DECIMAL(nodes.arriving) + " shorter than its table entry");
  ++nodes.arriving;
  nodes.arrived_splits = nodes.arrived_bytes = 0;
  return Status::ok;
}

// The first application of a node's first split (spec/format.md section 15.4): the node before
// added the faces the table says; this one starts from the models the first node left (but for
// its group model, its own from the initial state), its near list empty, and its candidates its
// cell's vertices.
bool Decoder::Impl::start_node() {
  const size_t k = nodes.applying;
  if (k > 0) {
    if (!node_counts_match(k - 1))
      return refuse(Status::corrupt, "node " + PMZ_DECIMAL(k - 1) +
                                         " added other faces or wedges than its table entry");
    if (k == 1) {
      nodes.first_models = std::move(nodes.models[0]);
      if (attrs) nodes.first_attribute_models = std::make_unique<AttributeModels>(*attrs->models);
    }
    nodes.models[k - 1].reset();  // its splits are all decoded
    nodes.models[k]->inherit(*nodes.first_models);
    if (attrs) *attrs->models = *nodes.first_attribute_models;
  }
  const NodeEntry& e = nodes.table.nodes[k];
  nodes.start_faces = level.mesh.face_count();
  nodes.start_wedges = attrs ? attrs->state.wedge_count : 0;
  frontier.cells = nodes.table.levels[e.level].side > 0;
  frontier.box = CellBox(nodes.table.levels[e.level], e.cell);
  if (!frontier.cells) {
    frontier.choice.begin_whole_node();
  } else {
    if (nodes.bins_level != int64_t(e.level)) {
      nodes.bins.build(nodes.table, e.level, record.coords.data(), level.mesh.vertex_count());
      nodes.bins_level = e.level;
    }
    frontier.choice.begin_node(nodes.bins.take(uint32_t(k)));
  }
  ++nodes.applying;
  return true;
}

// Refuses split `applied` (and everything after it): the mesh stays at the level before.
bool Decoder::Impl::refuse(Status s, const std::string& what) {
  fail(s, what);
  record.splits.resize(level.applied);
  record.available = level.applied;
  frontier.lazy.clear();
  frontier.ahead.clear();
  if (attrs) attrs->lazy.clear();
  return false;
}

bool Decoder::Impl::apply() {
  Split& s = record.splits[level.applied];
  if (level.mesh.face_count() + 2ull > limits.max_faces) {
    fail(Status::limit_exceeded, "face limit reached while refining");
    return false;
  }
  if (level.applied <
      frontier.decoded) {  // applied before, on this very mesh state: no ring, no symbols
    const uint8_t side = record.sides[level.applied];
    level.mesh.resplit_listed(s.v, record.sector_corners.data() + level.sector_end, s.b, s.a,
                              side & kHasLeft, side & kHasRight);
    level.sector_end += s.b;
    if (attrs) attrs->reapply(level.mesh, level.applied, side & kHasLeft, side & kHasRight);
    note_rewritten(level.mesh.sector_faces(), level.mesh.face_count());
    ++level.applied;
    return true;
  }
  if (!first_apply(frontier, level.applied)) return false;
  level.sector_end += s.b;
  if (attrs && frontier.lazy_first == frontier.decoded) attrs->chunk_done();
  note_rewritten(level.mesh.sector_faces(), level.mesh.face_count());
  ++level.applied;
  // The last node's faces (the others' are checked as the next node starts). The split stands:
  // the mesh is valid, the stream is not.
  if (nodes.present && frontier.decoded == info.total_splits &&
      !node_counts_match(nodes.table.nodes.size() - 1)) {
    fail(Status::corrupt, "the last node added other faces or wedges than its table entry");
    return false;
  }
  return true;
}

// The first application of split i (f.decoded), by the serial frontier or a node's worker: its
// vertex, wedge and position symbols with contexts from f's mesh, the split, and what re-applying
// it needs. A failure leaves the mesh at the level before the split: the serial frontier refuses
// the split, a worker keeps the status and message for the merge.
bool Decoder::Impl::first_apply(Frontier& f, uint64_t i, bool resume) {
  Split& s = record.splits[i];
  ProgressiveMesh& mesh = *f.mesh;
  const bool serial = &f == &frontier;
  auto stop = [&](Status st, const std::string& what) {
    if (serial) return refuse(st, what);
    f.status = st;
    f.message = what;
    return false;
  };
  auto stop_split = [&](const char* what) {
    return stop(Status::corrupt, "split " + PMZ_DECIMAL(i) + what);
  };
  auto invalid = [&] { return stop_split(" has an invalid wedge"); };
  SplitChunkReader& reader = f.lazy.front();
  if (!resume) {
    if (i - f.lazy_first == reader.group_end()) {  // a group's first split: start its scan
      if (serial && nodes.present && nodes.applying < nodes.first_split.size() &&
          i == nodes.first_split[nodes.applying] && !start_node())
        return false;
      f.group_first = i;
      f.choice_ok = reader.begin_group(f.choice, mesh.vertex_count());
      f.find_vertices(scan_at_group_start(), record.splits);
    }
    if (s.v == kNoCorner) return stop_split(": vertex choice malformed");
    if (!mesh.gather_ring(s.v)) return invalid();
    if (nodes.present &&
        f.cells) {  // v's ring within the node's cell (spec/format.md section 15.4)
      bool inside = f.box.contains(&record.coords[size_t(s.v) * 3]);
      for (uint32_t w : mesh.ring())
        inside = inside && f.box.contains(&record.coords[size_t(w) * 3]);
      if (!inside) return stop_split(" reaches outside its node's cell");
    }
    {  // first application: the wedge symbols, with contexts from v's ring
      const uint32_t k = uint32_t(mesh.ring().size());
      // Ring walks cost the valence: bound their total (first applications; re-applying after
      // coarsening repeats the same work) so splits piling on one vertex cannot go quadratic.
      // (A worker counts from the total before its level: a lower bound, checked exactly as the
      // nodes are merged in file order.)
      f.ring_work += k;
      if (!serial) f.rings.push_back(k);
      if (f.ring_work > kRingWorkPerSplit * (i + 1) + kRingWorkSlack)
        return stop(Status::limit_exceeded, kValences);
      // Decoded symbols cannot be put back: allocate what wedge_ranks needs before decoding them
      // (an allocation failure then leaves this split to retry, not a symbol lost).
      if (k > f.wedge_scratch_ring) {
        f.wedge_scratch.reserve(k);
        f.wedge_scratch_ring = k;
      }
      f.choice.reserve(k);
      // (About four sector corners per split on a regular mesh, valence 6: room for four per
      // split refine() made room for.)
      if (serial && record.sector_corners.capacity() - record.sector_corners.size() < k)
        record.sector_corners.reserve(
            std::max({2 * record.sector_corners.capacity(), record.sector_corners.size() + k,
                      4 * record.sides.capacity()}));
      if (attrs) attrs->reserve_split(mesh.face_count(), k);
      uint32_t count, rank;
      auto malformed = [&] { return stop_split(": wedge streams malformed"); };
      if (!reader.wedge_count(wedge_context(k, mesh.ring_closed()), count)) return malformed();
      if (info.level == kLevelSpeed) {  // the candidate's index (spec/format.md section 9.10)
        if (!reader.wedge_rank(rank_context(mesh.ring_closed(), false), rank)) return malformed();
        if (!speed_wedge_pick(mesh, count, rank, s.a, s.b)) return invalid();
      } else {
        if (!wedge_scores(record.coords.data(), f.choice.degrees(), s.v, mesh, count,
                          f.wedge_scratch))
          return invalid();
        if (!reader.wedge_rank(rank_context(mesh.ring_closed(), f.wedge_scratch.confident), rank))
          return malformed();
        if (!wedge_pick(mesh, count, rank, s.a, s.b, f.wedge_scratch)) return invalid();
      }
    }
    // A worker writes only within its node's face ids: beyond them it pauses, and the merge lets
    // it go on alone, as the serial decoder does (which finds a node that adds more faces than
    // its table entry where spec/format.md section 15 says).
    if (!serial && mesh.face_count() + uint64_t(s.a != kNoRank) + (s.b != kNoRank) > f.face_end)
      return !(f.paused = true);
  }
  const bool has_l = s.a != kNoRank, has_r = s.b != kNoRank;
  if (!mesh.split_gathered(s.v, s.a, s.b)) return invalid();
  {  // the position, then what re-applying the split needs
    PositionPrediction pred;
    int32_t residual[3], c[3];
    // (v's ring offsets: summed by the wedge scores over the same ring and coordinates.)
    const WedgeScratch& ws = f.wedge_scratch;
    bool decoded;
    if (info.level == kLevelSpeed) {
      speed_predict_position(record.coords.data(), mesh.u_ring(), pred);
      decoded = reader.speed_residuals(pred.context, residual);
    } else {
      predict_position(record.coords.data(), mesh.u_ring(), mesh.ring(), info.curvature,
                       info.fine_curvature, pred, ws.extent,
                       ws.ring_offsets_ok ? ws.ring_offsets : nullptr);
      decoded = reader.residuals(pred.context, pred.mix, residual);
    }
    if (!decoded) {
      mesh.undo_split(s.v, has_l, has_r);
      return stop_split(": residual streams malformed");
    }
    position_from_residuals(pred, residual, c);
    if (nodes.present && !f.box.contains(c)) {
      mesh.undo_split(s.v, has_l, has_r);
      return stop_split(" has u outside its node's cell");
    }
    f.grow_box(c);
    // Serially appended; a worker's vertex, split and face ids are within what was sized for
    // its level.
    const size_t u = mesh.vertex_count() - 1;
    auto put = [](auto& to, size_t at, auto x) {
      if (to.size() == at)
        to.push_back(x);
      else
        to[at] = x;
    };
    for (int a = 0; a < 3; ++a) {
      put(record.coords, u * 3 + a, c[a]);
      put(record.positions, u * 3 + a, quant.dequantize(c[a], a));
    }
    if (attrs &&
        !attrs->first_apply(mesh, record.coords.data(), record.positions.data(), has_l, has_r)) {
      record.coords.resize(record.coords.size() - 3);
      record.positions.resize(record.positions.size() - 3);
      mesh.undo_split(s.v, has_l, has_r);
      return stop_split(": attributes malformed");
    }
    put(record.parents, u, s.v);
    put(record.sides, i, uint8_t((has_l ? kHasLeft : 0) | (has_r ? kHasRight : 0)));
    // The vertex choice state (its umbrella sums need u's coordinates), then the group's
    // vertices kChoiceLag + 1 ahead (the lag: this split's ring is noted now).
    f.choice.applied(mesh, record.coords.data(), has_l, has_r);
    f.find_vertices(scan_after_split(uint32_t(i - f.group_first)), record.splits);
    s.a = mesh.sector_hint();
    s.b = uint32_t(mesh.sector_faces().size());
    for (uint32_t n : mesh.sector_corners())
      (serial ? record.sector_corners : f.sectors).push_back(n);  // (serially: reserved above)
    if (++f.decoded - f.lazy_first == reader.split_count()) {
      f.lazy_first = f.decoded;
      f.lazy.pop_front();  // its bytes are no longer needed
    }
  }
  return true;
}

// Several nodes of one level whose bytes all arrived, at once (threads > 1, a stream with nodes
// and without attributes, at a node's start): each on a worker with its own view of the mesh and
// vertex choice, writing the vertex, face and split ids the table gives it (nodes of a level touch
// disjoint state). Then merged in file order as the serial decoder would have applied them: the
// first failure (the worker's own, the ring work bound, a node's face count) ends the applied
// prefix there, the splits after it are undone and the serial error reported. Returns the splits
// applied (0: nothing to run in parallel here; the serial path goes on).
uint64_t Decoder::Impl::parallel_nodes(uint64_t max_splits, uint64_t face_target) {
#if defined(__wasm__)
  (void)max_splits, (void)face_target;
  return 0;
#else
  const size_t k = nodes.applying, total = nodes.table.nodes.size();
  if (threads < 2 || !nodes.present || attrs || stage == Stage::failed || k < 1 || k >= total ||
      level.applied != frontier.decoded || level.applied != nodes.first_split[k] ||
      !node_counts_match(k - 1))
    return 0;
  const std::vector<NodeEntry>& table = nodes.table.nodes;
  const uint32_t lv = table[k].level;
  if (nodes.table.levels[lv].side == 0) return 0;
  const uint64_t v0 = level.mesh.vertex_count(), f0 = level.mesh.face_count(), s0 = level.applied;
  // The level's nodes from k on that arrived whole and that the serial decoder would apply
  // whole within the targets (their table faces below face_target and the face limit).
  size_t end = k;
  uint64_t faces = f0;
  while (end < total && end < nodes.arriving && table[end].level == lv &&
         nodes.first_split[end] + table[end].splits - s0 <= max_splits &&
         faces + table[end].faces < face_target &&
         faces + table[end].faces + 2 <= limits.max_faces &&
         faces + table[end].faces <= info.full_faces)
    faces += table[end++].faces;
  if (end - k < 2) return 0;
  const uint64_t s1 = end < total ? nodes.first_split[end] : info.total_splits;
  const uint64_t v1 = v0 + (s1 - s0);
  if (v1 > info.full_vertices) return 0;
  std::vector<std::unique_ptr<Frontier>> work;
  std::vector<uint64_t> face_start;
  PMZ_TRY {
    // Room for every id the workers write: the owner's arrays sized to the level's end.
    resize_level(faces, v1, s1);
    if (k == 1) nodes.first_models = std::move(nodes.models[0]);
    nodes.models[k - 1].reset();  // its splits are all decoded
    if (nodes.bins_level != int64_t(lv)) {
      nodes.bins.build(nodes.table, lv, record.coords.data(), uint32_t(v0));
      nodes.bins_level = lv;
    }
    uint32_t epoch = frontier.choice.take_epochs(s1 - s0 + (end - k));
    uint64_t at = f0;
    for (size_t j = k; j < end; ++j) {
      Frontier& w = *work.emplace_back(std::make_unique<Frontier>());
      start_worker(w, j, uint32_t(v0 + nodes.first_split[j] - s0), at, epoch,
                   nodes.bins.take(uint32_t(j)), frontier.ring_work);
      epoch += uint32_t(table[j].splits + 1);
      for (uint64_t got = 0; got < table[j].splits; frontier.lazy.pop_front()) {
        got += frontier.lazy.front().split_count();
        w.lazy.push_back(std::move(frontier.lazy.front()));
      }
      face_start.push_back(at);
      at += table[j].faces;
    }
  }
  PMZ_CATCH_BAD_ALLOC {  // (the readers may be gone: refused like any split out of memory)
    resize_level(f0, v0, s0);
    refuse(Status::out_of_memory, "allocation failed while refining");
    return 0;
  }
  frontier.lazy_first = s1;
  // The workers take the nodes in file order.
  std::atomic<size_t> next{0};
  auto go = [&](size_t j, bool resume) {
    Frontier& w = *work[j];
    PMZ_TRY {
      if (!resume) nodes.models[k + j]->inherit(*nodes.first_models);
      const uint64_t last = nodes.first_split[k + j] + table[k + j].splits;
      if (resume && !first_apply(w, w.decoded, true)) return;
      for (;;) {  // (the fans ahead, as prefetch(): within the node's cell)
        const uint64_t ahead = w.decoded + FanPrefetcher::kWalkers;
        w.fans.step(level.mesh, record.coords.data(), record.coords.size(),
                    ahead < last ? record.splits[ahead].v : kNoCorner, frontier.choice.degrees(),
                    frontier.choice.sums_bytes());
        if (w.decoded >= last || !first_apply(w, w.decoded)) break;
      }
    }
    PMZ_CATCH_BAD_ALLOC {
      w.status = Status::out_of_memory;
      w.message = "allocation failed while refining";
    }
  };
  auto run = [&] {
    for (size_t j; (j = next++) < work.size();) go(j, false);
  };
  {
    std::vector<std::jthread> pool;
    try {  // (fewer threads if the system has none to give: this one runs the rest)
      for (uint32_t t = 1; t < std::min<size_t>(threads, work.size()); ++t) pool.emplace_back(run);
    } catch (const std::system_error&) {
    }
    run();
  }
  // The merge: where the serial decoder would have stopped (stop, with its error).
  uint64_t stop = s1, work_sum = frontier.ring_work;
  Status st = Status::ok;
  std::string what;
  for (size_t j = 0; j < work.size() && st == Status::ok; ++j) {
    Frontier& w = *work[j];
    const uint64_t first = nodes.first_split[k + j];
    if (w.paused) {  // the nodes after it undone, it goes on alone, with room for its faces
      for (size_t x = j + 1; x < work.size(); ++x) {
        Frontier& o = *work[x];
        undo_worker(o, nodes.first_split[k + x]);
        o.decoded = nodes.first_split[k + x];
        o.rings.clear();
        o.status = Status::ok;
        o.paused = false;
      }
      const uint64_t room = w.view.face_count() + 2 * (first + table[k + j].splits - w.decoded);
      if (room * 3 > level.mesh.corner_vertex.size()) {
        level.mesh.corner_vertex.resize(room * 3);
        level.mesh.opposite.resize(room * 3);
      }
      w.paused = false;
      w.face_end = UINT64_MAX;
      go(j, true);
    }
    for (size_t t = 0; t < w.rings.size(); ++t) {
      work_sum += w.rings[t];
      if (work_sum > kRingWorkPerSplit * (first + t + 1) + kRingWorkSlack) {
        stop = first + t, st = Status::limit_exceeded, what = kValences;
        break;
      }
    }
    if (st != Status::ok) break;
    if (w.status != Status::ok) {
      stop = w.decoded, st = w.status, what = w.message;
    } else if (k + j + 1 < end && w.view.face_count() != w.face_end) {
      stop = nodes.first_split[k + j + 1], st = Status::corrupt;
      what = "node " + PMZ_DECIMAL(k + j) + " added other faces or wedges than its table entry";
    }
    frontier.ring_work = work_sum;
  }
  // Undo what lies past stop (nodes touch disjoint state: in any node order), then take the
  // prefix over: sizes, sector lists, the change report, the box.
  uint64_t f_end = f0;
  for (size_t j = 0; j < work.size(); ++j) {
    Frontier& w = *work[j];
    undo_worker(w, std::max(stop, nodes.first_split[k + j]));
    if (nodes.first_split[k + j] >= stop) continue;
    f_end = w.view.face_count();
    uint64_t faces_now = face_start[j], corners = 0;
    for (uint64_t t = nodes.first_split[k + j]; t < std::min(w.decoded, stop); ++t) {
      const Split& x = record.splits[t];
      faces_now += new_faces(record.sides[t]);
      note_rewritten<3>({w.sectors.data() + corners, x.b}, faces_now);
      corners += x.b;
    }
    record.sector_corners.insert(record.sector_corners.end(), w.sectors.begin(),
                                 w.sectors.begin() + ptrdiff_t(corners));
    level.sector_end += corners;
    if (j) nodes.models[k + j - 1].reset();
    nodes.start_faces = face_start[j];
    nodes.applying = k + j + 1;
  }
  const uint64_t v_end = v0 + (stop - s0);
  resize_level(f_end, v_end, stop);
  for (uint64_t x = v0; x < v_end; ++x) frontier.grow_box(&record.coords[x * 3]);
  frontier.decoded = level.applied = stop;
  if (st != Status::ok) {
    refuse(st, what);
  } else if (end == total && !node_counts_match(total - 1)) {
    fail(Status::corrupt, "the last node added other faces or wedges than its table entry");
    return stop - s0 - 1;  // (as apply(): the last split stands but is not counted)
  }
  return stop - s0;
#endif
}

// ---- view-dependent decoding ----

// Node 0 is applied and nothing after it: the mesh arrays take every id of the stream, the chunks
// that arrived in order go to their nodes' readers, and the nodes' parents and cells are set up.
bool Decoder::Impl::enter_selection() {
  const std::vector<NodeEntry>& table = nodes.table.nodes;
  const size_t total = table.size();
  if (!node_counts_match(0))
    return refuse(Status::corrupt, "node 0 added other faces or wedges than its table entry");
  const uint64_t nv = info.full_vertices, nf = info.full_faces;
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
    // Room first, so that nothing below fails half way.
    level.mesh.reserve(nv, nf);
    record.coords.reserve(nv * 3);
    record.positions.reserve(nv * 3);
    record.parents.reserve(nv);
    record.sides.reserve(info.total_splits);
    record.splits.reserve(info.total_splits);
    frontier.choice.reserve_vertices(nv);
    frontier.choice.resize_vertices(nv);
  }
  PMZ_CATCH_BAD_ALLOC {
    fail(Status::out_of_memory, "allocation failed for the whole mesh's ids");
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
  level.mesh.corner_vertex.resize(nf * 3, 0);
  level.mesh.opposite.resize(nf * 3, kNoCorner);
  level.mesh.vertex_corner.resize(nv, kNoCorner);
  record.coords.resize(nv * 3);
  record.positions.resize(nv * 3);
  record.parents.resize(nv, 0xFFFFFFFFu);
  record.sides.resize(info.total_splits);
  record.splits.resize(info.total_splits, {kNoCorner, kNoRank, kNoRank});
  nodes.first_models = std::move(nodes.models[0]);
  sel.applied_nodes = 1;
  sel.on = true;
  level.changes.all = true;
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
  auto owned = std::make_unique<Frontier>();
  Frontier& w = *owned;
  start_worker(w, k, node_first_vertex(k), sel.first_face[k],
               frontier.choice.take_epochs(e.splits + 1), cell_list(k), sel.ring_work);
  w.lazy = std::move(sel.readers[k]);
  nodes.models[k]->inherit(*nodes.first_models);
  while (w.decoded < last && !w.lazy.empty()) {
    const uint64_t ahead = w.decoded + FanPrefetcher::kWalkers;
    w.fans.step(level.mesh, record.coords.data(), record.coords.size(),
                ahead < last ? record.splits[ahead].v : kNoCorner, frontier.choice.degrees(),
                frontier.choice.sums_bytes());
    if (!first_apply(w, w.decoded)) break;
  }
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
  sel.sectors[k].assign(w.sectors.begin(), w.sectors.end());
  sel.decoded[k] = 1;
  nodes.models[k].reset();
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
  std::fill_n(record.splits.begin() + ptrdiff_t(first), e.splits,
              Split{kNoCorner, kNoRank, kNoRank});
  sel.readers[k] = std::move(readers);
  nodes.models[k] = std::move(models);
  sel.arrival[k] = Selection::whole;
  sel.available += e.splits;
  return Status::ok;
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
  for (size_t k = 1; k < total; ++k) {  // (parents come first in file order)
    sel.priority[k] = projected_error(v, table[k]);
    bool w = sel.priority[k] > v.pixel_error || (v.pixel_error <= 0 && sel.priority[k] >= 0);
    for (uint32_t p : sel.parents[k]) w = w && want[p];
    want[k] = w;
  }
  PMZ_TRY {
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
    std::priority_queue<std::pair<float, uint32_t>> heap;
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
    for (uint32_t k = 1; k < total; ++k) {
      if (!want[k] || sel.applied[k]) continue;
      sel.complete = false;
      if (!sel.decoded[k] && sel.arrival[k] != Selection::whole) sel.fetch.push_back(k);
    }
    std::sort(sel.fetch.begin(), sel.fetch.end(), [&](uint32_t a, uint32_t b) {
      if (table[a].level != table[b].level) return table[a].level > table[b].level;
      return sel.priority[a] > sel.priority[b];
    });
  }
  PMZ_CATCH_BAD_ALLOC { fail(Status::out_of_memory, "allocation failed while refining"); }
  return n;
}

void Decoder::Impl::undo() {
  // undo_resplit may throw bad_alloc only from its scratch, before it changes anything: count
  // the split as undone only after it.
  const uint8_t side = record.sides[level.applied - 1];
  const Split& s = record.splits[level.applied - 1];
  level.mesh.undo_resplit(s.v, s.a, s.b, side & kHasLeft, side & kHasRight);
  level.sector_end -= s.b;
  --level.applied;
  if (attrs) {
    attrs->undo(level.mesh, level.applied, side & kHasLeft, side & kHasRight);
    level.changes.wedge_begin = std::min(level.changes.wedge_begin, attrs->state.wedge_count);
  }
  level.changes.face_begin = std::min(level.changes.face_begin, level.mesh.face_count());
  level.changes.vertex_begin = std::min(level.changes.vertex_begin, level.mesh.vertex_count());
  note_rewritten(level.mesh.sector_faces(), level.mesh.face_count());
}

Status Decoder::feed(const void* data, size_t size) {
  Impl& d = *impl_;
  if (d.stage == Stage::failed || size == 0) return d.status;
  const auto* p = static_cast<const uint8_t*>(data);
  d.input.parse_base = d.input.consumed - d.input.pending.size();
  d.input.consumed += size;
  PMZ_TRY {
    if (d.input.pending.empty()) {
      size_t used = d.parse(p, size);
      if (d.stage != Stage::failed) d.input.pending.assign(p + used, p + size);
    } else {
      d.input.pending.insert(d.input.pending.end(), p, p + size);
      size_t used = d.parse(d.input.pending.data(), d.input.pending.size());
      if (d.stage != Stage::failed)
        d.input.pending.erase(d.input.pending.begin(), d.input.pending.begin() + ptrdiff_t(used));
    }
  }
  PMZ_CATCH_BAD_ALLOC { d.fail(Status::out_of_memory, "allocation failed"); }
  if (d.stage == Stage::failed) d.input.pending.clear();
  return d.status;
}

Status Decoder::finish() {
  Impl& d = *impl_;
  if (d.stage != Stage::failed && d.stage != Stage::complete)
    d.fail(Status::truncated, "stream ended before its end marker");
  return d.status;
}

Status Decoder::status() const { return impl_->status; }
const std::string& Decoder::error_message() const { return impl_->message; }
const StreamInfo& Decoder::info() const { return impl_->info; }
uint64_t Decoder::bytes_consumed() const { return impl_->input.consumed; }

uint64_t Decoder::Impl::refine(uint64_t max_splits, uint64_t face_target) {
  uint64_t n = 0;
  if (sel.on) return 0;  // the view decides (update_view)
  PMZ_TRY {
    // Room for every split this call may apply (bounded by decoded input, not the header):
    // apply() must not grow a buffer once it changed the mesh (an allocation failure there would
    // leave a split half applied). With a face target, at most the missing faces (a split adds
    // at least one).
    uint64_t want = std::min(max_splits, record.available - level.applied);
    want = std::min(want, face_target - std::min<uint64_t>(face_target, level.mesh.face_count()));
    uint64_t target = level.applied + want;
    if (target > level.applied) {
      // Grown geometrically: at least to the next power of two and at least doubled. Reserving
      // exactly `target`, or all that is available, reallocates (and copies everything) on every
      // small call or every chunk that arrives (a viewer refining a few hundred per frame; a
      // stream refined as it arrives: 1.2M faces in 47 chunks took 3.3x the CPU time). Below
      // twice `target`, so still bounded by the decoded input. Once `target` is at least
      // 1 / kHeaderTrust of the header's split count, room for all of them at once: the
      // doublings up to there copied every buffer and faulted its pages in again (1.2M faces fed
      // in 997-byte slices with refine(5000) after each: about a quarter of the CPU time), and
      // the reservation stays within kHeaderTrust times the decoded input (untouched capacity
      // costs no memory until used).
      const uint64_t capacity = record.sides.capacity();
      uint64_t room =
          target <= capacity ? target
          : info.total_splits <= kHeaderTrust * target
              ? std::max(target, info.total_splits)
              : std::max(target, std::min<uint64_t>(info.total_splits,
                                                    std::max(std::bit_ceil(target), 2 * capacity)));
      uint64_t nv = info.base_vertices + room;
      level.mesh.reserve(nv, level.mesh.face_count() + 2 * (room - level.applied));
      record.coords.reserve(nv * 3);
      record.positions.reserve(nv * 3);
      record.parents.reserve(nv);
      record.sides.reserve(room);
      if (attrs)
        attrs->reserve(level.mesh.face_count() + 2 * (room - level.applied), room,
                       info.total_splits);
      frontier.choice.reserve_vertices(nv);
    }
    level.fans.reset();
    level.listed_ahead = 0;
    while (n < max_splits && level.applied < record.available &&
           level.mesh.face_count() < face_target) {
      // (A batch refused at its first split applied none: the loop's test then ends it.)
      const uint64_t m = parallel_nodes(max_splits - n, face_target);
      if (m || level.applied >= record.available) {
        n += m;
        level.fans.reset();
        continue;
      }
      prefetch();
      if (!apply()) break;
      ++n;
    }
  }
  PMZ_CATCH_BAD_ALLOC { fail(Status::out_of_memory, "allocation failed while refining"); }
  return n;
}

uint64_t Decoder::Impl::coarsen(uint64_t max_splits, uint64_t face_floor) {
  uint64_t n = 0;
  if (sel.on) return 0;
  level.fans.reset();
  UnlinkWindow window;
  PMZ_TRY {
    for (; n < max_splits && level.applied > 0; ++n) {
      const uint8_t side = record.sides[level.applied - 1];
      if (level.mesh.face_count() - (side & kHasLeft ? 1u : 0u) - (side & kHasRight ? 1u : 0u) <
          face_floor)
        break;
      // Splits are undone last first: the sector of the one kWalkers further on, and further
      // still what unlinking its new faces touches (see prefetch_unlink).
      constexpr uint32_t kAhead = FanPrefetcher::kWalkers;
      if (level.applied > kAhead)
        level.fans.step_sector(level.mesh, record.splits[level.applied - 1 - kAhead].a,
                               record.splits[level.applied - 1 - kAhead].b);
      else
        level.fans.step_sector(level.mesh, kNoCorner, 0);
      prefetch_unlink(window);
      undo();
    }
  }
  PMZ_CATCH_BAD_ALLOC {  // undo_resplit grows no scratch in practice (see its test);
                         // kept as a guard
    fail(Status::out_of_memory, "allocation failed while coarsening");
  }
  // The undone splits lowered face_begin: faces listed before then may now be at or above it
  // (rewritten again from there on, or removed). MeshChanges lists only faces below it.
  if (n > 0)
    std::erase_if(level.changes.modified_faces,
                  [&](uint32_t f) { return f >= level.changes.face_begin; });
  return n;
}

uint64_t Decoder::refine(uint64_t max_splits) { return impl_->refine(max_splits, UINT64_MAX); }
uint64_t Decoder::coarsen(uint64_t max_splits) { return impl_->coarsen(max_splits, 0); }

void Decoder::set_face_target(uint64_t faces) {
  Impl& d = *impl_;
  d.coarsen(UINT64_MAX, faces);  // the coarsest level still holding `faces`
  d.refine(UINT64_MAX, faces);   // or refine until it does
}

void Decoder::set_split_target(uint64_t splits) {
  Impl& d = *impl_;
  if (splits < d.level.applied)
    coarsen(d.level.applied - splits);
  else
    refine(splits - d.level.applied);
}

uint64_t Decoder::splits_applied() const {
  return impl_->level.applied + impl_->sel.applied_splits;
}
uint64_t Decoder::splits_available() const {
  return impl_->sel.on ? impl_->sel.available : impl_->record.available;
}
uint32_t Decoder::vertex_count() const { return impl_->level.mesh.vertex_count(); }
uint32_t Decoder::face_count() const { return impl_->level.mesh.face_count(); }
const float* Decoder::positions() const {
  return impl_->record.positions.empty() ? nullptr : impl_->record.positions.data();
}
const uint32_t* Decoder::indices() const {
  return impl_->level.mesh.corner_vertex.empty() ? nullptr : impl_->level.mesh.corner_vertex.data();
}
const uint32_t* Decoder::split_parents() const {
  return impl_->record.parents.empty() ? nullptr : impl_->record.parents.data();
}
const MeshChanges& Decoder::changes() const { return impl_->level.changes; }
void Decoder::clear_changes() {
  Impl& d = *impl_;
  d.level.changes.all = false;
  d.level.changes.modified_faces.clear();
  d.level.changes.vertex_begin = d.level.mesh.vertex_count();
  d.level.changes.face_begin = d.level.mesh.face_count();
  d.level.changes.wedge_begin = d.attrs ? d.attrs->state.wedge_count : 0;
}

// Attributes: nothing (0 / nullptr) without them, and before the base ATTR chunk.
uint32_t Decoder::wedge_count() const {
  const Impl& d = *impl_;
  return d.attrs && d.info.base_done ? d.attrs->state.wedge_count : 0;
}
const uint32_t* Decoder::wedge_vertices() const {
  return wedge_count() ? impl_->attrs->state.wedge_vertex.data() : nullptr;
}
const float* Decoder::wedge_positions() const {
  return wedge_count() ? impl_->attrs->wedge_positions.data() : nullptr;
}
const uint32_t* Decoder::wedge_indices() const {
  return wedge_count() ? impl_->attrs->state.corner_wedge.data() : nullptr;
}
uint32_t Decoder::texcoord_set_count() const {
  return wedge_count() ? impl_->attrs->state.head.texcoord_sets : 0;
}
const float* Decoder::texcoords(uint32_t set) const {
  return set < texcoord_set_count() ? impl_->attrs->texcoords[set].data() : nullptr;
}
const float* Decoder::normals() const {
  return wedge_count() && impl_->attrs->state.head.normals ? impl_->attrs->normals.data() : nullptr;
}
uint32_t Decoder::color_components() const {
  return wedge_count() ? impl_->attrs->state.head.color_components : 0;
}
const float* Decoder::colors() const {
  return color_components() ? impl_->attrs->colors.data() : nullptr;
}
const uint32_t* Decoder::face_materials() const {
  const Impl& d = *impl_;
  return d.attrs && d.info.base_done && !d.attrs->state.face_material.empty()
             ? d.attrs->state.face_material.data()
             : nullptr;
}
uint32_t Decoder::material_count() const { return uint32_t(impl_->materials.size()); }
const MaterialInfo* Decoder::material(uint32_t i) const {
  return i < impl_->materials.size() ? &impl_->materials[i] : nullptr;
}
const std::string& Decoder::material_library() const {
  static const std::string kNone;
  return impl_->attrs ? impl_->attrs->state.head.material_library : kNone;
}

// The public kinds are the codec's, in the same order.
static_assert(int(AttributeBits::texcoords) == AttributeCost::kTexcoords &&
              int(AttributeBits::normals) == AttributeCost::kNormals &&
              int(AttributeBits::colors) == AttributeCost::kColors &&
              int(AttributeBits::materials) == AttributeCost::kMaterials &&
              int(AttributeBits::wedges) == AttributeCost::kWedges &&
              int(AttributeBits::kinds) == AttributeCost::kKinds);
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

void Decoder::count_attribute_bits(AttributeBits* into) {
  impl_->attribute_bits = into ? into->bits : nullptr;
}

}  // namespace pmz
