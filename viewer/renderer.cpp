// SPDX-License-Identifier: MIT
#include "renderer.hpp"

#include <algorithm>
#include <cstring>

namespace pmzview {
namespace {

const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_morph_from;
layout(location = 2) in float a_morph_start;
layout(location = 3) in vec3 a_normal;  // per vertex (smooth), or per wedge (decoded)
layout(location = 4) in uint a_vertex;  // wedge mode: the wedge's position vertex
layout(location = 5) in vec2 a_texcoord;
layout(location = 6) in vec4 a_color;
uniform mat4 u_view;
uniform mat4 u_proj;
uniform float u_time;
uniform float u_morph_seconds;
uniform int u_wedges;           // 1: per-vertex data from the buffer textures by a_vertex
uniform int u_decoded_normals;  // 1: a_normal is the wedge's decoded normal
uniform samplerBuffer u_vertex_positions;
uniform samplerBuffer u_vertex_morph_from;
uniform samplerBuffer u_vertex_morph_start;
uniform samplerBuffer u_vertex_normals;
out vec3 v_view_position;
out vec3 v_view_normal;
out vec2 v_texcoord;
out vec4 v_color;
vec3 fetch3(samplerBuffer b, int v) {
  return vec3(texelFetch(b, 3 * v).r, texelFetch(b, 3 * v + 1).r, texelFetch(b, 3 * v + 2).r);
}
void main() {
  vec3 position = a_position, from = a_morph_from, normal = a_normal;
  float start = a_morph_start;
  if (u_wedges == 1) {
    int v = int(a_vertex);
    position = fetch3(u_vertex_positions, v);
    from = fetch3(u_vertex_morph_from, v);
    start = texelFetch(u_vertex_morph_start, v).r;
    if (u_decoded_normals == 0) normal = fetch3(u_vertex_normals, v);
  }
  float t = u_morph_seconds > 0.0 ? clamp((u_time - start) / u_morph_seconds, 0.0, 1.0) : 1.0;
  t = t * t * (3.0 - 2.0 * t);
  vec4 p = u_view * vec4(mix(from, position, t), 1.0);
  v_view_position = p.xyz;
  v_view_normal = mat3(u_view) * normal;
  v_texcoord = a_texcoord;
  v_color = a_color;
  gl_Position = u_proj * p;
}
)";

const char* kFragmentShader = R"(#version 330 core
in vec3 v_view_position;
in vec3 v_view_normal;
in vec2 v_texcoord;
in vec4 v_color;
uniform int u_smooth;
uniform int u_lines;
uniform int u_attributes;      // 0: the geometry look (grey, tinted back faces)
uniform int u_use_colors;      // multiply by the wedge colour
uniform int u_pass;            // -1: every face; else only faces whose material is in this pass
uniform int u_textured;        // this pass samples u_texture
uniform int u_fixed_material;  // >= 0: every face has this material (no per-face table)
uniform int u_material_count;  // the table's last entry (this index) is the default material
uniform int u_flip_v;          // texture coordinates with v = 0 at the image's bottom row
uniform usamplerBuffer u_face_materials;
uniform samplerBuffer u_materials;  // rgba32f per material: base colour rgb, pass
uniform sampler2D u_texture;
out vec4 color;
void main() {
  if (u_lines == 1) {
    color = vec4(0.07, 0.08, 0.10, 1.0);
    return;
  }
  vec3 base = gl_FrontFacing ? vec3(0.78, 0.80, 0.84) : vec3(0.70, 0.42, 0.34);
  if (u_attributes == 1) {
    int m = u_fixed_material >= 0
                ? u_fixed_material
                : int(min(texelFetch(u_face_materials, gl_PrimitiveID).r, uint(u_material_count)));
    vec4 material = texelFetch(u_materials, m);
    if (u_pass >= 0 && int(material.a) != u_pass) discard;
    base = material.rgb;
    if (u_textured == 1)
      base *= texture(u_texture, vec2(v_texcoord.x, u_flip_v == 1 ? 1.0 - v_texcoord.y : v_texcoord.y)).rgb;
    if (u_use_colors == 1) base *= v_color.rgb;
    if (!gl_FrontFacing) base *= 0.7;
  }
  vec3 flat_normal = cross(dFdx(v_view_position), dFdy(v_view_position));
  vec3 n = (u_smooth == 1 && dot(v_view_normal, v_view_normal) > 1e-30) ? v_view_normal : flat_normal;
  n = normalize(n);
  vec3 to_eye = normalize(-v_view_position);
  if (dot(n, to_eye) < 0.0) n = -n;  // two-sided lighting
  vec3 to_light = normalize(to_eye + vec3(0.35, 0.45, 0.0));
  float diffuse = max(dot(n, to_light), 0.0);
  float specular = pow(max(dot(n, normalize(to_light + to_eye)), 0.0), 40.0) * 0.22;
  color = vec4(base * (0.16 + 0.84 * diffuse) + vec3(specular), 1.0);
}
)";

