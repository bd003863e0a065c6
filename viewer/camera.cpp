// SPDX-License-Identifier: MIT
#include "camera.hpp"

#include <algorithm>
#include <cmath>
#include <pmz/decoder.hpp>

namespace pmzview {
namespace {

void normalize(float v[3]) {
  float l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (l > 0)
    for (int i = 0; i < 3; ++i) v[i] /= l;
}

void cross(const float a[3], const float b[3], float out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

// Camera basis: forward (eye to target), right, up.
void basis(const Camera& c, float f[3], float r[3], float u[3]) {
  float e[3];
  c.eye(e);
  for (int i = 0; i < 3; ++i) f[i] = c.target[i] - e[i];
  normalize(f);
  const float world_up[3] = {0, 1, 0};
  cross(f, world_up, r);
  normalize(r);
  cross(r, f, u);
}

}  // namespace

void Camera::frame(const float bmin[3], const float bmax[3], float aspect) {
  float diagonal2 = 0;
  for (int i = 0; i < 3; ++i) {
    target[i] = 0.5f * (bmin[i] + bmax[i]);
    diagonal2 += (bmax[i] - bmin[i]) * (bmax[i] - bmin[i]);
  }
  radius = diagonal2 > 0 ? 0.5f * std::sqrt(diagonal2) : 1.0f;
  // Back off along the current view direction until all eight box corners are inside the
  // frustum: tighter than fitting the bounding sphere, so flat objects fill the frame.
  float f[3], r[3], u[3];
  basis(*this, f, r, u);
  const float tan_y = std::tan(0.5f * fovy), tan_x = tan_y * aspect;
  float fit = 0;
  for (int corner = 0; corner < 8; ++corner) {
    float offset[3];
    for (int i = 0; i < 3; ++i) offset[i] = ((corner >> i) & 1 ? bmax[i] : bmin[i]) - target[i];
    float x = offset[0] * r[0] + offset[1] * r[1] + offset[2] * r[2];
    float y = offset[0] * u[0] + offset[1] * u[1] + offset[2] * u[2];
    float z = offset[0] * f[0] + offset[1] * f[1] + offset[2] * f[2];  // toward the far side
    fit = std::max({fit, std::abs(x) / tan_x - z, std::abs(y) / tan_y - z});
  }
  distance = fit > 0 ? fit * 1.08f : radius / std::sin(0.5f * fovy);
}

void Camera::orbit(float dx, float dy) {
  yaw -= dx * 0.008f;
  pitch = std::clamp(pitch + dy * 0.008f, -1.55f, 1.55f);
}

void Camera::pan(float dx, float dy, int viewport_height) {
  float f[3], r[3], u[3];
  basis(*this, f, r, u);
  // One pixel at the target's depth, in world units.
  float scale = 2 * distance * std::tan(0.5f * fovy) / float(std::max(viewport_height, 1));
  for (int i = 0; i < 3; ++i) target[i] += (-dx * r[i] + dy * u[i]) * scale;
}

void Camera::zoom(float steps) {
  distance = std::clamp(distance * std::pow(0.87f, steps), radius * 0.01f, radius * 100.0f);
}

void Camera::look(const float eye_at[3], const float look_at[3]) {
  float d[3];
  for (int i = 0; i < 3; ++i) {
    target[i] = look_at[i];
    d[i] = eye_at[i] - look_at[i];
  }
  distance = std::max(std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), 1e-6f);
  pitch = std::clamp(std::asin(std::clamp(d[1] / distance, -1.0f, 1.0f)), -1.55f, 1.55f);
  yaw = std::atan2(d[0], d[2]);
}

void Camera::eye(float out[3]) const {
  out[0] = target[0] + distance * std::cos(pitch) * std::sin(yaw);
  out[1] = target[1] + distance * std::sin(pitch);
  out[2] = target[2] + distance * std::cos(pitch) * std::cos(yaw);
}

Mat4 Camera::view() const {
  float e[3], f[3], r[3], u[3];
  eye(e);
  basis(*this, f, r, u);
  Mat4 m = {r[0], u[0], -f[0], 0, r[1], u[1], -f[1], 0, r[2], u[2], -f[2], 0, 0, 0, 0, 1};
  for (int i = 0; i < 3; ++i) m[12 + i] = -(m[i] * e[0] + m[4 + i] * e[1] + m[8 + i] * e[2]);
  return m;
}

Mat4 Camera::projection(float aspect) const {
  // Clip planes hug the bounding sphere for depth precision, but never reach behind the eye.
  float near_z = std::max(distance - 2 * radius, distance * 0.01f);
  float far_z = distance + 2 * radius;
  float t = 1.0f / std::tan(0.5f * fovy);
  Mat4 m{};
  m[0] = t / aspect;
  m[5] = t;
  m[10] = (far_z + near_z) / (near_z - far_z);
  m[11] = -1;
  m[14] = 2 * far_z * near_z / (near_z - far_z);
  return m;
}

pmz::View decoder_view(const Camera& camera, uint32_t width, uint32_t height, float pixel_error) {
  pmz::View v;
  camera.eye(v.eye);
  const Mat4 p = camera.projection(float(width) / float(std::max(height, 1u))), m = camera.view();
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) {
      float sum = 0;
      for (int k = 0; k < 4; ++k) sum += p[4 * k + r] * m[4 * c + k];
      v.view_projection[4 * c + r] = sum;
    }
  v.fov_y = camera.fovy;
  v.viewport_height = height;
  v.pixel_error = pixel_error;
  return v;
}

}  // namespace pmzview
