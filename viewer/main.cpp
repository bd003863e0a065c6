// SPDX-License-Identifier: MIT
// pmz-view: streams a .pmz file, stdin or URL and shows the mesh refining as bytes arrive.
// The worker thread (stream.cpp) reads and feeds the decoder; this thread moves the level of
// detail within a per-frame time budget, mirrors the changes and uploads only those. A mesh
// file (OBJ, PLY, glTF, ...) is shown as it is, through the same mirror and renderer.
// A stream with a node table is decoded for the camera (Decoder::update_view): the worker
// fetches by ranges only the nodes the view needs.
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <curl/curl.h>
#include <imgui.h>
#include <stb/stb_image_write.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <future>
#include <string>
#include <thread>

#include "camera.hpp"
#include "lod.hpp"
#include "materials.hpp"
#include "mesh_mirror.hpp"
#include "pmz/app_support.hpp"
#include "pmz/mesh_file_formats.hpp"
#include "renderer.hpp"
#include "source.hpp"
#include "static_mesh.hpp"
#include "stream.hpp"
#include "ui.hpp"

using namespace pmzview;

namespace {

struct Options {
  std::string source;
  double rate_kbps = 0;
  std::string screenshot;
  int width = 1024, height = 768;
  // --faces 0 / --ratio 0 are the base mesh: whether an option was given is kept apart from
  // its value.
  bool faces_set = false, ratio_set = false;
  uint64_t faces = 0;
  double ratio = 0;
  uint64_t bytes = 0;
  bool log = false, exit_when_complete = false;
  bool flat = false, wireframe = false, no_geomorph = false, no_attributes = false;
  float yaw_degrees = 34, pitch_degrees = 20;
  double budget_ms = 6;
  bool camera = false;  // --camera: eye and target
  float eye[3] = {0, 0, 0}, target[3] = {0, 0, 0};
  float pixel_error = 1;
  uint64_t max_faces = 0;  // --max-faces: the view's face budget (0: none)
};

// "pmz-view: message" on stderr, worded as by every tool; the exit status of a failed run.
int print_failure(const std::string& message) {
  pmz::app_support::print_error(message);
  return pmz::app_support::kExitFailure;
}

struct Textures {
  std::vector<Image> images;  // per material; empty: untextured
  std::vector<std::string> warnings;
};

Textures read_textures(const std::vector<ViewMaterial>& materials, const std::string& directory) {
  Textures t;
  load_textures(materials, directory, t.images, t.warnings);
  return t;
}

// Hands the textures to the renderer; each texture that could not be read is one warning line
// and its material is drawn with its base colour only.
void use_materials(Renderer& renderer, const std::string& source,
                   const std::vector<ViewMaterial>& materials, const Textures& textures,
                   bool texcoord_origin_top) {
  for (const std::string& w : textures.warnings)
    std::fprintf(stderr, "pmz-view: warning: %s: %s\n", source.c_str(), w.c_str());
  renderer.set_materials(materials, textures.images, texcoord_origin_top);
}

// A stream's material table and where its texture names are relative to: beside the .pmz
// (file or URL, and its OBJ's mtllib folder), the working directory for stdin. Call with the
// decoder locked, once its base mesh is in.
void stream_materials(const pmz::Decoder& decoder, const std::string& source,
                      std::vector<ViewMaterial>& materials, std::string& directory) {
  materials.clear();
  for (uint32_t i = 0; i < decoder.material_count(); ++i) {
    const pmz::MaterialInfo* m = decoder.material(i);
    ViewMaterial v;
    v.name = m->name;
    std::copy(m->base_color, m->base_color + 4, v.base_color);
    v.texture = m->base_color_texture;
    materials.push_back(v);
  }
  directory =
      (source == "-" ? "" : directory_of(source)) + directory_of(decoder.material_library());
}

// "attributes: texture coordinates, normals, 2 materials" for the overlay ("" when none).
std::string describe_attributes(const MeshMirror& mesh, size_t materials) {
  std::string line;
  auto add = [&](const std::string& part) { line += (line.empty() ? "" : ", ") + part; };
  if (mesh.has_texcoords) add("texture coordinates");
  if (mesh.has_normals) add("normals");
  if (mesh.has_colors) add("colours");
  if (materials) add(std::to_string(materials) + (materials == 1 ? " material" : " materials"));
  if (mesh.has_wedges) add(std::to_string(mesh.wedge_count) + " wedges");
  return line.empty() ? line : "attributes: " + line;
}

std::string g_glfw_error;
void on_glfw_error(int, const char* description) {
  g_glfw_error = description ? description : "unknown GLFW error";
}

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

void read_stats(const pmz::Decoder& decoder, Stats& s, pmz::StreamInfo& info) {
  info = decoder.info();
  s.faces = decoder.face_count();
  s.nodes = info.nodes;
  s.nodes_applied = decoder.nodes_applied();
  s.view_complete = decoder.view_complete();
  s.vertices = decoder.vertex_count();
  s.base_faces = info.base_faces;
  s.full_faces = info.full_faces;
  s.total_splits = info.total_splits;
  s.splits_applied = decoder.splits_applied();
  s.splits_available = decoder.splits_available();
  s.base_done = info.base_done;
  s.complete = info.complete;
}

// Frames the header's bounding box, or the mesh's own when the header has none.
bool frame_camera(Camera& camera, const pmz::StreamInfo& info, const MeshMirror& mesh,
                  float aspect) {
  float lo[3], hi[3];
  bool from_header = info.header_done;
  for (int i = 0; i < 3; ++i) {
    lo[i] = info.bbox_min[i];
    hi[i] = info.bbox_max[i];
    from_header = from_header && hi[i] >= lo[i];
  }
  from_header = from_header && (hi[0] > lo[0] || hi[1] > lo[1] || hi[2] > lo[2]);
  if (!from_header) {
    if (mesh.vertex_count == 0) return false;
    for (int i = 0; i < 3; ++i) lo[i] = hi[i] = mesh.positions[i];
    for (uint32_t v = 0; v < mesh.vertex_count; ++v)
      for (int i = 0; i < 3; ++i) {
        lo[i] = std::min(lo[i], mesh.positions[3 * size_t(v) + i]);
        hi[i] = std::max(hi[i], mesh.positions[3 * size_t(v) + i]);
      }
  }
  camera.frame(lo, hi, aspect);
  return true;
}

// faces: those drawn; nodes=A/B (streams with a node table): A of the B nodes resident;
// budget=N: --max-faces.
void log_line(double t, const Stats& s, const char* note) {
  char nodes[48] = "", budget[32] = "";
  if (s.nodes) std::snprintf(nodes, sizeof nodes, " nodes=%u/%" PRIu64, s.nodes_applied, s.nodes);
  if (s.nodes && s.face_budget)
    std::snprintf(budget, sizeof budget, " budget=%" PRIu64, s.face_budget);
  std::fprintf(stderr,
               "t=%.3f bytes=%" PRIu64 " total=%" PRIu64 " faces=%u full=%" PRIu64
               " vertices=%u splits=%" PRIu64 "/%" PRIu64 "%s%s fps=%.0f update_ms=%.1f%s%s\n",
               t, s.bytes, s.bytes_total, s.faces, s.full_faces, s.vertices, s.splits_applied,
               s.total_splits, nodes, budget, s.frames_per_second, s.update_ms, note[0] ? " " : "",
               note);
}

// "EX,EY,EZ,TX,TY,TZ": six finite numbers, the eye apart from the target.
bool parse_camera(const std::string& text, Options& o) {
  float c[6];
  char extra = 0;
  if (std::sscanf(text.c_str(), "%f,%f,%f,%f,%f,%f%c", c, c + 1, c + 2, c + 3, c + 4, c + 5,
                  &extra) != 6 ||
      !std::all_of(c, c + 6, [](float x) { return std::isfinite(x); }) ||
      (c[0] == c[3] && c[1] == c[4] && c[2] == c[5]))
    return false;
  std::copy(c, c + 3, o.eye);
  std::copy(c + 3, c + 6, o.target);
  return o.camera = true;
}

// Encoded in memory, then written like every tool's output (app_support::write_output: a temporary
// renamed into place, symlinks kept, devices written directly, removed on error and signals).
bool write_png(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb,
               std::string& error) {
  std::vector<uint8_t> png;
  const auto append = [](void* context, void* data, int size) {
    auto* out = static_cast<std::vector<uint8_t>*>(context);
    out->insert(out->end(), static_cast<uint8_t*>(data), static_cast<uint8_t*>(data) + size);
  };
  if (!stbi_write_png_to_func(append, &png, width, height, 3, rgb.data(), width * 3)) {
    error = path + ": cannot encode the PNG";
    return false;
  }
  return pmz::app_support::write_output(path, png.data(), png.size(), error);
}

int parse(int argc, char** argv, Options& o) {
  CLI::App app{"pmz-view: stream a .pmz mesh and watch it refine as its bytes arrive.", "pmz-view"};
  app.add_option("source", o.source,
                 "a .pmz file, - for stdin, an http:// or https:// URL, or a mesh file (" +
                     pmz::mesh_format_list(false, ", ", " or ", ".") + ") shown as it is")
      ->required();
  app.add_option("--rate", o.rate_kbps, "throttle the source to KBPS kilobytes (1000 B) per second")
      ->type_name("KBPS")
      ->check(CLI::PositiveNumber);
  app.add_option("--screenshot", o.screenshot, "render one frame off screen to FILE.png and exit")
      ->type_name("FILE.png");
  std::string size;
  app.add_option("--size", size, "screenshot size WxH (default 1024x768; also the window size)")
      ->type_name("WxH");
  auto* faces =
      app.add_option("--faces", o.faces, "level of detail: at least N faces (0: the base mesh)")
          ->type_name("N");
  auto* ratio =
      app.add_option("--ratio", o.ratio,
                     "level of detail: this fraction of the full face count (0: the base mesh)")
          ->type_name("R")
          ->check(CLI::Range(0.0, 1.0));
  auto* bytes =
      app.add_option("--bytes", o.bytes, "read only the first N bytes, show all they hold")
          ->type_name("N")
          ->check(CLI::PositiveNumber);
  faces->excludes(ratio)->excludes(bytes);
  ratio->excludes(bytes);
  app.add_flag("--log", o.log,
               "print 't=... bytes=... faces=...' lines to stderr ten times per second");
  app.add_flag("--exit-when-complete", o.exit_when_complete,
               "exit 0 once the whole stream is shown, or with a node table every part the "
               "view needs (1 on a stream error)");
  app.add_flag("--flat", o.flat, "start with flat shading");
  app.add_flag("--wireframe", o.wireframe, "start with the wireframe overlay");
  app.add_flag("--no-geomorph", o.no_geomorph, "start with geomorphs off");
  app.add_flag("--no-attributes", o.no_attributes,
               "start with the geometry look: no textures, colours or decoded normals");
  app.add_option("--yaw", o.yaw_degrees, "initial view azimuth in degrees")->type_name("DEG");
  app.add_option("--pitch", o.pitch_degrees, "initial view elevation in degrees")
      ->type_name("DEG")
      ->check(CLI::Range(-89.0, 89.0));
  std::string camera;
  auto* camera_option =
      app.add_option("--camera", camera,
                     "EX,EY,EZ,TX,TY,TZ: view from EX,EY,EZ towards TX,TY,TZ (y up, the mesh's "
                     "coordinates); a stream with a node table is decoded for that view, only "
                     "the parts it needs read (by HTTP Range requests for a URL)")
          ->type_name("EX,EY,EZ,TX,TY,TZ");
  camera_option->excludes(faces)->excludes(ratio)->excludes(bytes);
  app.add_option("--pixel-error", o.pixel_error,
                 "decoding for a view: refine while a part's error spans more pixels than this")
      ->type_name("P")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--max-faces", o.max_faces,
                 "decoding for a view: a face budget; the parts the view needs most come first, "
                 "those that would bring the mesh past N faces are neither fetched nor applied "
                 "(0: none)")
      ->type_name("N")
      ->capture_default_str();
  app.add_option("--budget-ms", o.budget_ms,
                 "refinement time per frame in milliseconds (at least 30% of the last frame's)")
      ->type_name("MS")
      ->check(CLI::PositiveNumber);
  pmz::app_support::set_footer(app, kKeyHelp);
  if (int rc = pmz::app_support::parse(app, argc, argv); rc >= 0) return rc;
  o.faces_set = faces->count() > 0;
  o.ratio_set = ratio->count() > 0;
  if (camera_option->count() && !parse_camera(camera, o)) {
    std::fprintf(stderr,
                 "pmz-view: --camera wants six numbers EX,EY,EZ,TX,TY,TZ, the eye apart from the "
                 "target, got '%s'\n",
                 camera.c_str());
    return 2;
  }
  if (!size.empty()) {
    char x = 0;
    char extra = 0;
    if (std::sscanf(size.c_str(), "%d%c%d%c", &o.width, &x, &o.height, &extra) != 3 ||
        (x != 'x' && x != 'X') || o.width < 16 || o.height < 16 || o.width > 16384 ||
        o.height > 16384) {
      std::fprintf(stderr, "pmz-view: --size wants WxH, e.g. 800x600 (16..16384), got '%s'\n",
                   size.c_str());
      return 2;
    }
  }
  return -1;  // go on
}