GLuint compile(GLenum type, const char* text, std::string& error) {
  GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[1024] = {};
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    error = std::string("shader compile failed: ") + log;
    glDeleteShader(shader);
    return 0;
  }
  return shader;
}

// Element counts per vertex in each vertex buffer.
constexpr int kComponents[4] = {3, 3, 1, 3};
// Bytes per wedge in each wedge buffer: vertex id, texcoords, rgba, decoded normal.
constexpr size_t kWedgeBytes[4] = {4, 8, 16, 12};
// Texture units: 0 the pass's texture, 1-4 the vertex buffers, then face materials, materials.
constexpr GLint kVertexUnit = 1, kFaceMaterialUnit = 5, kMaterialUnit = 6;
const char* const kVertexSamplers[4] = {"u_vertex_positions", "u_vertex_morph_from",
                                        "u_vertex_morph_start", "u_vertex_normals"};
constexpr float kGrey[3] = {0.78f, 0.80f, 0.84f};  // the geometry look's front faces

}  // namespace

Renderer::~Renderer() {
  if (!program_) return;
  glDeleteProgram(program_);
  glDeleteBuffers(4, vbo_);
  glDeleteBuffers(4, wbo_);
  glDeleteBuffers(1, &ebo_);
  glDeleteBuffers(1, &face_material_buffer_);
  glDeleteBuffers(1, &material_buffer_);
  glDeleteTextures(4, vertex_textures_);
  glDeleteTextures(1, &face_material_texture_);
  glDeleteTextures(1, &material_texture_);
  if (!textures_.empty()) glDeleteTextures(GLsizei(textures_.size()), textures_.data());
  glDeleteVertexArrays(1, &vao_);
}

bool Renderer::init(std::string& error) {
  GLuint vs = compile(GL_VERTEX_SHADER, kVertexShader, error);
  if (!vs) return false;
  GLuint fs = compile(GL_FRAGMENT_SHADER, kFragmentShader, error);
  if (!fs) return false;
  program_ = glCreateProgram();
  glAttachShader(program_, vs);
  glAttachShader(program_, fs);
  glLinkProgram(program_);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program_, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[1024] = {};
    glGetProgramInfoLog(program_, sizeof log, nullptr, log);
    error = std::string("shader link failed: ") + log;
    return false;
  }
  u_view_ = glGetUniformLocation(program_, "u_view");
  u_proj_ = glGetUniformLocation(program_, "u_proj");
  u_time_ = glGetUniformLocation(program_, "u_time");
  u_morph_ = glGetUniformLocation(program_, "u_morph_seconds");
  u_smooth_ = glGetUniformLocation(program_, "u_smooth");
  u_lines_ = glGetUniformLocation(program_, "u_lines");
  u_wedges_ = glGetUniformLocation(program_, "u_wedges");
  u_decoded_normals_ = glGetUniformLocation(program_, "u_decoded_normals");
  u_attributes_ = glGetUniformLocation(program_, "u_attributes");
  u_use_colors_ = glGetUniformLocation(program_, "u_use_colors");
  u_pass_ = glGetUniformLocation(program_, "u_pass");
  u_textured_ = glGetUniformLocation(program_, "u_textured");
  u_fixed_material_ = glGetUniformLocation(program_, "u_fixed_material");
  u_material_count_ = glGetUniformLocation(program_, "u_material_count");
  u_flip_v_ = glGetUniformLocation(program_, "u_flip_v");
  glUseProgram(program_);
  glUniform1i(glGetUniformLocation(program_, "u_texture"), 0);
  for (int i = 0; i < 4; ++i)
    glUniform1i(glGetUniformLocation(program_, kVertexSamplers[i]), kVertexUnit + i);
  glUniform1i(glGetUniformLocation(program_, "u_face_materials"), kFaceMaterialUnit);
  glUniform1i(glGetUniformLocation(program_, "u_materials"), kMaterialUnit);
  glUseProgram(0);

  glGenVertexArrays(1, &vao_);
  glGenBuffers(4, vbo_);
  glGenBuffers(4, wbo_);
  glGenBuffers(1, &ebo_);
  glGenBuffers(1, &face_material_buffer_);
  glGenBuffers(1, &material_buffer_);
  glGenTextures(4, vertex_textures_);
  glGenTextures(1, &face_material_texture_);
  glGenTextures(1, &material_texture_);
  configure_vertex_layout(false, false);
  return true;
}

