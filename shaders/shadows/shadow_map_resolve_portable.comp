#version 460
#extension GL_GOOGLE_include_directive : require
// shadow_map_resolve.glsl for a device without subgroup arithmetic and ballot operations.
#define SHADOWS_WITHOUT_SUBGROUP_OPS
#include "shadows/shadow_map_resolve.glsl"
