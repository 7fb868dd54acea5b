#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_basic : require
#include "izb.h"
#include "csm.h"
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = CSM_BINDING_FRAME, std430) readonly buffer FrameBuffer { IzbFrame izb; };
layout(set = 0, binding = CSM_BINDING_COUNTERS, std430) buffer Counters { uint counters[]; };
layout(set = 0, binding = CSM_BINDING_DEPTH) uniform sampler2D csm_depth;

// Counts texels that hold a depth (some triangle covered them fully).
void main() {
  ivec2 t = ivec2(gl_GlobalInvocationID.xy);
  uint res = uint(izb.grid.x);
  uint covered = 0u;
  if (all(lessThan(uvec2(t), uvec2(res)))) covered = texelFetch(csm_depth, t, 0).r < 1.0 ? 1u : 0u;
  uint sum = subgroupAdd(covered);
  if (subgroupElect() && sum > 0u) atomicAdd(counters[CSM_COUNTER_TEXELS], sum);
}