void Renderer::configure_vertex_layout(bool wedges, bool decoded_normals) {
  wedges_ = wedges;
  decoded_normals_ = decoded_normals;
  glBindVertexArray(vao_);
  for (GLuint i = 0; i < 7; ++i) glDisableVertexAttribArray(i);
  auto floats = [](GLuint location, GLuint buffer, int components) {
    glBindBuffer(GL_ARRAY_BUFFER, buffer);
    glEnableVertexAttribArray(location);
    glVertexAttribPointer(location, components, GL_FLOAT, GL_FALSE, 0, nullptr);
  };
  if (!wedges) {
    for (GLuint i = 0; i < 4; ++i) floats(i, vbo_[i], kComponents[i]);
  } else {
    glBindBuffer(GL_ARRAY_BUFFER, wbo_[0]);
    glEnableVertexAttribArray(4);
    glVertexAttribIPointer(4, 1, GL_UNSIGNED_INT, 0, nullptr);
    if (texcoords_) floats(5, wbo_[1], 2);
    if (colors_) floats(6, wbo_[2], 4);
    if (decoded_normals) floats(3, wbo_[3], 3);
  }
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo_);
  glBindVertexArray(0);
}

void Renderer::set_materials(const std::vector<ViewMaterial>& materials,
                             const std::vector<Image>& images, bool texcoord_origin_top) {
  if (!textures_.empty()) glDeleteTextures(GLsizei(textures_.size()), textures_.data());
  textures_.clear();
  materials_ = materials;
  material_textures_.assign(materials.size(), 0);
  texcoord_origin_top_ = texcoord_origin_top;
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  for (size_t m = 0; m < materials.size() && m < images.size(); ++m) {
    const Image& image = images[m];
    if (image.empty() || image.width > max_size || image.height > max_size) continue;
    GLuint texture = 0;
    glGenTextures(1, &texture);
    glBindTexture(GL_TEXTURE_2D, texture);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    // Rows top first, as stb_image returns them: t = 0 is the image's top row.
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, image.width, image.height, 0, GL_RGBA,
                 GL_UNSIGNED_BYTE, image.rgba.data());
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
    textures_.push_back(texture);
    material_textures_[m] = texture;
  }
  glBindTexture(GL_TEXTURE_2D, 0);
  materials_dirty_ = true;
}

void Renderer::upload_range(GLenum target, GLuint buffer, size_t element_size, const void* base,
                            uint32_t begin, uint32_t end) {
  if (begin >= end) return;
  glBindBuffer(target, buffer);
  size_t bytes = element_size * (end - begin);
  glBufferSubData(target, GLintptr(element_size * begin), GLsizeiptr(bytes),
                  static_cast<const char*>(base) + element_size * begin);
  bytes_uploaded += bytes;
}

void Renderer::upload_runs(GLenum target, GLuint buffer, size_t element_size, const void* base) {
  if (runs_.empty()) return;
  // Each call costs about as much as copying a few kB; past that one span is cheaper.
  constexpr size_t kCallCost = 4096;
  size_t run_cost = 0;
  for (const Run& r : runs_) run_cost += element_size * (r.end - r.begin) + kCallCost;
  if (run_cost > element_size * (runs_.back().end - runs_.front().begin)) {
    upload_range(target, buffer, element_size, base, runs_.front().begin, runs_.back().end);
    return;
  }
  for (const Run& r : runs_) upload_range(target, buffer, element_size, base, r.begin, r.end);
}

