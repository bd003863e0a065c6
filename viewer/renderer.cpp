#include "renderer.hpp"

#include <algorithm>
#include <cstring>

namespace pmzview {
namespace {

const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_morph_from;
layout(location = 2) in float a_morph_start;
layout(location = 3) in vec3 a_normal;
uniform mat4 u_view;
uniform mat4 u_proj;
uniform float u_time;
uniform float u_morph_seconds;
out vec3 v_view_position;
out vec3 v_view_normal;
void main() {
  float t = u_morph_seconds > 0.0 ? clamp((u_time - a_morph_start) / u_morph_seconds, 0.0, 1.0) : 1.0;
  t = t * t * (3.0 - 2.0 * t);
  vec4 p = u_view * vec4(mix(a_morph_from, a_position, t), 1.0);
  v_view_position = p.xyz;
  v_view_normal = mat3(u_view) * a_normal;
  gl_Position = u_proj * p;
}
)";

const char* kFragmentShader = R"(#version 330 core
in vec3 v_view_position;
in vec3 v_view_normal;
uniform int u_smooth;
uniform int u_lines;
out vec4 color;
void main() {
  if (u_lines == 1) {
    color = vec4(0.07, 0.08, 0.10, 1.0);
    return;
  }
  vec3 flat_normal = cross(dFdx(v_view_position), dFdy(v_view_position));
  vec3 n = (u_smooth == 1 && dot(v_view_normal, v_view_normal) > 1e-30) ? v_view_normal : flat_normal;
  n = normalize(n);
  vec3 to_eye = normalize(-v_view_position);
  if (dot(n, to_eye) < 0.0) n = -n;  // two-sided lighting
  vec3 to_light = normalize(to_eye + vec3(0.35, 0.45, 0.0));
  float diffuse = max(dot(n, to_light), 0.0);
  float specular = pow(max(dot(n, normalize(to_light + to_eye)), 0.0), 40.0) * 0.22;
  vec3 base = gl_FrontFacing ? vec3(0.78, 0.80, 0.84) : vec3(0.70, 0.42, 0.34);
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

}  // namespace

Renderer::~Renderer() {
  if (!program_) return;
  glDeleteProgram(program_);
  glDeleteBuffers(4, vbo_);
  glDeleteBuffers(1, &ebo_);
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

  glGenVertexArrays(1, &vao_);
  glGenBuffers(4, vbo_);
  glGenBuffers(1, &ebo_);
  glBindVertexArray(vao_);
  for (GLuint i = 0; i < 4; ++i) {
    glBindBuffer(GL_ARRAY_BUFFER, vbo_[i]);
    glEnableVertexAttribArray(i);
    glVertexAttribPointer(i, kComponents[i], GL_FLOAT, GL_FALSE, 0, nullptr);
  }
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo_);
  glBindVertexArray(0);
  return true;
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
  const uint32_t nv = mesh.vertex_count, nf = mesh.face_count;
  const void* vertex_arrays[4] = {mesh.positions.data(), mesh.morph_from.data(),
                                  mesh.morph_start.data(), mesh.normals.data()};
  glBindVertexArray(vao_);  // the element buffer binding belongs to the VAO
  bool all_vertices = mesh.dirty_all, all_faces = mesh.dirty_all;
  // Grow geometrically so a stream of small refinements reallocates O(log n) times.
  if (nv > vertex_capacity_) {
    vertex_capacity_ = std::max({nv, vertex_capacity_ * 2, 1024u});
    for (int i = 0; i < 4; ++i) {
      glBindBuffer(GL_ARRAY_BUFFER, vbo_[i]);
      glBufferData(GL_ARRAY_BUFFER,
                   GLsizeiptr(sizeof(float) * kComponents[i] * size_t(vertex_capacity_)), nullptr,
                   GL_DYNAMIC_DRAW);
    }
    all_vertices = true;
  }
  if (nf > face_capacity_) {
    face_capacity_ = std::max({nf, face_capacity_ * 2, 1024u});
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(sizeof(uint32_t) * 3 * size_t(face_capacity_)),
                 nullptr, GL_DYNAMIC_DRAW);
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
  if (all_faces) {
    upload_range(GL_ELEMENT_ARRAY_BUFFER, ebo_, sizeof(uint32_t) * 3, mesh.indices.data(), 0, nf);
  } else {
    mesh.dirty_faces.take_runs(nf, 16, runs_);
    upload_runs(GL_ELEMENT_ARRAY_BUFFER, ebo_, sizeof(uint32_t) * 3, mesh.indices.data());
  }
  glBindVertexArray(0);
  face_count_ = nf;
  mesh.clear_dirty();
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
  glBindVertexArray(vao_);
  GLsizei count = GLsizei(3 * size_t(face_count_));
  if (options.wireframe) {
    // Push the fill back so the lines drawn on top of it win the depth test.
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1, 1);
  }
  glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, nullptr);
  if (options.wireframe) {
    glDisable(GL_POLYGON_OFFSET_FILL);
    glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    glUniform1i(u_lines_, 1);
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
