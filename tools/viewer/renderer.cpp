#include "tools/viewer/renderer.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "tools/viewer/meshes.hpp"

namespace limber::viewer {
namespace {

using Eigen::Matrix4f;
using Eigen::Vector3f;

constexpr int kWantedSamples = 4;        // multisampling, where offered
constexpr float kShadowStrength = 0.5f;  // how much a shadow darkens the floor

// Shaders. Colours arrive as linear RGB and are lit in linear space; every fragment shader
// encodes its result to sRGB since the 8-bit framebuffer is shown as is.

constexpr const char* kVertexHeader = "#version 330 core\n";

constexpr const char* kFragmentHeader = R"(#version 330 core
vec3 encode(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}
uniform vec2 floor_centre;
uniform float floor_extent;
// 0 on the floor, 1 at its rim: it fades into the background, so the floor has no hard horizon.
float floor_fade(vec2 xy) { return smoothstep(0.55 * floor_extent, floor_extent, length(xy - floor_centre)); }
)";

// Solids are drawn instanced, one batch per unit shape and level (meshes.hpp): each instance
// brings its placement (scale included), normal matrix and colour. Triangle soups use the same shader with these
// attributes held constant (identity, their colour).
constexpr const char* kSolidVertex = R"(
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in mat4 model;          // locations 2–5
layout(location = 6) in mat3 normal_matrix;  // locations 6–8
layout(location = 9) in vec3 colour;
uniform mat4 view_projection;
out vec3 world_position;
out vec3 world_normal;
flat out vec3 surface_colour;
void main() {
  vec4 world = model * vec4(position, 1.0);
  world_position = world.xyz;
  world_normal = normal_matrix * normal;
  surface_colour = colour;
  gl_Position = view_projection * world;
}
)";

constexpr const char* kSolidFragment = R"(
in vec3 world_position;
in vec3 world_normal;
flat in vec3 surface_colour;
uniform vec3 eye;
uniform vec3 key_direction;  // towards the key light, unit
out vec4 fragment;
void main() {
  vec3 n = normalize(world_normal);
  if (!gl_FrontFacing) n = -n;  // triangle soups are lit on both sides
  vec3 v = normalize(eye - world_position);
  float key = max(dot(n, key_direction), 0.0);
  float head = max(dot(n, v), 0.0);
  // A bright sky and a dark ground as ambient: unlit sides still show which way they face.
  vec3 ambient = mix(vec3(0.03, 0.03, 0.035), vec3(0.15, 0.16, 0.19), 0.5 + 0.5 * n.z);
  float specular = key > 0.0 ? pow(max(dot(n, normalize(key_direction + v)), 0.0), 48.0) : 0.0;
  vec3 lit = surface_colour * (ambient + 0.78 * key + 0.26 * head) + 0.2 * specular;
  fragment = vec4(encode(lit), 1.0);
}
)";

// The floor is one quad of 4 vertices made from gl_VertexID (a triangle strip, no buffer).
constexpr const char* kFloorVertex = R"(
uniform mat4 view_projection;
uniform vec2 floor_centre;
uniform float floor_extent;
uniform float floor_height;
out vec2 world_xy;
void main() {
  vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1)) * 2.0 - 1.0;
  world_xy = floor_centre + floor_extent * corner;
  gl_Position = view_projection * vec4(world_xy, floor_height, 1.0);
}
)";

