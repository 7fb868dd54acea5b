// Push constants and bindings of the ray-traced ("rt") technique, shared by C++ and GLSL.
#ifndef RAY_TRACED_H
#define RAY_TRACED_H
#include "shared_prelude.h"

SHARED_BEGIN

struct RayTracedPush {
  mat4 inverse_view_projection;  // NDC -> world, for the μQuad corners (32 samples per pixel)
  vec4 light_direction;          // xyz: the direction light travels (unit)
  uvec4 extent;                  // xy: render size; z: samples per pixel (1 or 32); w: 1 = count rays
};

SHARED_CONST uint RT_BINDING_SCENE = 0u;
SHARED_CONST uint RT_BINDING_WORLD_POSITION = 1u;
SHARED_CONST uint RT_BINDING_GEOMETRIC_NORMAL = 2u;
SHARED_CONST uint RT_BINDING_ALBEDO = 3u;
SHARED_CONST uint RT_BINDING_SHADOW_TERM = 4u;
SHARED_CONST uint RT_BINDING_COUNTERS = 5u;

SHARED_CONST uint RT_COUNTER_SHADING_POINTS = 0u;  // covered pixels
SHARED_CONST uint RT_COUNTER_CANDIDATES = 1u;      // covered, receiving, facing the light
SHARED_CONST uint RT_COUNTER_RAYS = 2u;            // shadow rays traced
SHARED_CONST uint RT_COUNTER_OCCLUDED = 3u;        // of which hit an occluder
SHARED_CONST uint RT_COUNTER_COUNT = 4u;

SHARED_END

#ifdef __cplusplus
static_assert(sizeof(gpu_shared::RayTracedPush) == 96);
#endif
#endif
