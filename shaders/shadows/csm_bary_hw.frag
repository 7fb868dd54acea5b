#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_fragment_shader_barycentric : require
#include "izb.h"
#include "csm.h"

// The barycentric test with the hardware's barycentrics: the corners' values follow from the
// centre's and their screen derivatives (exact: orthographic, so barycentrics are linear).
void main() {
  vec3 b = gl_BaryCoordNoPerspEXT;
  vec3 dx = dFdx(b);
  vec3 dy = dFdy(b);
  float z = gl_FragCoord.z;
  float dzx = dFdx(z);
  float dzy = dFdy(z);
  for (int i = 0; i < 4; ++i) {
    vec2 o = vec2((i & 1) != 0 ? 0.5 : -0.5, (i & 2) != 0 ? 0.5 : -0.5);
    vec3 w = b + dx * o.x + dy * o.y;
    if (any(lessThan(w, vec3(kCsmBarycentricSlack)))) discard;
  }
  gl_FragDepth = clamp(z + 0.5 * (abs(dzx) + abs(dzy)), 0.0, 1.0);
}
