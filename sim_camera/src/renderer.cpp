#include "flowsteer/sim_camera/renderer.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "flowsteer/servo/flow_field.hpp"
#include "flowsteer/servo/segmentation.hpp"
#include "flowsteer/sim_camera/camera_noise.hpp"
#include "shaders.hpp"

namespace flowsteer::sim_camera {

namespace {

constexpr int kShadowMapSize = 1024;
constexpr int kNoiseSize = 256;
constexpr float kNear = 0.05F;
constexpr float kFar = 500.0F;
// How many views a submission draws at most (their cameras' uniform block, 208 bytes a view, is
// within the 16 KiB every driver allows), and the memory their layers may take (ids, flow, depth,
// depth buffer: 20 bytes a pixel); further views go to further submissions.
constexpr std::size_t kMaxViewsPerSubmission = 16;
constexpr std::size_t kLayerBytes = 64U << 20U;
constexpr std::size_t kLayerBytesPerPixel = 20;

// EGL gives every renderer of the process the same display, and one eglTerminate ends it for
// all: renderers count their uses of a display, and the last one to go terminates it.
std::mutex display_mutex;
std::map<EGLDisplay, int> display_users;

std::string egl_error(const char* what) {
  char code[16];
  std::snprintf(code, sizeof code, "0x%04x", eglGetError());
  return std::string(what) + " failed (EGL error " + code + ")";
}

void check_gl(const char* what) {
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) {
    char code[16];
    std::snprintf(code, sizeof code, "0x%04x", error);
    throw std::runtime_error(std::string("OpenGL: ") + what + " failed (error " + code + ")");
  }
}

GLuint compile(GLenum type, std::initializer_list<const char*> sources, const char* name) {
  const GLuint shader = glCreateShader(type);
  glShaderSource(shader, static_cast<GLsizei>(sources.size()), std::data(sources), nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok == GL_FALSE) {
    std::array<char, 4096> log{};
    glGetShaderInfoLog(shader, log.size(), nullptr, log.data());
    glDeleteShader(shader);
    throw std::runtime_error(std::string("OpenGL: shader ") + name +
                             " does not compile: " + log.data());
  }
  return shader;
}

GLuint link(std::initializer_list<const char*> vertex, std::initializer_list<const char*> fragment,
            const char* name) {
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex, name);
  const GLuint fs = compile(GL_FRAGMENT_SHADER, fragment, name);
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (ok == GL_FALSE) {
    std::array<char, 4096> log{};
    glGetProgramInfoLog(program, log.size(), nullptr, log.data());
    glDeleteProgram(program);
    throw std::runtime_error(std::string("OpenGL: program ") + name +
                             " does not link: " + log.data());
  }
  return program;
}

bool has_extension(const char* name) {
  GLint count = 0;
  glGetIntegerv(GL_NUM_EXTENSIONS, &count);
  for (GLint k = 0; k < count; ++k) {
    if (std::strcmp(
            reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, static_cast<GLuint>(k))),
            name) == 0) {
      return true;
    }
  }
  return false;
}

struct Vertex {
  float position[3];
  float normal[3];
};

// A vertex array with its buffers, drawn as indexed triangles.
struct Mesh {
  GLuint vao = 0;
  GLuint vbo = 0;
  GLuint ebo = 0;
  GLsizei index_count = 0;

  void upload(const std::vector<Vertex>& vertices, const std::vector<GLuint>& indices) {
    glGenVertexArrays(1, &vao);
    glGenBuffers(1, &vbo);
    glGenBuffers(1, &ebo);
    glBindVertexArray(vao);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(Vertex)),
                 vertices.data(), GL_STATIC_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(GLuint)),
                 indices.data(), GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), nullptr);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                          reinterpret_cast<const void*>(offsetof(Vertex, normal)));
    glBindVertexArray(0);
    index_count = static_cast<GLsizei>(indices.size());
  }
  void release() {
    glDeleteBuffers(1, &ebo);
    glDeleteBuffers(1, &vbo);
    glDeleteVertexArrays(1, &vao);
  }
  void draw() const {
    glBindVertexArray(vao);
    glDrawElements(GL_TRIANGLES, index_count, GL_UNSIGNED_INT, nullptr);
  }
};

// A quad's two triangles, its corners in order: counter-clockwise seen from its front, the side
// the face culling keeps, or clockwise.
constexpr std::array<GLuint, 6> kCounterClockwiseQuad = {0, 1, 2, 0, 2, 3};
constexpr std::array<GLuint, 6> kClockwiseQuad = {0, 2, 1, 0, 3, 2};

void add_quad(std::vector<Vertex>& v, std::vector<GLuint>& idx, const Eigen::Vector3f corners[4],
              const Eigen::Vector3f& normal, const std::array<GLuint, 6>& triangles) {
  const auto base = static_cast<GLuint>(v.size());
  for (int k = 0; k < 4; ++k) {
    v.push_back(
        {{corners[k].x(), corners[k].y(), corners[k].z()}, {normal.x(), normal.y(), normal.z()}});
  }
  for (const GLuint k : triangles) {
    idx.push_back(base + k);
  }
}

// A unit box: [-0.5, 0.5]² × [0, 1].
Mesh box_mesh() {
  std::vector<Vertex> v;
  std::vector<GLuint> idx;
  for (int axis = 0; axis < 3; ++axis) {
    for (const float side : {-1.0F, 1.0F}) {
      Eigen::Vector3f normal = Eigen::Vector3f::Zero();
      normal[axis] = side;
      const int a = (axis + 1) % 3;
      const int b = (axis + 2) % 3;
      Eigen::Vector3f corners[4];
      const float du[4] = {-1, 1, 1, -1};
      const float dv[4] = {-1, -1, 1, 1};
      for (int k = 0; k < 4; ++k) {
        Eigen::Vector3f c;
        c[axis] = 0.5F * side;
        c[a] = 0.5F * du[k];
        c[b] = 0.5F * dv[k];
        c.z() += 0.5F;
        corners[k] = c;
      }
      // (du, dv) turn counter-clockwise about +axis: seen from outside, the face at side -1
      // has its corners clockwise.
      add_quad(v, idx, corners, normal, side > 0 ? kCounterClockwiseQuad : kClockwiseQuad);
    }
  }
  Mesh m;
  m.upload(v, idx);
  return m;
}

// A mesh's vertex positions and triangles on the CPU side, for the geometry batch.
struct Shape {
  std::vector<Eigen::Vector3f> positions;
  std::vector<GLuint> indices;
};

// The box's triangles with each corner one vertex, for the geometry program (no normals): the
// same triangles, from an eighth of the vertices to transform.
Shape box_shape() {
  Shape shape;
  std::vector<Eigen::Vector3f>& v = shape.positions;
  for (int k = 0; k < 8; ++k) {
    v.emplace_back((k & 1) != 0 ? 0.5F : -0.5F, (k & 2) != 0 ? 0.5F : -0.5F,
                   (k & 4) != 0 ? 1.0F : 0.0F);
  }
  // box_mesh's faces in its order: corner (u, v) of a face on `axis` at `side`.
  std::vector<GLuint>& idx = shape.indices;
  for (int axis = 0; axis < 3; ++axis) {
    for (const int side : {0, 1}) {
      const int a = (axis + 1) % 3;
      const int b = (axis + 2) % 3;
      const int du[4] = {0, 1, 1, 0};
      const int dv[4] = {0, 0, 1, 1};
      GLuint corner[4];
      for (int k = 0; k < 4; ++k) {
        corner[k] = static_cast<GLuint>((side << axis) | (du[k] << a) | (dv[k] << b));
      }
      for (const GLuint k : side == 1 ? kCounterClockwiseQuad : kClockwiseQuad) {
        idx.push_back(corner[k]);
      }
    }
  }
  return shape;
}