constexpr const char* kFloorFragment = R"(
in vec2 world_xy;
uniform float spacing;
uniform vec3 background;
out vec4 fragment;
void main() {
  vec2 u = world_xy / spacing;
  vec2 w = fwidth(u);
  // Tiles only a few pixels wide fade to their mean, so the far floor does not shimmer.
  float detail = 1.0 - smoothstep(0.15, 0.5, max(w.x, w.y));
  float checker = mod(floor(u.x) + floor(u.y), 2.0);
  vec2 pixels_to_line = abs(fract(u - 0.5) - 0.5) / max(w, vec2(1e-6));
  float line = (1.0 - clamp(min(pixels_to_line.x, pixels_to_line.y), 0.0, 1.0)) * detail;
  vec3 tile = mix(vec3(0.40, 0.41, 0.42), vec3(0.34, 0.35, 0.36), 0.5 + (checker - 0.5) * detail);
  vec3 c = mix(tile, vec3(0.22, 0.23, 0.24), 0.75 * line);
  fragment = vec4(encode(mix(c, background, floor_fade(world_xy))), 1.0);
}
)";

// A solid squashed straight down onto the floor, instanced as the solids are.
constexpr const char* kShadowVertex = R"(
layout(location = 0) in vec3 position;
layout(location = 2) in mat4 model;
uniform mat4 view_projection;
uniform float floor_height;
out vec2 world_xy;
void main() {
  vec4 world = model * vec4(position, 1.0);
  world.z = floor_height;
  world_xy = world.xy;
  gl_Position = view_projection * world;
}
)";

constexpr const char* kShadowFragment = R"(
in vec2 world_xy;
uniform float strength;
out vec4 fragment;
void main() { fragment = vec4(0.0, 0.0, 0.0, strength * (1.0 - floor_fade(world_xy))); }
)";

constexpr const char* kLineVertex = R"(
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 colour;
uniform mat4 view_projection;
out vec3 line_colour;
void main() {
  line_colour = colour;
  gl_Position = view_projection * vec4(position, 1.0);
}
)";

constexpr const char* kLineFragment = R"(
in vec3 line_colour;
out vec4 fragment;
void main() { fragment = vec4(encode(line_colour), 1.0); }
)";

std::string first_line(const std::string& text) {
  const std::size_t end = text.find('\n');
  return end == std::string::npos ? text : text.substr(0, end);
}

std::string hex(unsigned value) {
  std::array<char, 16> text{};
  std::snprintf(text.data(), text.size(), "0x%04X", value);
  return text.data();
}

GLuint compile_shader(GLenum stage, const char* header, const char* body, const char* name) {
  const GLuint shader = glCreateShader(stage);
  const std::array<const char*, 2> sources{header, body};
  glShaderSource(shader, 2, sources.data(), nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok) return shader;
  std::array<char, 1024> log{};
  glGetShaderInfoLog(shader, static_cast<GLsizei>(log.size()), nullptr, log.data());
  glDeleteShader(shader);
  throw RenderError(std::string(name) + (stage == GL_VERTEX_SHADER ? " vertex" : " fragment") +
                    " shader does not compile: " + first_line(log.data()));
}

GLuint link_program(const char* name, const char* vertex_body, const char* fragment_body) {
  const GLuint vertex = compile_shader(GL_VERTEX_SHADER, kVertexHeader, vertex_body, name);
  GLuint fragment = 0;
  try {
    fragment = compile_shader(GL_FRAGMENT_SHADER, kFragmentHeader, fragment_body, name);
  } catch (...) {
    glDeleteShader(vertex);
    throw;
  }
  const GLuint program = glCreateProgram();
  glAttachShader(program, vertex);
  glAttachShader(program, fragment);
  glLinkProgram(program);
  glDeleteShader(vertex);  // flagged; freed with the program
  glDeleteShader(fragment);
  GLint ok = GL_FALSE;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (ok) return program;
  std::array<char, 1024> log{};
  glGetProgramInfoLog(program, static_cast<GLsizei>(log.size()), nullptr, log.data());
  glDeleteProgram(program);
  throw RenderError(std::string(name) + " shader program does not link: " + first_line(log.data()));
}

