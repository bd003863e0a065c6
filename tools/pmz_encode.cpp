// SPDX-License-Identifier: MIT
// pmz-encode: simplify meshes and write each as a progressive .pmz stream. One input with -o
// (a file, or - for stdout), or many with --out-dir encoded by -j worker threads (one line per
// asset; a failing asset does not stop the others). A .glb output (or --glb) carries the stream in
// a binary glTF as docs/gltf-binding.md says: the base mesh as an ordinary primitive, materials
// and their texture files kept.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <set>
#include <string>
#include <thread>

#include "decoded_mesh.hpp"
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
};

bool glb_output(const std::string& output, const EncodeSettings& settings) {
  return settings.glb || app_support::extension(output) == "glb";
}

// The stream in a binary glTF: its base mesh, decoded from the stream itself (the binding
// wants the stream's level 0 exactly), as the primitive; a glTF input's own images and texture
// files beside the input are embedded. Textures that cannot be embedded are named on stderr and
// stay URIs.
bool wrap_in_glb(const std::vector<uint8_t>& stream, const std::string& input, std::string& glb,
                 std::string& error) {
  pmz::Decoder decoder;
  decoder.feed(stream.data(), stream.size());
  if (decoder.finish() != pmz::Status::ok || !decoder.info().base_done)
    return error = "the written stream does not decode: " + decoder.error_message(), false;
  const pmz::StreamInfo& info = decoder.info();
  pmz::GlbStream s;
  s.bytes = {reinterpret_cast<const char*>(stream.data()), stream.size()};
  s.version = std::to_string(info.version_major) + "." + std::to_string(info.version_minor);
  s.full_vertices = info.full_vertices, s.full_faces = info.full_faces;
  std::copy(info.bbox_min, info.bbox_min + 3, s.bbox_min);
  std::copy(info.bbox_max, info.bbox_max + 3, s.bbox_max);
  pmz::GlbTextures textures;
  textures.dir = input == "-" ? "." : std::filesystem::path(input).parent_path().string();
  const std::string ext = app_support::extension(input);
  if ((ext == "gltf" || ext == "glb") && !pmz::read_gltf_images(input, textures.images, error))
    return false;
  if (!pmz::write_progressive_glb(pmz::tool::decoded_mesh(decoder), s, textures, glb, error))
    return false;
  for (const std::string& why : textures.not_embedded)
    app_support::print_error(input, "texture not embedded (kept as a URI): " + why);
  return true;
}

// Encodes one asset; on success `line` is its summary line, else `error` is one line naming
// the file.
bool encode(const std::string& input, const std::string& output, const EncodeSettings& settings,
            app_support::Progress* progress, std::string& line, std::string& error) {
  if (app_support::same_file(input, output))
    return error = output + ": is the input file; not overwriting it", false;
  const auto t0 = std::chrono::steady_clock::now();
  // Opened first: an unwritable output fails before minutes of work, and the temporary (removed
  // on error and on SIGINT/SIGTERM) exists while the work runs.
  app_support::OutputFile out;
  if (!out.open(output, true, error)) return false;
  pmz::IndexedMesh mesh;
  if (!tool::read_mesh_input(input, settings.stdin_format, mesh, error, progress)) {
    if (progress) progress->clear();
    return false;
  }
  pmz::SimplifyOptions sopt = settings.simplify;
  settings.simplifier.apply_clusters(sopt, mesh.vertex_count());
  if (progress) sopt.progress = [&](double f) { progress->update("simplifying", f); };
  pmz::CollapseSequence seq;
  std::vector<uint8_t> bytes;
  pmz::WriteStats st;
  bool ok = pmz::simplify(mesh, sopt, seq, error);
  if (ok && progress) progress->update("writing", 1);
  ok = ok && pmz::write_pmz(seq, settings.write, bytes, error, &st);
  std::string glb;
  const bool as_glb = glb_output(output, settings);
  ok = ok && (!as_glb || wrap_in_glb(bytes, input, glb, error));
  if (progress) progress->clear();
  if (!ok) return error = (input == "-" ? "stdin" : input) + ": " + error, false;
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
      ->required()
      ->type_name("MESH...");
  auto* out_opt = app.add_option("-o,--output", output,
                                 "output .pmz, or .glb (glTF with the stream; - for stdout)");
  auto* dir_opt = app.add_option(
      "--out-dir", out_dir,
      "write each input's NAME.pmz (NAME.glb with --glb) into this folder (several inputs; made if "
      "missing)");
  out_opt->excludes(dir_opt);
  app.add_flag("--glb", settings.glb,
               "write binary glTF: the base mesh as a primitive, the stream in the "
               "PMZ_progressive_mesh extension, materials and textures kept (docs/gltf-binding.md; "
               "implied by -o NAME.glb)");
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
  app_support::add_progress_options(app, quiet, force_progress);
  app_support::set_footer(app);
  if (int rc = app_support::parse(app, argc, argv); rc >= 0) return rc;

  auto usage = app_support::usage_error;
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

  if (inputs.size() == 1) {
    app_support::Progress progress(quiet, force_progress);
    std::string line, error;
    if (!encode(inputs[0], outputs[0], settings, progress.enabled() ? &progress : nullptr, line,
                error)) {
      app_support::print_error(error);
      return app_support::kExitFailure;
    }
    // With -o -, stdout carries the stream: the summary goes to stderr.
    std::fprintf(outputs[0] == "-" ? stderr : stdout, "%s\n", line.c_str());
    return app_support::kExitOk;
  }

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
  std::atomic<size_t> next{0};
  size_t finished = 0, failed = 0;
  auto worker = [&] {
    for (size_t k; (k = next.fetch_add(1)) < inputs.size();) {
      const size_t i = order[k].second;
      std::string line, error;
      const bool ok = encode(inputs[i], outputs[i], settings, nullptr, line, error);
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
