#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 64) in;

layout(set = 0, binding = IZB_BINDING_SOFT_TERM, r32f) uniform image2D soft_term;
layout(set = 0, binding = IZB_BINDING_HYBRID_LIST) readonly buffer HybridList { uvec4 hybrid_list[]; };

// Hybrid, last step where the IZB's range is limited: each pixel the resolve listed mixes the IZB's
// term (in the shadow term) toward the cascades' (in the soft term) by the fade at the IZB's range.
// It then marks the pixel unfiltered (-1) again, so the soft term is -1 wherever the next frame's
// cascades do not write, which their blur needs, without a frame-sized clear or store.
void main() {
  uint count = counters[IZB_COUNTER_HYBRID];
  for (uint k = 0u; k < 4u; ++k) {
    uint entry = (gl_WorkGroupID.x * gl_WorkGroupSize.x + gl_LocalInvocationIndex) * 4u + k;
    if (entry >= count) break;
    uvec4 e = hybrid_list[entry];
    ivec2 pixel = ivec2(e.x & 0xffffu, e.x >> 16u);
    float hard = imageLoad(shadow_term, pixel).r;
    float soft = imageLoad(soft_term, pixel).r;
    imageStore(shadow_term, pixel, vec4(mix(hard, soft, uintBitsToFloat(e.z))));
    imageStore(soft_term, pixel, vec4(-1.0));
  }
}
