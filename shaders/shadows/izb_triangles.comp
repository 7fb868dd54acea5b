#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 64) in;

layout(push_constant) uniform Push { IzbComputePush push; };
#include "shadows/izb_triangles.glsl"

void main() {
  uint slot = row_dispatch_index(gl_WorkGroupID, gl_LocalInvocationIndex, 64u);
  bool in_range = slot < counters[IZB_COUNTER_FRUSTUM_TRIANGLES];
  uint t = in_range ? frustum_triangle(slot) : 0u;
  bool listed = false;
  if (in_range) listed = set_up_triangle(t);
  list_triangle(listed, t);
}