// Uniforms are looked up by name when set: a score of lookups a frame, simpler than keeping locations.
void uniform(GLuint program, const char* name, const Matrix4f& value) {
  glUniformMatrix4fv(glGetUniformLocation(program, name), 1, GL_FALSE, value.data());
}
void uniform(GLuint program, const char* name, const Vector3f& value) {
  glUniform3f(glGetUniformLocation(program, name), value.x(), value.y(), value.z());
}
void uniform(GLuint program, const char* name, const Eigen::Vector2f& value) {
  glUniform2f(glGetUniformLocation(program, name), value.x(), value.y());
}
void uniform(GLuint program, const char* name, float value) { glUniform1f(glGetUniformLocation(program, name), value); }

// The floor's place, for the programs that draw on it.
void floor_uniforms(GLuint program, const Floor& floor) {
  uniform(program, "floor_centre", floor.centre);
  uniform(program, "floor_extent", floor.extent);
  uniform(program, "floor_height", floor.height);
}

float encode_srgb(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

const void* byte_offset(std::size_t bytes) { return reinterpret_cast<const void*>(bytes); }

// An attribute layout of 6 floats a vertex: position at 0, normal (or colour) at 1.
void describe_vertices() {
  constexpr GLsizei stride = 6 * sizeof(float);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, nullptr);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride, byte_offset(3 * sizeof(float)));
  glEnableVertexAttribArray(0);
  glEnableVertexAttribArray(1);
}

}  // namespace

// Outside the anonymous namespace: Renderer::Gl holds two (g++ warns of a member of an
// anonymous-namespace type once the file shares a unity batch).
struct Framebuffer {
  GLuint id = 0, colour = 0, depth_stencil = 0;
};

namespace {

void destroy(Framebuffer& framebuffer) {
  glDeleteFramebuffers(1, &framebuffer.id);
  glDeleteRenderbuffers(1, &framebuffer.colour);
  glDeleteRenderbuffers(1, &framebuffer.depth_stencil);
  framebuffer = {};
}

void storage(GLuint renderbuffer, int samples, GLenum format, int width, int height) {
  glBindRenderbuffer(GL_RENDERBUFFER, renderbuffer);
  if (samples > 0) {
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, format, width, height);
  } else {
    glRenderbufferStorage(GL_RENDERBUFFER, format, width, height);
  }
}

// Colour RGBA8 and, if asked, depth 24 + stencil 8; `samples` 0 for single-sampled. Returns the
// framebuffer status; on anything but complete, `framebuffer` is destroyed again.
GLenum create(Framebuffer& framebuffer, int width, int height, int samples, bool with_depth) {
  glGenFramebuffers(1, &framebuffer.id);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer.id);
  glGenRenderbuffers(1, &framebuffer.colour);
  storage(framebuffer.colour, samples, GL_RGBA8, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, framebuffer.colour);
  if (with_depth) {
    glGenRenderbuffers(1, &framebuffer.depth_stencil);
    storage(framebuffer.depth_stencil, samples, GL_DEPTH24_STENCIL8, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER, framebuffer.depth_stencil);
  }
  glBindRenderbuffer(GL_RENDERBUFFER, 0);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) destroy(framebuffer);
  return status;
}

// Towards the key light: mostly overhead, leaning towards the camera and a little to its left,
// so the sides the camera sees are lit and the terminator runs across the bodies.
Vector3f key_direction(const Matrix4f& view) {
  const auto horizontal = [](Vector3f v) {
    v.z() = 0;
    return v.squaredNorm() > 1e-12f ? Vector3f(v.normalized()) : Vector3f::Zero();
  };
  const Vector3f right = view.block<1, 3>(0, 0).transpose(), back = view.block<1, 3>(2, 0).transpose();
  return (Vector3f::UnitZ() + 0.45f * horizontal(back) - 0.35f * horizontal(right)).normalized();
}

}  // namespace