// A unit cylinder: radius 1, from z = 0 to 1, with its top cap, its circle of `segments`.
Mesh cylinder_mesh(int segments) {
  std::vector<Vertex> v;
  std::vector<GLuint> idx;
  for (int k = 0; k < segments; ++k) {
    const double a0 = 2.0 * std::numbers::pi * k / segments;
    const double a1 = 2.0 * std::numbers::pi * (k + 1) / segments;
    const Eigen::Vector3f p0(static_cast<float>(std::cos(a0)), static_cast<float>(std::sin(a0)),
                             0.0F);
    const Eigen::Vector3f p1(static_cast<float>(std::cos(a1)), static_cast<float>(std::sin(a1)),
                             0.0F);
    const auto base = static_cast<GLuint>(v.size());
    const Eigen::Vector3f up(0, 0, 1);
    for (const auto& [p, n] :
         {std::pair{p0, p0}, std::pair{p1, p1}, std::pair{Eigen::Vector3f(p1 + up), p1},
          std::pair{Eigen::Vector3f(p0 + up), p0}}) {
      v.push_back({{p.x(), p.y(), p.z()}, {n.x(), n.y(), n.z()}});
    }
    for (GLuint i : {0U, 1U, 2U, 0U, 2U, 3U}) {
      idx.push_back(base + i);
    }
    const auto cap = static_cast<GLuint>(v.size());
    v.push_back({{0, 0, 1}, {0, 0, 1}});
    v.push_back({{p0.x(), p0.y(), 1}, {0, 0, 1}});
    v.push_back({{p1.x(), p1.y(), 1}, {0, 0, 1}});
    for (GLuint i : {0U, 1U, 2U}) {
      idx.push_back(cap + i);
    }
  }
  Mesh m;
  m.upload(v, idx);
  return m;
}

// cylinder_mesh's triangles with the rings' points shared, for the geometry program (no
// normals): a third of the vertices. The ring's last point is computed at 2π as cylinder_mesh
// computes it, not taken as its first, so that every vertex is the same to the last bit.
Shape cylinder_shape(int segments) {
  Shape shape;
  std::vector<Eigen::Vector3f>& v = shape.positions;
  for (int k = 0; k <= segments; ++k) {
    const double a = 2.0 * std::numbers::pi * k / segments;
    const auto x = static_cast<float>(std::cos(a));
    const auto y = static_cast<float>(std::sin(a));
    v.emplace_back(x, y, 0.0F);  // 2k: bottom
    v.emplace_back(x, y, 1.0F);  // 2k + 1: top
  }
  const auto centre = static_cast<GLuint>(v.size());
  v.emplace_back(0.0F, 0.0F, 1.0F);
  std::vector<GLuint>& idx = shape.indices;
  for (GLuint k = 0; k < static_cast<GLuint>(segments); ++k) {
    const GLuint b0 = 2 * k;
    const GLuint t0 = b0 + 1;
    const GLuint b1 = b0 + 2;
    const GLuint t1 = b0 + 3;
    for (const GLuint i : {b0, b1, t1, b0, t1, t0, centre, t0, t1}) {
      idx.push_back(i);
    }
  }
  return shape;
}

// A cylinder's levels of detail, finest first: the segments of its circle. A crowd's view
// holds mostly far people, a few pixels wide; drawn with the finest level they would cost as
// many triangles as if they filled the view.
constexpr std::array<int, 4> kCylinderSegments = {48, 24, 12, 6};

std::array<Shape, kCylinderSegments.size()> cylinder_shapes() {
  std::array<Shape, kCylinderSegments.size()> shapes;
  for (std::size_t level = 0; level < shapes.size(); ++level) {
    shapes[level] = cylinder_shape(kCylinderSegments[level]);
  }
  return shapes;
}

// The ground: [-0.5, 0.5]² at z = 0, as one quad.
Shape ground_shape() {
  return {{{-0.5F, -0.5F, 0}, {0.5F, -0.5F, 0}, {0.5F, 0.5F, 0}, {-0.5F, 0.5F, 0}},
          {0, 1, 2, 0, 2, 3}};
}

Mesh ground_mesh() {
  std::vector<Vertex> v;
  std::vector<GLuint> idx;
  add_quad(v, idx, ground_shape().positions.data(), Eigen::Vector3f(0, 0, 1),
           kCounterClockwiseQuad);
  Mesh m;
  m.upload(v, idx);
  return m;
}

Eigen::Matrix4f model_matrix(const Eigen::Vector2d& centre, double yaw,
                             const Eigen::Vector3d& scale) {
  Eigen::Affine3d t = Eigen::Translation3d(centre.x(), centre.y(), 0.0) *
                      Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::Scaling(scale);
  return t.matrix().cast<float>();
}

// Tileable value noise of several octaves, in [0, 255]: the texture that gives surfaces
// contrast. Computed once; a fixed seed keeps renders identical from run to run.
std::vector<std::uint8_t> noise_texture() {
  std::vector<float> lattice(static_cast<std::size_t>(kNoiseSize * kNoiseSize));
  std::uint32_t state = 12345;
  for (float& v : lattice) {
    state = state * 1664525U + 1013904223U;  // LCG: repeatable, good enough for texture
    v = static_cast<float>(state >> 8) / static_cast<float>(1U << 24);
  }
  std::vector<float> sum(lattice.size(), 0.0F);
  float amplitude = 1.0F;
  float total = 0.0F;
  for (int cell = 32; cell >= 2; cell /= 2, amplitude *= 0.6F) {
    const int cells = kNoiseSize / cell;
    for (int y = 0; y < kNoiseSize; ++y) {
      for (int x = 0; x < kNoiseSize; ++x) {
        const int x0 = x / cell;
        const int y0 = y / cell;
        const float fx = static_cast<float>(x % cell) / static_cast<float>(cell);
        const float fy = static_cast<float>(y % cell) / static_cast<float>(cell);
        const float sx = fx * fx * (3.0F - 2.0F * fx);
        const float sy = fy * fy * (3.0F - 2.0F * fy);
        auto at = [&](int i, int j) {
          return lattice[static_cast<std::size_t>((j % cells) * kNoiseSize + (i % cells))];
        };
        const float top = at(x0, y0) + sx * (at(x0 + 1, y0) - at(x0, y0));
        const float bottom = at(x0, y0 + 1) + sx * (at(x0 + 1, y0 + 1) - at(x0, y0 + 1));
        sum[static_cast<std::size_t>(y * kNoiseSize + x)] +=
            amplitude * (top + sy * (bottom - top));
      }
    }
    total += amplitude;
  }
  std::vector<std::uint8_t> texels(sum.size());
  for (std::size_t i = 0; i < sum.size(); ++i) {
    texels[i] = static_cast<std::uint8_t>(std::lround(255.0F * sum[i] / total));
  }
  return texels;
}

// The programs' uniform locations, looked up once after linking: each glGetUniformLocation is a
// search by name, and a frame would otherwise make ~20 of them plus 4 per draw.
struct SceneUniforms {
  GLint model;
  GLint normal_matrix;
  GLint world_to_camera;
  GLint projection;
  GLint light_view_projection;
  GLint albedo;
  GLint pattern;
  GLint pattern_scale;
  GLint pattern_contrast;
  GLint id;
  GLint relative_velocity;
  GLint camera_omega;
  GLint ambient;
  GLint sun_direction;
  GLint sun_intensity;
  GLint sun_shadows;
  GLint point_count;
  GLint point_position;  // element 0: glUniform*v fills the array from there
  GLint point_intensity;
  GLint point_range;
};

SceneUniforms scene_uniforms(GLuint program) {
  auto at = [program](const char* name) { return glGetUniformLocation(program, name); };
  return {.model = at("u_model"),
          .normal_matrix = at("u_normal_matrix"),
          .world_to_camera = at("u_world_to_camera"),
          .projection = at("u_projection"),
          .light_view_projection = at("u_light_view_projection"),
          .albedo = at("u_albedo"),
          .pattern = at("u_pattern"),
          .pattern_scale = at("u_pattern_scale"),
          .pattern_contrast = at("u_pattern_contrast"),
          .id = at("u_id"),
          .relative_velocity = at("u_relative_velocity"),
          .camera_omega = at("u_camera_omega"),
          .ambient = at("u_ambient"),
          .sun_direction = at("u_sun_direction"),
          .sun_intensity = at("u_sun_intensity"),
          .sun_shadows = at("u_sun_shadows"),
          .point_count = at("u_point_count"),
          .point_position = at("u_point_position"),
          .point_intensity = at("u_point_intensity"),
          .point_range = at("u_point_range")};
}

struct ShadowUniforms {
  GLint model;
  GLint light_view_projection;
};

struct GeometryUniforms {
  GLint body_count;
  GLint view;
};

// The view's frustum as planes in the world frame, for leaving out bodies it cannot see: a
// crowd's view transforms the people in front, not the whole crowd. The test is conservative (a
// box around the body against each plane), so what it leaves out would have drawn no pixel.
class Frustum {
 public:
  Frustum(const Eigen::Matrix4f& projection, const Eigen::Matrix4f& world_to_camera) {
    const Eigen::Matrix4d clip = projection.cast<double>() * world_to_camera.cast<double>();
    // -w ≤ x, y ≤ w and -w ≤ z (the near plane); the far plane is past any world.
    const int rows[5][2] = {{0, 1}, {0, -1}, {1, 1}, {1, -1}, {2, 1}};
    for (int k = 0; k < 5; ++k) {
      planes_[k] = clip.row(3).transpose() + rows[k][1] * clip.row(rows[k][0]).transpose();
    }
  }

