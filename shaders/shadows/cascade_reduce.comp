#version 460
#extension GL_GOOGLE_include_directive : require
#include "cascades.h"
layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform Push { CascadeMaskPush push; };
layout(set = 0, binding = CASCADE_REDUCE_BINDING_SRC, r32ui) readonly uniform uimage2DArray src;
layout(set = 0, binding = CASCADE_REDUCE_BINDING_DST, r32ui) writeonly uniform uimage2DArray dst;

// One mip level of a mask chain. Each texel combines the 2x2 source texels it covers: readers take
// every texel their kernel footprint overlaps at the chosen level, so no wider dilation is needed.
void main() {
  ivec3 id = ivec3(gl_GlobalInvocationID);
  if (id.x >= int(push.dst_size) || id.y >= int(push.dst_size) || id.z >= int(push.cascades)) return;
  uint edge = 0u;
  uint lo = 0xffffu, hi = 0u;
  for (int i = 0; i < 4; ++i) {
    ivec2 t = min(id.xy * 2 + ivec2(i & 1, i >> 1), ivec2(int(push.src_size) - 1));
    uint v = imageLoad(src, ivec3(t, id.z)).r;
    edge = max(edge, v);
    lo = min(lo, v >> 16u);
    hi = max(hi, v & 0xffffu);
  }
  imageStore(dst, id, uvec4(push.depth_extent != 0u ? ((lo << 16u) | hi) : edge));
}
