// SPDX-License-Identifier: MIT
// pmz-encode: simplify meshes and write each as a progressive .pmz stream. One input with -o
// (a file, or - for stdout), or many with --out-dir encoded by -j worker threads (one line per
// asset; a failing asset does not stop the others). A .glb output (or --glb) carries the stream in
// a binary glTF as docs/gltf-binding.md says: the base mesh as an ordinary primitive, materials
// and their texture files kept; a glTF scene of several mesh nodes keeps its nodes, a stream per
// mesh.
#include <CLI/CLI.hpp>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <set>
#include <string>
#include <thread>

#include "decoded_mesh.hpp"
#include "encode_plan.hpp"
#include "pmz/app_support.hpp"
#include "pmz/decoder.hpp"
#include "pmz/format.hpp"
#include "pmz/mesh.hpp"
#include "pmz/progressive_glb.hpp"
#include "pmz/simplify.hpp"
#include "pmz/writer.hpp"
#include "tool_mesh.hpp"
#include "tool_simplify.hpp"

namespace {

namespace app_support = pmz::app_support;
namespace tool = pmz::tool;

struct EncodeSettings {
  pmz::SimplifyOptions simplify;   // metric, attribute mode, parameters (no target: all the way)
  tool::SimplifierCli simplifier;  // (its cell size, settled per mesh)
  pmz::WriteOptions write;
  std::string stdin_format;  // extension for a mesh read from stdin
  bool glb = false;          // every output a GLB (docs/gltf-binding.md)
  // --assemble: the mesh and the first level's cells from this plan (encode_plan.hpp), not
  // read from the input and simplified here.
  std::string plan_dir;
  // --memory: what the encodes of this process may use at once (0: no bound).
  uint64_t memory_budget = 0;
};

// The memory an encode of `mesh` takes at least at its peak (simplify() and write_pmz() hold
// the whole mesh: docs/design.md section 10, "The memory budget"), from measured peaks of
// geometry-only encodes (about 505-525 bytes a vertex on closed meshes with twice as many faces)
// taken a little low, and with attributes the arrays that are certainly held with the engine:
// the input's attributes and the engine's wedge per corner.
uint64_t encode_memory(const pmz::IndexedMesh& mesh) {
  const pmz::MeshAttributes& a = mesh.attributes;
  uint64_t attributes = a.corner_wedges.size() * 4 + a.wedge_vertices.size() * 4 +
                        a.normals.size() * 4 + a.colors.size() * 4 + a.face_materials.size() * 4;
  for (const std::vector<float>& t : a.texcoords) attributes += t.size() * 4;
  if (!a.empty()) attributes += uint64_t(mesh.face_count()) * 16;
  return uint64_t(mesh.vertex_count()) * 240 + uint64_t(mesh.face_count()) * 125 + attributes;
}

// The encodes running at once (--out-dir -j) share the budget: each takes its estimate from it
// before simplifying, waiting while the others hold too much of it, and gives it back when done.
// One that needs more than the whole budget is refused.
class MemoryBudget {
 public:
  explicit MemoryBudget(uint64_t bytes) : free_(bytes), total_(bytes) {}
  // False with `error` when `bytes` exceed the whole budget; else waits until they are free.
  bool take(uint64_t bytes, std::string& error) {
    if (total_ == 0) return true;
    if (bytes > total_)
      return error = "encoding it needs about " + pmz::app_support::byte_size_text(bytes) +
                     " of memory, more than the budget of " +
                     pmz::app_support::byte_size_text(total_) + " (--memory)",
             false;
    std::unique_lock<std::mutex> lock(mutex_);
    freed_.wait(lock, [&] { return free_ >= bytes; });
    free_ -= bytes;
    return true;
  }
  void give(uint64_t bytes) {
    if (total_ == 0) return;
#if defined(__GLIBC__)
    // What the encode freed goes back to the system too: another thread's encode would not
    // reuse this thread's malloc arena, and the process would hold both.
    malloc_trim(0);
#endif
    {
      std::lock_guard<std::mutex> lock(mutex_);
      free_ += bytes;
    }
    freed_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable freed_;
  uint64_t free_, total_;
};

// The budget's share an encode holds until it ends.
struct MemoryShare {
  MemoryBudget* budget = nullptr;
  uint64_t bytes = 0;
  // False with `error` when `n` bytes exceed the whole budget `b` (none: always true).
  bool take(MemoryBudget* b, uint64_t n, std::string& error) {
    if (!b) return true;
    if (!b->take(n, error)) return false;
    budget = b, bytes = n;
    return true;
  }
  ~MemoryShare() {
    if (budget) budget->give(bytes);
  }
};

bool glb_output(const std::string& output, const EncodeSettings& settings) {
  return settings.glb || app_support::extension(output) == "glb";
}

// What a GLB carries of a stream: its HEAD's fields and its base mesh, decoded from the stream
// itself (the binding wants the stream's level 0 exactly).
bool glb_stream(const std::vector<uint8_t>& stream, pmz::GlbStream& s, pmz::IndexedMesh& base,
                std::string& error) {
  pmz::Decoder decoder;
  decoder.feed(stream.data(), stream.size());
  if (decoder.finish() != pmz::Status::ok || !decoder.info().base_done)
    return error = "the written stream does not decode: " + decoder.error_message(), false;
  const pmz::StreamInfo& info = decoder.info();
  s.bytes = {reinterpret_cast<const char*>(stream.data()), stream.size()};
  s.version = std::to_string(info.version_major) + "." + std::to_string(info.version_minor);
  s.full_vertices = info.full_vertices, s.full_faces = info.full_faces;
  std::copy(info.bbox_min, info.bbox_min + 3, s.bbox_min);
  std::copy(info.bbox_max, info.bbox_max + 3, s.bbox_max);
  base = pmz::tool::decoded_mesh(decoder);
  return true;
}

// The stream in a binary glTF: its base mesh as the primitive; a glTF input's own images and
// texture files beside the input are embedded. Textures that cannot be embedded are named on
// stderr and stay URIs.
bool wrap_in_glb(const std::vector<uint8_t>& stream, const std::string& input, std::string& glb,
                 std::string& error) {
  pmz::GlbStream s;
  pmz::IndexedMesh base;
  if (!glb_stream(stream, s, base, error)) return false;
  pmz::GlbTextures textures;
  textures.dir = input == "-" ? "." : std::filesystem::path(input).parent_path().string();
  const std::string ext = app_support::extension(input);
  if ((ext == "gltf" || ext == "glb") && !pmz::read_gltf_images(input, textures.images, error))
    return false;
  if (!pmz::write_progressive_glb(base, s, textures, glb, error)) return false;
  for (const std::string& why : textures.not_embedded)
    app_support::print_error(input, "texture not embedded (kept as a URI): " + why);
  return true;
}

// A glTF input whose default scene has several mesh nodes, as a GLB that keeps the scene
// (docs/gltf-binding.md, "Scenes"): each mesh read in its own coordinates, repaired, simplified
// and written with the settings one mesh gets, its stream carried by its glTF mesh. `line` is
// the summary; errors name the input.
bool encode_scene(const pmz::GltfScene& scene, const std::string& input,
                  const EncodeSettings& settings, MemoryBudget* budget,
                  app_support::Progress* progress, std::string& glb, std::string& line,
                  std::string& error) {
  const size_t n = scene.mesh_count();
  std::vector<std::vector<uint8_t>> bytes(n);
  std::vector<pmz::GlbStream> streams(n);
  std::vector<pmz::IndexedMesh> bases(n);
  uint64_t faces = 0, vertices = 0, total = 0;
  for (size_t i = 0; i < n; ++i) {
    const std::string which = scene.mesh_name(i);
    pmz::PolygonSoup soup;
    if (!scene.read_mesh(i, soup, error)) return false;
    pmz::IndexedMesh mesh;
    pmz::MeshRepairStats stats;
    pmz::repair_mesh(soup, mesh, stats);
    if (mesh.face_count() == 0)
      return error = input + ": " + which + ": no usable faces (all degenerate)", false;
    if (const std::string summary = stats.summary(); !summary.empty())
      app_support::print_error(input, which + ": " + summary);
    MemoryShare share;
    if (!share.take(budget, encode_memory(mesh), error))
      return error = input + ": " + which + ": " + error, false;
    pmz::SimplifyOptions sopt = settings.simplify;
    settings.simplifier.apply_clusters(sopt, mesh.vertex_count());
    if (progress)
      sopt.progress = [&](double f) { progress->update("simplifying", (double(i) + f) / n); };
    pmz::CollapseSequence seq;
    if (!pmz::simplify(mesh, sopt, seq, error) ||
        !pmz::write_pmz(seq, settings.write, bytes[i], error) ||
        !glb_stream(bytes[i], streams[i], bases[i], error))
      return error = input + ": " + which + ": " + error, false;
    faces += seq.mesh.face_count(), vertices += seq.mesh.vertex_count(), total += bytes[i].size();
  }
  for (const std::string& why : scene.meshes_left_out()) app_support::print_error(input, why);
  std::vector<std::string> not_embedded;
  if (!scene.write_glb(bases, streams, not_embedded, glb, error))
    return error = input + ": " + error, false;
  for (const std::string& why : not_embedded)
    app_support::print_error(input, "texture not embedded (kept as a URI): " + why);
  line = std::to_string(n) + " meshes (" + std::to_string(scene.mesh_nodes()) + " nodes), " +
         std::to_string(faces) + " faces, " + std::to_string(vertices) + " vertices -> " +
         std::to_string(total) + " bytes of streams; in a GLB of " + std::to_string(glb.size()) +
         " bytes";
  return true;
}

// The scene of a .gltf or .glb input (read whole: a malformed one fails here), for a GLB output.
bool read_scene(const std::string& input, pmz::GltfScene& scene, std::string& error) {
  std::vector<uint8_t> data;
  return app_support::read_input(input, data, error) &&
         scene.read(input, {reinterpret_cast<const char*>(data.data()), data.size()}, error);
}

// Encodes one asset; on success `line` is its summary line, else `error` is one line naming
// the file.
bool encode(const std::string& input, const std::string& output, const EncodeSettings& settings,
            MemoryBudget* budget, app_support::Progress* progress, std::string& line,
            std::string& error) {
  if (app_support::same_file(input, output))
    return error = output + ": is the input file; not overwriting it", false;
  const auto t0 = std::chrono::steady_clock::now();
  // Opened first: an unwritable output fails before minutes of work, and the temporary (removed
  // on error and on SIGINT/SIGTERM) exists while the work runs.
  app_support::OutputFile out;
  if (!out.open(output, true, error)) return false;
  const bool as_glb = glb_output(output, settings);
  const std::string ext = app_support::extension(input);
  if (as_glb && settings.plan_dir.empty() && input != "-" && (ext == "gltf" || ext == "glb")) {
    pmz::GltfScene scene;
    std::string glb;
    if (!read_scene(input, scene, error)) return false;
    // One mesh node: the single-stream GLB below (the node's transform applied).
    if (scene.mesh_nodes() > 1) {
      const bool ok = encode_scene(scene, input, settings, budget, progress, glb, line, error);
      if (progress) progress->clear();
      if (!ok) return false;
      out.write(glb.data(), glb.size());
      if (!out.commit(error)) return false;
      const double secs =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      char buf[64];
      std::snprintf(buf, sizeof buf, ", %.2fs", secs);
      line = (output == "-" ? "stdout" : output) + ": " + line + buf;
      return true;
    }
  }
  pmz::IndexedMesh mesh;
  const tool::EncodePlan plan{settings.plan_dir};
  if (plan.dir.empty() ? !tool::read_mesh_input(input, settings.stdin_format, mesh, error, progress)
                       : !plan.read_mesh(mesh, error)) {
    if (progress) progress->clear();
    return false;
  }
  // What the encode's errors name: the plan, stdin or the input.
  const std::string source = !plan.dir.empty() ? plan.dir : input == "-" ? "stdin" : input;
  MemoryShare share;
  if (!share.take(budget, encode_memory(mesh), error)) {
    if (progress) progress->clear();
    return error = source + ": " + error, false;
  }
  pmz::SimplifyOptions sopt = settings.simplify;
  settings.simplifier.apply_clusters(sopt, mesh.vertex_count());
  if (progress) sopt.progress = [&](double f) { progress->update("simplifying", f); };
  if (!plan.dir.empty())
    sopt.clusters.first_level = [&](uint32_t cell, std::vector<uint8_t>& result, std::string& e) {
      return app_support::read_input(plan.result(std::to_string(cell)), result, e);
    };
  pmz::CollapseSequence seq;
  std::vector<uint8_t> bytes;
  pmz::WriteStats st;
  bool ok = pmz::simplify(mesh, sopt, seq, error);
  if (ok && progress) progress->update("writing", 1);
  ok = ok && pmz::write_pmz(seq, settings.write, bytes, error, &st);
  std::string glb;
  ok = ok && (!as_glb || wrap_in_glb(bytes, input, glb, error));
  if (progress) progress->clear();
  if (!ok) return error = source + ": " + error, false;
  if (as_glb)
    out.write(glb.data(), glb.size());
  else
    out.write(bytes.data(), bytes.size());
  if (!out.commit(error)) return false;
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double nv = seq.mesh.vertex_count();
  const double splits = std::max(1.0, double(seq.collapses.size()));
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "%s: %u faces, %u vertices -> %zu bytes, %.2f bits/vertex (connectivity %.2f, "
                "geometry %.2f bits/split), %.2fs",
                output == "-" ? "stdout" : output.c_str(), seq.mesh.face_count(),
                seq.mesh.vertex_count(), bytes.size(), bytes.size() * 8.0 / nv,
                st.connectivity_bits / splits, st.geometry_bits / splits, secs);
  line = buf;
  if (as_glb) line += "; in a GLB of " + std::to_string(glb.size()) + " bytes";
  if (!seq.mesh.attributes.empty()) {
    std::snprintf(buf, sizeof buf, "; attributes: %s, %llu bytes",
                  seq.mesh.attributes.describe().c_str(), (unsigned long long)st.attribute_bytes);
    line += buf;
  }
  if (settings.write.symbol_stats) {
    // Per kind of symbol, the bits its symbols take of their stream (the streams interleave
    // kinds, so their sizes cannot split them further).
    const char* kinds[pmz::kSymbolKinds] = {"groups",     "choice",      "wedge_count",
                                            "wedge_rank", "residual_t0", "residual_t1",
                                            "residual_n"};
    line += "\n  code bits/split:";
    for (int k = 0; k < pmz::kSymbolKinds; ++k) {
      std::snprintf(buf, sizeof buf, " %s %.2f", kinds[k], st.symbol_bits[k] / splits);
      line += buf;
    }
  }
  return true;
}

// --out-dir: made with its parents when missing (as mkdir -p); a path that exists but is not a
// folder is refused. Prints one line on failure.
bool make_output_folder(const std::string& dir) {
  std::error_code ec;
  if (std::filesystem::is_directory(dir, ec)) return true;
  if (std::filesystem::exists(std::filesystem::symlink_status(dir, ec))) {
    app_support::print_error(dir, "not a folder");
    return false;
  }
  if (!std::filesystem::create_directories(dir, ec) && !std::filesystem::is_directory(dir)) {
    app_support::print_error(dir, "cannot create the folder: " + ec.message());
    return false;
  }
  return true;
}

// One input to one output, its summary line printed.
int encode_one(const std::string& input, const std::string& output, const EncodeSettings& settings,
               bool quiet, bool force_progress) {
  app_support::Progress progress(quiet, force_progress);
  std::string line, error;
  MemoryBudget budget(settings.memory_budget);
  if (!encode(input, output, settings, &budget, progress.enabled() ? &progress : nullptr, line,
              error)) {
    app_support::print_error(error);
    return app_support::kExitFailure;
  }
  // With -o -, stdout carries the stream: the summary goes to stderr.
  std::fprintf(output == "-" ? stderr : stdout, "%s\n", line.c_str());
  return app_support::kExitOk;
}

// --plan: the mesh read and its first level's cells counted, then the plan written.
int write_plan(const std::string& input, const tool::EncodePlan& plan,
               const EncodeSettings& settings, const std::vector<std::string>& args, bool quiet,
               bool force_progress) {
  app_support::Progress progress(quiet, force_progress);
  pmz::IndexedMesh mesh;
  std::string error;
  bool ok = tool::read_mesh_input(input, settings.stdin_format, mesh, error,
                                  progress.enabled() ? &progress : nullptr);
  progress.clear();
  pmz::SimplifyOptions sopt = settings.simplify;
  settings.simplifier.apply_clusters(sopt, mesh.vertex_count());
  uint32_t tasks = 0;
  MemoryBudget budget(settings.memory_budget);
  MemoryShare share;
  if (ok && !share.take(&budget, encode_memory(mesh), error))
    ok = false, error = (input == "-" ? "stdin" : input) + ": " + error;
  if (ok && plan.exists())
    ok = false, error = plan.dir + ": holds a plan already (give a new or empty folder)";
  ok = ok && make_output_folder(plan.dir);
  // Each cell's region written as the engine reaches the first level's cells.
  std::vector<std::string> written;
  bool unwritten = false;  // a region could not be written (the error names it)
  const pmz::CellRegionSink sink = [&](uint32_t cell, const std::vector<uint8_t>& region,
                                       std::string& e) {
    written.push_back(plan.region(std::to_string(cell)));
    unwritten = !app_support::write_output(written.back(), region.data(), region.size(), e);
    return !unwritten;
  };
  if (ok && !pmz::cell_regions(mesh, sopt, sink, tasks, error))
    ok = false, error = unwritten ? error : (input == "-" ? "stdin" : input) + ": " + error;
  if (ok && !plan.write(mesh, args, tasks, error)) ok = false;
  if (!ok) {
    std::error_code ec;
    for (const std::string& f : written) std::filesystem::remove(f, ec);
    if (!error.empty()) app_support::print_error(error);
    return app_support::kExitFailure;
  }
  std::printf(
      "%s: %u tasks (the first level's cells) for %u faces; run pmz-encode --task %s ID "
      "for each ID in %s, then pmz-encode --assemble %s -o OUTPUT\n",
      plan.dir.c_str(), tasks, mesh.face_count(), plan.dir.c_str(), plan.file("tasks").c_str(),
      plan.dir.c_str());
  return app_support::kExitOk;
}

// --task DIR ID: one cell simplified, its result written whole (a temporary renamed).
int run_task(const tool::EncodePlan& plan, const std::string& id, const EncodeSettings& settings) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::string> ids;
  std::string error;
  bool ok = plan.read_tasks(ids, error);
  if (ok && (std::find(ids.begin(), ids.end(), id) == ids.end() || id.size() > 9 ||
             id.find_first_not_of("0123456789") != std::string::npos))
    ok = false, error = plan.file("tasks") + ": lists no task " + id;
  std::vector<uint8_t> result;
  std::error_code ec;
  if (ok && std::filesystem::exists(plan.region(id), ec)) {
    // The cell's region: all the task reads of the mesh.
    std::vector<uint8_t> region;
    ok = app_support::read_input(plan.region(id), region, error);
    if (ok && !pmz::simplify_cell_region(region, uint32_t(std::stoul(id)), result, error))
      ok = false, error = plan.region(id) + ": " + error;
  } else if (ok) {
    pmz::IndexedMesh mesh;
    ok = plan.read_mesh(mesh, error);
    pmz::SimplifyOptions sopt = settings.simplify;
    settings.simplifier.apply_clusters(sopt, mesh.vertex_count());
    if (ok && !pmz::simplify_cell(mesh, sopt, uint32_t(std::stoul(id)), result, error))
      ok = false, error = plan.dir + ": task " + id + ": " + error;
  }
  ok = ok && app_support::write_output(plan.result(id), result.data(), result.size(), error);
  if (!ok) {
    app_support::print_error(error);
    return app_support::kExitFailure;
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("%s: %zu bytes, %.2fs\n", plan.result(id).c_str(), result.size(), secs);
  return app_support::kExitOk;
}

// --assemble: every task's result present, else one line naming the first missing one.
bool all_tasks_done(const tool::EncodePlan& plan) {
  std::vector<std::string> ids;
  std::string error;
  if (!plan.read_tasks(ids, error)) {
    app_support::print_error(error);
    return false;
  }
  for (const std::string& id : ids) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(plan.result(id), ec)) {
      app_support::print_error(plan.result(id), "missing: task " + id +
                                                    " has not run (pmz-encode "
                                                    "--task " +
                                                    plan.dir + " " + id + ")");
      return false;
    }
  }
  return true;
}

