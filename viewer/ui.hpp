// SPDX-License-Identifier: MIT
// Interaction: mouse camera controls, keys, and the Dear ImGui overlay.
#pragma once
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <cstdint>
#include <string>

#include "camera.hpp"
#include "lod.hpp"

namespace pmzview {

// What the user controls; the main loop reads it every frame.
struct ViewState {
  LodTarget lod;
  bool wireframe = false;
  bool smooth = true;
  bool geomorph = true;
  bool attributes = true;  // textures, colours, decoded normals (false: geometry look)
  float morph_seconds = 0.5f;
  bool overlay = true;
  bool reset_view = false;  // reframe the camera on the next frame
};

// What the overlay shows; filled by the main loop.
struct Stats {
  uint32_t faces = 0, vertices = 0;
  uint64_t base_faces = 0, full_faces = 0;
  uint64_t splits_applied = 0, splits_available = 0, total_splits = 0;
  uint64_t bytes = 0, bytes_total = 0;  // total 0 = unknown
  double splits_per_second = 0, frames_per_second = 0;
  double update_ms = 0;  // slowest recent frame's refine + mirror + upload time
  bool base_done = false, complete = false;
  // View-dependent decoding: nodes resident of those in the stream (0: no node table), and
  // whether every node the view needs is applied; faces counts only those drawn.
  uint32_t nodes_applied = 0;
  uint64_t nodes = 0;
  uint64_t face_budget = 0;  // --max-faces (0: none)
  bool by_view = false, view_complete = false;
  bool attributes = false;      // the mesh has attribute wedges or materials
  std::string attributes_line;  // e.g. "attributes: texcoords, normals, 2 materials"
  std::string error;
};

// Key list for --help and the overlay.
extern const char* const kKeyHelp;

// Installs GLFW mouse/key callbacks; call before ImGui_ImplGlfw_InitForOpenGL so ImGui
// chains to them. The pointed-to objects must outlive the window.
void install_input(GLFWwindow* window, Camera* camera, ViewState* state, const Stats* stats);

void draw_overlay(ViewState& state, const Stats& stats);

}  // namespace pmzview
