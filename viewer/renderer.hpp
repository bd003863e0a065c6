// OpenGL 3.3 core renderer: the mesh in GPU buffers that grow geometrically and receive only
// the ranges MeshMirror marks dirty; lit shading (flat from screen-space derivatives, or
// smooth from the mirrored vertex normals), a wireframe overlay and GPU geomorphs.
#pragma once
#include <epoxy/gl.h>

#include <cstdint>
#include <string>
#include <vector>

#include "camera.hpp"
#include "mesh_mirror.hpp"

namespace pmzview {

struct RenderOptions {
  bool wireframe = false;
  bool smooth = false;
  float morph_seconds = 0;  // 0 = geomorphs off
  float now = 0;            // geomorph clock, same as MeshMirror::sync's
};

constexpr float kBackground[3] = {0.13f, 0.14f, 0.16f};

class Renderer {
 public:
  Renderer() = default;
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  bool init(std::string& error);  // needs a current GL 3.3 core context
  void upload(MeshMirror& mesh);  // sends the dirty ranges, then clears them
  // Draws into the bound framebuffer.
  void draw(const Camera& camera, int width, int height, const RenderOptions& options);
  // Renders one frame off screen (multisampled) and reads it back as top-down RGB rows.
  bool capture(const Camera& camera, int width, int height, const RenderOptions& options,
               std::vector<uint8_t>& rgb, std::string& error);

  uint64_t bytes_uploaded = 0;  // running total, for the overlay

 private:
  // Uploads runs_ one by one, or as one span when that copies less than the calls cost.
  void upload_runs(GLenum target, GLuint buffer, size_t element_size, const void* base);
  void upload_range(GLenum target, GLuint buffer, size_t element_size, const void* base,
                    uint32_t begin, uint32_t end);

  GLuint program_ = 0, vao_ = 0, ebo_ = 0;
  GLuint vbo_[4] = {0, 0, 0, 0};  // positions, morph_from, morph_start, normals
  uint32_t vertex_capacity_ = 0, face_capacity_ = 0, face_count_ = 0;
  GLint u_view_ = -1, u_proj_ = -1, u_time_ = -1, u_morph_ = -1, u_smooth_ = -1, u_lines_ = -1;
  std::vector<Run> runs_;
};

}  // namespace pmzview
