#version 460
#extension GL_GOOGLE_include_directive : require
#include "csm.h"
layout(local_size_x = 64) in;  // kCsmMeasureGroupSize

layout(push_constant) uniform Push { CsmMeasurePush push; };
layout(std430, set = 0, binding = CSM_MEASURE_BINDING_VERTICES) readonly buffer Vertices { float vertices[]; };
layout(std430, set = 0, binding = CSM_MEASURE_BINDING_INDICES) readonly buffer Indices { uint indices[]; };
layout(std430, set = 0, binding = CSM_MEASURE_BINDING_JOBS) readonly buffer Jobs { CsmMeasureJob jobs[]; };
layout(std430, set = 0, binding = CSM_MEASURE_BINDING_PARTIALS) writeonly buffer Partials { vec2 partials[]; };

shared vec2 sums[64];

vec2 light_xy(CsmMeasureJob job, uint index) {
  uint v = uint(int(indices[index]) + job.vertex_offset) * 8u;
  vec4 world = job.world * vec4(vertices[v], vertices[v + 1u], vertices[v + 2u], 1.0);
  return (mat3(push.to_light) * world.xyz).xy;
}

// measure_csm_suitability (csm_pass.cpp) in float: per instance (y), its triangles strided over
// groups_per_job workgroups (x); each workgroup leaves its sums of the projected area and of the part
// at least a texel's circumradius inside the edges; the CPU adds them up.
void main() {
  CsmMeasureJob job = jobs[gl_WorkGroupID.y];
  vec2 sum = vec2(0.0);
  const uint stride = push.groups_per_job * 64u;
  for (uint t = gl_WorkGroupID.x * 64u + gl_LocalInvocationID.x; t < job.triangle_count; t += stride) {
    uint first = job.first_index + 3u * t;
    vec2 p0 = light_xy(job, first), p1 = light_xy(job, first + 1u), p2 = light_xy(job, first + 2u);
    float area = 0.5 * abs((p1.x - p0.x) * (p2.y - p0.y) - (p2.x - p0.x) * (p1.y - p0.y));
    float perimeter = length(p1 - p0) + length(p2 - p1) + length(p0 - p2);
    if (!(area > 0.0) || !(perimeter > 0.0)) continue;
    sum.x += area;
    // Shrinking a triangle by distance d scales it about its incentre by (r - d) / r.
    float inradius = 2.0 * area / perimeter;
    if (inradius > push.circumradius) {
      float scale = (inradius - push.circumradius) / inradius;
      sum.y += area * scale * scale;
    }
  }
  sums[gl_LocalInvocationID.x] = sum;
  barrier();
  for (uint width = 32u; width > 0u; width /= 2u) {
    if (gl_LocalInvocationID.x < width) sums[gl_LocalInvocationID.x] += sums[gl_LocalInvocationID.x + width];
    barrier();
  }
  if (gl_LocalInvocationID.x == 0u) partials[gl_WorkGroupID.y * push.groups_per_job + gl_WorkGroupID.x] = sums[0];
}
