// Push constants and bindings of the ray-traced ("rt") technique, shared by C++ and GLSL.
#ifndef RAY_TRACED_H
#define RAY_TRACED_H
#include "shared_prelude.h"

SHARED_BEGIN

struct RayTracedPush {
  mat4 inverse_view_projection;  // NDC -> world, for the μQuad corners (32 samples per pixel)
  // xyz: the direction light travels (unit; a spot light: the way it shines; a point light: unused);
  // w: the light's size (area_light.h): the sun's tangent of its angular radius, a spot or point
  // light's radius in world units; read only with rays over the light (extent.w).
  vec4 light_direction;
  vec4 light_position;           // xyz: a spot or point light's position; w: its range (0: the sun)
  vec4 light_cone;               // x: cosine of a spot light's outer cone (a point light: -1); yzw: the camera's position
  // xy: render size; z: samples per pixel (1 or 32); w: bit 0 set = count rays, bits 1 and up: the
  // rays over the light a pixel traces at 1 sample per pixel (0: one ray toward its centre).
  uvec4 extent;
};

// RayTracedPush::extent.w: the statistics flag and the count of rays over the light above it.
SHARED_CONST uint RT_EXTENT_COUNT_RAYS = 1u;
SHARED_CONST uint RT_EXTENT_LIGHT_RAYS_SHIFT = 1u;

SHARED_CONST uint RT_BINDING_SCENE = 0u;
SHARED_CONST uint RT_BINDING_WORLD_POSITION = 1u;
SHARED_CONST uint RT_BINDING_GEOMETRIC_NORMAL = 2u;
SHARED_CONST uint RT_BINDING_ALBEDO = 3u;
SHARED_CONST uint RT_BINDING_SHADOW_TERM = 4u;
SHARED_CONST uint RT_BINDING_COUNTERS = 5u;
// The any-hit alpha test (rt_shadow.rahit): the scene's vertex and index buffers, one
// RayTracedInstance per top-level instance (its instanceCustomIndex), and the material textures.
SHARED_CONST uint RT_BINDING_VERTICES = 6u;
SHARED_CONST uint RT_BINDING_INDICES = 7u;
SHARED_CONST uint RT_BINDING_INSTANCES = 8u;
SHARED_CONST uint RT_BINDING_MATERIAL_TEXTURES = 9u;

// What the any-hit shader needs of an instance: where its mesh's triangles are and its alpha test.
struct RayTracedInstance {
  uint first_index;       // of the mesh in the scene index buffer
  int vertex_offset;
  uint base_color_texture;  // or kNoTexture
  uint alpha_threshold;   // engine::alpha_threshold; 0: opaque (the instance is then forced opaque)
};

SHARED_CONST uint RT_COUNTER_SHADING_POINTS = 0u;  // covered pixels
SHARED_CONST uint RT_COUNTER_CANDIDATES = 1u;      // covered, receiving, facing the light
SHARED_CONST uint RT_COUNTER_RAYS = 2u;            // shadow rays traced
SHARED_CONST uint RT_COUNTER_OCCLUDED = 3u;        // of which hit an occluder
SHARED_CONST uint RT_COUNTER_COUNT = 4u;

SHARED_END

#ifdef __cplusplus
static_assert(sizeof(gpu_shared::RayTracedPush) == 128);  // Vulkan's least push-constant limit
static_assert(sizeof(gpu_shared::RayTracedInstance) == 16);
#endif
#endif
