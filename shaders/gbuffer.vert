#version 460
#extension GL_GOOGLE_include_directive : require
#include "frame.h"

// Drawn without an index buffer: vertex i of a draw is corner i % 3 of the mesh's triangle i / 3, read
// through the index buffer here. Each vertex also hands the fragment stage its whole triangle (world
// corners and normals, flat, so the provoking vertex's copy is used): the exact plane and the smooth
// terminator then cost a CPU rasterizer per-vertex work instead of nine buffer reads per fragment.
layout(set = 0, binding = GBUFFER_BINDING_FRAME) uniform Frame { FrameUniforms frame; };
layout(set = 0, binding = GBUFFER_BINDING_VERTICES, std430) readonly buffer Vertices { float vertex_floats[]; };
layout(set = 0, binding = GBUFFER_BINDING_INDICES, std430) readonly buffer Indices { uint indices[]; };
layout(push_constant) uniform Push { DrawPush draw; };

layout(location = 0) out vec3 out_world_position;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec2 out_uv;
layout(location = 3) flat out vec3 out_corners[3];         // world positions of the triangle's corners
layout(location = 6) flat out vec3 out_corner_normals[3];  // their world normals, not normalised

uint corner_vertex(uint corner) { return uint(int(indices[draw.first_index + corner]) + draw.vertex_offset); }

vec3 fetch_vec3(uint v, uint first) {
  uint base = v * kVertexFloats + first;
  return vec3(vertex_floats[base], vertex_floats[base + 1u], vertex_floats[base + 2u]);
}

void main() {
  mat3 normal_matrix = transpose(inverse(mat3(draw.model)));
  uint self = corner_vertex(uint(gl_VertexIndex));
  vec4 world = draw.model * vec4(fetch_vec3(self, 0u), 1.0);
  out_world_position = world.xyz;
  out_normal = normal_matrix * fetch_vec3(self, 3u);
  uint base = self * kVertexFloats;
  out_uv = vec2(vertex_floats[base + 6u], vertex_floats[base + 7u]);
  uint first = uint(gl_VertexIndex) - uint(gl_VertexIndex) % 3u;
  for (uint k = 0u; k < 3u; ++k) {
    uint v = corner_vertex(first + k);
    out_corners[k] = (draw.model * vec4(fetch_vec3(v, 0u), 1.0)).xyz;
    out_corner_normals[k] = normal_matrix * fetch_vec3(v, 3u);
  }
  gl_Position = frame.view_projection * world;
}