  // Whether any point of the mesh box centre ± half (mesh units) under `model` may be in view.
  bool may_see(const Eigen::Matrix4f& model, const Eigen::Vector3d& centre,
               const Eigen::Vector3d& half) const {
    const Eigen::Matrix4d m = model.cast<double>();
    const Eigen::Vector4d c = m * centre.homogeneous();
    for (const Eigen::Vector4d& plane : planes_) {
      // The box's reach along the plane's normal: Σ |n · column| · half.
      const double reach = std::abs(plane.head<3>().dot(m.col(0).head<3>())) * half.x() +
                           std::abs(plane.head<3>().dot(m.col(1).head<3>())) * half.y() +
                           std::abs(plane.head<3>().dot(m.col(2).head<3>())) * half.z();
      if (plane.dot(c) + reach < 0.0) {
        return false;
      }
    }
    return true;
  }

 private:
  std::array<Eigen::Vector4d, 5> planes_;
};

// What one draw needs: the shape, its pose and size, how it looks, who it is and how it moves.
struct DrawItem {
  Solid::Shape shape;
  bool hidden;  // from this view: its own camera's body (it still casts a shadow)
  // An agent that has left the world: nothing draws it, but it keeps its place among the items,
  // whose shapes a geometry batch builds once per world.
  bool gone;
  Eigen::Matrix4f model;
  Material material;  // a copy: moving obstacles' poses are temporaries
  std::int32_t id;
  Eigen::Vector3d velocity_mps;  // world frame
};

// The geometry program's buffer textures' units, in GeometryBatch::Table's order, and its
// cameras' uniform block's binding.
constexpr GLint kFirstTableUnit = 2;
constexpr GLuint kCameraBlockBinding = 0;

// Every body of a world, each at every level of detail it has, and the ground in one vertex
// buffer; per submission, one index buffer of the triangles each view draws: the bodies it may
// see, each at its level for that view. One draw call per view. Each vertex names its body.
// The vertex shader reads the view's camera from a uniform block, and the bodies' model
// matrices and, per view and body, the velocity relative to the camera and the id from buffer
// textures, all filled for the submission (shaders::kGeometryVertex).
struct GeometryBatch {
  struct BatchVertex {
    float position[3];
    std::int32_t body;
  };
  struct IndexRange {
    std::size_t first;
    std::size_t count;
  };
  // A view's camera as the uniform block's std140 layout has it: world to camera, projection,
  // the ground's model, then ω.
  using CameraBlock = std::array<float, 52>;
  enum Table { models, velocities, ids, table_count };

  GLuint vao = 0;
  GLuint vbo = 0;
  GLuint ebo = 0;
  std::array<GLuint, table_count> buffers{};
  std::array<GLuint, table_count> textures{};
  GLuint camera_buffer = 0;
  std::uint64_t world_serial = 0;  // the world whose bodies the buffers hold; 0: none yet
  std::vector<std::array<float, 16>> model_texels;  // per body but the ground
  // Per view; the block has room for every view a submission may draw.
  std::array<CameraBlock, kMaxViewsPerSubmission> cameras{};
  std::size_t view_count = 0;
  std::vector<std::array<float, 4>> velocity_texels;  // per view and body, the ground included
  std::vector<std::int32_t> id_texels;                // per view and body, the ground included
  std::vector<BatchVertex> vertices;
  std::vector<GLuint> level_indices;     // every body's levels' triangles
  std::vector<IndexRange> levels;        // per body and level, into level_indices
  std::vector<std::size_t> first_level;  // per body, its first entry in levels
  std::vector<GLuint> view_indices;      // per submission, the triangles of each view
  std::vector<IndexRange> view_ranges;   // per view, into view_indices

  void create() {
    glGenVertexArrays(1, &vao);
    glGenBuffers(1, &vbo);
    glGenBuffers(1, &ebo);
    glGenBuffers(table_count, buffers.data());
    glGenTextures(table_count, textures.data());
    glGenBuffers(1, &camera_buffer);
    glBindVertexArray(vao);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(BatchVertex), nullptr);
    glEnableVertexAttribArray(1);
    glVertexAttribIPointer(1, 1, GL_INT, sizeof(BatchVertex),
                           reinterpret_cast<const void*>(offsetof(BatchVertex, body)));
    glBindVertexArray(0);
  }

  void release() {
    glDeleteBuffers(1, &camera_buffer);
    glDeleteTextures(table_count, textures.data());
    glDeleteBuffers(table_count, buffers.data());
    glDeleteBuffers(1, &ebo);
    glDeleteBuffers(1, &vbo);
    glDeleteVertexArrays(1, &vao);
  }

  // The bodies' shapes, each body's levels of detail finest first, in drawing order, the ground
  // last, once per world: bodies are added and removed only with a new world.
  void build(std::uint64_t serial, const std::vector<std::span<const Shape>>& bodies) {
    vertices.clear();
    level_indices.clear();
    levels.clear();
    first_level.clear();
    for (std::size_t body = 0; body < bodies.size(); ++body) {
      first_level.push_back(levels.size());
      for (const Shape& shape : bodies[body]) {
        const auto first = static_cast<GLuint>(vertices.size());
        for (const Eigen::Vector3f& p : shape.positions) {
          vertices.push_back({{p.x(), p.y(), p.z()}, static_cast<std::int32_t>(body)});
        }
        levels.push_back({level_indices.size(), shape.indices.size()});
        for (const GLuint index : shape.indices) {
          level_indices.push_back(first + index);
        }
      }
    }
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(BatchVertex)),
                 vertices.data(), GL_STATIC_DRAW);
    world_serial = serial;
  }

  void clear_views() {
    view_count = 0;
    velocity_texels.clear();
    id_texels.clear();
    view_indices.clear();
    view_ranges.clear();
  }

  // The bodies' poses, once for all the submissions of a world state.
  void upload_bodies(const std::vector<DrawItem>& items) {
    model_texels.clear();
    for (const DrawItem& item : items) {
      std::copy(item.model.data(), item.model.data() + 16, model_texels.emplace_back().begin());
    }
    upload_table(models, GL_RGBA32F, model_texels);
  }

  void add_view(const Eigen::Matrix4f& world_to_camera, const Eigen::Matrix4f& projection,
                const Eigen::Matrix4f& ground_model, const Eigen::Vector3d& omega) {
    CameraBlock& texels = cameras.at(view_count++);
    std::copy(world_to_camera.data(), world_to_camera.data() + 16, texels.begin());
    std::copy(projection.data(), projection.data() + 16, texels.begin() + 16);
    std::copy(ground_model.data(), ground_model.data() + 16, texels.begin() + 32);
    const Eigen::Vector3f w = omega.cast<float>();
    std::copy(w.data(), w.data() + 3, texels.begin() + 48);
    view_ranges.push_back({view_indices.size(), 0});
  }

  // The last view's body `body`, in body order: how it moves relative to the camera, its id,
  // and the level of detail it is drawn at, none where the view does not draw it.
  void add_body(std::size_t body, const Eigen::Vector3f& relative_velocity, std::int32_t id,
                std::optional<std::size_t> level) {
    velocity_texels.push_back(
        {relative_velocity.x(), relative_velocity.y(), relative_velocity.z(), 0.0F});
    id_texels.push_back(id);
    if (level) {
      const IndexRange& triangles = levels[first_level[body] + *level];
      const auto from = level_indices.begin() + static_cast<std::ptrdiff_t>(triangles.first);
      view_indices.insert(view_indices.end(), from,
                          from + static_cast<std::ptrdiff_t>(triangles.count));
      view_ranges.back().count += triangles.count;
    }
  }

  void upload_views() const {
    upload_table(velocities, GL_RGBA32F, velocity_texels);
    upload_table(ids, GL_R32I, id_texels);
    glBindBuffer(GL_UNIFORM_BUFFER, camera_buffer);
    glBufferData(GL_UNIFORM_BUFFER, sizeof cameras, cameras.data(), GL_STREAM_DRAW);
    glBindBufferBase(GL_UNIFORM_BUFFER, kCameraBlockBinding, camera_buffer);
    glBindVertexArray(vao);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                 static_cast<GLsizeiptr>(view_indices.size() * sizeof(GLuint)), view_indices.data(),
                 GL_STREAM_DRAW);
    glBindVertexArray(0);
  }

  // The triangles of view `view`, whose camera the uniform u_view names.
  void draw(std::size_t view) const {
    const IndexRange& triangles = view_ranges[view];
    glBindVertexArray(vao);
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(triangles.count), GL_UNSIGNED_INT,
                   reinterpret_cast<const void*>(triangles.first * sizeof(GLuint)));
    glBindVertexArray(0);
  }

  template <typename Row>
  void upload_table(Table table, GLenum format, const std::vector<Row>& rows) const {
    glBindBuffer(GL_TEXTURE_BUFFER, buffers[table]);
    glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(rows.size() * sizeof(Row)), rows.data(),
                 GL_STREAM_DRAW);
    glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(kFirstTableUnit + table));
    glBindTexture(GL_TEXTURE_BUFFER, textures[table]);
    glTexBuffer(GL_TEXTURE_BUFFER, format, buffers[table]);
  }
};

