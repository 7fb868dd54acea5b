#version 460
#extension GL_GOOGLE_include_directive : require
#include "izb.h"
layout(local_size_x = 64) in;

// One caster draw's world-space triangles from the module's geometry buffers, for meshes the client
// registered on the GPU only (no CPU copy to build them from).
layout(std430, set = 0, binding = 0) readonly buffer Vertices { float vertices[]; };  // 8 floats: position, normal, uv
layout(std430, set = 0, binding = 1) readonly buffer Indices { uint indices[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Casters { IzbCasterTriangle casters[]; };
layout(push_constant) uniform Push {
  mat4 world;
  uvec4 range;     // first index, vertex offset, triangle count, first destination triangle
  uvec4 material;  // draw ordinal, alpha threshold, base-colour texture
};

void main() {
  uint t = gl_GlobalInvocationID.x;
  if (t >= range.z) return;
  vec3 p[3];
  vec2 uv[3];
  for (uint c = 0u; c < 3u; ++c) {
    uint v = (indices[range.x + 3u * t + c] + range.y) * 8u;
    p[c] = (world * vec4(vertices[v], vertices[v + 1u], vertices[v + 2u], 1.0)).xyz;
    uv[c] = vec2(vertices[v + 6u], vertices[v + 7u]);
  }
  IzbCasterTriangle tri;
  tri.p0 = vec4(p[0], uintBitsToFloat(material.x));
  tri.p1 = vec4(p[1], uintBitsToFloat(material.y));
  tri.p2 = vec4(p[2], uintBitsToFloat(material.z));
  tri.uv01 = vec4(uv[0], uv[1]);
  tri.uv2 = vec4(uv[2], 0.0, 0.0);
  casters[range.w + t] = tri;
}
