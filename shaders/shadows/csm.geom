#version 460
#extension GL_GOOGLE_include_directive : require
#include "izb.h"
#include "csm.h"

// Hands each fragment its whole triangle in grid space (texels, light depth) so the fragment shader
// can test full coverage of its texel exactly.
layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;
layout(set = 0, binding = CSM_BINDING_FRAME, std430) readonly buffer FrameBuffer { IzbFrame izb; };

layout(location = 0) flat out vec3 out_a;
layout(location = 1) flat out vec3 out_b;
layout(location = 2) flat out vec3 out_c;

void main() {
  float res = izb.grid.x;
  vec3 g[3];
  for (int i = 0; i < 3; ++i) g[i] = vec3((gl_in[i].gl_Position.xy * 0.5 + 0.5) * res, gl_in[i].gl_Position.z);
  for (int i = 0; i < 3; ++i) {
    gl_Position = gl_in[i].gl_Position;
    out_a = g[0];
    out_b = g[1];
    out_c = g[2];
    EmitVertex();
  }
  EndPrimitive();
}
