// Structs and bindings of the shadow module's passes, shared by C++ and GLSL.
#ifndef SHADOWS_H
#define SHADOWS_H
#include "shared_prelude.h"

SHARED_BEGIN

// ---- Plain shadow map ("sm") ----
struct ShadowMapPush {
  mat4 model;
  mat4 light_view_projection;
};
struct ShadowMapResolveParams {
  mat4 light_view_projection;
  vec4 light_direction;  // xyz travel direction
  vec4 light_position;   // xyz: a spot light's position; w: its range (0: the sun)
  vec4 light_cone;       // x: cosine of the spot light's outer cone
  vec4 bias;             // x: constant depth bias; y: PCF radius in map texels (0: one tap)
  uvec4 extent;          // xy render size, zw map size
  vec4 camera_position;  // xyz (the shadow-ray offset, shadow_common.h)
};
SHARED_CONST uint SM_RESOLVE_BINDING_PARAMS = 0u;
SHARED_CONST uint SM_RESOLVE_BINDING_WORLD_POSITION = 1u;
SHARED_CONST uint SM_RESOLVE_BINDING_GEOMETRIC_NORMAL = 2u;
SHARED_CONST uint SM_RESOLVE_BINDING_SHADOW_MAP = 3u;
SHARED_CONST uint SM_RESOLVE_BINDING_SHADOW_TERM = 4u;
SHARED_CONST uint SM_RESOLVE_BINDING_RECEIVERS = 5u;  // RGBA8, a > 0.5: receives shadows

// ---- Alpha-tested casters in the shadow-map depth passes (sm, cascades) ----
struct AlphaDepthPush {
  mat4 model_view_projection;  // object -> light clip space
  uint base_color_texture;     // material texture index, or kNoTexture
  uint alpha_threshold;        // engine::alpha_threshold
  uint pad0, pad1;
};
SHARED_CONST uint ALPHA_DEPTH_BINDING_TEXTURES = 0u;

SHARED_END

#ifdef __cplusplus
static_assert(sizeof(gpu_shared::ShadowMapPush) == 128);
static_assert(sizeof(gpu_shared::AlphaDepthPush) == 80);
static_assert(sizeof(gpu_shared::ShadowMapResolveParams) == 64 + 96);
#endif
#endif