void Renderer::upload(MeshMirror& mesh) {
  const uint32_t nv = mesh.vertex_count, nf = mesh.face_count, nw = mesh.wedge_count;
  const void* vertex_arrays[4] = {mesh.positions.data(), mesh.morph_from.data(),
                                  mesh.morph_start.data(), mesh.normals.data()};
  const void* wedge_arrays[4] = {mesh.wedge_vertices.data(), mesh.texcoords.data(),
                                 mesh.colors.data(), mesh.wedge_normals.data()};
  const bool wedge_array_present[4] = {true, mesh.has_texcoords, mesh.has_colors, mesh.has_normals};
  if (mesh.dirty_all) {
    // Which attributes the stream has is fixed by its first full sync.
    texcoords_ = mesh.has_texcoords;
    colors_ = mesh.has_colors;
    face_materials_ = mesh.has_face_materials;
    configure_vertex_layout(mesh.has_wedges, mesh.has_normals);
    materials_dirty_ = true;
    wedge_capacity_ = 0;  // the set of wedge arrays may differ: allocate them anew
  }
  glBindVertexArray(vao_);  // the element buffer binding belongs to the VAO
  bool all_vertices = mesh.dirty_all, all_faces = mesh.dirty_all, all_wedges = mesh.dirty_all;
  // Grow geometrically so a stream of small refinements reallocates O(log n) times.
  if (nv > vertex_capacity_) {
    vertex_capacity_ = std::max({nv, vertex_capacity_ * 2, 1024u});
    for (int i = 0; i < 4; ++i) {
      glBindBuffer(GL_ARRAY_BUFFER, vbo_[i]);
      glBufferData(GL_ARRAY_BUFFER,
                   GLsizeiptr(sizeof(float) * kComponents[i] * size_t(vertex_capacity_)), nullptr,
                   GL_DYNAMIC_DRAW);
      // Wedge mode reads these by vertex id; re-attach after the store was re-specified.
      glBindTexture(GL_TEXTURE_BUFFER, vertex_textures_[i]);
      glTexBuffer(GL_TEXTURE_BUFFER, GL_R32F, vbo_[i]);
    }
    all_vertices = true;
  }
  if (wedges_ && nw > wedge_capacity_) {
    wedge_capacity_ = std::max({nw, wedge_capacity_ * 2, 1024u});
    for (int i = 0; i < 4; ++i) {
      if (!wedge_array_present[i]) continue;
      glBindBuffer(GL_ARRAY_BUFFER, wbo_[i]);
      glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(kWedgeBytes[i] * size_t(wedge_capacity_)), nullptr,
                   GL_DYNAMIC_DRAW);
    }
    all_wedges = true;
  }
  if (nf > face_capacity_) {
    face_capacity_ = std::max({nf, face_capacity_ * 2, 1024u});
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(sizeof(uint32_t) * 3 * size_t(face_capacity_)),
                 nullptr, GL_DYNAMIC_DRAW);
    glBindBuffer(GL_TEXTURE_BUFFER, face_material_buffer_);
    glBufferData(GL_TEXTURE_BUFFER, GLsizeiptr(sizeof(uint32_t) * size_t(face_capacity_)), nullptr,
                 GL_DYNAMIC_DRAW);
    glBindTexture(GL_TEXTURE_BUFFER, face_material_texture_);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_R32UI, face_material_buffer_);
    all_faces = true;
  }

  uint32_t vertex_begin = all_vertices ? 0 : std::min(mesh.dirty_vertex_begin, nv);
  for (int i = 0; i < 4; ++i)
    upload_range(GL_ARRAY_BUFFER, vbo_[i], sizeof(float) * kComponents[i], vertex_arrays[i],
                 vertex_begin, nv);
  if (!all_vertices) {
    // Normals also change on old vertices next to a split.
    mesh.dirty_normals.take_runs(vertex_begin, 16, runs_);
    upload_runs(GL_ARRAY_BUFFER, vbo_[3], sizeof(float) * 3, vertex_arrays[3]);
  }
  if (wedges_) {
    uint32_t wedge_begin = all_wedges ? 0 : std::min(mesh.dirty_wedge_begin, nw);
    for (int i = 0; i < 4; ++i)
      if (wedge_array_present[i])
        upload_range(GL_ARRAY_BUFFER, wbo_[i], kWedgeBytes[i], wedge_arrays[i], wedge_begin, nw);
  }
  // Faces: wedge indices in wedge mode, with each face's material beside them.
  const uint32_t* face_indices = wedges_ ? mesh.wedge_indices.data() : mesh.indices.data();
  if (all_faces) {
    upload_range(GL_ELEMENT_ARRAY_BUFFER, ebo_, sizeof(uint32_t) * 3, face_indices, 0, nf);
    if (face_materials_)
      upload_range(GL_TEXTURE_BUFFER, face_material_buffer_, sizeof(uint32_t),
                   mesh.face_materials.data(), 0, nf);
  } else {
    mesh.dirty_faces.take_runs(nf, 16, runs_);
    upload_runs(GL_ELEMENT_ARRAY_BUFFER, ebo_, sizeof(uint32_t) * 3, face_indices);
    if (face_materials_)
      upload_runs(GL_TEXTURE_BUFFER, face_material_buffer_, sizeof(uint32_t),
                  mesh.face_materials.data());
  }
  glBindVertexArray(0);

  if (materials_dirty_) {
    // Per material: base colour and its pass (0: untextured, k: the k-th textured material);
    // last, the default for faces without a (valid) material.
    std::vector<float> table;
    int pass = 0;
    for (size_t m = 0; m < materials_.size(); ++m) {
      const bool textured = texcoords_ && material_textures_[m] != 0;
      table.insert(table.end(), materials_[m].base_color, materials_[m].base_color + 3);
      table.push_back(textured ? float(++pass) : 0.0f);
    }
    for (int i = 0; i < 3; ++i) table.push_back(colors_ ? 1.0f : kGrey[i]);
    table.push_back(0);
    glBindBuffer(GL_TEXTURE_BUFFER, material_buffer_);
    glBufferData(GL_TEXTURE_BUFFER, GLsizeiptr(sizeof(float) * table.size()), table.data(),
                 GL_STATIC_DRAW);
    glBindTexture(GL_TEXTURE_BUFFER, material_texture_);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, material_buffer_);
    materials_dirty_ = false;
  }
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
  glBindTexture(GL_TEXTURE_BUFFER, 0);
  face_count_ = nf;
  mesh.clear_dirty();
}

