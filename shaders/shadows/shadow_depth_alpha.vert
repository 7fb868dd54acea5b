#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows.h"
layout(push_constant) uniform Push { AlphaDepthPush push; };
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 0) out vec2 out_uv;
void main() {
  out_uv = in_uv;
  gl_Position = push.model_view_projection * vec4(in_position, 1.0);
}