struct Renderer::Gl {
  GLuint solid_program = 0, floor_program = 0, shadow_program = 0, line_program = 0;
  GLuint mesh_array = 0, mesh_vertices = 0, mesh_indices = 0, instance_buffer = 0;
  GLuint stream_array = 0, stream_vertices = 0;  // triangle soups and lines, refilled per draw
  GLuint empty_array = 0;                        // the floor's (core profile needs one bound)
  std::array<IndexRange, kGroupCount> ranges{};
  SolidInstances instances;    // this frame's, kept only to reuse memory
  std::vector<float> staging;  // likewise

  int max_samples = 0;
  Framebuffer multisampled;  // drawn into when multisampling is on
  Framebuffer resolved;      // what ImGui draws over, present() shows and read_pixels() reads

  Gl();
  ~Gl() { release(); }
  Gl(const Gl&) = delete;
  Gl& operator=(const Gl&) = delete;
  void release();
  void create_programs();
  void create_buffers();
  void create_targets(int width, int height);
  GLuint scene_target() const { return multisampled.id != 0 ? multisampled.id : resolved.id; }

  void begin_frame(const Colour& background, int width, int height) const;
  void upload_instances(const std::vector<Solid>& solids, const CameraMatrices& camera, int height);
  void draw_instances(bool casters_only) const;
  void draw_floor(const Floor& floor, const Colour& background, const Matrix4f& view_projection) const;
  void draw_shadows(const Floor& floor, const Matrix4f& view_projection) const;
  void draw_solids(const Matrix4f& view_projection, const Vector3f& eye, const Vector3f& key_direction) const;
  void draw_meshes(const std::vector<TriangleSoup>& meshes);
  void draw_lines(const std::vector<Line>& lines, const Matrix4f& view_projection, bool depth_tested);
  void stream(const std::vector<float>& vertices) const;
};

Renderer::Gl::Gl() {
  try {
    create_programs();
  } catch (...) {
    release();  // a throwing constructor skips the destructor
    throw;
  }
  create_buffers();
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
}

void Renderer::Gl::create_programs() {
  solid_program = link_program("solid", kSolidVertex, kSolidFragment);
  floor_program = link_program("floor", kFloorVertex, kFloorFragment);
  shadow_program = link_program("shadow", kShadowVertex, kShadowFragment);
  line_program = link_program("line", kLineVertex, kLineFragment);
}

void Renderer::Gl::create_buffers() {
  const UnitMeshes meshes = build_unit_meshes();
  ranges = meshes.ranges;
  glGenVertexArrays(1, &mesh_array);
  glBindVertexArray(mesh_array);
  glGenBuffers(1, &mesh_vertices);
  glBindBuffer(GL_ARRAY_BUFFER, mesh_vertices);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(meshes.vertices.size() * sizeof(float)), meshes.vertices.data(),
               GL_STATIC_DRAW);
  glGenBuffers(1, &mesh_indices);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, mesh_indices);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(meshes.indices.size() * sizeof(std::uint32_t)),
               meshes.indices.data(), GL_STATIC_DRAW);
  describe_vertices();
  glGenBuffers(1, &instance_buffer);
  for (GLuint attribute = 2; attribute <= 9; ++attribute) {  // pointed per batch (draw_instances)
    glEnableVertexAttribArray(attribute);
    glVertexAttribDivisor(attribute, 1);
  }

  glGenVertexArrays(1, &stream_array);
  glBindVertexArray(stream_array);
  glGenBuffers(1, &stream_vertices);
  glBindBuffer(GL_ARRAY_BUFFER, stream_vertices);
  describe_vertices();

  glGenVertexArrays(1, &empty_array);
  glBindVertexArray(0);
}

void Renderer::Gl::release() {
  destroy(multisampled);
  destroy(resolved);
  for (const GLuint program : {solid_program, floor_program, shadow_program, line_program}) {
    glDeleteProgram(program);
  }
  for (const GLuint array : {mesh_array, stream_array, empty_array}) glDeleteVertexArrays(1, &array);
  for (const GLuint buffer : {mesh_vertices, mesh_indices, instance_buffer, stream_vertices}) glDeleteBuffers(1, &buffer);
}

