#version 460
#extension GL_GOOGLE_include_directive : require
#include "izb.h"
#include "csm.h"

// Underestimating conservative rasterization generates only texels the triangle fully covers, so
// every fragment here is one; the depth bound comes from the plane's screen derivatives.
void main() {
  float z = gl_FragCoord.z;
  gl_FragDepth = clamp(z + 0.5 * (abs(dFdx(z)) + abs(dFdy(z))), 0.0, 1.0);
}
