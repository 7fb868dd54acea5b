#version 460
#extension GL_GOOGLE_include_directive : require
#include "cascades.h"
layout(push_constant) uniform Push { CascadeDepthPush push; };
layout(location = 0) in vec3 in_position;
void main() { gl_Position = push.light_view_projection * (push.model * vec4(in_position, 1.0)); }
