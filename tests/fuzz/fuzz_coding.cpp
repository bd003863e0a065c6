// SPDX-License-Identifier: MIT
// The coding layer under the decoder: ByteReader (fixed-width reads, LEB128 varints, byte
// spans), zigzag, the stream reader (raw or zstd), the quantizer and float ordering, the
// corner-table core (build, split, exact undo), the range coder, the SPLT payload codec, the
// BASE codec and the node table.
// data[0] picks the part; the rest is its input.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "pmz/base_codec.hpp"
#include "pmz/coding.hpp"
#include "pmz/fan_wedge.hpp"
#include "pmz/format.hpp"
#include "pmz/node_table.hpp"
#include "pmz/progressive_mesh.hpp"
#include "pmz/range_coder.hpp"
#include "pmz/split_chunk.hpp"
#include "pmz/vertex_choice.hpp"

namespace {

// Random reads; the reader never passes its end, failures stick, and accepted varints
// re-encode to no more bytes than they took.
void fuzz_reader(const uint8_t* data, size_t size) {
  if (size < 1) return;
  const size_t ops = std::min<size_t>(data[0], size - 1);
  const uint8_t* op = data + 1;
  pmz::ByteReader r(data + 1 + ops, size - 1 - ops);
  for (size_t i = 0; i < ops; ++i) {
    const uint8_t* before = r.p;
    const bool was_ok = r.ok;
    switch (op[i] % 6) {
      case 0:
        r.u8();
        break;
      case 1:
        r.u32le();
        break;
      case 2:
        r.u64le();
        break;
      case 3: {
        float f = r.f32le();
        (void)f;
        break;
      }
      case 4: {
        uint64_t v = r.varint();
        if (r.ok) {
          std::vector<uint8_t> enc;
          pmz::put_varint(enc, v);
          PMZ_FUZZ_CHECK(enc.size() <= size_t(r.p - before));
          pmz::ByteReader again(enc.data(), enc.size());
          PMZ_FUZZ_CHECK(again.varint() == v && again.ok && again.remaining() == 0);
        }
        break;
      }
      case 5: {
        const uint8_t* b = r.bytes(op[i] / 6);
        PMZ_FUZZ_CHECK((b != nullptr) == r.ok || !was_ok);
        break;
      }
    }
    PMZ_FUZZ_CHECK(r.p >= before && r.p <= r.end);
    if (!was_ok) PMZ_FUZZ_CHECK(!r.ok);
  }
}

// Values -> varints/zigzag -> values.
void fuzz_round_trip(const uint8_t* data, size_t size) {
  std::vector<uint8_t> enc;
  std::vector<uint64_t> values;
  for (size_t i = 0; i + 8 <= size; i += 8) {
    uint64_t v;
    std::memcpy(&v, data + i, 8);
    v >>= (data[i] & 63);  // all lengths, not only 10-byte varints
    values.push_back(v);
    pmz::put_varint(enc, v);
    const int32_t s = int32_t(uint32_t(v));
    PMZ_FUZZ_CHECK(pmz::zigzag_decode(pmz::zigzag_encode(s)) == s);
  }
  pmz::ByteReader r(enc.data(), enc.size());
  for (uint64_t v : values) PMZ_FUZZ_CHECK(r.varint() == v);
  PMZ_FUZZ_CHECK(r.ok && r.remaining() == 0);
}

// Quantizer and float ordering.
void fuzz_quantizer(const uint8_t* data, size_t size) {
  if (size < 1 + 24) return;
  float box[6];
  std::memcpy(box, data + 1, 24);
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(box[a]) || !std::isfinite(box[a + 3])) return;
    if (box[a] > box[a + 3]) std::swap(box[a], box[a + 3]);
  }
  pmz::Quantizer q;
  q.init(data[0] % 31, box, box + 3);
  for (size_t i = 25; i + 4 <= size; i += 4) {
    int32_t bits;
    std::memcpy(&bits, data + i, 4);
    float f;
    std::memcpy(&f, &bits, 4);
    const int32_t ordered = pmz::float_to_ordered(f);
    const float back = pmz::ordered_to_float(ordered);
    PMZ_FUZZ_CHECK(std::memcmp(&back, &f, 4) == 0);
    const int axis = int(i % 3);
    (void)q.dequantize(bits, axis);
    if (!std::isfinite(f)) continue;
    const int32_t k = q.quantize(f, axis);
    if (q.bits) PMZ_FUZZ_CHECK(k >= 0 && uint32_t(k) <= q.max_q);
  }
}

