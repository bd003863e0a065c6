// SPDX-License-Identifier: MIT
#include "ui.hpp"

#include <imgui.h>

#include <algorithm>
#include <cinttypes>
#include <cstdio>

namespace pmzview {

const char* const kKeyHelp =
    "Mouse: left drag orbits, right or middle drag (or shift + left) pans, wheel zooms.\n"
    "Keys:\n"
    "  + / = / PageUp     more faces (x1.25)\n"
    "  - / PageDown       fewer faces (/1.25)\n"
    "  Home / End         base mesh / finest level received\n"
    "  F                  follow the stream (refine as bytes arrive)\n"
    "  W                  wireframe overlay\n"
    "  S                  smooth / flat shading\n"
    "  A                  attributes: textures, colours, decoded normals / geometry only\n"
    "  G                  geomorphs (new vertices glide out of their parent)\n"
    "  R                  reset the view\n"
    "  H                  hide / show the overlay\n"
    "  Q / Esc            quit\n";

namespace {

struct Input {
  Camera* camera = nullptr;
  ViewState* state = nullptr;
  const Stats* stats = nullptr;
  int dragging = -1;  // GLFW mouse button held, or -1
  bool pan = false;
  double x = 0, y = 0;
};
Input g_input;  // one window per process

bool imgui_wants_mouse() { return ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureMouse; }
bool imgui_wants_keys() { return ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureKeyboard; }

void on_mouse_button(GLFWwindow* window, int button, int action, int mods) {
  if (action == GLFW_RELEASE) {
    if (button == g_input.dragging) g_input.dragging = -1;
    return;
  }
  if (imgui_wants_mouse()) return;
  g_input.dragging = button;
  g_input.pan = button != GLFW_MOUSE_BUTTON_LEFT || (mods & GLFW_MOD_SHIFT);
  glfwGetCursorPos(window, &g_input.x, &g_input.y);
}

void on_cursor(GLFWwindow* window, double x, double y) {
  double dx = x - g_input.x, dy = y - g_input.y;
  g_input.x = x;
  g_input.y = y;
  if (g_input.dragging < 0) return;
  if (g_input.pan) {
    int width = 0, height = 0;
    glfwGetWindowSize(window, &width, &height);
    g_input.camera->pan(float(dx), float(dy), height);
  } else {
    g_input.camera->orbit(float(dx), float(dy));
  }
}

void on_scroll(GLFWwindow*, double, double dy) {
  if (!imgui_wants_mouse()) g_input.camera->zoom(float(dy));
}

void on_key(GLFWwindow* window, int key, int, int action, int) {
  if (action == GLFW_RELEASE || imgui_wants_keys()) return;
  ViewState& s = *g_input.state;
  const Stats& stats = *g_input.stats;
  auto set_faces = [&](double faces) {
    s.lod.follow = false;
    s.lod.faces = uint64_t(std::clamp(faces, double(stats.base_faces),
                                      double(std::max(stats.full_faces, stats.base_faces))));
  };
  switch (key) {
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_KP_ADD:
    case GLFW_KEY_PAGE_UP:
      set_faces(std::max(double(stats.faces) * 1.25, double(stats.faces) + 2));
      break;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT:
    case GLFW_KEY_PAGE_DOWN:
      set_faces(double(stats.faces) / 1.25);
      break;
    case GLFW_KEY_HOME:
      set_faces(0);
      break;
    case GLFW_KEY_END:
      s.lod.follow = true;
      break;
    case GLFW_KEY_F:
      s.lod.follow = !s.lod.follow;
      s.lod.faces = stats.faces;
      break;
    case GLFW_KEY_W:
      s.wireframe = !s.wireframe;
      break;
    case GLFW_KEY_S:
      s.smooth = !s.smooth;
      break;
    case GLFW_KEY_G:
      s.geomorph = !s.geomorph;
      break;
    case GLFW_KEY_A:
      s.attributes = !s.attributes;
      break;
    case GLFW_KEY_R:
      s.reset_view = true;
      break;
    case GLFW_KEY_H:
      s.overlay = !s.overlay;
      break;
    case GLFW_KEY_Q:
    case GLFW_KEY_ESCAPE:
      glfwSetWindowShouldClose(window, GLFW_TRUE);
      break;
    default:
      break;
  }
}

// 1234567 -> "1.23 M" style, for byte counts.
void format_bytes(char* out, size_t size, uint64_t bytes) {
  if (bytes >= 10000000)
    std::snprintf(out, size, "%.2f MB", double(bytes) / 1e6);
  else if (bytes >= 10000)
    std::snprintf(out, size, "%.1f kB", double(bytes) / 1e3);
  else
    std::snprintf(out, size, "%" PRIu64 " B", bytes);
}

}  // namespace

void install_input(GLFWwindow* window, Camera* camera, ViewState* state, const Stats* stats) {
  g_input.camera = camera;
  g_input.state = state;
  g_input.stats = stats;
  glfwSetMouseButtonCallback(window, on_mouse_button);
  glfwSetCursorPosCallback(window, on_cursor);
  glfwSetScrollCallback(window, on_scroll);
  glfwSetKeyCallback(window, on_key);
}

void draw_overlay(ViewState& s, const Stats& stats) {
  if (!s.overlay) return;
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowBgAlpha(0.75f);
  ImGui::Begin("pmz-view", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
  char received[32], total[32];
  format_bytes(received, sizeof received, stats.bytes);
  if (stats.bytes_total) {
    format_bytes(total, sizeof total, stats.bytes_total);
    ImGui::Text("bytes     %s / %s (%.0f%%)", received, total,
                100.0 * double(stats.bytes) / double(stats.bytes_total));
  } else {
    ImGui::Text("bytes     %s", received);
  }
  if (stats.nodes && stats.face_budget)
    ImGui::Text("faces     %u / %" PRIu64 ", budget %" PRIu64, stats.faces, stats.full_faces,
                stats.face_budget);
  else
    ImGui::Text("faces     %u / %" PRIu64, stats.faces, stats.full_faces);
  if (stats.nodes)
    ImGui::Text("nodes     %u / %" PRIu64 " resident%s", stats.nodes_applied, stats.nodes,
                stats.by_view ? (stats.view_complete ? ", view complete" : ", fetching") : "");
  ImGui::Text("vertices  %u", stats.vertices);
  ImGui::Text("splits    %" PRIu64 " applied, %" PRIu64 " received, %" PRIu64 " total",
              stats.splits_applied, stats.splits_available, stats.total_splits);
  ImGui::Text("refine    %.0f splits/s", stats.splits_per_second);
  ImGui::Text("frame     %.0f fps, update %.1f ms", stats.frames_per_second, stats.update_ms);
  if (!stats.base_done)
    ImGui::TextColored(ImVec4(1, 0.8f, 0.3f, 1), "waiting for the base mesh...");
  else if (stats.complete)
    ImGui::TextColored(ImVec4(0.5f, 1, 0.5f, 1), "stream complete");
  if (!stats.attributes_line.empty()) ImGui::Text("%s", stats.attributes_line.c_str());
  if (!stats.error.empty()) ImGui::TextColored(ImVec4(1, 0.4f, 0.4f, 1), "%s", stats.error.c_str());

  ImGui::Separator();
  if (stats.base_done && stats.full_faces > stats.base_faces) {
    uint32_t lo = uint32_t(stats.base_faces),
             hi = uint32_t(std::min<uint64_t>(stats.full_faces, UINT32_MAX));
    uint32_t value =
        s.lod.follow ? stats.faces : uint32_t(std::clamp<uint64_t>(s.lod.faces, lo, hi));
    if (ImGui::SliderScalar("faces", ImGuiDataType_U32, &value, &lo, &hi, "%u",
                            ImGuiSliderFlags_Logarithmic)) {
      s.lod.follow = false;
      s.lod.faces = value;
    }
  }
  if (ImGui::Checkbox("follow stream (F)", &s.lod.follow) && !s.lod.follow)
    s.lod.faces = stats.faces;
  ImGui::Checkbox("wireframe (W)", &s.wireframe);
  ImGui::Checkbox("smooth shading (S)", &s.smooth);
  if (stats.attributes) ImGui::Checkbox("attributes (A)", &s.attributes);
  ImGui::Checkbox("geomorphs (G)", &s.geomorph);
  if (s.geomorph) ImGui::SliderFloat("morph s", &s.morph_seconds, 0.05f, 3.0f, "%.2f");
  if (ImGui::Button("reset view (R)")) s.reset_view = true;
  ImGui::End();
}

}  // namespace pmzview
