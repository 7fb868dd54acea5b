#version 460
#extension GL_GOOGLE_include_directive : require
// The shadow term into an output image of this storage format.
#define HOST_OUTPUT_FORMAT r16f
#include "shadows/host_output.glsl"