// Corner table: build from arbitrary faces, then splits and undos; every undo restores the
// exact index and adjacency buffers (a vertex may keep a different, still valid, corner).
// Each split is also redone from its sector hint (resplit) or its listed sector corners
// (resplit_listed) and undone that way (undo_resplit): the same buffers and the same rewritten
// faces, in the same order, as split / undo_split.
struct Applied {
  uint32_t v;
  bool l, r;
  pmz::BigVector<uint32_t> cv, op, vc;  // the mesh's own buffer type (huge-page allocator)
  uint32_t hint = 0, count = 0;
};

void restored(const pmz::ProgressiveMesh& m, const Applied& a) {
  PMZ_FUZZ_CHECK(m.corner_vertex == a.cv && m.opposite == a.op);
  PMZ_FUZZ_CHECK(m.vertex_corner.size() == a.vc.size());
  for (uint32_t x = 0; x < m.vertex_count(); ++x) {
    const uint32_t c = m.vertex_corner[x];
    PMZ_FUZZ_CHECK((c == pmz::kNoCorner) == (a.vc[x] == pmz::kNoCorner));
    if (c != pmz::kNoCorner) PMZ_FUZZ_CHECK(c < m.corner_vertex.size() && m.corner_vertex[c] == x);
  }
}

void fuzz_mesh(const uint8_t* data, size_t size) {
  if (size < 2) return;
  const uint32_t nv = 3 + data[0] % 29;
  const size_t nf = std::min<size_t>(data[1] % 48, (size - 2) / 3);
  std::vector<uint32_t> idx(nf * 3);
  for (size_t i = 0; i < nf * 3; ++i) idx[i] = data[2 + i] % (nv + 1);  // some out of range
  pmz::ProgressiveMesh m;
  std::string error;
  if (!m.build(nv, idx.data(), nf, error)) {
    PMZ_FUZZ_CHECK(!error.empty());
    return;
  }
  std::vector<Applied> stack;
  for (size_t i = 2 + nf * 3; i + 3 <= size; i += 3) {
    const uint8_t* s = data + i;
    if (s[0] == 0xFF && !stack.empty()) {
      Applied& a = stack.back();
      if (s[1] & 1)
        m.undo_resplit(a.v, a.hint, a.count, a.l, a.r);
      else
        m.undo_split(a.v, a.l, a.r);
      restored(m, a);
      stack.pop_back();
      continue;
    }
    const uint32_t v = s[0] % (m.vertex_count() + 1);
    const uint32_t l = s[1] == 0xFF ? pmz::kNoRank : s[1] % 16,
                   r = s[2] == 0xFF ? pmz::kNoRank : s[2] % 16;
    Applied a{v,          l != pmz::kNoRank, r != pmz::kNoRank, m.corner_vertex,
              m.opposite, m.vertex_corner};
    const uint32_t faces = m.face_count();
    if (!m.split(v, l, r)) {
      restored(m, a);
      continue;
    }
    PMZ_FUZZ_CHECK(m.face_count() == faces + a.l + a.r);
    for (uint32_t c : m.corner_vertex) PMZ_FUZZ_CHECK(c < m.vertex_count());
    for (size_t c = 0; c < m.opposite.size(); ++c)
      if (m.opposite[c] != pmz::kNoCorner) PMZ_FUZZ_CHECK(m.opposite[m.opposite[c]] == c);
    a.hint = m.sector_hint();
    a.count = uint32_t(m.sector_faces().size());
    const pmz::BigVector<uint32_t> cv = m.corner_vertex, op = m.opposite;
    const std::vector<uint32_t> sector(m.sector_faces().begin(), m.sector_faces().end());
    const std::vector<uint32_t> listed(m.sector_corners().begin(), m.sector_corners().end());
    PMZ_FUZZ_CHECK(listed.size() == a.count && (a.count == 0 || listed[0] == a.hint));
    const uint32_t u = m.vertex_count() - 1, cu = m.vertex_corner[u], cvv = m.vertex_corner[v];
    auto redone = [&] {
      PMZ_FUZZ_CHECK(m.corner_vertex == cv && m.opposite == op && m.vertex_count() == u + 1);
      PMZ_FUZZ_CHECK(m.vertex_corner[u] == cu && m.vertex_corner[v] == cvv);
      PMZ_FUZZ_CHECK(std::equal(sector.begin(), sector.end(), m.sector_faces().begin(),
                                m.sector_faces().end()));
    };
    m.undo_split(v, a.l, a.r);
    restored(m, a);
    const std::vector<uint32_t> undone(m.sector_faces().begin(), m.sector_faces().end());
    m.resplit(v, a.hint, a.count, a.l, a.r);
    redone();
    m.undo_resplit(v, a.hint, a.count, a.l, a.r);
    restored(m, a);
    PMZ_FUZZ_CHECK(
        std::equal(undone.begin(), undone.end(), m.sector_faces().begin(), m.sector_faces().end()));
    m.resplit_listed(v, listed.data(), a.count, a.hint, a.l, a.r);  // from the fan entries
    redone();
    m.undo_resplit(v, a.hint, a.count, a.l, a.r);
    restored(m, a);
    m.resplit(v, a.hint, a.count, a.l, a.r);
    redone();
    stack.push_back(std::move(a));
  }
  while (!stack.empty()) {
    Applied& a = stack.back();
    m.undo_split(a.v, a.l, a.r);
    restored(m, a);
    stack.pop_back();
  }
}

