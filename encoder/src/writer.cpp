// SPDX-License-Identifier: MIT
// The .pmz writer: inverts a collapse sequence into vertex splits, groups them into batches of
// independent splits (within windows of the greedy order, so the mesh at every window boundary
// is the greedy prefix), and codes them by replaying the decoder's own ProgressiveMesh.
#include "pmz/writer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <memory>

#include "attr_writer.hpp"
#include "node_cones.hpp"
#include "pmz/base_codec.hpp"
#include "pmz/cluster_plan.hpp"
#include "pmz/fan_wedge.hpp"
#include "pmz/format.hpp"
#include "pmz/node_table.hpp"
#include "pmz/progressive_mesh.hpp"
#include "pmz/speed_level.hpp"
#include "pmz/split_chunk.hpp"
#include "pmz/triangle_distance.hpp"
#include "pmz/vertex_choice.hpp"
#include "survivors.hpp"

namespace pmz {

static_assert(kWriteSymbolKinds == kSymbolKinds, "WriteStats::symbol_bits has a slot per kind");

namespace {

constexpr double kWindowGrowth = 1.5;  // a window grows the vertex count by at most 50%
// Chunk sizes: a decoder uses a chunk's splits once the whole chunk is there, so a chunk's
// bytes are the lag between what arrived and what shows. The first chunk holds
// kFirstChunkSplits (a first view after a few hundred bytes); then each about kEarlyShare of
// the stream so far (at least kMinChunkBytes), until that reaches kLagBytes; then the larger
// of kLagBytes and kLagShare of the stream so far (bytes estimated from the last chunk's bytes
// per split), within kMaxChunkSplits. The early chunks grow with the stream because its first
// kilobytes carry the largest error drops (a chunk costs about 10 bytes: header and coder
// ending). Groups continue across chunks (spec/format.md section 8).
constexpr uint32_t kFirstChunkSplits = 16, kMinChunkSplits = 16, kMaxChunkSplits = 65536;
constexpr double kLagBytes = 1536, kLagShare = 0.025, kEarlyShare = 0.25, kMinChunkBytes = 96;
// HEAD (curvature, fine_curvature) pairs the writer tries (eighths; spec/format.md section 13):
// those best on some corpus mesh out of a wider set (plus no offset at all).
struct Curvatures {
  uint32_t curvature, fine;
};
constexpr Curvatures kCurvatureCandidates[] = {{0, 0}, {0, 4}, {0, 5}, {0, 6}, {1, 4},
                                               {2, 4}, {2, 6}, {3, 2}, {4, 2}};

struct Plan {
  uint32_t base_vertices = 0;
  std::vector<uint32_t> base_faces;   // decoded ids (== greedy ids for base vertices)
  std::vector<uint32_t> input_of;     // decoded id -> input id
  std::vector<uint32_t> order;        // final position -> collapse index
  std::vector<uint32_t> group_sizes;  // batches in final order
  std::vector<uint32_t> decoded_id;   // input id -> decoded id
  std::vector<uint8_t> base_stream;   // BASE's range-coded traversal
};

// Ranks of vl/vr (kNoVertex -> kNoRank) in the ring gathered last; false if absent.
bool find_ranks(const ProgressiveMesh& pm, uint32_t vl, uint32_t vr, uint32_t& rl, uint32_t& rr) {
  rl = vl == kNoVertex ? kNoRank : pm.rank_of(vl);
  rr = vr == kNoVertex ? kNoRank : pm.rank_of(vr);
  return (vl == kNoVertex || rl != kNoRank) && (vr == kNoVertex || rr != kNoRank);
}

// HEAD's bounding box and the quantizer over the whole input (spec/format.md section 5).
void file_quantizer(const IndexedMesh& mesh, uint32_t bits, FileHeader& h, Quantizer& quant) {
  h.position_bits = bits;
  for (int a = 0; a < 3; ++a) {
    h.bbox_min[a] = INFINITY;
    h.bbox_max[a] = -INFINITY;
  }
  for (uint32_t i = 0; i < mesh.vertex_count(); ++i)
    for (int a = 0; a < 3; ++a) {
      h.bbox_min[a] = std::min(h.bbox_min[a], mesh.positions[i * 3 + a]);
      h.bbox_max[a] = std::max(h.bbox_max[a], mesh.positions[i * 3 + a]);
    }
  quant.init(h.position_bits, h.bbox_min, h.bbox_max);
}

// node_splits: with a node table, each node's split count in file order; a node's splits stay
// together (each node starts a window of its own).
bool make_plan(const CollapseSequence& seq, const WriteOptions& opt, Plan& plan, std::string& error,
               const std::vector<uint64_t>& node_splits = {}) {
  const IndexedMesh& mesh = seq.mesh;
  const uint32_t n = mesh.vertex_count();
  const size_t total = seq.collapses.size();
  if (n == 0 || mesh.face_count() == 0) return error = "empty mesh", false;
  // How many collapses the base mesh is behind: --base-faces stops early.
  uint64_t faces = mesh.face_count();
  size_t used = 0;
  std::vector<uint8_t> removed(n, 0);
  for (; used < total; ++used) {
    if (opt.base_faces && faces <= opt.base_faces) break;
    const HalfEdgeCollapse& c = seq.collapses[used];
    auto bad = [&](uint32_t x) { return x != kNoVertex && (x >= n || removed[x]); };
    if (c.u >= n || c.v >= n || c.u == c.v || removed[c.u] || removed[c.v] || bad(c.vl) ||
        bad(c.vr) || (c.vl == kNoVertex && c.vr == kNoVertex))
      return error = "collapse " + std::to_string(used) + " is inconsistent with the mesh", false;
    removed[c.u] = 1;
    faces -= (c.vl != kNoVertex) + (c.vr != kNoVertex);
  }
  const std::vector<uint32_t> survivor = collapse_survivors(seq, used);

  // Base faces, in input ids of the surviving vertices.
  std::vector<uint32_t> base_faces;
  for (uint32_t f = 0; f < mesh.face_count(); ++f) {
    uint32_t t[3];
    for (int k = 0; k < 3; ++k) t[k] = survivor[mesh.indices[f * 3 + k]];
    if (t[0] == t[1] || t[0] == t[2] || t[1] == t[2]) continue;
    base_faces.insert(base_faces.end(), t, t + 3);
  }
  const uint32_t base_face_n = uint32_t(base_faces.size() / 3);
  // Base order (spec/format.md section 7): the base coder numbers vertices and faces in its
  // traversal order (components started from the faces in input order), then the vertices
  // without faces in ascending input id.
  std::vector<uint32_t> gid(n, kNoVertex), input_of_gid(n);
  uint32_t base_n = 0;
  {
    std::vector<uint32_t> surviving, local(n, kNoVertex);
    for (uint32_t i = 0; i < n; ++i)
      if (!removed[i]) local[i] = uint32_t(surviving.size()), surviving.push_back(i);
    for (uint32_t& x : base_faces) x = local[x];
    FileHeader h;
    Quantizer quant;
    file_quantizer(mesh, opt.position_bits, h, quant);
    std::vector<int32_t> coords(surviving.size() * 3);
    for (size_t d = 0; d < surviving.size(); ++d)
      for (int a = 0; a < 3; ++a)
        coords[d * 3 + a] = quant.quantize(mesh.positions[size_t(surviving[d]) * 3 + a], a);
    base_n = uint32_t(surviving.size());
    std::vector<uint32_t> given_of;
    BaseMesh decoded;
    plan.base_stream.clear();
    if (!encode_base(coords.data(), base_n, base_faces.data(), base_face_n, plan.base_stream,
                     given_of, decoded, error))
      return error = "base mesh: " + error, false;
    plan.base_faces = std::move(decoded.faces);
    for (uint32_t d = 0; d < base_n; ++d) gid[input_of_gid[d] = surviving[given_of[d]]] = d;
  }
  // Greedy ids of the splits: u of each split in decode order (base vertices: as above; for
  // them also the decoded ids).
  for (size_t j = 0; j < used; ++j) {
    uint32_t u = seq.collapses[used - 1 - j].u;
    input_of_gid[gid[u] = base_n + uint32_t(j)] = u;
  }
  plan.base_vertices = base_n;
  if (plan.base_faces.size() / 3 != faces)
    return error = "collapse sequence does not reproduce the mesh's face count", false;

  // Greedy replay: layer each split after every earlier split of its window whose
  // footprint (closed one-ring of v, plus u) it overlaps.
  ProgressiveMesh pm;
  if (!pm.build(base_n, plan.base_faces.data(), faces, error))
    return error = "base mesh: " + error, false;
  std::vector<int32_t> last_layer(n, -1);
  std::vector<uint32_t> layer(used);
  int32_t window_first = 0, max_layer = -1;
  uint32_t window_start = base_n;
  size_t next_node = 0;
  uint64_t node_start = 0;
  for (size_t j = 0; j < used; ++j) {
    const HalfEdgeCollapse& c = seq.collapses[used - 1 - j];
    uint32_t v = gid[c.v];
    uint32_t vl = c.vl == kNoVertex ? kNoVertex : gid[c.vl];
    uint32_t vr = c.vr == kNoVertex ? kNoVertex : gid[c.vr];
    uint32_t rl, rr;
    if (!pm.gather_ring(v) || !find_ranks(pm, vl, vr, rl, rr))
      return error = "collapse " + std::to_string(used - 1 - j) +
                     " is not a manifold half-edge collapse",
             false;
    const bool node_starts = next_node < node_splits.size() && j == node_start;
    if (node_starts) node_start += node_splits[next_node++];
    if (node_starts || pm.vertex_count() > uint64_t(double(window_start) * kWindowGrowth)) {
      window_first = max_layer + 1;
      window_start = pm.vertex_count();
    }
    // Two splits commute when neither v is in the other's closed one-ring; a split only
    // changes adjacency at its own v and u, so marking centres (v, u) is enough.
    int32_t l = std::max(window_first, last_layer[v] + 1);
    for (uint32_t w : pm.ring()) l = std::max(l, last_layer[w] + 1);
    layer[j] = uint32_t(l);
    max_layer = std::max(max_layer, l);
    last_layer[v] = l;
    last_layer[pm.vertex_count()] = l;
    if (!pm.split(v, rl, rr))
      return error = "collapse " + std::to_string(used - 1 - j) + " cannot be inverted", false;
  }

  // Final order: by layer, then by v's decoded id (known: v exists before its layer).
  std::vector<uint32_t> start(size_t(max_layer + 2), 0);
  for (uint32_t l : layer) ++start[l + 1];
  for (size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
  std::vector<uint32_t> by_layer(used);
  for (uint32_t j = 0; j < used; ++j) by_layer[start[layer[j]]++] = j;
  std::vector<uint32_t> did_of_gid(n);
  for (uint32_t i = 0; i < base_n; ++i) did_of_gid[i] = i;
  plan.order.clear();
  plan.group_sizes.clear();
  std::vector<std::pair<uint32_t, uint32_t>> batch;  // (decoded v, j)
  size_t at = 0;
  while (at < used) {
    uint32_t l = layer[by_layer[at]];
    batch.clear();
    for (; at < used && layer[by_layer[at]] == l; ++at) {
      uint32_t j = by_layer[at];
      batch.push_back({did_of_gid[gid[seq.collapses[used - 1 - j].v]], j});
    }
    std::sort(batch.begin(), batch.end());
    for (auto [dv, j] : batch) {
      did_of_gid[base_n + j] = base_n + uint32_t(plan.order.size());
      plan.order.push_back(uint32_t(used - 1 - j));
    }
    plan.group_sizes.push_back(uint32_t(batch.size()));
  }
  plan.input_of.assign(base_n + used, 0);
  plan.decoded_id.assign(n, kNoVertex);
  for (uint32_t g = 0; g < base_n + used; ++g) {
    plan.input_of[did_of_gid[g]] = input_of_gid[g];
    plan.decoded_id[input_of_gid[g]] = did_of_gid[g];
  }
  return true;
}

using Face = std::array<uint32_t, 3>;
// What write_pmz refuses before any work.
bool check_write_input(const CollapseSequence& seq, const WriteOptions& opt, std::string& error) {
  if (opt.position_bits > 30) return error = "position bits must be 0..30", false;
  if (opt.level > kMaxLevel) return error = "level must be 0..1", false;
  for (float x : seq.mesh.positions)
    if (!std::isfinite(x)) return error = "non-finite vertex coordinate", false;
  return true;
}

// HEAD's fields known before the splits are coded (all but the curvature weights and the
// flags), and every vertex's quantized position by decoded id.
void begin_header(const IndexedMesh& mesh, const Plan& plan, const WriteOptions& opt, FileHeader& h,
                  std::vector<int32_t>& coords) {
  Quantizer quant;
  file_quantizer(mesh, opt.position_bits, h, quant);
  const uint32_t total_v = uint32_t(plan.input_of.size());
  coords.resize(size_t(total_v) * 3);
  for (uint32_t d = 0; d < total_v; ++d)
    for (int a = 0; a < 3; ++a)
      coords[d * 3 + a] = quant.quantize(mesh.positions[plan.input_of[d] * 3 + a], a);
  h.base_vertices = plan.base_vertices;
  h.base_faces = uint32_t(plan.base_faces.size() / 3);
  h.full_faces = mesh.face_count();
  h.total_splits = total_v - plan.base_vertices;
  h.level = opt.level;
}

constexpr size_t kMaxCandidates = std::size(kCurvatureCandidates);

// The splits: replayed in final order with the decoder's core to get ranks and predictions.
// The curvature weight (HEAD) is the file's: one replay codes the splits once per candidate
// (only the residuals differ) into SPLT chunks (each followed by its ATTR chunk), and the
// smallest is kept (spec/format.md section 13). The speed level has no curvature offsets: one
// candidate, (0, 0).
class SplitCoder {
 public:
  SplitCoder(const CollapseSequence& seq, const WriteOptions& opt, const Plan& plan,
             std::vector<int32_t>& coords, AttributeWriter* attrs)
      : seq_(seq),
        opt_(opt),
        plan_(plan),
        coords_(coords),
        attrs_(attrs),
        speed_(opt.level == kLevelSpeed),
        candidates_(speed_ ? 1 : kMaxCandidates) {}

  // The base mesh built (and its attributes coded into base_attributes), the choice set up.
  bool start(const FileHeader& h, std::vector<uint8_t>& base_attributes, std::string& error) {
    if (!pm_.build(plan_.base_vertices, plan_.base_faces.data(), h.base_faces, error)) return false;
    if (attrs_) attrs_->encode_base(pm_, coords_.data(), base_attributes);
    choice_.reset(pm_, coords_.data(), h.position_bits, !speed_);
    for (auto& m : models_) {
      m = std::make_unique<SplitModels>();
      m->speed = speed_;
    }
    return true;
  }

  // A stream with a node table (nodes: its levels and nodes, split counts set; the groups
  // of make_plan never straddle two nodes), whose cones gather each node's faces at its end.
  void set_nodes(const NodeTable* nodes, NodeCones* cones) {
    nodes_ = nodes;
    cones_ = cones;
    uint64_t at = 0;
    for (const NodeEntry& n : nodes->nodes) {
      node_first_.push_back(at);
      at += n.splits;
    }
  }

  // Every stream group in order; a chunk ends once it holds chunk_limit_ splits, inside a
  // group or not.
  bool code_groups(std::string& error) {
    uint32_t at = 0;
    for (uint32_t group : plan_.group_sizes) {
      while (nodes_ && node_ < nodes_->nodes.size() && at == node_first_[node_]) start_node();
      if (!code_group(at, group, error)) return false;
      at += group;
    }
    flush();
    if (nodes_) end_node();
    return true;
  }

  // With a node table: per node, its bytes in candidate k's split bytes and the faces it adds.
  uint64_t node_bytes(size_t k, size_t node) const { return node_bytes_[k][node]; }
  uint64_t node_faces(size_t node) const { return node_faces_[node]; }
  uint64_t node_wedges(size_t node) const { return node_wedges_[node]; }
  // With a node table: per split in coding order, the distance from u to v's fan before it (the
  // surface u was collapsed onto), in the input's units.
  const std::vector<float>& deviations() const { return deviation_; }

  // The candidate with the fewest split bytes (the first of equals).
  size_t best() const {
    size_t best = 0;
    for (size_t k = 1; k < candidates_; ++k)
      if (trial_[k].size() < trial_[best].size()) best = k;
    return best;
  }
  const std::vector<uint8_t>& split_bytes(size_t k) const { return trial_[k]; }
  const WriteStats& stats(size_t k) const { return trial_st_[k]; }
  // The full mesh, after code_groups.
  const ProgressiveMesh& mesh() const { return pm_; }

 private:
  // The choice bits of the group of n splits from final position `at`, then each split.
  bool code_group(uint32_t at, uint32_t n, std::string& error) {
    vs_.clear();
    for (uint32_t i = at; i < at + n; ++i)
      vs_.push_back(plan_.decoded_id[seq_.collapses[plan_.order[i]].v]);
    choice_.start_group();
    bool near;
    if (!choice_bits(choice_, pm_, pm_.vertex_count(), vs_, chunk_choice_, near))
      return error = "internal: a group's split vertices are adjacent", false;
    chunk_groups_.push_back({n, near});
    for (uint32_t i = at; i < at + n; ++i) {
      if (!code_split(plan_.order[i], error)) return false;
      if (chunk_[0].size() >= chunk_limit_) flush();
    }
    return true;
  }

  // The end of a node's bytes (after flush()), then the next node: models from the first
  // node's, its cell's candidates (spec/format.md section 15.4); its chunks are sized by the
  // whole stream's bytes so far, as a reader in file order sees them.
  void end_node() {
    for (size_t k = 0; k < candidates_; ++k) {
      const uint64_t start = node_start_bytes_[k];
      node_bytes_[k].push_back(trial_[k].size() - start);
      node_start_bytes_[k] = trial_[k].size();
    }
    node_faces_.push_back(pm_.face_count() - node_start_faces_);
    node_start_faces_ = pm_.face_count();
    cones_->node_done(pm_, node_start_vertices_, pm_.vertex_count());
    const uint32_t wedges = attrs_ ? attrs_->wedge_count() : 0;
    node_wedges_.push_back(wedges - node_start_wedges_);
    node_start_wedges_ = wedges;
  }
  void start_node() {
    flush();
    if (node_ > 0) end_node();
    if (node_ == 1) {  // the first node's models: where every later node's start
      for (size_t k = 0; k < candidates_; ++k) first_models_[k] = std::move(models_[k]);
      if (attrs_) first_attribute_models_ = attrs_->models();
    }
    for (size_t k = 0; k < candidates_; ++k) {
      node_start_bytes_[k] = trial_[k].size();
      if (node_ > 0) {
        models_[k] = std::make_unique<SplitModels>();
        models_[k]->inherit(*first_models_[k]);
      }
    }
    if (attrs_ && node_ > 0) attrs_->restart_models(first_attribute_models_);
    node_start_faces_ = pm_.face_count();
    node_start_vertices_ = pm_.vertex_count();
    node_start_wedges_ = attrs_ ? attrs_->wedge_count() : 0;
    const NodeEntry& n = nodes_->nodes[node_];
    whole_ = nodes_->levels[n.level].side == 0;
    box_ = CellBox(nodes_->levels[n.level], n.cell);
    if (whole_) {
      choice_.begin_whole_node();
    } else {
      if (int64_t(n.level) != bins_level_) {
        bins_.build(*nodes_, n.level, coords_.data(), pm_.vertex_count());
        bins_level_ = n.level;
      }
      choice_.begin_node(bins_.take(uint32_t(node_)));
    }
    ++node_;
  }
  // After gather_ring(v): the distance from vertex u to v's fan (its faces (v, ring[j],
  // ring[j + 1])), at the input's positions (a collapse moves no vertex).
  float fan_distance(uint32_t v, uint32_t u) const {
    const auto at = [&](uint32_t x) { return &seq_.mesh.positions[size_t(plan_.input_of[x]) * 3]; };
    const std::span<const uint32_t> ring = pm_.ring();
    const size_t faces = pm_.ring_closed() ? ring.size() : ring.size() - 1;
    const double p[3] = {at(u)[0], at(u)[1], at(u)[2]};
    double best = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < faces; ++j)
      best = std::min(
          best, point_triangle_distance2(p, at(v), at(ring[j]), at(ring[(j + 1) % ring.size()])));
    return faces ? float(std::sqrt(best)) : 0.0f;
  }
  // With a node table: v, its ring and u lie in the node's cell (spec/format.md section 15.4).
  bool in_node(uint32_t v, uint32_t u) const {
    if (!nodes_ || whole_) return true;
    auto in = [&](uint32_t x) { return box_.contains(&coords_[size_t(x) * 3]); };
    if (!in(v) || !in(u)) return false;
    for (uint32_t w : pm_.ring())
      if (!in(w)) return false;
    return true;
  }

  // One split: applied to the replay, its wedge and rank symbols, its attributes, and its
  // position residuals once per candidate.
  bool code_split(uint32_t collapse, std::string& error) {
    const HalfEdgeCollapse& c = seq_.collapses[collapse];
    uint32_t v = plan_.decoded_id[c.v];
    uint32_t vl = c.vl == kNoVertex ? kNoVertex : plan_.decoded_id[c.vl];
    uint32_t vr = c.vr == kNoVertex ? kNoVertex : plan_.decoded_id[c.vr];
    uint32_t rl, rr;
    if (!pm_.gather_ring(v) || !find_ranks(pm_, vl, vr, rl, rr) ||
        plan_.decoded_id[c.u] != pm_.vertex_count())
      return error = "internal: reordered split does not replay", false;
    if (!in_node(v, pm_.vertex_count()))
      return error =
                 "a split reaches outside its node's cell (levels made at other position bits?)",
             false;
    if (nodes_) deviation_.push_back(fan_distance(v, pm_.vertex_count()));
    SplitSymbols code;
    code.v = v;
    code.wedge_context = wedge_context(uint32_t(pm_.ring().size()), pm_.ring_closed());
    if (!(speed_ ? wedge_index(pm_, rl, rr, code.wedge_count, code.wedge_rank)
                 : wedge_symbols(coords_.data(), choice_.degrees(), v, pm_, rl, rr,
                                 code.wedge_count, code.wedge_rank, scratch_)) ||
        !pm_.split_gathered(v, rl, rr))
      return error = "internal: split rejected", false;
    code.rank_context = rank_context(pm_.ring_closed(), !speed_ && scratch_.confident);
    choice_.applied(pm_, coords_.data(), rl != kNoRank, rr != kNoRank);
    const uint32_t u = pm_.vertex_count() - 1;
    if (attrs_) attrs_->encode_split(pm_, coords_.data(), collapse, rl != kNoRank, rr != kNoRank);
    if (speed_) {
      PositionPrediction pred;
      speed_predict_position(coords_.data(), pm_.u_ring(), pred);
      position_residuals(pred, &coords_[size_t(u) * 3], code.residual);
      for (int s = 0; s < 3; ++s)
        code.residual_context[s] = pred.context[s], code.mix_context[s] = 0;
      chunk_[0].push_back(code);
      return true;
    }
    RingBasis basis;  // the ring part once; per candidate only the offset and contexts
    ring_basis(coords_.data(), pm_.u_ring(), pm_.ring(), true, true, basis);
    for (size_t k = 0; k < candidates_; ++k) {
      PositionPrediction pred;
      predict_from_basis(coords_.data(), pm_.u_ring(), uint32_t(pm_.ring().size()), basis,
                         kCurvatureCandidates[k].curvature, kCurvatureCandidates[k].fine, pred);
      position_residuals(pred, &coords_[size_t(u) * 3], code.residual);
      for (int s = 0; s < 3; ++s)
        code.residual_context[s] = pred.context[s], code.mix_context[s] = pred.mix[s];
      chunk_[k].push_back(code);
    }
    return true;
  }

  // Ends the current chunk: its SPLT chunk (and ATTR chunk) per candidate; a group it cuts
  // continues in the next (open_, and its choice bits not coded yet). Then the next chunk's
  // size (see kLagBytes).
  void flush() {
    if (chunk_[0].empty()) return;
    OpenGroup next;
    size_t used = 0;
    for (size_t k = 0; k < candidates_; ++k) {
      payload_.clear();
      uint64_t sizes[kSplitStreamCount];
      OpenGroup open = open_;
      encode_split_chunk(chunk_groups_, chunk_choice_, chunk_[k].data(), chunk_[k].size(),
                         *models_[k], payload_, sizes,
                         opt_.symbol_stats ? trial_st_[k].symbol_bits : nullptr, &open, &used);
      next = open;
      trial_st_[k].connectivity_bits += sizes[kStreamConnectivity] * 8;
      trial_st_[k].geometry_bits += sizes[kStreamGeometry] * 8;
      const size_t before = trial_[k].size();
      append_chunk(trial_[k], kChunkSplits, payload_);
      if (attrs_) {
        if (k == 0) attrs_->finish_chunk(chunk_attributes_);
        const size_t at_attributes = trial_[k].size();
        append_chunk(trial_[k], kChunkAttributes, chunk_attributes_);
        trial_st_[k].attribute_bytes += trial_[k].size() - at_attributes;
      }
      trial_st_[k].split_bytes += trial_[k].size() - before;
      if (k == 0) {
        const double per_split = double(trial_[k].size() - before) / double(chunk_[k].size());
        const double so_far = double(plan_.base_stream.size() + trial_[k].size());
        const double target = std::max({kMinChunkBytes, std::min(kLagBytes, kEarlyShare * so_far),
                                        kLagShare * double(trial_[k].size())});
        chunk_limit_ = uint32_t(
            std::clamp(target / per_split, double(kMinChunkSplits), double(kMaxChunkSplits)));
      }
      chunk_[k].clear();
    }
    open_ = next;
    chunk_groups_.clear();
    chunk_choice_.erase(chunk_choice_.begin(), chunk_choice_.begin() + ptrdiff_t(used));
  }

  const CollapseSequence& seq_;
  const WriteOptions& opt_;
  const Plan& plan_;
  std::vector<int32_t>& coords_;
  AttributeWriter* attrs_;
  const bool speed_;
  const size_t candidates_;
  ProgressiveMesh pm_;
  VertexChoice choice_;
  WedgeScratch scratch_;
  std::unique_ptr<SplitModels> models_[kMaxCandidates];
  std::vector<uint8_t> trial_[kMaxCandidates];
  WriteStats trial_st_[kMaxCandidates];
  // The chunk being gathered: its symbols per candidate, its groups and choice bits (the same
  // for every candidate).
  std::vector<SplitSymbols> chunk_[kMaxCandidates];
  std::vector<GroupCode> chunk_groups_;
  std::vector<uint32_t> chunk_choice_, vs_;
  std::vector<uint8_t> payload_, chunk_attributes_;
  uint32_t chunk_limit_ = kFirstChunkSplits;
  OpenGroup open_;  // the group the last chunk cut
  // With a node table: the next node, each node's first split, the level binned last, the
  // current node's grid and cell, per candidate where the node's bytes start and each node's
  // size, and the faces each node adds.
  const NodeTable* nodes_ = nullptr;
  NodeCones* cones_ = nullptr;
  size_t node_ = 0;
  std::vector<uint64_t> node_first_;
  CellBins bins_;
  int64_t bins_level_ = -1;
  bool whole_ = true;  // the current node holds every vertex; else its cell's box
  CellBox box_;
  uint64_t node_start_bytes_[kMaxCandidates] = {};
  std::vector<uint64_t> node_bytes_[kMaxCandidates];
  uint64_t node_start_faces_ = 0, node_start_wedges_ = 0;
  uint32_t node_start_vertices_ = 0;
  std::vector<uint64_t> node_faces_, node_wedges_;
  std::vector<float> deviation_;
  std::unique_ptr<SplitModels> first_models_[kMaxCandidates];
  AttributeModels first_attribute_models_;
};

// The file: signature, HEAD (with the attribute header), BASE (the stream alone: its counts are
// HEAD's) and its ATTR chunk, the chosen candidate's split chunks, END.
void assemble_file(FileHeader& h, const Plan& plan, const AttributeWriter* attrs,
                   const std::vector<uint8_t>& base_attributes, const NodeTable* nodes,
                   const std::vector<uint8_t>& split_bytes, WriteStats& st,
                   std::vector<uint8_t>& out) {
  out.assign(kSignature, kSignature + 8);
  std::vector<uint8_t> head;
  if (attrs) h.flags |= kFlagAttributes;
  if (nodes) h.flags |= kFlagNodes;
  write_head_payload(head, h);
  if (attrs) {
    AttributeHeader a = attrs->header();
    a.full_wedges = attrs->wedge_count();
    write_attribute_header(head, a);
  }
  append_chunk(out, kChunkHead, head);
  st.header_bytes = out.size();
  append_chunk(out, kChunkBase, plan.base_stream);
  if (attrs) {
    const size_t before = out.size();
    append_chunk(out, kChunkAttributes, base_attributes);
    st.attribute_bytes += out.size() - before;
  }
  st.base_bytes = out.size() - st.header_bytes;
  // With nodes, the NODE chunk follows the first node's chunks (the first node decodes without
  // it, so a reader in file order refines from the first bytes on).
  const size_t first = nodes ? size_t(nodes->nodes[0].bytes) : 0;
  out.insert(out.end(), split_bytes.begin(), split_bytes.begin() + ptrdiff_t(first));
  if (nodes) {
    std::vector<uint8_t> table;
    write_node_table(table, *nodes);
    const size_t before = out.size();
    append_chunk(out, kChunkNodes, table);
    st.node_table_bytes = out.size() - before;
  }
  out.insert(out.end(), split_bytes.begin() + ptrdiff_t(first), split_bytes.end());
  append_chunk(out, kChunkEnd, {});
}

Face canonical_face(uint32_t a, uint32_t b, uint32_t c) {
  if (b < a && b < c) return {b, c, a};
  if (c < a && c < b) return {c, a, b};
  return {a, b, c};
}

// The full decode must reproduce the input's faces (as a set, up to rotation).
bool check_full_decode(const IndexedMesh& mesh, const ProgressiveMesh& pm, const Plan& plan,
                       std::string& error) {
  std::vector<Face> want, got;
  for (uint32_t f = 0; f < mesh.face_count(); ++f)
    want.push_back(
        canonical_face(mesh.indices[f * 3], mesh.indices[f * 3 + 1], mesh.indices[f * 3 + 2]));
  for (uint32_t f = 0; f < pm.face_count(); ++f) {
    const uint32_t* t = &pm.corner_vertex[f * 3];
    got.push_back(canonical_face(plan.input_of[t[0]], plan.input_of[t[1]], plan.input_of[t[2]]));
  }
  std::sort(want.begin(), want.end());
  std::sort(got.begin(), got.end());
  if (want != got) return error = "internal: decoded faces differ from the input", false;
  return true;
}

}  // namespace

// The node table of a sequence made in levels of cells (SimplifyOptions::clusters): its grids,
// and per node of `plan` its level, cell, split count and sphere. Faces, bytes, error bounds and
// cones are filled once the splits are coded.
NodeTable node_table_of(const CollapseSequence& seq, const ClusterPlan& plan) {
  NodeTable t;
  t.cones = true;
  for (const CollapseSequence::Level& l : seq.levels) {
    NodeGrid g;
    g.side = l.grid.side;
    std::copy(l.grid.origin, l.grid.origin + 3, g.origin);
    t.levels.push_back(g);
  }
  for (const ClusterNode& c : plan.nodes) {
    NodeEntry n;
    n.level = c.level;
    if (t.levels[c.level].side > 0) std::copy(c.cell, c.cell + 3, n.cell);
    n.splits = c.count;
    std::copy(c.center, c.center + 3, n.center);
    n.radius = c.radius;
    t.nodes.push_back(n);
  }
  return t;
}

// The nodes' error bounds (spec/format.md section 15.2), from each split's deviation (how far u
// lies from the fan it collapses onto, SplitCoder::deviations) in coding order. Undone in reverse
// (the collapse order), a collapse u -> v moves what u had absorbed by then as far as u's
// deviation further: a vertex's bound is the largest over what it absorbed, a node's the largest
// over its collapses, raised to its descendants' so that a parent's bound covers its children's.
void bound_node_errors(const CollapseSequence& seq, const Plan& plan,
                       const std::vector<float>& deviation, NodeTable& t) {
  std::vector<float> absorbed(seq.mesh.vertex_count(), 0);
  std::vector<uint64_t> first;
  uint64_t at = 0;
  for (NodeEntry& n : t.nodes) {
    first.push_back(at);
    at += n.splits;
    n.error = 0;
  }
  size_t k = t.nodes.size() - 1;
  for (size_t i = deviation.size(); i-- > 0;) {
    while (k > 0 && i < first[k]) --k;
    const HalfEdgeCollapse& c = seq.collapses[plan.order[i]];
    const float e = absorbed[plan.decoded_id[c.u]] + deviation[i];
    float& v = absorbed[plan.decoded_id[c.v]];
    v = std::max(v, e);
    t.nodes[k].error = std::max(t.nodes[k].error, e);
  }
  const NodeIndex index(t);
  for (size_t n = t.nodes.size(); n-- > 0;)
    for (uint32_t q : index.parents(uint32_t(n)))
      t.nodes[q].error = std::max(t.nodes[q].error, t.nodes[n].error);
}

// A sequence made in levels of cells: its node table, the collapses node by node and each
// node's split count (nodes stays null for a sequence without levels).
bool in_nodes(const CollapseSequence& seq, const WriteOptions& opt,
              std::unique_ptr<NodeTable>& nodes, CollapseSequence& by_node,
              std::vector<uint64_t>& node_splits, std::string& error) {
  if (seq.levels.empty()) return true;
  if (opt.base_faces) return error = "a base face count cannot be set with clusters", false;
  const ClusterPlan plan = plan_clusters(seq, opt.position_bits);
  // One node, or a first node with a cell (no collapse on the whole mesh): a stream without a
  // node table (spec/format.md section 15.1 wants the first node on the whole mesh).
  if (plan.nodes.size() < 2 || seq.levels[plan.nodes[0].level].grid.side != 0) return true;
  nodes = std::make_unique<NodeTable>(node_table_of(seq, plan));
  nodes->attributes = !seq.mesh.attributes.empty();
  by_node = node_ordered(seq, plan);
  for (const NodeEntry& n : nodes->nodes) node_splits.push_back(n.splits);
  return true;
}

bool write_pmz(const CollapseSequence& seq_in, const WriteOptions& opt, std::vector<uint8_t>& out,
               std::string& error, WriteStats* stats) {
  if (!check_write_input(seq_in, opt, error)) return false;
  // A sequence made in levels of cells is written node by node with a node table
  // (spec/format.md section 15).
  std::unique_ptr<NodeTable> nodes;
  CollapseSequence by_node;
  std::vector<uint64_t> node_splits;
  if (!in_nodes(seq_in, opt, nodes, by_node, node_splits, error)) return false;
  const CollapseSequence& seq = nodes ? by_node : seq_in;
  Plan plan;
  if (!make_plan(seq, opt, plan, error, node_splits)) return false;
  FileHeader h;
  std::vector<int32_t> coords;
  begin_header(seq.mesh, plan, opt, h, coords);
  // Attributes (spec/format.md section 14.1): the ATTR chunks follow BASE and each SPLT chunk.
  std::unique_ptr<AttributeWriter> attrs;
  if (!seq.mesh.attributes.empty()) {
    attrs = std::make_unique<AttributeWriter>();
    if (!attrs->init(seq, plan.order.size(), opt, plan.input_of, error)) return false;
  }
  std::vector<uint8_t> base_attributes;
  SplitCoder splits(seq, opt, plan, coords, attrs.get());
  std::unique_ptr<NodeCones> cones;
  if (nodes) {
    Quantizer quant;
    quant.init(h.position_bits, h.bbox_min, h.bbox_max);
    cones = std::make_unique<NodeCones>(quant, coords.data());
    // The spheres hold the input's positions; the decoded ones lie within half a step on each
    // axis, and a cone's test (spec/format.md section 15.5) takes them in the sphere.
    for (NodeEntry& n : nodes->nodes) n.radius += float(0.8660254 * double(quant.scale));
    splits.set_nodes(nodes.get(), cones.get());
  }
  if (!splits.start(h, base_attributes, error) || !splits.code_groups(error)) return false;
  const size_t best = splits.best();
  if (nodes)
    for (size_t k = 0; k < nodes->nodes.size(); ++k) {
      nodes->nodes[k].bytes = splits.node_bytes(best, k);
      nodes->nodes[k].faces = splits.node_faces(k);
      nodes->nodes[k].wedges = splits.node_wedges(k);
    }
  if (nodes) {
    bound_node_errors(seq, plan, splits.deviations(), *nodes);
    cones->finish(splits.mesh(), h.base_vertices, *nodes);
  }
  h.curvature = kCurvatureCandidates[best].curvature;
  h.fine_curvature = kCurvatureCandidates[best].fine;
  WriteStats st = splits.stats(best);
  std::vector<uint8_t> file;
  assemble_file(h, plan, attrs.get(), base_attributes, nodes.get(), splits.split_bytes(best), st,
                file);
  if (!check_full_decode(seq.mesh, splits.mesh(), plan, error)) return false;
  if (attrs && !attrs->check_full(splits.mesh(), error)) return false;
  out.swap(file);  // only a checked stream replaces the caller's bytes
  if (stats) *stats = st;
  return true;
}

std::vector<uint32_t> decoded_vertex_order(const CollapseSequence& seq,
                                           const WriteOptions& options) {
  std::unique_ptr<NodeTable> nodes;
  CollapseSequence by_node;
  std::vector<uint64_t> node_splits;
  Plan plan;
  std::string error;
  if (!in_nodes(seq, options, nodes, by_node, node_splits, error) ||
      !make_plan(nodes ? by_node : seq, options, plan, error, node_splits))
    return {};
  return plan.input_of;
}

}  // namespace pmz