// The point lights as the scene program's uniforms hold them: fixed lights, then carried ones.
// Elements past `count` stay zero, so equal values mean an equal upload.
struct PointUniforms {
  int count = 0;
  std::array<float, 3 * kMaxPointLights> position{};
  std::array<float, kMaxPointLights> intensity{};
  std::array<float, kMaxPointLights> range{};

  void add(const Eigen::Vector3d& position_m, float light_intensity, double range_m) {
    const auto k = static_cast<std::size_t>(count++);
    intensity.at(k) = light_intensity;  // World keeps the lights within kMaxPointLights
    range[k] = static_cast<float>(range_m);
    position[3 * k] = static_cast<float>(position_m.x());
    position[3 * k + 1] = static_cast<float>(position_m.y());
    position[3 * k + 2] = static_cast<float>(position_m.z());
  }
  bool operator==(const PointUniforms&) const = default;
};

}  // namespace

// What a view draws of a body: nothing where the body is out of the view or lies between pixel
// centres (a far person at 64² is a tenth of a pixel wide: drawn, it would cost its triangles
// and colour nothing), else the coarsest level of detail that keeps its outline. Both the lit
// and the geometry programs draw what it says, so that their channels stay the same.
class BodyDetail {
 public:
  BodyDetail(const Eigen::Matrix4f& projection, const Eigen::Matrix4f& world_to_camera,
             const base::CameraIntrinsics& k)
      : frustum_(projection, world_to_camera),
        world_to_camera_(world_to_camera.cast<double>()),
        k_(k) {}

  // An index into kCylinderSegments for a cylinder, 0 for a box; none where nothing is drawn.
  std::optional<std::size_t> level(const DrawItem& item) const {
    // Both unit meshes lie within [-1, 1]² × [0, 1].
    if (!frustum_.may_see(item.model, {0.0, 0.0, 0.5}, {1.0, 1.0, 0.5})) {
      return std::nullopt;
    }
    const Eigen::Matrix4d to_camera = world_to_camera_ * item.model.cast<double>();
    if (!may_cover_a_pixel_centre(to_camera)) {
      return std::nullopt;
    }
    return item.shape == Solid::Shape::box ? 0 : cylinder_level(to_camera);
  }

 private:
  // How far a coarser level's outline may lie from the finest's in the image, in pixels: well
  // within the half pixel by which rasterising already places any outline.
  static constexpr double kOutlineTolerancePx = 0.25;
  // What the float arithmetic that draws a body may move its outline by, at most.
  static constexpr double kRoundingMarginPx = 1e-3;

  // Whether the image's bounding box of the unit meshes' bound, [-1, 1]² × [0, 1] under
  // `to_camera`, holds a pixel centre (a whole number in the projection's pixel coordinates);
  // true where a corner is not in front of the near plane.
  bool may_cover_a_pixel_centre(const Eigen::Matrix4d& to_camera) const {
    Eigen::AlignedBox2d image;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d p =
          to_camera.topRows<3>() * Eigen::Vector4d((corner & 1) != 0 ? 1.0 : -1.0,
                                                   (corner & 2) != 0 ? 1.0 : -1.0,
                                                   (corner & 4) != 0 ? 1.0 : 0.0, 1.0);
      if (p.z() <= kNear) {
        return true;
      }
      image.extend(Eigen::Vector2d(k_.cx_px + k_.fx_px * p.x() / p.z(),
                                   k_.cy_px + k_.fy_px * p.y() / p.z()));
    }
    auto holds_a_whole_number = [](double low, double high, int size) {
      return std::floor(std::min(high + kRoundingMarginPx, size - 1.0)) >=
             std::ceil(std::max(low - kRoundingMarginPx, 0.0));
    };
    return holds_a_whole_number(image.min().x(), image.max().x(), k_.width_px) &&
           holds_a_whole_number(image.min().y(), image.max().y(), k_.height_px);
  }

  // The coarsest level whose outline lies within kOutlineTolerancePx of the circle's. A chord
  // of n segments lies up to r (1 − cos(π/n)) inside the circle; the projection x = f X/Z moves
  // an image point by at most f d/Z² per metre a world point moves (d its distance, Z its
  // depth), taken at the body's nearest depth and farthest distance.
  std::size_t cylinder_level(const Eigen::Matrix4d& to_camera) const {
    const Eigen::Vector3d centre = to_camera.topRows<3>() * Eigen::Vector4d(0.0, 0.0, 0.5, 1.0);
    const double radius =
        std::max(to_camera.col(0).head<3>().norm(), to_camera.col(1).head<3>().norm());
    const double reach = std::hypot(radius, 0.5 * to_camera.col(2).head<3>().norm());
    const double nearest_depth = centre.z() - reach;
    if (nearest_depth <= kNear) {
      return 0;
    }
    const double px_per_m =
        std::max(k_.fx_px, k_.fy_px) * (centre.norm() + reach) / (nearest_depth * nearest_depth);
    for (std::size_t level = kCylinderSegments.size() - 1; level > 0; --level) {
      const double inside_m =
          radius * (1.0 - std::cos(std::numbers::pi / kCylinderSegments[level]));
      if (inside_m * px_per_m <= kOutlineTolerancePx) {
        return level;
      }
    }
    return 0;
  }

  Frustum frustum_;
  Eigen::Matrix4d world_to_camera_;
  base::CameraIntrinsics k_;
};

struct Renderer::Impl {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  std::string description;
  GLuint scene_program = 0;
  GLuint shadow_program = 0;
  GLuint geometry_program = 0;
  SceneUniforms scene{};
  ShadowUniforms shadow{};
  GeometryUniforms geometry{};
  std::optional<PointUniforms> uploaded_points;  // none before the first frame
  Mesh box;
  std::array<Mesh, kCylinderSegments.size()> cylinders;  // per level of detail
  Mesh ground;
  Shape box_positions = box_shape();
  std::array<Shape, kCylinderSegments.size()> cylinder_positions = cylinder_shapes();
  Shape ground_positions = ground_shape();
  GeometryBatch batch;
  std::vector<std::span<const Shape>> batch_shapes;
  GLuint fbo = 0;
  std::array<GLuint, 5> renderbuffers{};  // color, id, flow, depth, depth-stencil
  int fbo_width = 0;
  int fbo_height = 0;
  // The geometry channels of a submission's views, a layer each: the textures (id, flow, depth,
  // depth buffer), a framebuffer of all their layers and one of a single layer (to read a view
  // back, or to draw it where views are drawn one by one).
  bool layered = false;  // a submission's views drawn by one call (ViewSubmission)
  std::array<GLuint, 4> layer_textures{};
  GLuint layered_fbo = 0;
  GLuint layer_fbo = 0;
  int layers_width = 0;
  int layers_height = 0;
  int layer_count = 0;
  GLuint shadow_fbo = 0;
  GLuint shadow_texture = 0;
  GLuint noise_texture_id = 0;
  std::uint64_t shadow_world_serial = 0;
  double shadow_time_s = -1.0;
  Eigen::Matrix4f light_view_projection = Eigen::Matrix4f::Identity();
  std::vector<DrawItem> items;