// Range coder: values -> encode_uint -> decode_uint -> the same values; the decoder never
// reads past its input (ASan) and says so when it would.
void fuzz_range_round_trip(const uint8_t* data, size_t size) {
  std::vector<uint32_t> values;
  for (size_t i = 0; i + 4 <= size; i += 4) {
    uint32_t v;
    std::memcpy(&v, data + i, 4);
    values.push_back(v >> (data[i] % 33 == 32 ? 0 : data[i] % 32));
  }
  std::vector<uint8_t> bytes;
  {
    pmz::RangeEncoder enc(bytes);
    pmz::UIntModel m;
    for (uint32_t v : values) pmz::encode_uint(enc, m, v);
    enc.finish();
  }
  pmz::RangeDecoder dec(bytes.data(), bytes.size());
  pmz::UIntModel m;
  for (uint32_t v : values) {
    uint32_t x = 0;
    PMZ_FUZZ_CHECK(pmz::decode_uint(dec, m, x) && x == v);
  }
  PMZ_FUZZ_CHECK(dec.ok);
  // The same stream cut short: never reads past it.
  if (!bytes.empty()) {
    std::vector<uint8_t> cut(bytes.begin(), bytes.end() - 1);
    pmz::RangeDecoder short_dec(cut.data(), cut.size());
    pmz::UIntModel m2;
    uint32_t x;
    for (size_t i = 0; i < values.size() && pmz::decode_uint(short_dec, m2, x); ++i) {
    }
  }
}