void Renderer::draw_passes(GLsizei count, const RenderOptions& options) {
  const bool attributes = wedges_ && options.attributes;
  glUniform1i(u_attributes_, attributes ? 1 : 0);
  glUniform1i(u_decoded_normals_, attributes && decoded_normals_ ? 1 : 0);
  glUniform1i(u_use_colors_, colors_ ? 1 : 0);
  glUniform1i(u_material_count_, GLint(materials_.size()));
  // Without per-face ids every face has the first material (or the default, which is entry 0
  // of an empty table).
  glUniform1i(u_fixed_material_, face_materials_ ? -1 : 0);
  glUniform1i(u_flip_v_, texcoord_origin_top_ ? 0 : 1);
  glUniform1i(u_textured_, 0);
  glUniform1i(u_pass_, -1);
  if (!attributes || !texcoords_ || textures_.empty()) {
    glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, nullptr);
    return;
  }
  // One pass for the untextured materials, then one per textured material; each fragment
  // is kept by exactly one pass (its face's material's).
  glActiveTexture(GL_TEXTURE0);
  for (size_t pass = 0; pass <= textures_.size(); ++pass) {
    glUniform1i(u_pass_, GLint(pass));
    glUniform1i(u_textured_, pass > 0 ? 1 : 0);
    glBindTexture(GL_TEXTURE_2D, pass > 0 ? textures_[pass - 1] : 0);
    glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, nullptr);
  }
  glBindTexture(GL_TEXTURE_2D, 0);
}

