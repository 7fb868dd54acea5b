#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"

// Each texel's farthest node depth becomes the depth the trace's early test compares against
// (0 for an empty texel: nothing can pass).
void main() {
  ivec2 texel = ivec2(gl_FragCoord.xy);
  gl_FragDepth = uintBitsToFloat(farthest[texel_index(texel)]);
}