// SPLT payload decoding on arbitrary bytes: groups all or nothing; then, group by group, the
// vertex choice over vertices of the given degrees (all candidates: no split is applied, so
// near groups find no candidate and fail), wedge and residual symbols with contexts taken from
// the input, until a stream ends. The decoded symbols re-encode (same contexts) to a payload
// that decodes to the same.
void fuzz_split_chunk(const uint8_t* data, size_t size) {
  if (size < 3) return;
  const uint32_t vertices_before = 1 + data[0];
  const uint64_t max_splits = uint64_t(data[1]) << (data[1] % 12);
  const uint8_t ctx_seed = data[2];
  data += 3;
  size -= 3;
  // A fan of triangles around vertex 0 over the first vertices: degrees 0, 2, 3 and 12+.
  std::vector<uint32_t> faces;
  const uint32_t fan = std::min<uint32_t>(vertices_before - 1, 1 + ctx_seed % 16);
  for (uint32_t i = 1; i < fan; ++i) faces.insert(faces.end(), {0, i, i + 1});
  pmz::ProgressiveMesh pm;
  std::string error;
  PMZ_FUZZ_CHECK(pm.build(vertices_before, faces.data(), faces.size() / 3, error));
  pmz::SplitChunkReader reader;
  auto models = std::make_unique<pmz::SplitModels>();
  if (!reader.open(data, size, max_splits, *models, error)) {
    PMZ_FUZZ_CHECK(!error.empty());
    return;
  }
  const size_t count = reader.split_count();
  PMZ_FUZZ_CHECK(count >= 1 && count <= max_splits);
  uint64_t n = 0, stream_bytes[pmz::kSplitStreamCount];
  PMZ_FUZZ_CHECK(pmz::split_chunk_stream_sizes(data, size, n, stream_bytes) && n == count);
  auto contexts = [&](size_t i, pmz::SplitSymbols& s) {
    const uint32_t h = uint32_t(i * 2654435761u) ^ ctx_seed;
    const uint32_t k = 2 + h % 12;
    const bool closed = (h >> 4) & 1;
    s.wedge_context = pmz::wedge_context(k, closed);
    s.rank_context = pmz::rank_context(closed, (h >> 5) & 1);
    for (int a = 0; a < 3; ++a) s.residual_context[a] = (h >> (8 + 3 * a)) % pmz::kResidualContexts;
    for (int a = 0; a < 3; ++a)
      s.mix_context[a] =
          (h >> (17 + 3 * a)) % (a < 2 ? pmz::kMixTangentContexts : pmz::kMixNormalContexts);
  };
  // No split is applied here, so the vertex count (and every group's limit) stays vertices_before.
  // No split is applied: coordinates only feed the umbrella classes (all 0 here).
  const std::vector<int32_t> zero(size_t(vertices_before) * 3, 0);
  pmz::VertexChoice choice;
  choice.reset(pm, zero.data(), 14);
  std::vector<pmz::SplitSymbols> got;
  std::vector<uint32_t> sizes;
  while (got.size() < count) {
    const uint32_t limit = vertices_before;
    const size_t first = got.size();
    const uint64_t end_before = reader.group_end();
    const bool whole = reader.group_symbols(choice, pm, got,
                                            [&](pmz::SplitSymbols& s) { contexts(got.size(), s); });
    if (reader.group_end() == end_before) break;  // no group left
    std::vector<uint32_t> vs;
    for (size_t i = first; i < got.size(); ++i) vs.push_back(got[i].v);
    if (whole) PMZ_FUZZ_CHECK(reader.group_end() == got.size());
    for (size_t j = 0; j < vs.size(); ++j)
      PMZ_FUZZ_CHECK(vs[j] < limit && (j == 0 || vs[j - 1] < vs[j]));
    // Exclusion: no vertex in the one-ring of one found kChoiceLag + 1 or more before it.
    bool independent = true;
    for (size_t j = 0; j < vs.size(); ++j)
      pm.for_each_fan_face(vs[j], [&](uint32_t a, uint32_t b) {
        for (uint32_t x : {a, b}) {
          const auto it = std::lower_bound(vs.begin(), vs.end(), x);
          if (it == vs.end() || *it != x) continue;
          independent = false;
          PMZ_FUZZ_CHECK(size_t(it - vs.begin()) < j + 1 + pmz::kChoiceLag);
        }
      });
    // The writer codes only groups of pairwise non-adjacent vertices: re-encode those.
    if (!independent) {
      got.resize(first);
      break;
    }
    if (!vs.empty()) sizes.push_back(uint32_t(vs.size()));
    if (!whole) break;
  }
  if (got.empty()) return;
  // Re-encode the decoded prefix (its groups, all over every vertex, the last one possibly cut)
  // and decode it again.
  pmz::VertexChoice enc_choice, dec_choice;
  enc_choice.reset(pm, zero.data(), 14);
  dec_choice.reset(pm, zero.data(), 14);
  std::vector<pmz::GroupCode> groups;
  std::vector<uint32_t> bits;
  size_t at = 0;
  for (uint32_t g : sizes) {
    enc_choice.start_group();
    std::vector<uint32_t> group_vs;
    for (size_t i = at; i < at + g; ++i) group_vs.push_back(got[i].v);
    bool near = true;
    PMZ_FUZZ_CHECK(pmz::choice_bits(enc_choice, pm, vertices_before, group_vs, bits, near));
    PMZ_FUZZ_CHECK(!near);  // nothing noted: the near list is empty
    groups.push_back({g, near});
    at += g;
  }
  std::vector<uint8_t> payload;
  auto enc_models = std::make_unique<pmz::SplitModels>(),
       dec_models = std::make_unique<pmz::SplitModels>();
  pmz::encode_split_chunk(groups, bits, got.data(), got.size(), *enc_models, payload);
  pmz::SplitChunkReader r2;
  PMZ_FUZZ_CHECK(r2.open(payload.data(), payload.size(), got.size(), *dec_models, error));
  PMZ_FUZZ_CHECK(r2.split_count() == got.size());
  std::vector<pmz::SplitSymbols> again;
  while (again.size() < got.size())
    PMZ_FUZZ_CHECK(r2.group_symbols(dec_choice, pm, again,
                                    [&](pmz::SplitSymbols& s) { contexts(again.size(), s); }));
  PMZ_FUZZ_CHECK(again.size() == got.size());
  for (size_t i = 0; i < got.size(); ++i) {
    PMZ_FUZZ_CHECK(again[i].v == got[i].v && again[i].wedge_count == got[i].wedge_count &&
                   again[i].wedge_rank == got[i].wedge_rank);
    PMZ_FUZZ_CHECK(std::memcmp(again[i].residual, got[i].residual, sizeof got[i].residual) == 0);
  }
}

