#pragma once

// GLSL 3.30 core sources of the renderer's programs. A fragment shader is compiled from
// kVersion, then kGeometryOutputs, then its own source: the lit scene writes its colour
// beside the geometry channels, the geometry program the channels alone.
namespace flowsteer::sim_camera::shaders {

inline constexpr const char* kVersion = "#version 330 core\n";

// The channels synthetic perception reads: the object's id, the flow and the depth.
// relative_velocity: the object's minus the camera's, optical frame, m/s.
// camera_omega: the camera's angular velocity, optical frame, rad/s.
inline constexpr const char* kGeometryOutputs = R"(
in vec3 v_camera;
layout(location = 1) out int o_id;
layout(location = 2) out vec2 o_flow;
layout(location = 3) out float o_depth;

void write_geometry(int id, vec3 relative_velocity, vec3 camera_omega) {
  o_id = id;
  // CGF Eq. 1 at the point seen through this pixel: translation over depth, plus rotation.
  float z = v_camera.z;
  vec2 p = v_camera.xy / z;
  vec3 v = relative_velocity;
  vec3 w = camera_omega;
  vec2 translation = vec2(v.x - p.x * v.z, v.y - p.y * v.z) / z;
  vec2 rotation = vec2(p.x * p.y * w.x - (1.0 + p.x * p.x) * w.y + p.y * w.z,
                       (1.0 + p.y * p.y) * w.x - p.x * p.y * w.y - p.x * w.z);
  o_flow = translation + rotation;
  o_depth = z;
}
)";

inline constexpr const char* kSceneVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
uniform mat4 u_model;
uniform mat3 u_normal_matrix;
uniform mat4 u_world_to_camera;  // to the optical frame: x right, y down, z forward
uniform mat4 u_projection;
uniform mat4 u_light_view_projection;
out vec3 v_world;
out vec3 v_normal;
out vec3 v_camera;
out vec4 v_light_clip;
void main() {
  vec4 world = u_model * vec4(a_position, 1.0);
  v_world = world.xyz;
  v_normal = u_normal_matrix * a_normal;
  v_camera = (u_world_to_camera * world).xyz;
  v_light_clip = u_light_view_projection * world;
  gl_Position = u_projection * vec4(v_camera, 1.0);
}
)";

inline constexpr const char* kSceneFragment = R"(
in vec3 v_world;
in vec3 v_normal;
in vec4 v_light_clip;
uniform vec3 u_albedo;
uniform int u_pattern;  // 0 plain, 1 checker, 2 noise, 3 stripes
uniform float u_pattern_scale;
uniform float u_pattern_contrast;
uniform int u_id;
uniform vec3 u_relative_velocity;  // object minus camera, optical frame, m/s
uniform vec3 u_camera_omega;       // the camera's angular velocity, optical frame, rad/s
uniform float u_ambient;
uniform vec3 u_sun_direction;  // towards the sun, world frame
uniform float u_sun_intensity;
uniform int u_sun_shadows;
uniform sampler2DShadow u_shadow_map;
uniform int u_point_count;
uniform vec3 u_point_position[8];  // kMaxPointLights
uniform float u_point_intensity[8];
uniform float u_point_range[8];
layout(location = 0) out vec4 o_color;

uniform sampler2D u_noise;  // tileable value noise, mipmapped

// The noise texture (several octaves already) projected along the surface's dominant axis.
float noise(vec3 p, vec3 n) {
  vec3 a = abs(n);
  vec2 uv = a.z > 0.5 ? p.xy : (a.x > a.y ? p.yz : p.xz);
  return texture(u_noise, uv * 0.125).r;
}

float pattern_value(vec3 w, vec3 n) {
  vec3 p = w / u_pattern_scale;
  if (u_pattern == 1) {
    return mod(floor(p.x) + floor(p.y) + floor(p.z), 2.0);
  }
  if (u_pattern == 2) {
    return noise(p, n);
  }
  if (u_pattern == 3) {
    return 0.7 * step(0.5, fract(p.z)) + 0.3 * noise(3.0 * p, n);
  }
  return 1.0;
}

