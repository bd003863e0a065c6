// SPDX-License-Identifier: MIT
// pmz-decode: decode a .pmz stream (or its first N bytes, as a partial download would) to any
// mesh format meshio writes (OBJ with its MTL, PLY and glb keep the attributes), at a chosen
// level of detail. Reads a file or
// stdin (-); the level goes to meshio's writer as an IndexedMesh (decoder -> IndexedMesh ->
// write_mesh_to) into a safe output (app_support: temporary + rename, or stdout with -). No
// OpenMesh.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "decoded_mesh.hpp"
#include "pmz/app_support.hpp"
#include "pmz/decoder.hpp"
#include "pmz/mesh.hpp"
#include "tool_mesh.hpp"

namespace app_support = pmz::app_support;
namespace tool = pmz::tool;

namespace {

// --camera: the stream read as a view-dependent client reads it over HTTP, here by file ranges:
// in order up to its node table, then the ranges of the nodes the view needs, until it has all
// (within max_faces, Decoder::set_view_face_budget: 0, none).
int decode_view(const std::string& input, const pmz::View& view, uint32_t threads,
                uint64_t max_faces, app_support::OutputFile& out, const std::string& format) {
  std::ifstream file(input, std::ios::binary);
  std::string error;
  if (!file) {
    app_support::print_error(input, "cannot open");
    return app_support::kExitFailure;
  }
  file.seekg(0, std::ios::end);
  const uint64_t total = uint64_t(file.tellg());
  file.seekg(0);
  pmz::Decoder d;
  d.set_threads(threads);
  d.set_view_face_budget(max_faces);
  uint64_t read = 0;
  std::vector<uint8_t> buffer;
  const auto read_range = [&](uint64_t offset, uint64_t size) {
    buffer.resize(size);
    file.clear();
    file.seekg(std::streamoff(offset));
    file.read(reinterpret_cast<char*>(buffer.data()), std::streamsize(size));
    read += uint64_t(file.gcount());
    return uint64_t(file.gcount()) == size;
  };
  // In order (small reads: the node table is near the front) until the table or the end.
  constexpr uint64_t kSlice = 16384;
  uint64_t in_order = 0;
  while (d.status() == pmz::Status::ok && !d.info().nodes && !d.info().complete &&
         in_order < total) {
    const uint64_t n = std::min(kSlice, total - in_order);
    if (!read_range(in_order, n)) break;
    d.feed(buffer.data(), n);
    in_order += n;
  }
  while (d.status() == pmz::Status::ok) {
    d.update_view(view);
    if (d.status() != pmz::Status::ok || d.view_complete()) break;
    const std::vector<uint32_t> fetch = d.nodes_to_fetch();
    if (fetch.empty()) {  // refining in file order (no node table): read on
      if (in_order >= total) break;
      const uint64_t n = std::min<uint64_t>(1 << 20, total - in_order);
      if (!read_range(in_order, n)) break;
      d.feed(buffer.data(), n);
      in_order += n;
      continue;
    }
    for (uint32_t k : fetch) {
      uint64_t offset = 0, size = 0;
      if (!d.node_range(k, offset, size)) continue;
      if (offset + size > total || !read_range(offset, size)) {
        app_support::print_error(input,
                                 "node " + std::to_string(k) + " lies past the end of the file");
        return app_support::kExitFailure;
      }
      if (d.feed_node(k, buffer.data(), size) != pmz::Status::ok) break;
    }
  }
  if (d.status() != pmz::Status::ok || !d.info().base_done) {
    app_support::print_error(
        input, d.info().base_done ? d.error_message() : "the file does not hold a base mesh");
    return app_support::kExitFailure;
  }
  if (!d.view_complete())
    app_support::print_error(input, "warning: the file ends before every part the view needs");
  if (max_faces && !d.info().nodes)
    app_support::print_error(input, "warning: no node table: --max-faces does not apply");
  const pmz::IndexedMesh level = tool::decoded_mesh(d);
  if (!tool::write_mesh_into(out, format, level, error) || !out.commit(error)) {
    app_support::print_error(error);
    return app_support::kExitFailure;
  }
  std::fprintf(stderr,
               "pmz-decode: %u faces%s, %u vertices; %u of %llu nodes; read %llu of %llu bytes "
               "(%.1f%%)\n",
               level.face_count(),
               max_faces ? (" (budget " + std::to_string(max_faces) + ")").c_str() : "",
               level.vertex_count(), d.nodes_applied(),
               (unsigned long long)std::max<uint64_t>(d.info().nodes, 1), (unsigned long long)read,
               (unsigned long long)total, total ? 100.0 * double(read) / double(total) : 0.0);
  return app_support::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  app_support::init("pmz-decode");
  CLI::App app{
      "pmz-decode: decode a .pmz stream (or its first N bytes) to a mesh at a chosen level of "
      "detail",
      "pmz-decode"};
  std::string input, output, format;
  uint64_t faces = 0, vertices = 0, bytes = 0;
  double ratio = 1;
  app.add_option("input", input, "input .pmz (- for stdin)")->required();
  app.add_option("-o,--output", output,
                 tool::mesh_files_help("output mesh", true,
                                       "- for stdout; .off and .stl hold no attributes"))
      ->required();
  tool::add_format_option(app, format, false, true,
                          "format of an output without a mesh extension (stdout, devices)");
  auto* of =
      app.add_option("--faces", faces, "smallest level with at least N faces (0: the base mesh)");
  auto* orr =
      app.add_option("--ratio", ratio, "this fraction of the full face count (0: the base mesh)")
          ->check(CLI::Range(0.0, 1.0));
  auto* ov = app.add_option("--vertices", vertices,
                            "level with N vertices (clamped to the base and full mesh)");
  app.add_option("--bytes", bytes, "decode only the first N bytes of the input");
  uint32_t threads = 0;
  app.add_option("--threads", threads,
                 "decoding threads (0, the default: the machine's cores; the output is the same "
                 "for every count)");
  bool salvage = false;
  app.add_flag("--salvage", salvage,
               "on a damaged or truncated stream, still write its last good level (exit 1 even "
               "so)");
  std::string camera, size = "1920x1080";
  float pixel_error = 1, fov = 60;
  auto* oc = app.add_option("--camera", camera,
                            "EX,EY,EZ,TX,TY,TZ: only what a camera at EX,EY,EZ looking at TX,TY,TZ "
                            "(y up, the mesh's coordinates) needs, reading the file by ranges");
  app.add_option("--pixel-error", pixel_error,
                 "with --camera: refine while a part's error spans more pixels than this (0: "
                 "every part in view)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber)
      ->needs(oc);
  app.add_option("--size", size, "with --camera: the viewport, WxH pixels")
      ->capture_default_str()
      ->needs(oc);
  app.add_option("--fov", fov, "with --camera: vertical field of view, degrees")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 179.0))
      ->needs(oc);
  uint64_t max_faces = 0;
  app.add_option("--max-faces", max_faces,
                 "with --camera: a face budget; the parts the view needs most come first, those "
                 "that would bring the mesh past N faces are neither read nor applied (0: none)")
      ->capture_default_str()
      ->needs(oc);
  oc->excludes(of)->excludes(orr)->excludes(ov);
  of->excludes(orr)->excludes(ov);
  orr->excludes(ov);
  app_support::set_footer(
      app,
      "Without --faces, --ratio or --vertices: the finest level the input holds. A "
      "target beyond what the input holds gets a warning and the finest level it "
      "holds.");
  if (int rc = app_support::parse(app, argc, argv); rc >= 0) return rc;