// A BASE payload (the range-coded stream) after its counts (varint vertex count, varint face
// count, as HEAD holds them), counts capped:
// decoded or refused, never a crash. A decoded mesh that is edge-manifold (what the decoder
// accepts) codes again to a stream that decodes to the same mesh up to the writer's numbering.
void fuzz_base(const uint8_t* data, size_t size) {
  pmz::ByteReader r(data, size);
  const uint64_t n = r.varint(), fn = r.varint();
  if (!r.ok || n > 4096 || fn > 8192) return;
  pmz::BaseMesh m;
  std::string error;
  const pmz::Status res = pmz::decode_base(r.p, r.remaining(), uint32_t(n), uint32_t(fn), m, error);
  if (res != pmz::Status::ok) {
    PMZ_FUZZ_CHECK(!error.empty());
    return;
  }
  PMZ_FUZZ_CHECK(m.coords.size() == n * 3 && m.faces.size() == fn * 3);
  for (uint32_t x : m.faces) PMZ_FUZZ_CHECK(x < n);
  pmz::ProgressiveMesh pm;
  if (!pm.build(uint32_t(n), m.faces.data(), fn, error)) return;
  std::vector<uint8_t> stream;
  std::vector<uint32_t> given_of;
  pmz::BaseMesh enc, dec;
  PMZ_FUZZ_CHECK(pmz::encode_base(m.coords.data(), uint32_t(n), m.faces.data(), uint32_t(fn),
                                  stream, given_of, enc, error));
  PMZ_FUZZ_CHECK(pmz::decode_base(stream.data(), stream.size(), uint32_t(n), uint32_t(fn), dec,
                                  error) == pmz::Status::ok);
  PMZ_FUZZ_CHECK(dec.faces == enc.faces && dec.coords == enc.coords && given_of.size() == n);
  for (uint32_t d = 0; d < n; ++d)
    for (int a = 0; a < 3; ++a)
      PMZ_FUZZ_CHECK(dec.coords[d * 3 + a] == m.coords[size_t(given_of[d]) * 3 + a]);
  std::vector<std::array<uint32_t, 3>> want, got;
  auto rotated = [](uint32_t a, uint32_t b, uint32_t c) {
    if (b < a && b < c) return std::array<uint32_t, 3>{b, c, a};
    if (c < a && c < b) return std::array<uint32_t, 3>{c, a, b};
    return std::array<uint32_t, 3>{a, b, c};
  };
  for (size_t f = 0; f < fn; ++f) {
    want.push_back(rotated(m.faces[f * 3], m.faces[f * 3 + 1], m.faces[f * 3 + 2]));
    got.push_back(rotated(given_of[dec.faces[f * 3]], given_of[dec.faces[f * 3 + 1]],
                          given_of[dec.faces[f * 3 + 2]]));
  }
  std::sort(want.begin(), want.end());
  std::sort(got.begin(), got.end());
  PMZ_FUZZ_CHECK(want == got);
}

