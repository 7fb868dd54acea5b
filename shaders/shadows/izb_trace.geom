#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"

// Software conservative rasterization: each triangle becomes the quad of whole texels covering its
// grid-space bounds; the fragment shader then keeps exactly the texels the triangle touches.
layout(triangles) in;
layout(triangle_strip, max_vertices = 4) out;

void main() {
  float res = float(izb_resolution());
  vec2 g0 = (gl_in[0].gl_Position.xy * 0.5 + 0.5) * res;
  vec2 g1 = (gl_in[1].gl_Position.xy * 0.5 + 0.5) * res;
  vec2 g2 = (gl_in[2].gl_Position.xy * 0.5 + 0.5) * res;
  float area = (g1.x - g0.x) * (g2.y - g0.y) - (g2.x - g0.x) * (g1.y - g0.y);
  if (abs(area) < 1.0e-10) return;  // edge-on to the light: occludes no ray of positive length
  vec2 lo = floor(min(min(g0, g1), g2));
  vec2 hi = floor(max(max(g0, g1), g2)) + 1.0;
  lo = max(lo, vec2(0.0));
  hi = min(hi, vec2(res));
  if (any(greaterThanEqual(lo, hi))) return;
  vec2 nlo = lo / res * 2.0 - 1.0;
  vec2 nhi = hi / res * 2.0 - 1.0;
  vec2 corners[4] = vec2[4](vec2(nlo.x, nlo.y), vec2(nhi.x, nlo.y), vec2(nlo.x, nhi.y), vec2(nhi.x, nhi.y));
  for (int i = 0; i < 4; ++i) {
    gl_Position = vec4(corners[i], 0.5, 1.0);
    gl_PrimitiveID = gl_PrimitiveIDIn;
    EmitVertex();
  }
  EndPrimitive();
}
