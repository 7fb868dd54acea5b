#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 256) in;

layout(push_constant) uniform Push { IzbComputePush push; };
layout(set = 0, binding = IZB_BINDING_BOUNDS_PARTIALS, std430) buffer BoundsPartials { vec4 bounds_partials[]; };
#include "shadows/izb_setup.glsl"

// IZB_FLAG_CPU_DEVICE: the light frustum's second step as a dispatch of its own.
void main() { set_up_frustum(); }