float sun_visibility() {
  if (u_sun_shadows == 0) {
    return 1.0;
  }
  vec3 ndc = v_light_clip.xyz / v_light_clip.w;
  vec3 uvz = 0.5 * ndc + 0.5;
  if (any(lessThan(uvz.xy, vec2(0.0))) || any(greaterThan(uvz.xy, vec2(1.0)))) {
    return 1.0;
  }
  // One tap: with linear filtering the comparison is already blended over 2×2 texels.
  return texture(u_shadow_map, vec3(uvz.xy, uvz.z - 0.0015));
}

void main() {
  vec3 n = normalize(v_normal);
  float light = u_ambient;
  light += u_sun_intensity * max(dot(n, u_sun_direction), 0.0) * sun_visibility();
  for (int k = 0; k < u_point_count; ++k) {
    vec3 to_light = u_point_position[k] - v_world;
    float d = length(to_light);
    float falloff = clamp(1.0 - d / u_point_range[k], 0.0, 1.0);
    light += u_point_intensity[k] * falloff * falloff * max(dot(n, to_light / d), 0.0);
  }
  float texture_factor = 1.0 - u_pattern_contrast + u_pattern_contrast * pattern_value(v_world, n);
  vec3 linear = u_albedo * texture_factor * light;
  o_color = vec4(pow(clamp(linear, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
  write_geometry(u_id, u_relative_velocity, u_camera_omega);
}
)";

// Geometry only: no lights, no texture, no colour written. Every body is in one vertex buffer,
// each vertex naming its body; each view of a submission is one draw of the triangles it sees,
// its index u_view. Per view, the uniform block holds the camera and the ground's model matrix
// (the ground follows the camera); per body, a buffer texture holds its model matrix (four RGBA
// texels); per view and body, two more hold the body's velocity relative to the camera and its
// id. Compiled after "#version", the definition of MAX_VIEWS (the most views of a submission)
// and, where the views of a submission are drawn into the layers of one framebuffer, that of
// LAYERED: the view then chooses its layer; without it each view is drawn into a framebuffer of
// its layer alone.
inline constexpr const char* kGeometryVertex = R"(
#ifdef LAYERED
#extension GL_ARB_shader_viewport_layer_array : require
#endif
layout(location = 0) in vec3 a_position;
layout(location = 1) in int a_body;
struct Camera {
  mat4 world_to_camera;  // to the optical frame: x right, y down, z forward
  mat4 projection;
  mat4 ground_model;
  vec4 omega;  // the camera's angular velocity, optical frame, rad/s
};
layout(std140) uniform Cameras { Camera u_cameras[MAX_VIEWS]; };
uniform samplerBuffer u_models;
uniform samplerBuffer u_velocities;
uniform isamplerBuffer u_ids;
uniform int u_body_count;  // the ground last
uniform int u_view;
out vec3 v_camera;
flat out int v_id;
flat out vec3 v_relative_velocity;
flat out vec3 v_camera_omega;

void main() {
#ifdef LAYERED
  gl_Layer = u_view;
#endif
  int seen = u_view * u_body_count + a_body;
  v_id = texelFetch(u_ids, seen).r;
  v_relative_velocity = texelFetch(u_velocities, seen).xyz;
  v_camera_omega = u_cameras[u_view].omega.xyz;
  int texel = 4 * a_body;
  mat4 model = a_body == u_body_count - 1
                   ? u_cameras[u_view].ground_model
                   : mat4(texelFetch(u_models, texel), texelFetch(u_models, texel + 1),
                          texelFetch(u_models, texel + 2), texelFetch(u_models, texel + 3));
  // As the scene program computes it, so that both give the same channels to the last bit.
  vec4 world = model * vec4(a_position, 1.0);
  v_camera = (u_cameras[u_view].world_to_camera * world).xyz;
  gl_Position = u_cameras[u_view].projection * vec4(v_camera, 1.0);
}
)";

inline constexpr const char* kGeometryFragment = R"(
flat in int v_id;
flat in vec3 v_relative_velocity;
flat in vec3 v_camera_omega;
void main() { write_geometry(v_id, v_relative_velocity, v_camera_omega); }
)";

inline constexpr const char* kShadowVertex = R"(#version 330 core
layout(location = 0) in vec3 a_position;
uniform mat4 u_model;
uniform mat4 u_light_view_projection;
void main() { gl_Position = u_light_view_projection * u_model * vec4(a_position, 1.0); }
)";

inline constexpr const char* kShadowFragment = R"(#version 330 core
void main() {}
)";

}  // namespace flowsteer::sim_camera::shaders
