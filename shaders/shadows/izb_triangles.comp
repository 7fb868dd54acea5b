#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 64) in;

layout(push_constant) uniform Push { IzbComputePush push; };
#include "shadows/izb_triangles.glsl"

void main() { set_up_triangle_slot(row_dispatch_index(gl_WorkGroupID, gl_LocalInvocationIndex, 64u)); }