  std::string problem;
  format = app_support::mesh_output_format(output, format, problem);
  if (format.empty()) return app_support::usage_error(problem);
  if (app_support::same_file(input, output)) {
    app_support::print_error(output, "is the input file; not overwriting it");
    return app_support::kExitFailure;
  }
  const std::string shown = input == "-" ? "stdin" : input;
  // Opened first: an unwritable output fails before the work, and the temporary (removed on
  // error and on SIGINT/SIGTERM) exists while the input streams in.
  app_support::OutputFile out;
  std::string error;
  if (!out.open(output, tool::binary_mesh_format(format), error)) {
    app_support::print_error(error);
    return app_support::kExitFailure;
  }
  if (oc->count()) {
    float c[6];
    unsigned w = 0, h = 0;
    if (std::sscanf(camera.c_str(), "%f,%f,%f,%f,%f,%f", c, c + 1, c + 2, c + 3, c + 4, c + 5) !=
            6 ||
        !std::all_of(c, c + 6, [](float x) { return std::isfinite(x); }))
      return app_support::usage_error("--camera takes six numbers: EX,EY,EZ,TX,TY,TZ");
    if (std::sscanf(size.c_str(), "%ux%u", &w, &h) != 2 || !w || !h)
      return app_support::usage_error("--size takes WxH, e.g. 1920x1080");
    if (input == "-") return app_support::usage_error("--camera reads a file by ranges, not stdin");
    const pmz::View view =
        pmz::look_at(c, c + 3, fov * float(M_PI / 180), w, h, 1e-4f, pixel_error);
    return decode_view(input, view, threads, max_faces, out, format);
  }
  std::vector<uint8_t> data;
  if (!app_support::read_input(input, data, error)) {
    app_support::print_error(error);
    return app_support::kExitFailure;
  }
  size_t n = bytes ? std::min<size_t>(bytes, data.size()) : data.size();
  pmz::Decoder d;
  d.set_threads(threads);
  pmz::Status s = d.feed(data.data(), n);
  if (s == pmz::Status::ok && !bytes) s = d.finish();
  // One line per failure: what is wrong with the stream, and what became of the output.
  const auto stream_failed = [&](const char* outcome) {
    app_support::print_error(shown, app_support::stream_error(n, d.error_message()) + outcome);
    return app_support::kExitFailure;
  };
  const char* nothing_written = "; nothing written (--salvage writes the last good level)";
  if (s != pmz::Status::ok) {
    // A damaged stream still has a last good level, but writing it unasked would pass a coarse
    // mesh off as the file's content: only --salvage writes it (and still exits 1).
    if (!salvage) return stream_failed(nothing_written);
    if (!d.info().base_done) return stream_failed("; nothing written (no complete level)");
    stream_failed("; writing the last good level");
  }
  if (!d.info().base_done) {
    app_support::print_error(shown,
                             "the first " + std::to_string(n) + " bytes do not hold the base mesh");
    return app_support::kExitFailure;
  }
  const pmz::StreamInfo& info = d.info();
  // 0 is a level like any other (the base mesh), not "unset": options are told apart by count.
  uint64_t wanted_faces = 0;
  if (of->count())
    d.set_face_target(wanted_faces = faces);
  else if (orr->count())
    d.set_face_target(wanted_faces = uint64_t(ratio * double(info.full_faces) + 0.5));
  else if (ov->count())
    d.set_split_target(vertices > info.base_vertices ? vertices - info.base_vertices : 0);
  else
    d.refine();
  // Wedge and residual symbols are decoded as splits are first applied: damage there shows
  // only now, and is treated like damage found while reading.
  const bool refine_failed = s == pmz::Status::ok && d.status() != pmz::Status::ok;
  if (refine_failed) {
    s = d.status();
    if (!salvage) return stream_failed(nothing_written);
    stream_failed("; writing the last good level");
  }
  // A target the given bytes cannot reach: say what it asked and what was written.
  const bool all_available = d.splits_available() == info.total_splits;
  const std::string held = all_available ? "the file holds"
                                         : "the " + std::string(bytes ? "first " : "") +
                                               std::to_string(n) + " bytes hold";
  if ((of->count() || orr->count()) && d.face_count() < wanted_faces)
    app_support::print_error(
        shown, "warning: " + std::to_string(wanted_faces) + " faces asked; " + held + " " +
                   std::to_string(d.face_count()) +
                   (all_available ? "" : " of " + std::to_string(info.full_faces)) +
                   ": writing those");
  if (ov->count() && d.vertex_count() < vertices)
    app_support::print_error(
        shown, "warning: " + std::to_string(vertices) + " vertices asked; " + held + " " +
                   std::to_string(d.vertex_count()) +
                   (all_available ? "" : " of " + std::to_string(info.full_vertices)) +
                   ": writing those");
  const pmz::IndexedMesh level = tool::decoded_mesh(d);
  tool::warn_if_attributes_lost(output, format, level);
  if (!tool::write_mesh_into(out, format, level, error) || !out.commit(error)) {
    app_support::print_error(error);
    return app_support::kExitFailure;
  }
  std::fprintf(stderr, "pmz-decode: %u faces, %u vertices (%llu of %llu splits)\n", d.face_count(),
               d.vertex_count(), (unsigned long long)d.splits_applied(),
               (unsigned long long)info.total_splits);
  return s == pmz::Status::ok || (bytes && !refine_failed) ? app_support::kExitOk
                                                           : app_support::kExitFailure;
}