  ~Impl() {
    if (context != EGL_NO_CONTEXT) {
      eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context);
      box.release();
      for (Mesh& cylinder : cylinders) {
        cylinder.release();
      }
      ground.release();
      batch.release();
      glDeleteRenderbuffers(static_cast<GLsizei>(renderbuffers.size()), renderbuffers.data());
      glDeleteFramebuffers(1, &fbo);
      glDeleteTextures(static_cast<GLsizei>(layer_textures.size()), layer_textures.data());
      glDeleteFramebuffers(1, &layered_fbo);
      glDeleteFramebuffers(1, &layer_fbo);
      glDeleteTextures(1, &shadow_texture);
      glDeleteTextures(1, &noise_texture_id);
      glDeleteFramebuffers(1, &shadow_fbo);
      glDeleteProgram(scene_program);
      glDeleteProgram(shadow_program);
      glDeleteProgram(geometry_program);
      eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      eglDestroyContext(display, context);
    }
    if (display != EGL_NO_DISPLAY) {
      const std::lock_guard lock(display_mutex);
      if (--display_users[display] == 0) {
        display_users.erase(display);
        eglTerminate(display);
      }
    }
  }

  void open_display() {
    const std::lock_guard lock(display_mutex);
    find_display();
    ++display_users[display];
  }

  void find_display() {
    const auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (get_platform_display == nullptr) {
      throw std::runtime_error(
          "no EGL display available: EGL has no eglGetPlatformDisplayEXT (is libegl1 with a "
          "vendor library such as libegl-mesa0 installed?)");
    }
    // A GPU through the device platform first, then Mesa's surfaceless platform (llvmpipe).
    const auto query_devices =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    if (query_devices != nullptr) {
      std::array<EGLDeviceEXT, 8> devices{};
      EGLint count = 0;
      if (query_devices(static_cast<EGLint>(devices.size()), devices.data(), &count) && count > 0) {
        for (EGLint k = 0; k < count && display == EGL_NO_DISPLAY; ++k) {
          EGLDisplay d = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[k], nullptr);
          if (d != EGL_NO_DISPLAY && eglInitialize(d, nullptr, nullptr)) {
            const char* vendor = eglQueryString(d, EGL_VENDOR);
            // Mesa's software device is the surfaceless one below; prefer a real GPU here.
            if (vendor != nullptr && std::string(vendor).find("Mesa") == std::string::npos) {
              display = d;
            } else if (!display_users.contains(d)) {
              eglTerminate(d);
            }
          }
        }
      }
    }
    if (display == EGL_NO_DISPLAY) {
      EGLDisplay d =
          get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
      if (d == EGL_NO_DISPLAY || !eglInitialize(d, nullptr, nullptr)) {
        throw std::runtime_error(
            "no EGL display available: " + egl_error("the surfaceless platform (Mesa)") +
            "; install libegl-mesa0 and libgl1-mesa-dri, or run where a "
            "GPU's EGL driver is present");
      }
      display = d;
    }
  }

  void create_context() {
    if (!eglBindAPI(EGL_OPENGL_API)) {
      throw std::runtime_error(egl_error("eglBindAPI(EGL_OPENGL_API)"));
    }
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                 3,
                                 EGL_CONTEXT_MINOR_VERSION,
                                 3,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                 EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                 EGL_NONE};
    context = eglCreateContext(display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attributes);
    if (context == EGL_NO_CONTEXT) {
      throw std::runtime_error(egl_error("creating an OpenGL 3.3 core context"));
    }
    if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
      throw std::runtime_error(egl_error("eglMakeCurrent without a surface"));
    }
    description = std::string("OpenGL ") + reinterpret_cast<const char*>(glGetString(GL_VERSION)) +
                  ", " + reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  }

  // Whether views are drawn layered: where asked, or by default on a GPU, where the driver can.
  static bool draws_layered(ViewSubmission submission) {
    if (submission == ViewSubmission::per_view ||
        !has_extension("GL_ARB_shader_viewport_layer_array")) {
      return false;
    }
    const std::string renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const bool software = renderer.starts_with("llvmpipe") || renderer.starts_with("softpipe");
    return submission == ViewSubmission::layered || !software;
  }

  void create_resources(ViewSubmission submission) {
    layered = draws_layered(submission);
    scene_program =
        link({shaders::kSceneVertex},
             {shaders::kVersion, shaders::kGeometryOutputs, shaders::kSceneFragment}, "scene");
    shadow_program = link({shaders::kShadowVertex}, {shaders::kShadowFragment}, "shadow");
    const std::string defines = "#define MAX_VIEWS " + std::to_string(kMaxViewsPerSubmission) +
                                (layered ? "\n#define LAYERED\n" : "\n");
    geometry_program = link(
        {shaders::kVersion, defines.c_str(), shaders::kGeometryVertex},
        {shaders::kVersion, shaders::kGeometryOutputs, shaders::kGeometryFragment}, "geometry");
    scene = scene_uniforms(scene_program);
    shadow = {
        .model = glGetUniformLocation(shadow_program, "u_model"),
        .light_view_projection = glGetUniformLocation(shadow_program, "u_light_view_projection")};
    auto at = [this](const char* name) { return glGetUniformLocation(geometry_program, name); };
    geometry = {.body_count = at("u_body_count"), .view = at("u_view")};
    glUseProgram(geometry_program);
    const char* tables[] = {"u_models", "u_velocities", "u_ids"};
    for (int table = 0; table < GeometryBatch::table_count; ++table) {
      glUniform1i(at(tables[table]), kFirstTableUnit + table);
    }
    glUniformBlockBinding(geometry_program, glGetUniformBlockIndex(geometry_program, "Cameras"),
                          kCameraBlockBinding);
    // The samplers' texture units never change.
    glUseProgram(scene_program);
    glUniform1i(glGetUniformLocation(scene_program, "u_shadow_map"), 0);
    glUniform1i(glGetUniformLocation(scene_program, "u_noise"), 1);
    box = box_mesh();
    for (std::size_t level = 0; level < cylinders.size(); ++level) {
      cylinders[level] = cylinder_mesh(kCylinderSegments[level]);
    }
    ground = ground_mesh();
    batch.create();
    glGenTextures(1, &shadow_texture);
    glBindTexture(GL_TEXTURE_2D, shadow_texture);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, kShadowMapSize, kShadowMapSize, 0,
                 GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glGenFramebuffers(1, &shadow_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadow_texture, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      throw std::runtime_error("OpenGL: the shadow-map framebuffer is incomplete");
    }
    const std::vector<std::uint8_t> noise = noise_texture();
    glGenTextures(1, &noise_texture_id);
    glBindTexture(GL_TEXTURE_2D, noise_texture_id);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_R8, kNoiseSize, kNoiseSize, 0, GL_RED, GL_UNSIGNED_BYTE,
                 noise.data());
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
    glGenFramebuffers(1, &fbo);
    glGenFramebuffers(1, &layered_fbo);
    glGenFramebuffers(1, &layer_fbo);
    check_gl("creating the renderer's resources");
  }

  void resize(int width, int height) {
    if (width == fbo_width && height == fbo_height) {
      return;
    }
    if (renderbuffers[0] != 0) {
      glDeleteRenderbuffers(static_cast<GLsizei>(renderbuffers.size()), renderbuffers.data());
    }
    glGenRenderbuffers(static_cast<GLsizei>(renderbuffers.size()), renderbuffers.data());
    const GLenum formats[] = {GL_RGBA8, GL_R32I, GL_RG32F, GL_R32F, GL_DEPTH_COMPONENT24};
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    for (std::size_t k = 0; k < renderbuffers.size(); ++k) {
      glBindRenderbuffer(GL_RENDERBUFFER, renderbuffers[k]);
      glRenderbufferStorage(GL_RENDERBUFFER, formats[k], width, height);
      const GLenum attachment =
          k < 4 ? GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(k) : GL_DEPTH_ATTACHMENT;
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, attachment, GL_RENDERBUFFER, renderbuffers[k]);
    }
    const GLenum draw_buffers[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2,
                                   GL_COLOR_ATTACHMENT3};
    glDrawBuffers(4, draw_buffers);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      throw std::runtime_error("OpenGL: the " + std::to_string(width) + "x" +
                               std::to_string(height) + " framebuffer is incomplete");
    }
    check_gl("allocating the framebuffer");
    fbo_width = width;
    fbo_height = height;
  }

  void collect_items(const World& world, std::optional<std::size_t> self) {
    items.clear();
    const WorldSpec& spec = world.spec();
    for (std::size_t i = 0; i < spec.agents.size(); ++i) {
      const AgentSpec& a = spec.agents[i];
      const AgentState& s = world.agents()[i];
      const Eigen::Vector2d v = s.velocity_mps();
      items.push_back({Solid::Shape::cylinder,
                       self && *self == i,
                       !world.present(i),
                       model_matrix(s.position_m, 0.0, {a.radius_m, a.radius_m, a.height_m}),
                       a.material,
                       agent_render_id(i),
                       {v.x(), v.y(), 0.0}});
    }
    auto add_solid = [&](const Solid& s, std::int32_t id, const Eigen::Vector2d& velocity) {
      const bool box_shape = s.shape == Solid::Shape::box;
      const Eigen::Vector3d scale = box_shape
                                        ? Eigen::Vector3d(s.size_m.x(), s.size_m.y(), s.height_m)
                                        : Eigen::Vector3d(s.radius_m, s.radius_m, s.height_m);
      items.push_back({s.shape,
                       false,
                       false,
                       model_matrix(s.centre_m, s.yaw_rad, scale),
                       s.material,
                       id,
                       {velocity.x(), velocity.y(), 0.0}});
    };
    for (std::size_t k = 0; k < spec.obstacles.size(); ++k) {
      add_solid(spec.obstacles[k], obstacle_render_id(k), Eigen::Vector2d::Zero());
    }
    for (std::size_t k = 0; k < spec.moving.size(); ++k) {
      add_solid(world.moving_now(k), moving_render_id(k), world.moving()[k].velocity_mps);
    }
  }

  // The sun's shadow map, once per world state: every view of that instant shares it.
  void render_shadow_map(const World& world) {
    const auto& sun = world.spec().lighting.sun;
    if (!sun || !sun->shadows ||
        (shadow_world_serial == world.serial() && shadow_time_s == world.time_s())) {
      return;
    }
    shadow_world_serial = world.serial();
    shadow_time_s = world.time_s();
    // Fit an orthographic light frustum around everything that stands on the ground.
    // Each solid with the reach of its shadow: height / tan(elevation) beyond its footprint.
    Eigen::AlignedBox2d bounds;
    const double shadow_per_height = 1.0 / std::tan(sun->elevation_rad);
    auto extend = [&](const Eigen::Vector2d& centre, double reach_m, double height_m) {
      const double r = reach_m + height_m * shadow_per_height;
      bounds.extend(centre + Eigen::Vector2d(r, r));
      bounds.extend(centre - Eigen::Vector2d(r, r));
    };
    auto reach = [](const Solid& s) {
      return s.shape == Solid::Shape::box ? 0.5 * s.size_m.norm() : s.radius_m;
    };
    for (std::size_t i = 0; i < world.agents().size(); ++i) {
      if (!world.present(i)) {
        continue;
      }
      const AgentSpec& a = world.spec().agents[i];
      extend(world.agents()[i].position_m, a.radius_m, a.height_m);
    }
    for (const Solid& s : world.spec().obstacles) {
      extend(s.centre_m, reach(s), s.height_m);
    }
    for (std::size_t k = 0; k < world.moving().size(); ++k) {
      const Solid s = world.moving_now(k);
      extend(s.centre_m, reach(s), s.height_m);
    }
    const Eigen::Vector2d centre2 = bounds.center();
    const double radius = 0.5 * bounds.diagonal().norm() + 1.0;
    const Eigen::Vector3d centre(centre2.x(), centre2.y(), 0.0);
    const Eigen::Vector3d to_sun(std::cos(sun->elevation_rad) * std::cos(sun->azimuth_rad),
                                 std::cos(sun->elevation_rad) * std::sin(sun->azimuth_rad),
                                 std::sin(sun->elevation_rad));
    const Eigen::Vector3d eye = centre + 2.0 * radius * to_sun;
    const Eigen::Vector3d forward = (centre - eye).normalized();
    Eigen::Vector3d up =
        std::abs(forward.z()) > 0.99 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d right = forward.cross(up).normalized();
    up = right.cross(forward);
    Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
    view.block<1, 3>(0, 0) = right.transpose();
    view.block<1, 3>(1, 0) = up.transpose();
    view.block<1, 3>(2, 0) = -forward.transpose();
    view.block<3, 1>(0, 3) = -view.block<3, 3>(0, 0) * eye;
    const double near = 0.1;
    const double far = 4.0 * radius;
    Eigen::Matrix4d ortho = Eigen::Matrix4d::Identity();
    ortho(0, 0) = 1.0 / radius;
    ortho(1, 1) = 1.0 / radius;
    ortho(2, 2) = -2.0 / (far - near);
    ortho(2, 3) = -(far + near) / (far - near);
    light_view_projection = (ortho * view).cast<float>();

    glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
    glViewport(0, 0, kShadowMapSize, kShadowMapSize);
    glDisable(GL_CULL_FACE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glClear(GL_DEPTH_BUFFER_BIT);
    glUseProgram(shadow_program);
    glUniformMatrix4fv(shadow.light_view_projection, 1, GL_FALSE, light_view_projection.data());
    collect_items(world, std::nullopt);
    for (const DrawItem& item : items) {
      if (!item.gone) {
        glUniformMatrix4fv(shadow.model, 1, GL_FALSE, item.model.data());
        (item.shape == Solid::Shape::box ? box : cylinders.front()).draw();
      }
    }
    check_gl("rendering the shadow map");
  }

  void set_material(const Material& m) {
    glUniform3f(scene.albedo, m.albedo.x(), m.albedo.y(), m.albedo.z());
    glUniform1i(scene.pattern, static_cast<int>(m.pattern));
    glUniform1f(scene.pattern_scale, m.pattern_scale_m);
    glUniform1f(scene.pattern_contrast, m.pattern_contrast);
  }

  // The point lights go to the scene program only when they differ from what it holds: fixed
  // lights change with the world, carried ones when their agents move.
  void upload_points(const World& world) {
    const WorldSpec& spec = world.spec();
    PointUniforms points;
    for (const PointLight& p : spec.lighting.points) {
      points.add(p.position_m, p.intensity, p.range_m);
    }
    for (std::size_t i = 0; i < spec.agents.size(); ++i) {
      if (const auto& carried = spec.agents[i].carried_light; carried && world.present(i)) {
        const AgentState& a = world.agents()[i];
        const Eigen::Vector2d offset =
            Eigen::Rotation2Dd(a.yaw_rad) * carried->position_m.head<2>();
        points.add(
            {a.position_m.x() + offset.x(), a.position_m.y() + offset.y(), carried->position_m.z()},
            carried->intensity, carried->range_m);
      }
    }
    if (uploaded_points == points) {
      return;
    }
    glUniform1i(scene.point_count, points.count);
    glUniform3fv(scene.point_position, points.count, points.position.data());
    glUniform1fv(scene.point_intensity, points.count, points.intensity.data());
    glUniform1fv(scene.point_range, points.count, points.range.data());
    uploaded_points = points;
  }

  // The optical frame's pose and projection for a view, and how the camera moves.
  struct CameraPose {
    Eigen::Matrix3d rotation;  // world to the optical frame (x right, y down, z forward)
    Eigen::Matrix4f world_to_camera;
    Eigen::Matrix4f projection;
    Eigen::Vector3d velocity_mps;  // world frame
    Eigen::Vector3d omega;         // optical frame
  };

  static CameraPose camera_pose(const View& view, const base::CameraIntrinsics& k) {
    CameraPose pose;
    // Camera pitched down.
    const double c = std::cos(view.yaw_rad);
    const double s = std::sin(view.yaw_rad);
    const double cp = std::cos(view.camera.pitch_rad);
    const double sp = std::sin(view.camera.pitch_rad);
    const Eigen::Vector3d forward(c * cp, s * cp, -sp);
    const Eigen::Vector3d right(s, -c, 0.0);
    const Eigen::Vector3d down = forward.cross(right);
    pose.rotation << right.transpose(), down.transpose(), forward.transpose();
    const Eigen::Vector3d eye(view.position_m.x(), view.position_m.y(), view.camera.height_m);
    pose.world_to_camera = Eigen::Matrix4f::Identity();
    pose.world_to_camera.block<3, 3>(0, 0) = pose.rotation.cast<float>();
    pose.world_to_camera.block<3, 1>(0, 3) = (-pose.rotation * eye).cast<float>();
    // Pixel centres at integer coordinates; row 0 lands on the first row glReadPixels returns.
    Eigen::Matrix4f& projection = pose.projection;
    projection = Eigen::Matrix4f::Zero();
    projection(0, 0) = static_cast<float>(2.0 * k.fx_px / k.width_px);
    projection(0, 2) = static_cast<float>(2.0 * (k.cx_px + 0.5) / k.width_px - 1.0);
    projection(1, 1) = static_cast<float>(2.0 * k.fy_px / k.height_px);
    projection(1, 2) = static_cast<float>(2.0 * (k.cy_px + 0.5) / k.height_px - 1.0);
    projection(2, 2) = (kFar + kNear) / (kFar - kNear);
    projection(2, 3) = -2.0F * kFar * kNear / (kFar - kNear);
    projection(3, 2) = 1.0F;
    pose.velocity_mps = Eigen::Vector3d(view.speed_mps * c, view.speed_mps * s, 0.0);
    pose.omega = servo::camera_angular_velocity(view.turn_rate, view.camera.pitch_rad);
    return pose;
  }

  void make_current() {
    if (!eglBindAPI(EGL_OPENGL_API) ||
        !eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
      throw std::runtime_error(
          egl_error("eglMakeCurrent (a renderer is used by two threads at once)"));
    }
  }

  // The context and EGL's state of this thread are released after each render: a renderer may be
  // used, or destroyed, on another thread, and a worker thread that ends after the last renderer
  // (a thread pool's, at exit) must not have EGL free its state then.
  static void release_thread() { eglReleaseThread(); }

  void render(const World& world, const View& view, RenderChannels channels, RenderedView& out) {
    if (channels == RenderChannels::geometry) {
      RenderedView* const target = &out;
      render_geometry(world, std::span(&view, 1), std::span(&target, 1));
      return;
    }
    make_current();
    const base::CameraIntrinsics k = view.intrinsics();
    render_shadow_map(world);
    resize(k.width_px, k.height_px);
    const CameraPose pose = camera_pose(view, k);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    set_view_state(k);
    const GLenum draw_buffers[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2,
                                   GL_COLOR_ATTACHMENT3};
    glDrawBuffers(4, draw_buffers);
    clear_geometry();
    draw_lit(world, view, pose);
    check_gl("rendering the view");
    out.image.create(k.height_px, k.width_px, CV_8UC3);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, k.width_px, k.height_px, GL_BGR, GL_UNSIGNED_BYTE, out.image.data);
    read_geometry(k, pose.omega, out);
    release_thread();
  }

  void render_geometry(const World& world, std::span<const View> views,
                       std::span<RenderedView* const> out) {
    if (views.size() != out.size()) {
      throw std::invalid_argument("Renderer::render_geometry: " + std::to_string(views.size()) +
                                  " views but " + std::to_string(out.size()) + " outputs");
    }
    make_current();
    glUseProgram(geometry_program);
    set_bodies(world);
    // A submission per run of views of the same size (a world's cameras usually all are), of
    // at most kMaxViewsPerSubmission views and kLayerBytes.
    for (std::size_t first = 0; first < views.size();) {
      const CameraSpec& camera = views[first].camera;
      const std::size_t layer_bytes = kLayerBytesPerPixel *
                                      static_cast<std::size_t>(camera.width_px) *
                                      static_cast<std::size_t>(camera.height_px);
      const std::size_t last =
          first + std::clamp(kLayerBytes / layer_bytes, std::size_t{1}, kMaxViewsPerSubmission);
      std::size_t end = first + 1;
      while (end < views.size() && end < last && views[end].camera.width_px == camera.width_px &&
             views[end].camera.height_px == camera.height_px) {
        ++end;
      }
      draw_layers(world, views.subspan(first, end - first), out.subspan(first, end - first));
      first = end;
    }
    release_thread();
  }

  // The lit scene: colour, shaded by the sun (with its shadow map) and the point lights, beside
  // the geometry channels.
  void draw_lit(const World& world, const View& view, const CameraPose& pose) {
    const WorldSpec& spec = world.spec();
    const Lighting& lighting = spec.lighting;
    const float sky_light =
        lighting.ambient + (lighting.sun ? 0.6F * lighting.sun->intensity : 0.0F);
    const std::array<float, 4> sky = {std::min(1.0F, 0.55F * sky_light),
                                      std::min(1.0F, 0.7F * sky_light),
                                      std::min(1.0F, 0.9F * sky_light), 1.0F};
    glClearBufferfv(GL_COLOR, 0, sky.data());

    glUseProgram(scene_program);
    glUniformMatrix4fv(scene.world_to_camera, 1, GL_FALSE, pose.world_to_camera.data());
    glUniformMatrix4fv(scene.projection, 1, GL_FALSE, pose.projection.data());
    glUniformMatrix4fv(scene.light_view_projection, 1, GL_FALSE, light_view_projection.data());
    glUniform3f(scene.camera_omega, static_cast<float>(pose.omega.x()),
                static_cast<float>(pose.omega.y()), static_cast<float>(pose.omega.z()));
    glUniform1f(scene.ambient, lighting.ambient);
    if (lighting.sun) {
      const SunLight& sun = *lighting.sun;
      glUniform3f(scene.sun_direction,
                  static_cast<float>(std::cos(sun.elevation_rad) * std::cos(sun.azimuth_rad)),
                  static_cast<float>(std::cos(sun.elevation_rad) * std::sin(sun.azimuth_rad)),
                  static_cast<float>(std::sin(sun.elevation_rad)));
      glUniform1f(scene.sun_intensity, sun.intensity);
      glUniform1i(scene.sun_shadows, sun.shadows ? 1 : 0);
    } else {
      glUniform1f(scene.sun_intensity, 0.0F);
      glUniform1i(scene.sun_shadows, 0);
    }
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, shadow_texture);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, noise_texture_id);
    upload_points(world);

    auto draw = [&](const Mesh& mesh, const Eigen::Matrix4f& model, const Material& material,
                    std::int32_t id, const Eigen::Vector3d& velocity) {
      const Eigen::Matrix3f normal = model.block<3, 3>(0, 0).inverse().transpose();
      const Eigen::Vector3f relative =
          (pose.rotation * (velocity - pose.velocity_mps)).cast<float>();
      glUniformMatrix4fv(scene.model, 1, GL_FALSE, model.data());
      glUniformMatrix3fv(scene.normal_matrix, 1, GL_FALSE, normal.data());
      glUniform1i(scene.id, id);
      glUniform3f(scene.relative_velocity, relative.x(), relative.y(), relative.z());
      set_material(material);
      mesh.draw();
    };
    collect_items(world, view.self);
    const BodyDetail detail(pose.projection, pose.world_to_camera, view.intrinsics());
    for (const DrawItem& item : items) {
      if (item.hidden || item.gone) {
        continue;
      }
      if (const std::optional<std::size_t> level = detail.level(item)) {
        const Mesh& mesh = item.shape == Solid::Shape::box ? box : cylinders[*level];
        draw(mesh, item.model, item.material, item.id, item.velocity_mps);
      }
    }
    // The ground last: the depth test then skips shading it behind everything else.
    draw(ground, ground_model(world, view), spec.ground, servo::kGroundId, Eigen::Vector3d::Zero());
  }

  static void set_view_state(const base::CameraIntrinsics& k) {
    glViewport(0, 0, k.width_px, k.height_px);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    // Every shape is closed and convex with its triangles counter-clockwise seen from outside:
    // a face seen from behind is hidden by the shape's own front, and drawing it is wasted. The
    // projection keeps the optical frame's y down, a mirror image of OpenGL's window, where the
    // front faces are therefore clockwise.
    glEnable(GL_CULL_FACE);
    glFrontFace(GL_CW);
  }

  // Draw buffers 1–3 (ids, flow, depth) and the depth buffer of the bound framebuffer, as a view
  // of nothing but sky.
  static void clear_geometry() {
    const std::array<GLint, 4> no_id = {servo::kSkyId, 0, 0, 0};
    const std::array<float, 4> zero = {0, 0, 0, 0};
    const std::array<float, 4> infinite = {std::numeric_limits<float>::infinity(), 0, 0, 0};
    const float far_depth = 1.0F;
    glClearBufferiv(GL_COLOR, 1, no_id.data());
    glClearBufferfv(GL_COLOR, 2, zero.data());
    glClearBufferfv(GL_COLOR, 3, infinite.data());
    glClearBufferfv(GL_DEPTH, 0, &far_depth);
  }

  // The layered textures for `count` views of width × height. They only grow in layers at a
  // size, so that submissions of fewer views (agents that reached their goals) reuse them.
  void resize_layers(int width, int height, int count) {
    if (width == layers_width && height == layers_height && count <= layer_count) {
      return;
    }
    if (layer_textures[0] != 0) {
      glDeleteTextures(static_cast<GLsizei>(layer_textures.size()), layer_textures.data());
    }
    glGenTextures(static_cast<GLsizei>(layer_textures.size()), layer_textures.data());
    const std::array<std::array<GLenum, 3>, 4> formats = {
        {{GL_R32I, GL_RED_INTEGER, GL_INT},
         {GL_RG32F, GL_RG, GL_FLOAT},
         {GL_R32F, GL_RED, GL_FLOAT},
         {GL_DEPTH_COMPONENT24, GL_DEPTH_COMPONENT, GL_FLOAT}}};
    glBindFramebuffer(GL_FRAMEBUFFER, layered_fbo);
    for (std::size_t k = 0; k < layer_textures.size(); ++k) {
      glBindTexture(GL_TEXTURE_2D_ARRAY, layer_textures[k]);
      glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, static_cast<GLint>(formats[k][0]), width, height, count,
                   0, formats[k][1], formats[k][2], nullptr);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAX_LEVEL, 0);
      glFramebufferTexture(GL_FRAMEBUFFER, layer_attachment(k), layer_textures[k], 0);
    }
    set_geometry_draw_buffers();
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      throw std::runtime_error("OpenGL: the layered " + std::to_string(width) + "x" +
                               std::to_string(height) + "x" + std::to_string(count) +
                               " framebuffer is incomplete");
    }
    check_gl("allocating the layered framebuffer");
    layers_width = width;
    layers_height = height;
    layer_count = count;
  }

  // The layer textures' attachments: ids, flow and depth at 1–3, as in the lit framebuffer.
  static GLenum layer_attachment(std::size_t texture) {
    return texture < 3 ? GL_COLOR_ATTACHMENT1 + static_cast<GLenum>(texture) : GL_DEPTH_ATTACHMENT;
  }

  static void set_geometry_draw_buffers() {
    const GLenum draw_buffers[] = {GL_NONE, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2,
                                   GL_COLOR_ATTACHMENT3};
    glDrawBuffers(4, draw_buffers);
  }

  // Binds the framebuffer of layer `layer` alone.
  void bind_layer(int layer) {
    glBindFramebuffer(GL_FRAMEBUFFER, layer_fbo);
    for (std::size_t k = 0; k < layer_textures.size(); ++k) {
      glFramebufferTextureLayer(GL_FRAMEBUFFER, layer_attachment(k), layer_textures[k], 0, layer);
    }
    set_geometry_draw_buffers();
  }

  // Ids, flow and depth of views of one size, for synthetic perception: no lights, no shadow map,
  // no texture. A draw per view, into the layered framebuffer or into its layer's own.
  void draw_layers(const World& world, std::span<const View> views,
                   std::span<RenderedView* const> out) {
    const base::CameraIntrinsics k = views.front().intrinsics();
    const auto count = static_cast<int>(views.size());
    resize_layers(k.width_px, k.height_px, count);
    set_view_state(k);
    set_views(world, views, k);
    if (layered) {
      glBindFramebuffer(GL_FRAMEBUFFER, layered_fbo);
      clear_geometry();
    }
    for (int v = 0; v < count; ++v) {
      if (!layered) {
        bind_layer(v);
        clear_geometry();
      }
      glUniform1i(geometry.view, v);
      batch.draw(static_cast<std::size_t>(v));
    }
    check_gl("rendering the views");
    for (int v = 0; v < count; ++v) {
      const View& view = views[static_cast<std::size_t>(v)];
      bind_layer(v);
      RenderedView& target = *out[static_cast<std::size_t>(v)];
      read_geometry(k, servo::camera_angular_velocity(view.turn_rate, view.camera.pitch_rad),
                    target);
      target.image.release();
    }
  }

  // The batch's bodies as the world now has them, in the lit scene's order, the ground last:
  // their shapes once per world, their poses once per call of render_geometry.
  void set_bodies(const World& world) {
    collect_items(world, std::nullopt);
    if (batch.world_serial != world.serial()) {
      batch_shapes.clear();
      for (const DrawItem& item : items) {
        batch_shapes.push_back(item.shape == Solid::Shape::box
                                   ? std::span<const Shape>(&box_positions, 1)
                                   : std::span<const Shape>(cylinder_positions));
      }
      batch_shapes.emplace_back(&ground_positions, 1);
      batch.build(world.serial(), batch_shapes);
    }
    batch.upload_bodies(items);
    glUniform1i(geometry.body_count, static_cast<GLint>(items.size() + 1));
  }

  // A submission's views: per view its camera and what it sees of each body set_bodies holds.
  void set_views(const World& world, std::span<const View> views, const base::CameraIntrinsics& k) {
    batch.clear_views();
    for (const View& view : views) {
      const CameraPose pose = camera_pose(view, k);
      batch.add_view(pose.world_to_camera, pose.projection, ground_model(world, view), pose.omega);
      const BodyDetail detail(pose.projection, pose.world_to_camera, k);
      auto relative = [&pose](const Eigen::Vector3d& velocity) {
        return (pose.rotation * (velocity - pose.velocity_mps)).cast<float>().eval();
      };
      for (std::size_t body = 0; body < items.size(); ++body) {
        const DrawItem& item = items[body];
        const bool own_body = view.self && item.id == agent_render_id(*view.self);
        batch.add_body(body, relative(item.velocity_mps), item.id,
                       own_body || item.gone ? std::nullopt : detail.level(item));
      }
      batch.add_body(items.size(), relative(Eigen::Vector3d::Zero()), servo::kGroundId, 0);
    }
    batch.upload_views();
  }

  static Eigen::Matrix4f ground_model(const World& world, const View& view) {
    const double size = world.spec().ground_size_m;
    return model_matrix(view.position_m, 0.0, {size, size, 1.0});
  }

  // The geometry channels from the bound framebuffer's attachments 1–3; the sky, at infinite
  // depth, gets the flow of the camera's rotation alone.
  static void read_geometry(const base::CameraIntrinsics& k, const Eigen::Vector3d& omega,
                            RenderedView& out) {
    out.object_ids.create(k.height_px, k.width_px, CV_32SC1);
    out.flow.create(k.height_px, k.width_px, CV_32FC2);
    out.depth_m.create(k.height_px, k.width_px, CV_32FC1);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, k.width_px, k.height_px, GL_RED_INTEGER, GL_INT, out.object_ids.data);
    glReadBuffer(GL_COLOR_ATTACHMENT2);
    glReadPixels(0, 0, k.width_px, k.height_px, GL_RG, GL_FLOAT, out.flow.data);
    glReadBuffer(GL_COLOR_ATTACHMENT3);
    glReadPixels(0, 0, k.width_px, k.height_px, GL_RED, GL_FLOAT, out.depth_m.data);
    check_gl("reading the view back");
    for (int row = 0; row < k.height_px; ++row) {
      const auto* ids = out.object_ids.ptr<std::int32_t>(row);
      auto* flow = out.flow.ptr<cv::Vec2f>(row);
      const double y = (row - k.cy_px) / k.fy_px;
      for (int col = 0; col < k.width_px; ++col) {
        if (ids[col] == servo::kSkyId) {
          const Eigen::Vector2d r = servo::rotational_flow((col - k.cx_px) / k.fx_px, y, omega);
          flow[col] = cv::Vec2f(static_cast<float>(r.x()), static_cast<float>(r.y()));
        }
      }
    }
  }
};

