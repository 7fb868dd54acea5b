#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 8, local_size_y = 8) in;

// List-length statistics over the light grid: longest list, total nodes, non-empty texels.
void main() {
  uvec2 t = gl_GlobalInvocationID.xy;
  uint res = izb_resolution();
  uint length = all(lessThan(t, uvec2(res))) ? list_length(t.y * res + t.x, 0xffffffffu) : 0u;
  uint longest = subgroupMax(length);
  uint sum = subgroupAdd(length);
  uint nonempty = subgroupAdd(length > 0u ? 1u : 0u);
  if (subgroupElect() && sum > 0u) {
    atomicMax(counters[IZB_COUNTER_LIST_MAX], longest);
    atomicAdd(counters[IZB_COUNTER_LIST_SUM], sum);
    atomicAdd(counters[IZB_COUNTER_NONEMPTY], nonempty);
  }
}