// Multisampled where offered and complete, else the scene is drawn straight into `resolved`.
void Renderer::Gl::create_targets(int width, int height) {
  if (width < 1 || height < 1) {
    throw RenderError("framebuffer size " + std::to_string(width) + " x " + std::to_string(height) + " is empty");
  }
  destroy(multisampled);
  destroy(resolved);
  if (max_samples >= kWantedSamples) create(multisampled, width, height, kWantedSamples, true);
  const GLenum status = create(resolved, width, height, 0, multisampled.id == 0);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    destroy(multisampled);
    throw RenderError("framebuffer incomplete (status " + hex(status) + ")");
  }
}

void Renderer::Gl::begin_frame(const Colour& background, int width, int height) const {
  // ImGui and others change state between frames, so everything this draw relies on is set here.
  glBindFramebuffer(GL_FRAMEBUFFER, scene_target());
  glViewport(0, 0, width, height);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_BLEND);
  glBlendEquation(GL_FUNC_ADD);
  glDisable(GL_STENCIL_TEST);
  glDisable(GL_POLYGON_OFFSET_FILL);
  glDisable(GL_SAMPLE_ALPHA_TO_COVERAGE);
  glEnable(GL_MULTISAMPLE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glFrontFace(GL_CCW);
  glCullFace(GL_BACK);
  glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  glLineWidth(1);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDepthMask(GL_TRUE);
  glStencilMask(0xFF);
  glClearColor(encode_srgb(background.r), encode_srgb(background.g), encode_srgb(background.b), 1);
  glClearDepth(1);
  glClearStencil(0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
}

// Instanced drawing: a few draws per frame rather than one per part, which llvmpipe pays for.
void Renderer::Gl::upload_instances(const std::vector<Solid>& solids, const CameraMatrices& camera, int height) {
  gather_instances(solids, camera, height, instances);
  glBindBuffer(GL_ARRAY_BUFFER, instance_buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(instances.data.size() * sizeof(float)), instances.data.data(),
               GL_STREAM_DRAW);
}

// OpenGL 3.3 has no base instance, so each batch re-points the instance attributes at its start.
void Renderer::Gl::draw_instances(bool casters_only) const {
  glBindVertexArray(mesh_array);
  glBindBuffer(GL_ARRAY_BUFFER, instance_buffer);
  constexpr GLsizei stride = SolidInstances::kFloats * sizeof(float);
  for (std::size_t group = 0; group < kGroupCount; ++group) {
    const SolidInstances::Group& instanced = instances.groups[group];
    const std::size_t count = casters_only ? instanced.casters : instanced.count;
    if (count == 0) continue;
    const std::size_t start = instanced.first * stride;
    for (GLuint column = 0; column < 4; ++column) {
      glVertexAttribPointer(2 + column, 4, GL_FLOAT, GL_FALSE, stride, byte_offset(start + 4 * column * sizeof(float)));
    }
    for (GLuint column = 0; column < 3; ++column) {
      glVertexAttribPointer(6 + column, 3, GL_FLOAT, GL_FALSE, stride, byte_offset(start + (16 + 3 * column) * sizeof(float)));
    }
    glVertexAttribPointer(9, 3, GL_FLOAT, GL_FALSE, stride, byte_offset(start + 25 * sizeof(float)));
    const IndexRange& range = ranges[group];
    glDrawElementsInstanced(GL_TRIANGLES, static_cast<GLsizei>(range.count), GL_UNSIGNED_INT,
                            byte_offset(range.first * sizeof(std::uint32_t)), static_cast<GLsizei>(count));
  }
}

// Marks its pixels with stencil 1, where shadows may fall. The quad is counter-clockwise seen from +z.
void Renderer::Gl::draw_floor(const Floor& floor, const Colour& background, const Matrix4f& view_projection) const {
  glUseProgram(floor_program);
  uniform(floor_program, "view_projection", view_projection);
  floor_uniforms(floor_program, floor);
  uniform(floor_program, "spacing", floor.spacing > 0 ? floor.spacing : 1.0f);
  uniform(floor_program, "background", Vector3f(background.r, background.g, background.b));
  glEnable(GL_CULL_FACE);  // one-sided: from below the floor, the solids stay in sight
  glEnable(GL_STENCIL_TEST);
  glStencilFunc(GL_ALWAYS, 1, 0xFF);
  glStencilOp(GL_KEEP, GL_KEEP, GL_REPLACE);
  glBindVertexArray(empty_array);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  glDisable(GL_STENCIL_TEST);
}

// Drawn right after the floor and before anything else, so the stencil alone decides where:
// floor pixels (1) are darkened once and then counted up (2). No depth test is needed, so
// shadows cannot z-fight with the floor.
void Renderer::Gl::draw_shadows(const Floor& floor, const Matrix4f& view_projection) const {
  glUseProgram(shadow_program);
  uniform(shadow_program, "view_projection", view_projection);
  floor_uniforms(shadow_program, floor);
  uniform(shadow_program, "strength", kShadowStrength);
  // Squashed flat, a closed solid's upward-facing triangles cover its shadow and stay
  // counter-clockwise seen from above (where the camera is); the rest fold over and are culled.
  glEnable(GL_CULL_FACE);
  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);
  glEnable(GL_STENCIL_TEST);
  glStencilFunc(GL_EQUAL, 1, 0xFF);
  glStencilOp(GL_KEEP, GL_KEEP, GL_INCR);
  glEnable(GL_BLEND);
  glBlendFunc(GL_ZERO, GL_ONE_MINUS_SRC_ALPHA);  // floor × (1 − alpha)
  draw_instances(true);
  glDisable(GL_BLEND);
  glDisable(GL_STENCIL_TEST);
  glDepthMask(GL_TRUE);
  glEnable(GL_DEPTH_TEST);
}

