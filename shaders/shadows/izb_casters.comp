#version 460
#extension GL_GOOGLE_include_directive : require
#include "izb.h"
layout(local_size_x = 64) in;

layout(push_constant) uniform Push { IzbCastersPush push; };
// Read and written as words: the w components carry uint bits and the uvs are copied, never
// reinterpreted as floats (a denormal pattern would not survive a float move everywhere).
layout(std430, set = 0, binding = IZB_CASTERS_BINDING_VERTICES) readonly buffer Vertices { uint vertices[]; };
layout(std430, set = 0, binding = IZB_CASTERS_BINDING_INDICES) readonly buffer Indices { uint indices[]; };
layout(std430, set = 0, binding = IZB_CASTERS_BINDING_DRAWS) readonly buffer Draws { IzbCasterDraw draws[]; };
layout(std430, set = 0, binding = IZB_CASTERS_BINDING_TRIANGLES) writeonly buffer Triangles { uvec4 triangles[]; };

// glm's mat4 * vec4 with w = 1, operation for operation and unfused, so the triangles are the bits the
// CPU computes for the same matrix and vertex.
vec3 to_world(mat4 m, vec3 p) {
  precise vec3 a = m[0].xyz * p.x + m[1].xyz * p.y;
  precise vec3 b = m[2].xyz * p.z + m[3].xyz;
  precise vec3 w = a + b;
  return w;
}

// One thread per caster triangle: its draw by binary search over the draws' first triangles.
void main() {
  uint t = (gl_WorkGroupID.y * push.groups_x + gl_WorkGroupID.x) * 64u + gl_LocalInvocationID.x;
  if (t >= push.triangle_count) return;
  uint lo = 0u, hi = push.draw_count;  // the last draw whose first triangle is <= t
  while (hi - lo > 1u) {
    uint mid = (lo + hi) / 2u;
    if (draws[mid].first_triangle <= t) lo = mid;
    else hi = mid;
  }
  IzbCasterDraw d = draws[lo];
  uint first = d.first_index + 3u * (t - d.first_triangle);
  uint w[3] = uint[3](d.ordinal, d.alpha_threshold, d.texture);
  uvec2 uv[3];
  for (uint k = 0u; k < 3u; ++k) {
    uint v = uint(int(indices[first + k]) + d.vertex_offset) * 8u;
    vec3 p = vec3(uintBitsToFloat(vertices[v]), uintBitsToFloat(vertices[v + 1u]), uintBitsToFloat(vertices[v + 2u]));
    triangles[5u * t + k] = uvec4(floatBitsToUint(to_world(d.world, p)), w[k]);
    uv[k] = uvec2(vertices[v + 6u], vertices[v + 7u]);
  }
  triangles[5u * t + 3u] = uvec4(uv[0], uv[1]);
  triangles[5u * t + 4u] = uvec4(uv[2], 0u, 0u);
}
