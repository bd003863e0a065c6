// pmz-view: streams a .pmz file, stdin or URL and shows the mesh refining as bytes arrive.
// The worker thread (stream.cpp) reads and feeds the decoder; this thread moves the level of
// detail within a per-frame time budget, mirrors the changes and uploads only those. A mesh
// file (OBJ, PLY, glTF, ...) is shown as it is, through the same mirror and renderer.
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
};

int fail(const std::string& message) {
  std::fprintf(stderr, "pmz-view: %s\n", message.c_str());
  return 1;
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

void log_line(double t, const Stats& s, const char* note) {
  std::fprintf(stderr,
               "t=%.3f bytes=%" PRIu64 " total=%" PRIu64 " faces=%u full=%" PRIu64
               " vertices=%u splits=%" PRIu64 "/%" PRIu64 " fps=%.0f update_ms=%.1f%s%s\n",
               t, s.bytes, s.bytes_total, s.faces, s.full_faces, s.vertices, s.splits_applied,
               s.total_splits, s.frames_per_second, s.update_ms, note[0] ? " " : "", note);
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
                 "a .pmz file, - for stdin, an http:// or https:// URL, or a mesh file "
                 "(.obj .ply .gltf .glb .off .stl) shown as it is")
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
               "exit 0 once the whole stream is shown (1 on a stream error)");
  app.add_flag("--flat", o.flat, "start with flat shading");
  app.add_flag("--wireframe", o.wireframe, "start with the wireframe overlay");
  app.add_flag("--no-geomorph", o.no_geomorph, "start with geomorphs off");
  app.add_flag("--no-attributes", o.no_attributes,
               "start with the geometry look: no textures, colours or decoded normals");
  app.add_option("--yaw", o.yaw_degrees, "initial view azimuth in degrees")->type_name("DEG");
  app.add_option("--pitch", o.pitch_degrees, "initial view elevation in degrees")
      ->type_name("DEG")
      ->check(CLI::Range(-89.0, 89.0));
  app.add_option("--budget-ms", o.budget_ms,
                 "refinement time per frame in milliseconds (at least 30% of the last frame's)")
      ->type_name("MS")
      ->check(CLI::PositiveNumber);
  pmz::app_support::set_footer(app, kKeyHelp);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "pmz-view: %s (see --help)\n", e.what());
    return 2;
  }
  o.faces_set = faces->count() > 0;
  o.ratio_set = ratio->count() > 0;
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

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (int rc = parse(argc, argv, o); rc >= 0) return rc;
  const bool screenshot = !o.screenshot.empty();

  std::string error;
  const bool is_static = is_mesh_file(o.source);
  StaticMesh static_mesh;
  std::unique_ptr<Source> source;
  if (is_static) {
    if (o.bytes || o.rate_kbps > 0 || o.faces_set || o.ratio_set)
      std::fprintf(stderr,
                   "pmz-view: warning: %s is a mesh file, shown whole: --bytes, --rate, --faces "
                   "and --ratio apply to .pmz streams\n",
                   o.source.c_str());
    if (!load_static_mesh(o.source, static_mesh, error)) return fail(error);
  } else {
    source = open_source(o.source, error);
    if (!source) return fail(error);
  }
  curl_global_init(CURL_GLOBAL_DEFAULT);

  if (!std::getenv("DISPLAY") && !std::getenv("WAYLAND_DISPLAY"))
    return fail(
        "no display: DISPLAY is not set (run in a desktop session, or headless under xvfb-run -a)");
  glfwSetErrorCallback(on_glfw_error);
  if (!glfwInit())
    return fail("cannot open a window: " + g_glfw_error + " (no usable display? try xvfb-run -a)");
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_SAMPLES, 4);
  // A screenshot renders into its own framebuffer: the window only carries the context.
  glfwWindowHint(GLFW_VISIBLE, screenshot ? GLFW_FALSE : GLFW_TRUE);
  GLFWwindow* window = screenshot
                           ? glfwCreateWindow(64, 64, "pmz-view", nullptr, nullptr)
                           : glfwCreateWindow(o.width, o.height, ("pmz-view: " + o.source).c_str(),
                                              nullptr, nullptr);
  if (!window) {
    glfwTerminate();
    return fail("cannot create an OpenGL 3.3 core window: " + g_glfw_error);
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(1);

  int rc = 0;
  {
    Renderer renderer;
    if (!renderer.init(error)) {
      glfwDestroyWindow(window);
      glfwTerminate();
      return fail(error);
    }
    Camera camera;
    camera.yaw = o.yaw_degrees * float(M_PI / 180);
    camera.pitch = o.pitch_degrees * float(M_PI / 180);
    ViewState state;
    state.smooth = !o.flat;
    state.wireframe = o.wireframe;
    state.geomorph = !o.no_geomorph;
    state.attributes = !o.no_attributes;
    state.lod.follow = !o.faces_set && !o.ratio_set;
    state.lod.faces = o.faces;
    bool ratio_pending = o.ratio_set;  // needs the header's full face count
    Stats stats;
    pmz::StreamInfo info;
    MeshMirror mirror;
    LodStepper stepper;

    Stream stream;
    if (!is_static) {
      StreamOptions stream_options;
      stream_options.bytes_per_second = o.rate_kbps * 1000;
      stream_options.byte_limit = o.bytes;
      stream.start(std::move(source), stream_options);
    }
    const auto t0 = Clock::now();
    size_t material_count = 0;
    // A stream's materials, read once its base mesh is in.
    std::vector<ViewMaterial> stream_material_table;
    std::string texture_directory;
    bool stream_materials_read = false;
    std::future<Textures> textures_pending;
    if (is_static) {
      const std::vector<ViewMaterial> materials =
          view_materials(static_mesh.mesh.attributes.materials);
      use_materials(renderer, o.source, materials,
                    read_textures(materials, static_mesh.texture_directory),
                    static_mesh.texcoord_origin_top);
      material_count = materials.size();
      mirror.sync(static_mesh.frame(), 0, 0);
      stats.faces = stats.base_faces = mirror.face_count;
      stats.full_faces = mirror.face_count;
      stats.vertices = mirror.vertex_count;
      stats.base_done = stats.complete = true;
      stats.attributes = mirror.has_wedges;
      stats.attributes_line = describe_attributes(mirror, material_count);
    }

    // One frame of the mirrored mesh into --screenshot; `note` ends the summary line.
    auto write_screenshot = [&](const std::string& note) {
      renderer.upload(mirror);
      frame_camera(camera, info, mirror, float(o.width) / float(o.height));
      RenderOptions render_options;
      render_options.smooth = state.smooth;
      render_options.wireframe = state.wireframe;
      render_options.attributes = state.attributes;
      std::vector<uint8_t> rgb;
      if (!renderer.capture(camera, o.width, o.height, render_options, rgb, error) ||
          !write_png(o.screenshot, o.width, o.height, rgb, error))
        return fail(error);
      std::printf("pmz-view: wrote %s (%dx%d): %u faces, %u vertices%s%s\n", o.screenshot.c_str(),
                  o.width, o.height, stats.faces, stats.vertices, note.c_str(),
                  stats.attributes_line.empty() ? "" : (", " + stats.attributes_line).c_str());
      return 0;
    };

    if (screenshot && is_static) {
      rc = write_screenshot("");
    } else if (screenshot) {
      // The whole requested prefix first, then exactly that level of detail.
      while (!stream.done()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
      if (!stream.error().empty()) {
        rc = fail(o.source + ": " + stream.error());
      } else {
        {
          std::lock_guard<std::mutex> lock(stream.mutex);
          pmz::Decoder& decoder = stream.decoder;
          if (decoder.info().base_done) {
            if (ratio_pending)
              state.lod.faces = uint64_t(std::llround(o.ratio * double(decoder.info().full_faces)));
            stepper.step(decoder, state.lod, -1);
            mirror.sync(decoder, 0, 0);
            stream_materials(decoder, o.source, stream_material_table, texture_directory);
          }
          read_stats(decoder, stats, info);
        }
        use_materials(renderer, o.source, stream_material_table,
                      read_textures(stream_material_table, texture_directory), false);
        stats.attributes_line = describe_attributes(mirror, stream_material_table.size());
        if (!stats.base_done) {
          rc = fail(o.bytes ? "the first " + std::to_string(o.bytes) +
                                  " bytes do not hold the base mesh"
                            : o.source + ": the stream ended before its base mesh");
        } else {
          rc = write_screenshot(", " + std::to_string(stream.bytes_received()) + " bytes read");
        }
      }
    } else {
      install_input(window, &camera, &state, &stats);
      IMGUI_CHECKVERSION();
      ImGui::CreateContext();
      ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in the working directory
      ImGui::StyleColorsDark();
      ImGui_ImplGlfw_InitForOpenGL(window, true);
      ImGui_ImplOpenGL3_Init("#version 330 core");

      bool framed = false, error_reported = false;
      int lock_misses = 0;
      double next_log = 0, window_start = 0;
      uint64_t window_splits = 0, window_frames = 0;
      double window_update_ms = 0;  // slowest decoder step + mirror + upload in the window
      double last_frame_seconds = 0, frame_start = 0;
      while (!glfwWindowShouldClose(window)) {
        const double t = seconds_since(t0);
        last_frame_seconds = t - frame_start;
        frame_start = t;
        const float now = float(t);
        const float morph_seconds = state.geomorph ? state.morph_seconds : 0;
        const auto update_start = Clock::now();
        // Never wait on the worker for long: a busy lock costs a frame or two at most.
        bool locked = !is_static &&
                      (lock_misses >= 3 ? (stream.mutex.lock(), true) : stream.mutex.try_lock());
        if (is_static) {
          // Synced once before the loop; nothing arrives.
        } else if (locked) {
          lock_misses = 0;
          pmz::Decoder& decoder = stream.decoder;
          if (ratio_pending && decoder.info().header_done) {
            state.lod.faces = uint64_t(std::llround(o.ratio * double(decoder.info().full_faces)));
            ratio_pending = false;
          }
          if (decoder.info().base_done) {
            // The budget, or a share of the last frame when frames are slow anyway (software
            // GL, huge meshes): refinement then keeps pace instead of crawling a batch a frame.
            const double budget =
                std::min(std::max(o.budget_ms / 1000, 0.3 * last_frame_seconds), 1.0);
            window_splits += stepper.step(decoder, state.lod, budget);
            mirror.sync(decoder, now, morph_seconds);
          }
          read_stats(decoder, stats, info);
          const bool read_materials_now = stats.base_done && !stream_materials_read;
          if (read_materials_now)
            stream_materials(decoder, o.source, stream_material_table, texture_directory);
          stream.mutex.unlock();
          if (read_materials_now) {
            // Base colours now; the textures are read (or fetched) on their own thread and
            // drawn once they are in, so neither the stream nor the frames wait for them.
            renderer.set_materials(stream_material_table, {}, false);
            textures_pending = std::async(std::launch::async, read_textures, stream_material_table,
                                          texture_directory);
            stream_materials_read = true;
          }
          stats.attributes = mirror.has_wedges;
          stats.attributes_line = describe_attributes(mirror, stream_material_table.size());
        } else {
          ++lock_misses;
        }
        if (textures_pending.valid() &&
            textures_pending.wait_for(std::chrono::seconds(0)) == std::future_status::ready)
          use_materials(renderer, o.source, stream_material_table, textures_pending.get(), false);
        renderer.upload(mirror);
        window_update_ms = std::max(window_update_ms, seconds_since(update_start) * 1000);
        stats.bytes = stream.bytes_received();
        stats.bytes_total = stream.bytes_total();

        const bool stream_done = is_static || stream.done();
        if (stream_done && !stream.error().empty() && !error_reported) {
          error_reported = true;
          stats.error = stream.error();
          // Nothing to show, or a run that promised to end on success: give up now.
          if (!stats.base_done || o.exit_when_complete) {
            rc = fail(o.source + ": " + stats.error);
            break;
          }
          std::fprintf(stderr, "pmz-view: %s: %s (showing what was decoded)\n", o.source.c_str(),
                       stats.error.c_str());
        }
        if (stream_done && stream.error().empty() && !stats.base_done) {
          rc = fail(o.bytes ? "the first " + std::to_string(o.bytes) +
                                  " bytes do not hold the base mesh"
                            : o.source + ": the stream ended before its base mesh");
          break;
        }

        int fb_width = 0, fb_height = 0;
        glfwGetFramebufferSize(window, &fb_width, &fb_height);
        if ((!framed || state.reset_view) && fb_height > 0) {
          framed = frame_camera(camera, info, mirror, float(fb_width) / float(fb_height));
          if (state.reset_view) {
            camera.yaw = o.yaw_degrees * float(M_PI / 180);
            camera.pitch = o.pitch_degrees * float(M_PI / 180);
          }
          state.reset_view = false;
        }

        RenderOptions render_options;
        render_options.smooth = state.smooth;
        render_options.wireframe = state.wireframe;
        render_options.morph_seconds = morph_seconds;
        render_options.now = now;
        render_options.attributes = state.attributes;
        renderer.draw(camera, fb_width, fb_height, render_options);
        ImGui_ImplOpenGL3_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        ImGui::NewFrame();
        draw_overlay(state, stats);
        ImGui::Render();
        ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
        glfwSwapBuffers(window);

        ++window_frames;
        if (t - window_start >= 0.5) {
          stats.splits_per_second = double(window_splits) / (t - window_start);
          stats.frames_per_second = double(window_frames) / (t - window_start);
          stats.update_ms = window_update_ms;
          window_update_ms = 0;
          window_start = t;
          window_splits = window_frames = 0;
        }
        const bool finished =
            is_static || (stream_done && stream.error().empty() && stepper.settled() &&
                          (stats.complete || o.bytes) &&
                          (!state.lod.follow || stats.splits_applied == stats.splits_available));
        if (o.log && (t >= next_log || (finished && o.exit_when_complete))) {
          log_line(t, stats, finished ? "complete" : "");
          next_log = t + 0.1;
        }
        if (finished && o.exit_when_complete) break;

        // Idle (nothing arriving, refining or gliding): sleep until input instead of spinning.
        const bool idle = is_static || (stream_done && stepper.settled() &&
                                        now - mirror.last_morph_start > morph_seconds);
        const double frame_seconds = seconds_since(t0) - t;
        if (idle) {
          glfwWaitEventsTimeout(0.25);
        } else {
          // Cap at ~60 fps where swaps do not wait for vblank (e.g. Xvfb).
          if (frame_seconds < 1.0 / 60)
            std::this_thread::sleep_for(std::chrono::duration<double>(1.0 / 60 - frame_seconds));
          glfwPollEvents();
        }
      }
      ImGui_ImplOpenGL3_Shutdown();
      ImGui_ImplGlfw_Shutdown();
      ImGui::DestroyContext();
    }
    stream.stop();
  }
  glfwDestroyWindow(window);
  glfwTerminate();
  curl_global_cleanup();
  return rc;
}