// pmz-view's run. A mesh file is shown whole; a .pmz stream is decoded on its own thread while
// the frames show what has arrived. The steps: open the source, then the window and the
// renderer, then one of three ways to the end: a screenshot of a mesh file, a screenshot of a
// stream's requested prefix, or the interactive loop (update, draw, measure, wait per frame).
class Viewer {
 public:
  explicit Viewer(const Options& o)
      : o_(o),
        shown_(o.source == "-" ? "stdin" : o.source),
        screenshot_(!o.screenshot.empty()),
        is_static_(is_mesh_file(o.source)),
        // For a view: --camera's, or the window's orbit camera (not for a fixed level of detail,
        // nor for a screenshot of the whole stream).
        by_view_(!is_static_ && !o.faces_set && !o.ratio_set && !o.bytes &&
                 (o.camera || !screenshot_)) {}
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;

  int run() {
    if (!open_input()) return print_failure(error_);
    curl_global_init(CURL_GLOBAL_DEFAULT);
    if (!open_window()) return print_failure(error_);
    const int rc = show();
    close_window();
    curl_global_cleanup();
    return rc;
  }

 private:
  // The mesh file, read whole, or the stream's source (file, stdin or URL), opened.
  bool open_input() {
    if (!is_static_) {
      source_ = open_source(o_.source, error_);
      return source_ != nullptr;
    }
    if (o_.bytes || o_.rate_kbps > 0 || o_.faces_set || o_.ratio_set)
      std::fprintf(stderr,
                   "pmz-view: warning: %s is a mesh file, shown whole: --bytes, --rate, --faces "
                   "and --ratio apply to .pmz streams\n",
                   o_.source.c_str());
    return load_static_mesh(o_.source, static_mesh_, error_);
  }

