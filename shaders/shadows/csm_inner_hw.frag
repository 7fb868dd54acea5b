#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_NV_conservative_raster_underestimation : require
#include "izb.h"
#include "csm.h"

// Underestimating conservative rasterization produces only fully covered texels; the depth bound
// comes from the plane's screen derivatives.
void main() {
  if (!gl_FragFullyCoveredNV) discard;
  float z = gl_FragCoord.z;
  gl_FragDepth = clamp(z + 0.5 * (abs(dFdx(z)) + abs(dFdy(z))), 0.0, 1.0);
}
