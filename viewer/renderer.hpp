// SPDX-License-Identifier: MIT
// OpenGL 3.3 core renderer: the mesh in GPU buffers that grow geometrically and receive only
// the ranges MeshMirror marks dirty; lit shading (flat from screen-space derivatives, or
// smooth from the mirrored vertex normals or the decoded ones), a wireframe overlay and GPU
// geomorphs. With attribute wedges the vertex buffers hold wedges (position vertex id,
// texture coordinates, colour, decoded normal) and the per-vertex buffers are read as buffer
// textures by that id; a face's material comes from a buffer texture by gl_PrimitiveID, and
// each textured material is one pass that keeps only its own faces.
#pragma once
#include <epoxy/gl.h>

#include <cstdint>
#include <string>
#include <vector>

#include "camera.hpp"
#include "materials.hpp"
#include "mesh_mirror.hpp"

namespace pmzview {

struct RenderOptions {
  bool wireframe = false;
  bool smooth = false;
  float morph_seconds = 0;  // 0 = geomorphs off
  float now = 0;            // geomorph clock, same as MeshMirror::sync's
  bool attributes = true;   // textures, colours and decoded normals (false: geometry look)
};

constexpr float kBackground[3] = {0.13f, 0.14f, 0.16f};

class Renderer {
 public:
  Renderer() = default;
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  bool init(std::string& error);  // needs a current GL 3.3 core context
  // The stream's material table and each material's texture (empty image: untextured).
  // texcoord_origin_top: v = 0 is the image's top row (glTF), else its bottom row (OBJ).
  void set_materials(const std::vector<ViewMaterial>& materials, const std::vector<Image>& images,
                     bool texcoord_origin_top);
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

  void configure_vertex_layout(bool wedges, bool decoded_normals);
  void draw_passes(GLsizei count, const RenderOptions& options);

  GLuint program_ = 0, vao_ = 0, ebo_ = 0;
  GLuint vbo_[4] = {0, 0, 0, 0};  // per vertex: positions, morph_from, morph_start, normals
  GLuint vertex_textures_[4] = {0, 0, 0, 0};  // the same four as buffer textures (wedge mode)
  GLuint wbo_[4] = {0, 0, 0, 0};  // per wedge: vertex id, texcoords, colours, decoded normals
  GLuint face_material_buffer_ = 0, face_material_texture_ = 0;
  GLuint material_buffer_ = 0, material_texture_ = 0;  // rgb + pass per material, + default
  std::vector<GLuint> textures_;                       // per textured pass (1..), GL names
  uint32_t vertex_capacity_ = 0, face_capacity_ = 0, face_count_ = 0, wedge_capacity_ = 0;
  bool wedges_ = false, decoded_normals_ = false, colors_ = false, face_materials_ = false;
  bool texcoords_ = false, texcoord_origin_top_ = false, materials_dirty_ = true;
  std::vector<ViewMaterial> materials_;
  std::vector<GLuint> material_textures_;  // per material: GL texture or 0
  GLint u_view_ = -1, u_proj_ = -1, u_time_ = -1, u_morph_ = -1, u_smooth_ = -1, u_lines_ = -1;
  GLint u_wedges_ = -1, u_decoded_normals_ = -1, u_attributes_ = -1, u_use_colors_ = -1;
  GLint u_pass_ = -1, u_fixed_material_ = -1, u_material_count_ = -1, u_flip_v_ = -1;
  GLint u_textured_ = -1;
  std::vector<Run> runs_;
};

}  // namespace pmzview
