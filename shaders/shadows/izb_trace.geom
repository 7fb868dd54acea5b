#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"

// Software conservative rasterization: each triangle becomes the quad of whole texels covering its
// grid-space bounds; the fragment shader keeps exactly the texels the triangle touches. The quad's
// depth follows the triangle's plane, so the depth bias and early depth test act on it as they would
// on the triangle.
layout(triangles) in;
layout(triangle_strip, max_vertices = 4) out;

void main() {
  float res = float(izb_resolution());
  vec3 a = vec3((gl_in[0].gl_Position.xy * 0.5 + 0.5) * res, gl_in[0].gl_Position.z);
  vec3 b = vec3((gl_in[1].gl_Position.xy * 0.5 + 0.5) * res, gl_in[1].gl_Position.z);
  vec3 c = vec3((gl_in[2].gl_Position.xy * 0.5 + 0.5) * res, gl_in[2].gl_Position.z);
  float area = edge_fn(c.xy, a.xy, b.xy);
  if (abs(area) < 1.0e-10) return;  // edge-on to the light: occludes no ray of positive length
  vec2 lo = floor(min(min(a.xy, b.xy), c.xy));
  vec2 hi = floor(max(max(a.xy, b.xy), c.xy)) + 1.0;
  lo = max(lo, vec2(0.0));
  hi = min(hi, vec2(res));
  if (any(greaterThanEqual(lo, hi))) return;
  float dzdx = ((b.z - a.z) * (c.y - a.y) - (c.z - a.z) * (b.y - a.y)) / area;
  float dzdy = ((c.z - a.z) * (b.x - a.x) - (b.z - a.z) * (c.x - a.x)) / area;
  vec2 corners[4] = vec2[4](vec2(lo.x, lo.y), vec2(hi.x, lo.y), vec2(lo.x, hi.y), vec2(hi.x, hi.y));
  for (int i = 0; i < 4; ++i) {
    float z = a.z + dzdx * (corners[i].x - a.x) + dzdy * (corners[i].y - a.y);
    gl_Position = vec4(corners[i] / res * 2.0 - 1.0, z, 1.0);
    gl_PrimitiveID = gl_PrimitiveIDIn;
    EmitVertex();
  }
  EndPrimitive();
}
