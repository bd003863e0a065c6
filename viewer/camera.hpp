// SPDX-License-Identifier: MIT
// Orbit camera: yaw/pitch/distance around a target, framed on the mesh's bounding sphere.
#pragma once
#include <array>
#include <cstdint>

namespace pmz {
struct View;
}

namespace pmzview {

using Mat4 = std::array<float, 16>;  // column-major, as OpenGL expects

struct Camera {
  float target[3] = {0, 0, 0};
  float yaw = 0.6f, pitch = 0.35f;  // radians
  float distance = 3;
  float radius = 1;    // of the framed bounding sphere: sets clip planes and zoom limits
  float fovy = 0.70f;  // radians

  // Centers on the box and backs off until its bounding sphere fits the narrower field of view.
  void frame(const float bmin[3], const float bmax[3], float aspect);
  void orbit(float dx_pixels, float dy_pixels);
  void pan(float dx_pixels, float dy_pixels, int viewport_height);
  void zoom(float steps);  // > 0 moves closer
  // Orbits `target` from `eye` (y up; an eye straight above or below is tilted slightly).
  void look(const float eye[3], const float target[3]);

  void eye(float out[3]) const;
  Mat4 view() const;
  Mat4 projection(float aspect) const;
};

// The camera as pmz::Decoder::update_view() takes it, for a width x height viewport.
pmz::View decoder_view(const Camera& camera, uint32_t width, uint32_t height, float pixel_error);

}  // namespace pmzview
