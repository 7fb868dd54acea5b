#version 460
#extension GL_GOOGLE_include_directive : require
#include "frame.h"

layout(set = 0, binding = GBUFFER_BINDING_FRAME) uniform Frame { FrameUniforms frame; };
layout(set = 0, binding = GBUFFER_BINDING_VERTICES, std430) readonly buffer Vertices { float vertex_floats[]; };
layout(set = 0, binding = GBUFFER_BINDING_INDICES, std430) readonly buffer Indices { uint indices[]; };
layout(push_constant) uniform Push { DrawPush draw; };

layout(location = 0) in vec3 in_world_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec4 out_albedo;
layout(location = 1) out vec4 out_normal;
layout(location = 2) out vec4 out_geometric_normal;

vec3 fetch_world_position(uint corner) {
  uint v = uint(int(indices[draw.first_index + 3u * uint(gl_PrimitiveID) + corner]) + draw.vertex_offset);
  vec3 p = vec3(vertex_floats[v * kVertexFloats], vertex_floats[v * kVertexFloats + 1u],
                vertex_floats[v * kVertexFloats + 2u]);
  return (draw.model * vec4(p, 1.0)).xyz;
}

void main() {
  if ((draw.flags & DRAW_FLAG_ALPHA_MASK) != 0u && draw.base_color.a < draw.alpha_cutoff) discard;
  // The exact plane of the triangle, from its vertices: derivatives of the interpolated position
  // would be noisy, and the 32-sample footprint needs the true plane.
  vec3 p0 = fetch_world_position(0u);
  vec3 p1 = fetch_world_position(1u);
  vec3 p2 = fetch_world_position(2u);
  vec3 geometric = cross(p1 - p0, p2 - p0);
  float len = length(geometric);
  geometric = len > 0.0 ? geometric / len : normalize(in_normal);
  vec3 to_camera = frame.camera_position.xyz - in_world_position;
  if (dot(geometric, to_camera) < 0.0) geometric = -geometric;
  vec3 shading = normalize(in_normal);
  if (dot(shading, geometric) < 0.0) shading = -shading;

  float receives = (draw.flags & DRAW_FLAG_RECEIVES_SHADOW) != 0u ? 1.0 : 0.0;
  out_albedo = vec4(draw.base_color.rgb, receives);
  out_normal = vec4(shading, 1.0);
  out_geometric_normal = vec4(geometric, 1.0);
}