void rasterize_on_calling_threads() {
  setenv("LP_NUM_THREADS", "0", 0);
}

View View::of_agent(const World& world, std::size_t agent) {
  const AgentState& s = world.agents().at(agent);
  View v;
  v.position_m = s.position_m;
  v.yaw_rad = s.yaw_rad;
  v.speed_mps = s.speed_mps;
  v.turn_rate = s.turn_rate;
  v.camera = world.spec().agents[agent].camera;
  v.self = agent;
  return v;
}

base::CameraIntrinsics View::intrinsics() const {
  return base::CameraIntrinsics::from_horizontal_fov(camera.width_px, camera.height_px,
                                                     camera.hfov_rad);
}

std::unique_ptr<Renderer> Renderer::create(ViewSubmission submission) {
  auto impl = std::make_unique<Impl>();
  impl->open_display();
  impl->create_context();
  impl->create_resources(submission);
  eglReleaseThread();
  return std::unique_ptr<Renderer>(new Renderer(std::move(impl)));
}

Renderer::Renderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Renderer::~Renderer() = default;

void Renderer::render(const World& world, const View& view, RenderedView& out,
                      RenderChannels channels) {
  impl_->render(world, view, channels, out);
  if (channels == RenderChannels::all) {
    // Seeded by the world's step, not a counter of this renderer's: a run's pixels do not depend
    // on which thread's renderer drew them.
    const auto step = std::llround(world.time_s() / world.spec().step_s);
    add_camera_noise(out.image, view.camera.noise_sigma_levels, camera_noise_seed(view.self, step));
  }
}

void Renderer::render_geometry(const World& world, std::span<const View> views,
                               std::span<RenderedView* const> out) {
  impl_->render_geometry(world, views, out);
}

const std::string& Renderer::description() const {
  return impl_->description;
}

}  // namespace flowsteer::sim_camera
