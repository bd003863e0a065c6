// SPDX-License-Identifier: MIT
// The streaming decoder's framing and chunks: HEAD, BASE, SPLT, ATTR, NODE and END taken out of
// whatever slices arrive and checked (once per chunk; the state: decoder_impl.hpp).
#include <thread>

#include "decoder_impl.hpp"

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

Decoder::Decoder(const DecoderLimits& limits) : impl_(new Impl) {
  impl_->limits = limits;
  impl_->frontier.mesh = &impl_->level.mesh;
  set_threads(0);
}

void Decoder::set_threads(uint32_t n) {
#if defined(__wasm__) && !defined(__EMSCRIPTEN_PTHREADS__)
  n = 1;  // (the WebAssembly build without threads: scripts/web.sh's single-threaded module)
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
      if (nodes.arrived_splits && nodes.arrival) {  // its first chunks' groups went there
        models->groups = nodes.arrival->groups;
        models->near = nodes.arrival->near;
      }
    }
    SplitChunkReader r;
    if (!r.open(p, n, e.splits - nodes.arrived_splits, *models, err, frontier.open))
      return fail(Status::corrupt, err);
    frontier.open = r.open_group();
    // Its splits not applied yet: those the mesh arrays cover so far (cover_node_ids() gives
    // the others that value when it grows them to the node).
    const uint64_t at = nodes.first_split[k] + nodes.arrived_splits;
    const uint64_t end = std::min<uint64_t>(at + r.split_count(), record.splits.size());
    if (at < end)
      std::fill(record.splits.begin() + ptrdiff_t(at), record.splits.begin() + ptrdiff_t(end),
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
    if (!*models && nodes.arriving > 0) {  // its groups only, until its models are made
      models = &nodes.arrival;
      if (*models && nodes.arrived_splits == 0) {
        (*models)->groups = UIntModel();
        (*models)->near = kProbInit;
      }
    }
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
  if (size > record.splits.capacity() && header_trusted(size)) {
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
  if (!read_node_table(p, n, info.total_splits, n / 16 + 1, attrs != nullptr,
                       info.version_minor >= 1, nodes.table, err))
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

// A copy of the models the first node left (in a spare's memory if there is one).
std::unique_ptr<SplitModels> Decoder::Impl::first_models_copy() {
  if (!nodes.spare) return std::make_unique<SplitModels>(*nodes.first_models);
  std::unique_ptr<SplitModels> m = std::move(nodes.spare);
  *m = *nodes.first_models;
  return m;
}

// Node k's models as its first application starts (spec/format.md section 15.4): those the first
// node left but for the group models, its own (still in nodes.arrival while its chunks arrive;
// made with its models when they arrived for a view). Its readers, the first of `readers`, decode
// with them.
SplitModels& Decoder::Impl::node_models(size_t k, std::deque<SplitChunkReader>& readers) {
  std::unique_ptr<SplitModels>& m = nodes.models[k];
  if (m) {
    m->inherit(*nodes.first_models);
  } else {
    m = first_models_copy();
    const bool arriving = k == nodes.arriving && nodes.arrived_splits && nodes.arrival;
    m->groups = arriving ? nodes.arrival->groups : UIntModel();
    m->near = arriving ? nodes.arrival->near : kProbInit;
  }
  uint64_t got = 0;
  for (size_t i = 0; i < readers.size() && got < nodes.table.nodes[k].splits; ++i) {
    readers[i].set_models(*m);
    got += readers[i].split_count();
  }
  return *m;
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
    drop_models(k - 1);  // its splits are all decoded
    node_models(k, frontier.lazy);
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

}  // namespace pmz