// A NODE payload (spec/format.md section 15.1) after a u32 split total and a flags byte (bit 0:
// attributes, bit 1: cones follow the nodes, 15.5): a table accepted is consistent (split counts
// sum to the total, every node after its parents), writes back to bytes that read as the same
// table, and bins vertices (coordinates from the payload's bytes) into its cells without going out
// of bounds.
void fuzz_node_table(const uint8_t* data, size_t size) {
  if (size < 5) return;
  uint32_t total;
  std::memcpy(&total, data, 4);
  const bool attributes = data[4] & 1, cones = data[4] & 2;
  pmz::NodeTable t;
  std::string error;
  if (!pmz::read_node_table(data + 5, size - 5, total, 4096, attributes, cones, t, error)) {
    PMZ_FUZZ_CHECK(!error.empty());
    return;
  }
  uint64_t splits = 0;
  const pmz::NodeIndex index(t);
  for (uint32_t k = 0; k < t.nodes.size(); ++k) {
    splits += t.nodes[k].splits;
    for (uint32_t p : index.parents(k)) PMZ_FUZZ_CHECK(p < k);
  }
  PMZ_FUZZ_CHECK(splits == total);
  std::vector<uint8_t> again;
  pmz::write_node_table(again, t);
  pmz::NodeTable back;
  PMZ_FUZZ_CHECK(pmz::read_node_table(again.data(), again.size(), total, 4096, attributes, cones,
                                      back, error));
  PMZ_FUZZ_CHECK(back.nodes.size() == t.nodes.size() && back.levels.size() == t.levels.size());
  for (size_t k = 0; k < t.nodes.size(); ++k)
    PMZ_FUZZ_CHECK(back.nodes[k].splits == t.nodes[k].splits &&
                   back.nodes[k].cell[0] == t.nodes[k].cell[0] &&
                   back.nodes[k].bytes == t.nodes[k].bytes &&
                   back.nodes[k].cone_cutoff == t.nodes[k].cone_cutoff &&
                   back.nodes[k].cone_axis[2] == t.nodes[k].cone_axis[2]);
  std::vector<int32_t> coords((size - 5) / 4 * 3 / 3 * 3);
  for (size_t i = 0; i + 4 <= size - 5 && i / 4 < coords.size(); i += 4)
    std::memcpy(&coords[i / 4], data + 5 + i, 4);
  const uint32_t count = uint32_t(coords.size() / 3);
  pmz::CellBins bins;
  for (uint32_t level = 0; level < t.levels.size(); ++level) {
    bins.build(t, level, coords.data(), count);
    for (uint32_t k = 0; k < t.nodes.size(); ++k) {
      if (t.nodes[k].level != level) continue;
      const pmz::CellBox box(t.levels[level], t.nodes[k].cell);
      std::vector<uint32_t> want;  // every vertex in its box, ascending
      for (uint32_t v = 0; v < count; ++v)
        if (box.contains(&coords[size_t(v) * 3])) want.push_back(v);
      PMZ_FUZZ_CHECK(bins.take(k) == want);
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const uint8_t* p = data + 1;
  const size_t n = size - 1;
  switch (data[0] % 9) {
    case 0:
      fuzz_reader(p, n);
      break;
    case 1:
      fuzz_round_trip(p, n);
      break;
    case 2:
      fuzz_reader(p, n);
      break;  // was the zstd stream reader (format 5)
    case 3:
      fuzz_quantizer(p, n);
      break;
    case 4:
      fuzz_mesh(p, n);
      break;
    case 5:
      fuzz_range_round_trip(p, n);
      break;
    case 6:
      fuzz_split_chunk(p, n);
      break;
    case 7:
      fuzz_base(p, n);
      break;
    case 8:
      fuzz_node_table(p, n);
      break;
  }
  return 0;
}