  // An OpenGL 3.3 core context: in a visible window, or in a hidden one for a screenshot (which
  // renders into its own framebuffer).
  bool open_window() {
    if (!std::getenv("DISPLAY") && !std::getenv("WAYLAND_DISPLAY")) {
      error_ =
          "no display: DISPLAY is not set (run in a desktop session, or headless under xvfb-run "
          "-a)";
      return false;
    }
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit()) {
      error_ = "cannot open a window: " + g_glfw_error + " (no usable display? try xvfb-run -a)";
      return false;
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_SAMPLES, 4);
    glfwWindowHint(GLFW_VISIBLE, screenshot_ ? GLFW_FALSE : GLFW_TRUE);
    window_ = screenshot_ ? glfwCreateWindow(64, 64, "pmz-view", nullptr, nullptr)
                          : glfwCreateWindow(o_.width, o_.height,
                                             ("pmz-view: " + o_.source).c_str(), nullptr, nullptr);
    if (!window_) {
      glfwTerminate();
      error_ = "cannot create an OpenGL 3.3 core window: " + g_glfw_error;
      return false;
    }
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(1);
    return true;
  }

  // The renderer (it needs the context) released before the window.
  void close_window() {
    renderer_.reset();
    glfwDestroyWindow(window_);
    glfwTerminate();
  }

  // Everything that needs the window: the renderer, the view, the stream; then to the end.
  int show() {
    renderer_ = std::make_unique<Renderer>();
    if (!renderer_->init(error_)) return print_failure(error_);
    set_up_view();
    if (!is_static_) {
      StreamOptions stream_options;
      stream_options.bytes_per_second = o_.rate_kbps * 1000;
      stream_options.byte_limit = o_.bytes;
      stream_options.by_nodes = by_view_;
      stream_.decoder.set_view_face_budget(o_.max_faces);  // (before the worker starts)
      stats_.face_budget = by_view_ ? o_.max_faces : 0;
      stream_.start(std::move(source_), stream_options);
    }
    t0_ = Clock::now();
    if (is_static_) show_static_mesh();
    const int rc = !screenshot_ ? run_interactive()
                   : is_static_ ? write_screenshot("")
                   : by_view_   ? screenshot_of_view()
                                : screenshot_of_stream();
    stream_.stop();
    // A texture fetch (curl) still running ends before the renderer and curl are released.
    if (textures_pending_.valid()) textures_pending_.wait();
    return rc;
  }

  // The camera and the view state from the options.
  void set_up_view() {
    reset_camera_angles();
    state_.smooth = !o_.flat;
    state_.wireframe = o_.wireframe;
    state_.geomorph = !o_.no_geomorph;
    state_.attributes = !o_.no_attributes;
    state_.lod.follow = !o_.faces_set && !o_.ratio_set;
    state_.lod.faces = o_.faces;
    ratio_pending_ = o_.ratio_set;
  }

  void reset_camera_angles() {
    camera_.yaw = o_.yaw_degrees * float(M_PI / 180);
    camera_.pitch = o_.pitch_degrees * float(M_PI / 180);
  }

  // A mesh file: its materials and textures, its mesh mirrored once, its statistics.
  void show_static_mesh() {
    const std::vector<ViewMaterial> materials =
        view_materials(static_mesh_.mesh.attributes.materials);
    use_materials(*renderer_, o_.source, materials,
                  read_textures(materials, static_mesh_.texture_directory),
                  static_mesh_.texcoord_origin_top);
    mirror_.sync(static_mesh_.frame(), 0, 0);
    stats_.faces = stats_.base_faces = mirror_.face_count;
    stats_.full_faces = mirror_.face_count;
    stats_.vertices = mirror_.vertex_count;
    stats_.base_done = stats_.complete = true;
    stats_.attributes = mirror_.has_wedges;
    stats_.attributes_line = describe_attributes(mirror_, materials.size());
  }

  // One frame of the mirrored mesh into --screenshot; `note` ends the summary line.
  int write_screenshot(const std::string& note) {
    renderer_->upload(mirror_);
    frame(float(o_.width) / float(o_.height));
    RenderOptions render_options;
    render_options.smooth = state_.smooth;
    render_options.wireframe = state_.wireframe;
    render_options.attributes = state_.attributes;
    std::vector<uint8_t> rgb;
    if (!renderer_->capture(camera_, o_.width, o_.height, render_options, rgb, error_) ||
        !write_png(o_.screenshot, o_.width, o_.height, rgb, error_))
      return print_failure(error_);
    std::printf("pmz-view: wrote %s (%dx%d): %u faces, %u vertices%s%s\n", o_.screenshot.c_str(),
                o_.width, o_.height, stats_.faces, stats_.vertices, note.c_str(),
                stats_.attributes_line.empty() ? "" : (", " + stats_.attributes_line).c_str());
    return 0;
  }

  // The whole requested prefix first, then exactly that level of detail.
  int screenshot_of_stream() {
    while (!stream_.done()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (!stream_.error().empty()) return print_failure(shown_ + ": " + stream_.error());
    {
      std::lock_guard<std::mutex> lock(stream_.mutex);
      pmz::Decoder& decoder = stream_.decoder;
      if (decoder.info().base_done) {
        if (ratio_pending_)
          state_.lod.faces = uint64_t(std::llround(o_.ratio * double(decoder.info().full_faces)));
        stepper_.step(decoder, state_.lod, -1);
        mirror_.sync(decoder, 0, 0);
        stream_materials(decoder, o_.source, stream_material_table_, texture_directory_);
      }
      read_stats(decoder, stats_, info_);
      count_drawn_faces(decoder);
    }
    use_materials(*renderer_, o_.source, stream_material_table_,
                  read_textures(stream_material_table_, texture_directory_), false);
    stats_.attributes_line = describe_attributes(mirror_, stream_material_table_.size());
    if (!stats_.base_done) return print_failure(no_base_mesh_message());
    return write_screenshot(", " + std::to_string(stream_.bytes_received()) + " bytes read");
  }

  // Decoded for a view, the mesh holds every face id of the stream, those of the nodes not
  // applied degenerate (0, 0, 0): stats_.faces counts the faces drawn. Counted again only
  // when the resident nodes changed.
  void count_drawn_faces(const pmz::Decoder& decoder) {
    if (!by_view_ || !stats_.nodes || stats_.nodes_applied < 2) return;
    if (drawn_.nodes_applied != stats_.nodes_applied || drawn_.moves != loop_.view_moves) {
      const uint32_t* t = decoder.indices();
      drawn_.faces = 0;
      for (uint32_t f = 0; f < decoder.face_count(); ++f, t += 3)
        drawn_.faces += t[0] != t[1] || t[1] != t[2];
      drawn_.nodes_applied = stats_.nodes_applied;
      drawn_.moves = loop_.view_moves;
    }
    stats_.faces = drawn_.faces;
  }

  // Frames the mesh (its bounding sphere sets the clip planes), then takes --camera's view.
  bool frame(float aspect) {
    if (!frame_camera(camera_, info_, mirror_, aspect)) return false;
    if (o_.camera) camera_.look(o_.eye, o_.target);
    return true;
  }

  // --camera with --screenshot: every node the view needs, then one frame of it.
  int screenshot_of_view() {
    bool framed = false, complete = false;
    for (;;) {
      uint64_t moved = 0;
      {
        std::lock_guard<std::mutex> lock(stream_.mutex);
        pmz::Decoder& decoder = stream_.decoder;
        if (decoder.info().base_done) {
          mirror_.sync(decoder, 0, 0);
          read_stats(decoder, stats_, info_);
          count_drawn_faces(decoder);
          if (!framed) framed = frame(float(o_.width) / float(o_.height));
          if (framed) {
            const pmz::View view =
                decoder_view(camera_, uint32_t(o_.width), uint32_t(o_.height), o_.pixel_error);
            moved = stepper_.step_view(decoder, view, 0.05);
            loop_.view_moves += moved;
            complete = decoder.view_complete();
          }
        }
      }
      if (complete) break;
      if (stream_.done() && !moved) break;  // an error, or the stream ended short
      if (!moved) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    if (!stream_.error().empty()) return print_failure(shown_ + ": " + stream_.error());
    {
      std::lock_guard<std::mutex> lock(stream_.mutex);
      mirror_.sync(stream_.decoder, 0, 0);
      read_stats(stream_.decoder, stats_, info_);
      count_drawn_faces(stream_.decoder);
    }
    if (!stats_.base_done) return print_failure(no_base_mesh_message());
    if (!complete)
      pmz::app_support::print_error(shown_,
                                    "warning: the stream ends before every part the view needs");
    std::string note = ", " + std::to_string(stream_.bytes_received()) + " of " +
                       std::to_string(stream_.bytes_total()) + " bytes read";
    if (stats_.nodes)
      note += ", " + std::to_string(stats_.nodes_applied) + " of " + std::to_string(stats_.nodes) +
              " nodes";
    if (stats_.nodes && stats_.face_budget)
      note += ", budget " + std::to_string(stats_.face_budget) + " faces";
    return write_screenshot(note);
  }

  std::string no_base_mesh_message() const {
    return shown_ + ": " +
           (o_.bytes ? "the first " + std::to_string(o_.bytes) + " bytes do not hold the base mesh"
                     : "the stream ended before its base mesh");
  }

  // The window's frames until it is closed, the stream fails for good, or (with
  // --exit-when-complete) everything is shown.
  int run_interactive() {
    start_overlay();
    int rc = 0;
    while (!glfwWindowShouldClose(window_)) {
      const double t = seconds_since(t0_);
      loop_.last_frame_seconds = t - loop_.frame_start;
      loop_.frame_start = t;
      const float now = float(t);
      const float morph_seconds = state_.geomorph ? state_.morph_seconds : 0;
      update_mesh(now, morph_seconds);
      const bool stream_done = is_static_ || stream_.done();
      if (!check_stream(stream_done, rc)) break;
      draw_frame(now, morph_seconds);
      measure_window(t);
      const bool finished =
          is_static_ ||
          (by_view_ ? stream_.error().empty() && stepper_.settled() && stats_.view_complete
                    : stream_done && stream_.error().empty() && stepper_.settled() &&
                          (stats_.complete || o_.bytes) &&
                          (!state_.lod.follow || stats_.splits_applied == stats_.splits_available));
      if (o_.log && (t >= loop_.next_log || (finished && o_.exit_when_complete))) {
        log_line(t, stats_, finished ? "complete" : "");
        loop_.next_log = t + 0.1;
      }
      if (finished && o_.exit_when_complete) break;
      wait_for_next_frame(t, now, morph_seconds, stream_done);
    }
    stop_overlay();
    return rc;
  }

  void start_overlay() {
    install_input(window_, &camera_, &state_, &stats_);
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in the working directory
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForOpenGL(window_, true);
    ImGui_ImplOpenGL3_Init("#version 330 core");
  }

  void stop_overlay() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }

  // What arrived since the last frame into the mirror and the renderer, with the statistics.
  void update_mesh(float now, float morph_seconds) {
    const auto update_start = Clock::now();
    if (!is_static_) sync_with_decoder(now, morph_seconds);  // a mesh file was synced once
    if (textures_pending_.valid() &&
        textures_pending_.wait_for(std::chrono::seconds(0)) == std::future_status::ready)
      use_materials(*renderer_, o_.source, stream_material_table_, textures_pending_.get(), false);
    renderer_->upload(mirror_);
    loop_.window_update_ms = std::max(loop_.window_update_ms, seconds_since(update_start) * 1000);
    stats_.bytes = stream_.bytes_received();
    stats_.bytes_total = stream_.bytes_total();
    stats_.by_view = by_view_ && stream_.fetching_nodes();
  }

  // Refines within the frame's budget and mirrors the decoder's mesh. Never waits on the worker
  // for long: a busy lock costs a frame or two at most.
  void sync_with_decoder(float now, float morph_seconds) {
    const bool locked =
        loop_.lock_misses >= 3 ? (stream_.mutex.lock(), true) : stream_.mutex.try_lock();
    if (!locked) {
      ++loop_.lock_misses;
      return;
    }
    loop_.lock_misses = 0;
    pmz::Decoder& decoder = stream_.decoder;
    if (ratio_pending_ && decoder.info().header_done) {
      state_.lod.faces = uint64_t(std::llround(o_.ratio * double(decoder.info().full_faces)));
      ratio_pending_ = false;
    }
    if (decoder.info().base_done) {
      // The budget, or a share of the last frame when frames are slow anyway (software GL, huge
      // meshes): refinement then keeps pace instead of crawling a batch a frame.
      const double budget =
          std::min(std::max(o_.budget_ms / 1000, 0.3 * loop_.last_frame_seconds), 1.0);
      if (!by_view_) {
        loop_.window_splits += stepper_.step(decoder, state_.lod, budget);
      } else if (loop_.framed) {  // (the camera needs the mesh framed first)
        int fb_width = 0, fb_height = 0;
        glfwGetFramebufferSize(window_, &fb_width, &fb_height);
        if (fb_width > 0 && fb_height > 0) {
          const uint64_t moved = stepper_.step_view(
              decoder,
              decoder_view(camera_, uint32_t(fb_width), uint32_t(fb_height), o_.pixel_error),
              budget);
          loop_.window_splits += moved;
          loop_.view_moves += moved;
        }
      }
      mirror_.sync(decoder, now, morph_seconds);
    }
    read_stats(decoder, stats_, info_);
    count_drawn_faces(decoder);
    const bool read_materials_now = stats_.base_done && !stream_materials_read_;
    if (read_materials_now)
      stream_materials(decoder, o_.source, stream_material_table_, texture_directory_);
    stream_.mutex.unlock();
    if (read_materials_now) {
      // Base colours now; the textures are read (or fetched) on their own thread and drawn
      // once they are in, so neither the stream nor the frames wait for them.
      renderer_->set_materials(stream_material_table_, {}, false);
      textures_pending_ =
          std::async(std::launch::async, read_textures, stream_material_table_, texture_directory_);
      stream_materials_read_ = true;
    }
    stats_.attributes = mirror_.has_wedges;
    stats_.attributes_line = describe_attributes(mirror_, stream_material_table_.size());
  }

  // A stream error is reported once. False (rc set) when the run ends here: nothing to show, a
  // run that promised to end on success, or a stream that ended before its base mesh.
  bool check_stream(bool stream_done, int& rc) {
    if (stream_done && !stream_.error().empty() && !loop_.error_reported) {
      loop_.error_reported = true;
      stats_.error = stream_.error();
      if (!stats_.base_done || o_.exit_when_complete) {
        rc = print_failure(shown_ + ": " + stats_.error);
        return false;
      }
      pmz::app_support::print_error(shown_, stats_.error + " (showing what was decoded)");
    }
    if (stream_done && stream_.error().empty() && !stats_.base_done) {
      rc = print_failure(no_base_mesh_message());
      return false;
    }
    return true;
  }

  // The view framed (first frame, or on reset), the mesh and the overlay drawn, buffers swapped.
  void draw_frame(float now, float morph_seconds) {
    int fb_width = 0, fb_height = 0;
    glfwGetFramebufferSize(window_, &fb_width, &fb_height);
    if ((!loop_.framed || state_.reset_view) && fb_height > 0) {
      loop_.framed = frame(float(fb_width) / float(fb_height));
      if (state_.reset_view) {
        reset_camera_angles();
        if (o_.camera) camera_.look(o_.eye, o_.target);
      }
      state_.reset_view = false;
    }
    RenderOptions render_options;
    render_options.smooth = state_.smooth;
    render_options.wireframe = state_.wireframe;
    render_options.morph_seconds = morph_seconds;
    render_options.now = now;
    render_options.attributes = state_.attributes;
    renderer_->draw(camera_, fb_width, fb_height, render_options);
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    draw_overlay(state_, stats_);
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    glfwSwapBuffers(window_);
  }

  // Splits and frames per second, and the slowest update, over half-second windows.
  void measure_window(double t) {
    ++loop_.window_frames;
    if (t - loop_.window_start < 0.5) return;
    stats_.splits_per_second = double(loop_.window_splits) / (t - loop_.window_start);
    stats_.frames_per_second = double(loop_.window_frames) / (t - loop_.window_start);
    stats_.update_ms = loop_.window_update_ms;
    loop_.window_update_ms = 0;
    loop_.window_start = t;
    loop_.window_splits = loop_.window_frames = 0;
  }

  // Idle (nothing arriving, refining or gliding): sleeps until input instead of spinning.
  // Otherwise caps at ~60 fps where swaps do not wait for vblank (e.g. Xvfb).
  void wait_for_next_frame(double t, float now, float morph_seconds, bool stream_done) {
    const bool settled = stepper_.settled() && now - mirror_.last_morph_start > morph_seconds;
    const bool idle = is_static_ || (settled && (by_view_ ? stats_.view_complete : stream_done));
    const double frame_seconds = seconds_since(t0_) - t;
    if (idle) {
      glfwWaitEventsTimeout(0.25);
      return;
    }
    if (frame_seconds < 1.0 / 60)
      std::this_thread::sleep_for(std::chrono::duration<double>(1.0 / 60 - frame_seconds));
    glfwPollEvents();
  }

  const Options& o_;
  const std::string shown_;  // the source as messages name it ("stdin" for -), like every tool
  const bool screenshot_, is_static_;
  const bool by_view_;  // decoded for a view (--camera or the window's camera)
  std::string error_;
  StaticMesh static_mesh_;
  std::unique_ptr<Source> source_;
  GLFWwindow* window_ = nullptr;
  std::unique_ptr<Renderer> renderer_;
  Camera camera_;
  ViewState state_;
  bool ratio_pending_ = false;  // --ratio needs the header's full face count
  Stats stats_;
  pmz::StreamInfo info_;
  MeshMirror mirror_;
  LodStepper stepper_;
  Stream stream_;
  Clock::time_point t0_;
  // A stream's materials, read once its base mesh is in; its textures on their own thread.
  std::vector<ViewMaterial> stream_material_table_;
  std::string texture_directory_;
  bool stream_materials_read_ = false;
  std::future<Textures> textures_pending_;
  // The interactive loop's state across frames.
  struct {
    bool framed = false, error_reported = false;
    int lock_misses = 0;
    double next_log = 0, window_start = 0;
    uint64_t window_splits = 0, window_frames = 0;
    double window_update_ms = 0;  // slowest decoder step + mirror + upload in the window
    double last_frame_seconds = 0, frame_start = 0;
    uint64_t view_moves = 0;  // splits applied or undone for the view, in all
  } loop_;
  struct {
    uint32_t nodes_applied = 0, faces = 0;
    uint64_t moves = UINT64_MAX;
  } drawn_;  // the last count_drawn_faces()
};

}  // namespace

int main(int argc, char** argv) {
  pmz::app_support::init("pmz-view");
  Options o;
  if (int rc = parse(argc, argv, o); rc >= 0) return rc;
  return Viewer(o).run();
}
