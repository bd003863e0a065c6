// SPDX-License-Identifier: MIT
// pmz-info: a .pmz file's header, counts, bytes per section and per stream, and bits per
// vertex split divided into connectivity (groups, vertex choice, wedges) and geometry (residuals):
// the two streams of every SPLT chunk.
// Reads the container (chunk framing, CRCs, the base mesh and each chunk's split groups, through
// the decoder's feed) without applying the splits; a truncated file is described up to where it
// ends. --decode also applies every split (checking their symbols) and times it.
// A stream with attributes: per kind (texture coordinates, normals, colours, materials) HEAD's
// bits and the bytes its ATTR symbols take. Each ATTR chunk is one range-coded stream of all
// kinds, decoded as the splits are first applied: all splits are applied by a decoder that
// counts what every symbol costs (with --decode a second one, so that the timed one does not).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <string>
#include <vector>

#include "pmz/app_support.hpp"
#include "pmz/attribute_codec.hpp"
#include "pmz/coding.hpp"
#include "pmz/decoder.hpp"
#include "pmz/format.hpp"
#include "pmz/node_table.hpp"
#include "pmz/split_chunk.hpp"

namespace app_support = pmz::app_support;

namespace {

// HEAD's attribute fields, when its flags say the stream has attributes.
bool read_attribute_fields(const uint8_t* p, size_t n, pmz::AttributeHeader& a) {
  pmz::FileHeader h;
  size_t fixed = 0;
  if (!pmz::read_head_payload(p, n, h, &fixed) || !(h.flags & pmz::kFlagAttributes)) return false;
  pmz::ByteReader r(p + fixed, n - fixed);
  std::string error;
  return pmz::read_attribute_header(r, a, error);
}

// One line of the attribute table: a kind HEAD declares, or a share of the ATTR bytes that
// belongs to no kind.
struct AttributeEntry {
  const char* key;             // --json
  const char* name;            // text
  std::string detail, fields;  // text; --json (HEAD's fields, bits 0: lossless)
  uint64_t bytes;
};

std::string bits_text(uint32_t bits) {
  return bits ? std::to_string(bits) + " bits" : std::string("lossless float32");
}
std::string field(const char* name, uint64_t value) {
  return std::string(",\"") + name + "\":" + std::to_string(value);
}

// The kinds HEAD declares, with the bytes their symbols cost (rounded); then, when counted, the
// wedge references and the framing, which make the bytes add up to attr_bytes.
std::vector<AttributeEntry> attribute_entries(const pmz::AttributeHeader& a,
                                              const pmz::AttributeBits& cost, bool counted,
                                              uint64_t attr_bytes) {
  std::vector<AttributeEntry> out;
  auto bytes = [](double bits) { return uint64_t(std::llround(bits / 8)); };
  if (a.texcoord_sets)
    out.push_back({"texcoords", "texture coordinates",
                   std::to_string(a.texcoord_sets) + (a.texcoord_sets > 1 ? " sets, " : " set, ") +
                       bits_text(a.texcoord_bits),
                   field("sets", a.texcoord_sets) + field("bits", a.texcoord_bits),
                   bytes(cost.bits[pmz::AttributeBits::texcoords])});
  if (a.normals)
    out.push_back({"normals", "normals",
                   a.normal_bits ? "octahedral, " + bits_text(a.normal_bits) : bits_text(0),
                   field("bits", a.normal_bits), bytes(cost.bits[pmz::AttributeBits::normals])});
  if (a.color_components)
    out.push_back(
        {"colors", "colours",
         std::string(a.color_components == 4 ? "RGBA, " : "RGB, ") + bits_text(a.color_bits),
         field("components", a.color_components) + field("bits", a.color_bits),
         bytes(cost.bits[pmz::AttributeBits::colors])});
  if (!a.materials.empty())
    out.push_back({"materials", "materials", std::to_string(a.materials.size()),
                   field("count", a.materials.size()),
                   bytes(cost.bits[pmz::AttributeBits::materials])});
  if (!counted) return out;
  out.push_back({"wedges", "wedge references", "which wedge each corner takes", "",
                 bytes(cost.bits[pmz::AttributeBits::wedges])});
  uint64_t sum = 0;
  for (const AttributeEntry& e : out) sum += e.bytes;
  out.push_back({"framing", "framing", "chunk headers, coder start and end", "",
                 attr_bytes - std::min(sum, attr_bytes)});
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  app_support::init("pmz-info");
  CLI::App app{
      "pmz-info: print a .pmz file's header, counts, bytes per section, bits per vertex split "
      "and each attribute kind's bits and bytes (without decoding the splits unless --decode or "
      "the file has attributes)",
      "pmz-info"};
  std::string input;
  bool json = false, decode = false;
  app.add_option("input", input, "input .pmz (- for stdin)")->required();
  app.add_flag("--json", json, "machine-readable output");
  app.add_flag("--decode", decode,
               "also apply every split (finds damage in their symbols) and time the refinement");
  app_support::set_footer(
      app,
      "A truncated file is described up to where it ends (exit 0, 'truncated' / "
      "\"complete\": false); a damaged one up to the damage (exit 1). A file with attributes "
      "has its splits applied (their ATTR symbols are decoded then) to give each attribute kind "
      "the bytes its symbols cost: how far each symbol narrowed the range coder's interval. Wedge "
      "references (which wedge each corner takes, shared by the kinds) and framing (chunk "
      "headers, the coder's start and end) complete attribute_bytes; --json's other_bytes "
      "counts the ATTR chunks too.");
  if (int rc = app_support::parse(app, argc, argv); rc >= 0) return rc;

  std::vector<uint8_t> data;
  std::string error;
  if (!app_support::read_input(input, data, error)) {
    app_support::print_error(error);
    return app_support::kExitFailure;
  }
  const std::string shown = input == "-" ? "stdin" : input;
  pmz::Decoder d;
  pmz::AttributeBits attr_cost;                     // what the ATTR symbols cost, per kind
  if (!decode) d.count_attribute_bits(&attr_cost);  // --decode times d: a second decoder counts
  pmz::Status s = d.feed(data.data(), data.size());
  if (s == pmz::Status::ok) s = d.finish();
  const bool truncated = s == pmz::Status::truncated;
  const bool damaged = s != pmz::Status::ok && !truncated;
  if (!d.info().header_done) {
    app_support::print_error(shown, app_support::stream_error(data.size(), d.error_message()));
    return app_support::kExitFailure;
  }
  double refine_s = 0, refine_cpu = 0, warm_s = 0, warm_cpu = 0;
  if (decode && !damaged) {
    // Wall time, and the process's CPU time (std::clock), which other processes on a busy
    // machine do not inflate.
    auto t0 = std::chrono::steady_clock::now();
    std::clock_t c0 = std::clock();
    d.refine();
    refine_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    refine_cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
    // Wedge and residual symbols are decoded as splits are first applied: damage shows now
    // (a truncated file stays truncated).
    if (d.status() != s) {
      app_support::print_error(shown, app_support::stream_error(data.size(), d.error_message()));
      return app_support::kExitFailure;
    }
    // Again with memory already touched and positions computed: the per-frame refinement cost.
    d.coarsen();
    t0 = std::chrono::steady_clock::now();
    c0 = std::clock();
    d.refine();
    warm_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    warm_cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
  }

  // The bytes of each attribute kind: every split applied (that decodes the ATTR symbols) by a
  // decoder that counts what each symbol costs.
  const bool counted = (d.info().flags & pmz::kFlagAttributes) && !damaged;
  if (counted) {
    pmz::Decoder counter;
    if (decode) {
      counter.count_attribute_bits(&attr_cost);
      if (counter.feed(data.data(), data.size()) == pmz::Status::ok) counter.finish();
    }
    pmz::Decoder& c = decode ? counter : d;
    c.refine();
    if (c.status() != s) {
      app_support::print_error(shown, app_support::stream_error(data.size(), c.error_message()));
      return app_support::kExitFailure;
    }
  }

  // Section sizes from the framing, up to END (the decoder ignores what follows) or up to where
  // the bytes end inside a chunk.
  uint64_t head = 8, base = 0, splits = 0, other = 0, chunks = 0, unfinished = 0;
  uint64_t attr_bytes = 0, attr_chunks = 0;  // ATTR chunks, also in `other`
  uint64_t node_table_bytes = 0;             // the NODE chunk, also in `other`
  pmz::AttributeHeader attr_head;
  bool attributes = false;
  uint64_t stream_bytes[pmz::kSplitStreamCount] = {};
  for (size_t at = 8; at < data.size();) {
    pmz::ChunkFrame f;
    if (pmz::parse_chunk_frame(data.data() + at, data.size() - at, f) != pmz::FrameStatus::ok ||
        f.payload_size > data.size() - at - f.header_size) {
      unfinished = data.size() - at;  // a chunk cut off (or, when damaged, unreadable framing)
      break;
    }
    const uint64_t total = f.header_size + f.payload_size;
    if (f.type == pmz::kChunkEnd) {
      other += total;
      break;
    }
    if (f.type == pmz::kChunkHead) {
      head += total;
      attributes = read_attribute_fields(data.data() + at + f.header_size, size_t(f.payload_size),
                                         attr_head);
    } else if (f.type == pmz::kChunkAttributes && attributes) {
      attr_bytes += total;
      ++attr_chunks;
      other += total;
    } else if (f.type == pmz::kChunkBase) {
      base += total;
    } else if (f.type == pmz::kChunkNodes && (d.info().flags & pmz::kFlagNodes)) {
      node_table_bytes += total;
      other += total;
    } else if (f.type == pmz::kChunkSplits) {
      splits += total;
      ++chunks;
      uint64_t count = 0, sizes[pmz::kSplitStreamCount] = {};
      pmz::split_chunk_stream_sizes(data.data() + at + f.header_size, size_t(f.payload_size), count,
                                    sizes);
      for (int k = 0; k < pmz::kSplitStreamCount; ++k) stream_bytes[k] += sizes[k];
    } else
      other += total;
    at += total;
  }
  const pmz::StreamInfo& i = d.info();
  const uint64_t available = d.splits_available();
  const double ns = double(std::max<uint64_t>(1, available));
  // The two streams of every SPLT chunk are exactly this split (per symbol kind: pmz-encode's
  // ideal code lengths). Over the splits present, so a truncated file's figures are its own.
  const double conn = double(stream_bytes[pmz::kStreamConnectivity]) * 8 / ns;
  const double geom = double(stream_bytes[pmz::kStreamGeometry]) * 8 / ns;
  const char* names[pmz::kSplitStreamCount] = {"connectivity", "geometry"};
  const bool timed = decode && !damaged;
  const double splits_per_s = refine_s > 0 ? double(available) / refine_s : 0;
  const double warm_per_s = warm_s > 0 ? double(available) / warm_s : 0;
  const char* state = damaged ? "damaged" : truncated ? "truncated" : "complete";
  // Bytes per kind once an ATTR chunk was counted (a truncated file may have none yet).
  const bool per_kind = counted && attr_chunks > 0;
  const std::vector<AttributeEntry> kinds =
      attributes ? attribute_entries(attr_head, attr_cost, per_kind, attr_bytes)
                 : std::vector<AttributeEntry>{};
  if (json) {
    std::printf(
        "{\"file\":\"%s\",\"bytes\":%zu,\"state\":\"%s\",\"complete\":%s,"
        "\"version\":\"%u.%u\",\"level\":%u,\"position_bits\":%u,\"curvature\":%u,"
        "\"fine_curvature\":%u,"
        "\"base_vertices\":%llu,\"base_faces\":%llu,\"full_vertices\":%llu,\"full_faces\":%llu,"
        "\"splits\":%llu,\"splits_available\":%llu,\"base_complete\":%s,\"split_chunks\":%llu,"
        "\"nodes\":%llu,\"node_table_bytes\":%llu,"
        "\"header_bytes\":%llu,\"base_bytes\":%llu,\"split_bytes\":%llu,\"other_bytes\":%llu,"
        "\"unfinished_chunk_bytes\":%llu,\"bits_per_vertex\":%.4f,"
        "\"connectivity_bits_per_split\":%.4f,\"geometry_bits_per_split\":%.4f,",
        shown.c_str(), data.size(), state, truncated || damaged ? "false" : "true", i.version_major,
        i.version_minor, i.level, i.position_bits, i.curvature, i.fine_curvature,
        (unsigned long long)i.base_vertices, (unsigned long long)i.base_faces,
        (unsigned long long)i.full_vertices, (unsigned long long)i.full_faces,
        (unsigned long long)i.total_splits, (unsigned long long)available,
        i.base_done ? "true" : "false", (unsigned long long)chunks, (unsigned long long)i.nodes,
        (unsigned long long)node_table_bytes, (unsigned long long)head, (unsigned long long)base,
        (unsigned long long)splits, (unsigned long long)other, (unsigned long long)unfinished,
        data.size() * 8.0 / double(std::max<uint64_t>(1, i.full_vertices)), conn, geom);
    if (timed)
      std::printf(
          "\"refine_splits_per_second\":%.0f,\"rerefine_splits_per_second\":%.0f,"
          "\"refine_cpu_ms\":%.3f,\"rerefine_cpu_ms\":%.3f,",
          splits_per_s, warm_per_s, refine_cpu * 1e3, warm_cpu * 1e3);
    std::printf("\"stream_bytes\":{");
    for (int k = 0; k < pmz::kSplitStreamCount; ++k)
      std::printf("%s\"%s\":%llu", k ? "," : "", names[k], (unsigned long long)stream_bytes[k]);
    std::printf("},\"attribute_bytes\":%llu,\"attribute_chunks\":%llu",
                (unsigned long long)attr_bytes, (unsigned long long)attr_chunks);
    if (attributes) {
      // Per kind: its name, HEAD's fields and, when counted, its bytes; counted, the entries'
      // bytes add up to attribute_bytes.
      std::printf(",\"attribute_bytes_counted\":%s,\"attributes\":{", per_kind ? "true" : "false");
      for (size_t k = 0; k < kinds.size(); ++k) {
        const AttributeEntry& e = kinds[k];
        std::printf("%s\"%s\":{\"name\":\"%s\"%s", k ? "," : "", e.key, e.name, e.fields.c_str());
        if (per_kind) std::printf(",\"bytes\":%llu", (unsigned long long)e.bytes);
        std::printf("}");
      }
      std::printf("}");
    }
    std::printf("}\n");
  } else {
    std::printf("%s: %zu bytes, format %u.%u, level %u (%s), %s, curvature %u/8 + %u/8\n",
                shown.c_str(), data.size(), i.version_major, i.version_minor, i.level,
                i.level == 1 ? "speed" : "default",
                i.position_bits ? (std::to_string(i.position_bits) + "-bit positions").c_str()
                                : "lossless float32 positions",
                i.curvature, i.fine_curvature);
    std::printf("  bbox      (%g %g %g) - (%g %g %g)\n", i.bbox_min[0], i.bbox_min[1],
                i.bbox_min[2], i.bbox_max[0], i.bbox_max[1], i.bbox_max[2]);
    std::printf("  base      %llu vertices, %llu faces%s\n", (unsigned long long)i.base_vertices,
                (unsigned long long)i.base_faces, i.base_done ? "" : " (not all in the file)");
    std::printf("  full      %llu vertices, %llu faces, %llu splits in %llu chunks\n",
                (unsigned long long)i.full_vertices, (unsigned long long)i.full_faces,
                (unsigned long long)i.total_splits, (unsigned long long)chunks);
    if (i.nodes)
      std::printf(
          "  nodes     %llu, decodable independently once their parents are (table %llu "
          "bytes)\n",
          (unsigned long long)i.nodes, (unsigned long long)node_table_bytes);
    if (truncated || damaged)
      std::printf(
          "  %-9s %llu of %llu splits available (%.1f%%)%s\n", state, (unsigned long long)available,
          (unsigned long long)i.total_splits,
          100.0 * double(available) / double(std::max<uint64_t>(1, i.total_splits)),
          unfinished
              ? ("; the last " + std::to_string(unfinished) + " bytes are a chunk cut off").c_str()
              : "");
    if (attributes)
      std::printf(
          "  sections  header %llu, base %llu, splits %llu, attributes %llu, other %llu bytes\n",
          (unsigned long long)head, (unsigned long long)base, (unsigned long long)splits,
          (unsigned long long)attr_bytes, (unsigned long long)(other - attr_bytes));
    else
      std::printf("  sections  header %llu, base %llu, splits %llu, other %llu bytes\n",
                  (unsigned long long)head, (unsigned long long)base, (unsigned long long)splits,
                  (unsigned long long)other);
    std::printf(
        "  per split connectivity %.2f bits, geometry %.2f bits; %.2f bits/vertex overall\n", conn,
        geom, data.size() * 8.0 / double(std::max<uint64_t>(1, i.full_vertices)));
    std::printf(
        "  streams   connectivity %llu bytes, geometry %llu bytes (SPLT framing and counts "
        "%llu)\n",
        (unsigned long long)stream_bytes[pmz::kStreamConnectivity],
        (unsigned long long)stream_bytes[pmz::kStreamGeometry],
        (unsigned long long)(splits - stream_bytes[pmz::kStreamConnectivity] -
                             stream_bytes[pmz::kStreamGeometry]));
    if (attributes) {
      // What is known: HEAD's kinds always, their bytes once counted.
      std::printf("  attributes %llu bytes in %llu ATTR chunk%s%s\n",
                  (unsigned long long)attr_bytes, (unsigned long long)attr_chunks,
                  attr_chunks == 1 ? "" : "s",
                  !counted    ? ", not counted per kind (the stream is damaged)"
                  : !per_kind ? " (none in the file yet)"
                              : ", bytes by what their symbols cost:");
      for (const AttributeEntry& e : kinds) {
        if (per_kind)
          std::printf("    %-20s %-34s %8llu\n", e.name, e.detail.c_str(),
                      (unsigned long long)e.bytes);
        else
          std::printf("    %-20s %s\n", e.name, e.detail.c_str());
      }
    }
    if (timed) {
      std::printf(
          "  full refinement %.3f ms (%.1f M splits/s); after coarsening, again %.3f ms (%.1f M "
          "splits/s)\n",
          refine_s * 1e3, splits_per_s / 1e6, warm_s * 1e3, warm_per_s / 1e6);
      std::printf("  cpu time  full refinement %.3f ms, again %.3f ms\n", refine_cpu * 1e3,
                  warm_cpu * 1e3);
    }
  }
  if (damaged) {
    app_support::print_error(shown, app_support::stream_error(data.size(), d.error_message()));
    return app_support::kExitFailure;
  }
  return app_support::kExitOk;
}