void Renderer::draw(const Camera& camera, int width, int height, const RenderOptions& options) {
  glViewport(0, 0, width, height);
  glClearColor(kBackground[0], kBackground[1], kBackground[2], 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  if (face_count_ == 0 || width <= 0 || height <= 0) return;
  glEnable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glUseProgram(program_);
  Mat4 view = camera.view(), proj = camera.projection(float(width) / float(height));
  glUniformMatrix4fv(u_view_, 1, GL_FALSE, view.data());
  glUniformMatrix4fv(u_proj_, 1, GL_FALSE, proj.data());
  glUniform1f(u_time_, options.now);
  glUniform1f(u_morph_, options.morph_seconds);
  glUniform1i(u_smooth_, options.smooth ? 1 : 0);
  glUniform1i(u_lines_, 0);
  glUniform1i(u_wedges_, wedges_ ? 1 : 0);
  for (int i = 0; i < 4; ++i) {
    glActiveTexture(GLenum(GL_TEXTURE0 + kVertexUnit + i));
    glBindTexture(GL_TEXTURE_BUFFER, vertex_textures_[i]);
  }
  glActiveTexture(GL_TEXTURE0 + kFaceMaterialUnit);
  glBindTexture(GL_TEXTURE_BUFFER, face_material_texture_);
  glActiveTexture(GL_TEXTURE0 + kMaterialUnit);
  glBindTexture(GL_TEXTURE_BUFFER, material_texture_);
  glActiveTexture(GL_TEXTURE0);
  glBindVertexArray(vao_);
  GLsizei count = GLsizei(3 * size_t(face_count_));
  if (options.wireframe) {
    // Push the fill back so the lines drawn on top of it win the depth test.
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1, 1);
  }
  draw_passes(count, options);
  if (options.wireframe) {
    glDisable(GL_POLYGON_OFFSET_FILL);
    glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    glUniform1i(u_lines_, 1);
    glUniform1i(u_pass_, -1);
    glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, nullptr);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  }
  glBindVertexArray(0);
  glUseProgram(0);
}

bool Renderer::capture(const Camera& camera, int width, int height, const RenderOptions& options,
                       std::vector<uint8_t>& rgb, std::string& error) {
  GLint max_samples = 0, max_size = 0;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
  if (width > max_size || height > max_size) {
    error = "screenshot size exceeds the GL limit of " + std::to_string(max_size);
    return false;
  }
  GLsizei samples = std::min(max_samples, 4);
  GLuint fbo[2], color[2], depth;
  glGenFramebuffers(2, fbo);
  glGenRenderbuffers(2, color);
  glGenRenderbuffers(1, &depth);
  // fbo[0]: multisampled color + depth; fbo[1]: single-sampled color to resolve into.
  glBindRenderbuffer(GL_RENDERBUFFER, color[0]);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, width, height);
  glBindRenderbuffer(GL_RENDERBUFFER, depth);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, width, height);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo[0]);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color[0]);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
  bool ok = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  glBindRenderbuffer(GL_RENDERBUFFER, color[1]);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo[1]);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color[1]);
  ok = ok && glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  if (ok) {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo[0]);
    draw(camera, width, height, options);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo[0]);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, fbo[1]);
    glBlitFramebuffer(0, 0, width, height, 0, 0, width, height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo[1]);
    rgb.resize(size_t(width) * height * 3);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
    // GL rows run bottom-up; images top-down.
    size_t stride = size_t(width) * 3;
    std::vector<uint8_t> row(stride);
    for (int y = 0; y < height / 2; ++y) {
      uint8_t* a = &rgb[stride * y];
      uint8_t* b = &rgb[stride * (height - 1 - y)];
      std::memcpy(row.data(), a, stride);
      std::memcpy(a, b, stride);
      std::memcpy(b, row.data(), stride);
    }
    ok = glGetError() == GL_NO_ERROR;
    if (!ok) error = "reading the frame back failed";
  } else {
    error = "cannot create an offscreen framebuffer";
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDeleteFramebuffers(2, fbo);
  glDeleteRenderbuffers(2, color);
  glDeleteRenderbuffers(1, &depth);
  return ok;
}

}  // namespace pmzview
