#version 460
#extension GL_GOOGLE_include_directive : require
// host_inputs.glsl for a device without subgroup ballot.
#define SHADOWS_WITHOUT_SUBGROUP_OPS
#include "shadows/host_inputs.glsl"