void Renderer::Gl::draw_solids(const Matrix4f& view_projection, const Vector3f& eye, const Vector3f& key_direction) const {
  glUseProgram(solid_program);
  uniform(solid_program, "view_projection", view_projection);
  uniform(solid_program, "eye", eye);
  uniform(solid_program, "key_direction", key_direction);
  glEnable(GL_CULL_FACE);
  draw_instances(false);
}

void Renderer::Gl::stream(const std::vector<float>& vertices) const {
  glBindVertexArray(stream_array);
  glBindBuffer(GL_ARRAY_BUFFER, stream_vertices);
  // A fresh store each time, so the driver need not wait for the previous draw's data.
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)), vertices.data(), GL_STREAM_DRAW);
}

// All soups in one buffer; lit on both sides, so no culling.
void Renderer::Gl::draw_meshes(const std::vector<TriangleSoup>& meshes) {
  soup_vertices(meshes, staging);
  if (staging.empty()) return;
  stream(staging);
  glDisable(GL_CULL_FACE);
  // The stream array leaves the instance attributes disabled, so they take these constant values.
  for (GLuint column = 0; column < 4; ++column) {
    glVertexAttrib4f(2 + column, column == 0, column == 1, column == 2, column == 3);
  }
  for (GLuint column = 0; column < 3; ++column) glVertexAttrib3f(6 + column, column == 0, column == 1, column == 2);
  GLint first = 0;
  for (const TriangleSoup& mesh : meshes) {
    const auto count = static_cast<GLsizei>(mesh.vertices.size() / 3 * 3);
    if (count == 0) continue;
    glVertexAttrib3f(9, mesh.colour.r, mesh.colour.g, mesh.colour.b);
    glDrawArrays(GL_TRIANGLES, first, count);
    first += count;
  }
}

