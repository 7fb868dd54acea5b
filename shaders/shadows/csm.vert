#version 460
#extension GL_GOOGLE_include_directive : require
#include "izb.h"
#include "csm.h"

layout(set = 0, binding = CSM_BINDING_FRAME, std430) readonly buffer FrameBuffer { IzbFrame izb; };
layout(push_constant) uniform Push { IzbDrawPush draw; };
layout(location = 0) in vec3 in_position;

void main() { gl_Position = izb.light_view_projection * (draw.model * vec4(in_position, 1.0)); }