// --memory's value in bytes (0: no bound); false when it is not one.
bool memory_budget(const std::string& text, uint64_t& bytes) {
  if (text == "auto") return bytes = app_support::machine_memory() / 10 * 9, true;
  return app_support::parse_byte_size(text, bytes);
}

}  // namespace

int main(int argc, char** argv) {
  app_support::init("pmz-encode");
  CLI::App app{
      "pmz-encode: simplify meshes with the multi-feature metric and write each as a progressive "
      ".pmz stream",
      "pmz-encode"};
  std::vector<std::string> inputs;
  std::string output, out_dir, format;
  unsigned jobs = std::max(1u, std::thread::hardware_concurrency());
  bool quiet = false, force_progress = false;
  EncodeSettings settings;
  tool::SimplifierCli& simplifier = settings.simplifier;
  app.add_option("inputs", inputs,
                 tool::mesh_files_help("input meshes", false, "- reads one from stdin"))
      ->type_name("MESH...");
  auto* out_opt = app.add_option("-o,--output", output,
                                 "output .pmz, or .glb (glTF with the stream; - for stdout)");
  auto* dir_opt = app.add_option(
      "--out-dir", out_dir,
      "write each input's NAME.pmz (NAME.glb with --glb) into this folder (several inputs; made if "
      "missing)");
  out_opt->excludes(dir_opt);
  app.add_flag(
      "--glb", settings.glb,
      "write binary glTF: the base mesh as a primitive, the stream in the "
      "PMZ_progressive_mesh extension, materials and textures kept; a glTF scene of several "
      "mesh nodes keeps its nodes, a stream per mesh (docs/gltf-binding.md; implied by "
      "-o NAME.glb)");
  app.add_option("-j,--jobs", jobs, "assets encoded at once with --out-dir (default: cores)")
      ->check(CLI::Range(1u, 1024u))
      ->capture_default_str();
  tool::add_format_option(app, format, true, false, "format of a mesh read from stdin");
  simplifier.add_to(app);
  app.add_option("--position-bits", settings.write.position_bits,
                 "quantization bits (0 = lossless float32)")
      ->check(CLI::Range(0, 30))
      ->capture_default_str();
  app.add_option("--level", settings.write.level,
                 "compression level: 0 smallest (default), 1 speed (faster decoding, about 20% "
                 "larger; spec/format.md section 9.10)")
      ->check(CLI::Range(0, 1))
      ->capture_default_str();
  app.add_option("--texcoord-bits", settings.write.texcoord_bits,
                 "texture coordinate bits over each set's bounding box (0 = lossless float32)")
      ->check(CLI::Range(0, 24))
      ->capture_default_str();
  app.add_option("--normal-bits", settings.write.normal_bits,
                 "normal bits per octahedral component (0 = lossless float32)")
      ->check(CLI::Range(0, 16) & !CLI::IsMember({1}))
      ->capture_default_str();
  app.add_option("--color-bits", settings.write.color_bits,
                 "colour bits per component over [0, 1] (0 = lossless float32)")
      ->check(CLI::Range(0, 16))
      ->capture_default_str();
  app.add_option("--base-faces", settings.write.base_faces,
                 "stop simplifying at this many faces (0: as far as possible)")
      ->capture_default_str();
  app.add_flag("--symbol-stats", settings.write.symbol_stats,
               "also print the code length per kind of split symbol (groups, choice, wedges, "
               "residual slots)");
  std::string memory = "auto";
  app.add_option("--memory", memory,
                 "memory the encodes may use at once: an input whose encode needs more (an "
                 "estimate from its vertex and face counts, once it is read) is refused, and "
                 "encodes run at once with -j wait for each other within it; bytes, or with k, "
                 "M, G: 1500M, 8G; 0: no bound; auto: 90% of the machine's memory (its RAM, or "
                 "its cgroup's limit when lower)")
      ->type_name("SIZE")
      ->capture_default_str();
  std::string plan_dir, assemble_dir;
  std::vector<std::string> task;
  auto* plan_opt =
      app.add_option("--plan", plan_dir,
                     "instead of encoding, write the encode as tasks into this folder (made if "
                     "missing): the mesh, these options, and one task per cell of the first cell "
                     "level, their ids one a line in DIR/tasks; then --task for each, then "
                     "--assemble (docs/design.md section 10)")
          ->type_name("DIR");
  auto* task_opt = app.add_option("--task", task,
                                  "run task ID of the plan in DIR, its result written into DIR "
                                  "(any process on any machine that sees DIR; a rerun rewrites "
                                  "the same result)")
                       ->expected(2)
                       ->type_name("DIR ID");
  auto* assemble_opt =
      app.add_option("--assemble", assemble_dir,
                     "write -o from the plan in DIR once every task has run: the bytes the "
                     "input encoded with the plan's options gives")
          ->type_name("DIR");
  plan_opt->excludes(out_opt)->excludes(dir_opt)->excludes(task_opt)->excludes(assemble_opt);
  task_opt->excludes(out_opt)->excludes(dir_opt)->excludes(assemble_opt);
  assemble_opt->excludes(dir_opt);
  app_support::add_progress_options(app, quiet, force_progress);
  app_support::set_footer(app);
  if (int rc = app_support::parse(app, argc, argv); rc >= 0) return rc;

  auto usage = app_support::usage_error;
  // --memory in bytes into the settings (after a plan's options are parsed again too).
  auto settle_memory = [&] { return memory_budget(memory, settings.memory_budget); };
  auto memory_problem = [&] {
    return "--memory " + memory + ": not a size (1500M, 8G, 0 or auto)";
  };
  const bool task_mode = task_opt->count() > 0, assemble_mode = assemble_opt->count() > 0;
  if (task_mode || assemble_mode) {
    if (assemble_mode && out_opt->count() == 0) return usage("--assemble needs -o FILE");
    // The plan's options are every step's: any other given here is refused, not ignored.
    const std::set<const CLI::Option*> own = {task_opt,
                                              assemble_opt,
                                              out_opt,
                                              app.get_option("--glb"),
                                              app.get_option("--quiet"),
                                              app.get_option("--progress"),
                                              app.get_option("--cell-threads"),
                                              app.get_option("--memory")};
    if (!inputs.empty()) return usage("the input is the plan's (give it to --plan)");
    for (const CLI::Option* o : app.get_options())
      if (o->count() && !own.count(o))
        return usage(o->get_name() + ": the plan's options are used (give it to --plan)");
    const tool::EncodePlan plan{task_mode ? task[0] : assemble_dir};
    std::vector<std::string> args;
    std::string error;
    if (!plan.read_options(args, error)) {
      app_support::print_error(error);
      return app_support::kExitFailure;
    }
    // The plan's command line parsed again, then what this one gives on top.
    const std::string given_output = output;
    const bool given_glb = settings.glb, given_quiet = quiet, given_progress = force_progress;
    const uint32_t given_threads = simplifier.cell_threads;
    const bool threads_given = app.get_option("--cell-threads")->count() > 0;
    const std::string given_memory = memory;
    const bool memory_given = app.get_option("--memory")->count() > 0;
    try {
      std::reverse(args.begin(), args.end());
      app.parse(args);
    } catch (const CLI::ParseError& e) {
      app_support::print_error(plan.file("options"),
                               std::string("not options of this pmz-encode: ") + e.what());
      return app_support::kExitFailure;
    }
    if (inputs.size() != 1 || plan_opt->count() == 0) {
      app_support::print_error(plan.file("options"), "not the options of a plan");
      return app_support::kExitFailure;
    }
    output = given_output, quiet = given_quiet, force_progress = given_progress;
    settings.glb = settings.glb || given_glb;
    if (threads_given) simplifier.cell_threads = given_threads;
    if (memory_given) memory = given_memory;
    if (!settle_memory()) return usage(memory_problem());
    simplifier.apply(settings.simplify);
    settings.simplify.clusters.position_bits = settings.write.position_bits;
    settings.stdin_format = format;
    if (task_mode) return run_task(plan, task[1], settings);
    if (!all_tasks_done(plan)) return app_support::kExitFailure;
    settings.plan_dir = plan.dir;
    return encode_one(inputs[0], output, settings, quiet, force_progress);
  }
  if (inputs.empty()) return usage("give an input mesh");
  if (!settle_memory()) return usage(memory_problem());
  if (plan_opt->count()) {
    if (inputs.size() != 1) return usage("--plan takes one input");
    if (const std::string problem = tool::stdin_input_problem(inputs, format); !problem.empty())
      return usage(problem);
    simplifier.apply(settings.simplify);
    settings.simplify.clusters.position_bits = settings.write.position_bits;
    settings.stdin_format = format;
    return write_plan(inputs[0], tool::EncodePlan{plan_dir}, settings,
                      std::vector<std::string>(argv + 1, argv + argc), quiet, force_progress);
  }
  if (out_opt->count() == 0 && dir_opt->count() == 0)
    return usage("give -o FILE (one input) or --out-dir DIR");
  if (out_opt->count() && inputs.size() > 1)
    return usage("several inputs need --out-dir DIR, not -o");
  if (const std::string problem = tool::stdin_input_problem(inputs, format); !problem.empty())
    return usage(problem);
  if (dir_opt->count() && std::count(inputs.begin(), inputs.end(), "-"))
    return usage("a mesh read from stdin needs -o FILE (it has no name for --out-dir)");
  simplifier.apply(settings.simplify);
  settings.simplify.clusters.position_bits = settings.write.position_bits;
  settings.stdin_format = format;

  std::vector<std::string> outputs;
  if (out_opt->count()) {
    outputs.push_back(output);
  } else {
    std::set<std::string> seen;
    for (const std::string& in : inputs) {
      outputs.push_back(
          (std::filesystem::path(out_dir) / std::filesystem::path(in).stem()).string() +
          (settings.glb ? ".glb" : ".pmz"));
      if (!seen.insert(outputs.back()).second)
        return usage("two inputs would both write " + outputs.back());
    }
    if (!make_output_folder(out_dir)) return app_support::kExitFailure;
  }

  if (inputs.size() == 1) return encode_one(inputs[0], outputs[0], settings, quiet, force_progress);

  // A batch: workers take the next asset until none is left, largest files first so that no
  // big asset is left to run alone at the end; lines are printed whole as assets finish, and
  // an overall bar (on a terminal) counts finished assets.
  std::vector<std::pair<uintmax_t, size_t>> order;  // (file size, input index)
  for (size_t i = 0; i < inputs.size(); ++i) {
    std::error_code ec;
    const uintmax_t size = std::filesystem::file_size(inputs[i], ec);
    order.emplace_back(ec ? 0 : size, i);
  }
  std::stable_sort(order.begin(), order.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  app_support::Progress progress(quiet, force_progress);
  std::mutex print_mutex;
  MemoryBudget budget(settings.memory_budget);
  std::atomic<size_t> next{0};
  size_t finished = 0, failed = 0;
  auto worker = [&] {
    for (size_t k; (k = next.fetch_add(1)) < inputs.size();) {
      const size_t i = order[k].second;
      std::string line, error;
      const bool ok = encode(inputs[i], outputs[i], settings, &budget, nullptr, line, error);
      std::lock_guard<std::mutex> lock(print_mutex);
      progress.clear();
      if (ok) {
        std::printf("%s\n", line.c_str());
        std::fflush(stdout);
      } else {
        app_support::print_error(error);
        ++failed;
      }
      progress.update("encoded", double(++finished) / double(inputs.size()));
    }
  };
  std::vector<std::thread> workers;
  const size_t n_workers = std::min<size_t>(jobs, inputs.size());
  for (size_t w = 1; w < n_workers; ++w) workers.emplace_back(worker);
  worker();
  for (std::thread& t : workers) t.join();
  progress.clear();
  if (failed) {
    app_support::print_error(std::to_string(failed) + " of " + std::to_string(inputs.size()) +
                             " assets failed");
    return app_support::kExitFailure;
  }
  return app_support::kExitOk;
}