void Renderer::Gl::draw_lines(const std::vector<Line>& lines, const Matrix4f& view_projection, bool depth_tested) {
  if (lines.empty()) return;
  staging.clear();
  staging.reserve(lines.size() * 12);
  for (const Line& l : lines) {
    const Colour& c = l.colour;
    staging.insert(staging.end(),
                   {l.from.x(), l.from.y(), l.from.z(), c.r, c.g, c.b, l.to.x(), l.to.y(), l.to.z(), c.r, c.g, c.b});
  }
  stream(staging);
  glUseProgram(line_program);
  uniform(line_program, "view_projection", view_projection);
  if (depth_tested) {
    glEnable(GL_DEPTH_TEST);
  } else {
    glDisable(GL_DEPTH_TEST);
  }
  glDrawArrays(GL_LINES, 0, static_cast<GLsizei>(2 * lines.size()));
  glEnable(GL_DEPTH_TEST);
}

Renderer::Renderer(int width, int height) {
  auto gl = std::make_unique<Gl>();
  gl->create_targets(width, height);
  gl_ = gl.release();
  width_ = width, height_ = height;
}

Renderer::~Renderer() { delete gl_; }

void Renderer::resize(int width, int height) {
  if (width == width_ && height == height_) return;
  gl_->create_targets(width, height);
  width_ = width, height_ = height;
}

void Renderer::draw(const DrawList& list, const CameraMatrices& camera) {
  Gl& gl = *gl_;
  const Matrix4f view_projection = camera.projection * camera.view;
  gl.begin_frame(list.background, width_, height_);
  gl.upload_instances(list.solids, camera, height_);
  if (list.floor) {
    gl.draw_floor(*list.floor, list.background, view_projection);
    if (camera.eye.z() > list.floor->height) gl.draw_shadows(*list.floor, view_projection);
  }
  gl.draw_solids(view_projection, camera.eye, key_direction(camera.view));
  gl.draw_meshes(list.meshes);
  gl.draw_lines(list.lines, view_projection, true);
  gl.draw_lines(list.on_top, view_projection, false);
  if (gl.multisampled.id != 0) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, gl.multisampled.id);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, gl.resolved.id);
    glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, gl.resolved.id);  // for ImGui
  glBindVertexArray(0);
  glUseProgram(0);
}

void Renderer::present(int window_width, int window_height) {
  if (window_width < 1 || window_height < 1) return;  // minimised
  glBindFramebuffer(GL_READ_FRAMEBUFFER, gl_->resolved.id);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glDisable(GL_SCISSOR_TEST);  // blits are clipped by it
  const bool same_size = window_width == width_ && window_height == height_;
  glBlitFramebuffer(0, 0, width_, height_, 0, 0, window_width, window_height, GL_COLOR_BUFFER_BIT,
                    same_size ? GL_NEAREST : GL_LINEAR);
}

std::vector<std::uint8_t> Renderer::read_pixels() {
  const auto row = static_cast<std::size_t>(width_) * 4;
  std::vector<std::uint8_t> pixels(row * static_cast<std::size_t>(height_));
  glBindFramebuffer(GL_READ_FRAMEBUFFER, gl_->resolved.id);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glPixelStorei(GL_PACK_ROW_LENGTH, 0);
  glPixelStorei(GL_PACK_SKIP_ROWS, 0);
  glPixelStorei(GL_PACK_SKIP_PIXELS, 0);
  glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
  for (std::size_t top = 0, bottom = pixels.size() - row; top < bottom; top += row, bottom -= row) {
    std::swap_ranges(pixels.begin() + static_cast<std::ptrdiff_t>(top), pixels.begin() + static_cast<std::ptrdiff_t>(top + row),
                     pixels.begin() + static_cast<std::ptrdiff_t>(bottom));
  }
  for (std::size_t i = 3; i < pixels.size(); i += 4) pixels[i] = 255;  // ImGui's blending writes alpha
  return pixels;
}

}  // namespace limber::viewer
