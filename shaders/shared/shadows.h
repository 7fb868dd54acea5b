// Structs and bindings of the shadow module's passes, shared by C++ and GLSL.
#ifndef SHADOWS_H
#define SHADOWS_H
#include "shared_prelude.h"
#include "light_tiles.h"

SHARED_BEGIN

// ---- Plain shadow map ("sm") ----
struct ShadowMapPush {
  mat4 model;
  mat4 light_view_projection;
};
// The widest PCSS blocker search and filter radius (pcss.glsl) of sm and cascades, in map texels along
// the finer axis: wider, 16 search taps would be too sparse to find thin occluders. Penumbrae wider
// than this are clamped to it.
SHARED_CONST float kPcssMaxTexels = 32.0f;

struct ShadowMapResolveParams {
  mat4 light_view_projection;
  vec4 light_direction;  // xyz travel direction
  vec4 light_position;   // xyz: a spot light's position; w: its range (0: the sun)
  vec4 light_cone;       // x: cosine of the spot light's outer cone; z: 1 for a point light's face, w its
                         // index (light_tiles.h's order)
  vec4 bias;             // x: constant depth bias; y: PCF radius in map texels (0: one tap)
  uvec4 extent;          // xy render size, zw map size
  vec4 camera_position;  // xyz (the shadow-ray offset, shadow_common.h)
  // PCSS (a light with a size; pcss.glsl's PcssMap): the transpose of light_view_projection's inverse
  // (receiver planes into the map); x the light's size (sun: tan of its angular radius; else its
  // radius), y an orthographic map's depth range (world units), zw a perspective map's near and far
  // planes; xy a texel's size in map units, z the widest search and filter radius in texels, w 1 for
  // a perspective map.
  mat4 light_plane_matrix;
  vec4 pcss;
  vec4 pcss_texel;
};
SHARED_CONST uint SM_RESOLVE_BINDING_PARAMS = 0u;
SHARED_CONST uint SM_RESOLVE_BINDING_WORLD_POSITION = 1u;
SHARED_CONST uint SM_RESOLVE_BINDING_GEOMETRIC_NORMAL = 2u;
SHARED_CONST uint SM_RESOLVE_BINDING_SHADOW_MAP = 3u;
SHARED_CONST uint SM_RESOLVE_BINDING_SHADOW_TERM = 4u;
SHARED_CONST uint SM_RESOLVE_BINDING_RECEIVERS = 5u;  // RGBA8, a > 0.5: receives shadows
SHARED_CONST uint SM_RESOLVE_BINDING_BLOCKS = 6u;     // kSmBlock² depth blocks' planes (shadow_map_blocks.comp)
SHARED_CONST uint SM_RESOLVE_BINDING_BLOCK_TEXELS = 10u;  // the same, as an RGBA32F texel buffer (a CPU device reads it)
SHARED_CONST uint SM_RESOLVE_BINDING_COUNTERS = 7u;   // SM_COUNTER_* (with stats)
SHARED_CONST uint SM_RESOLVE_BINDING_LIST = 8u;       // the CPU device's list of pixels to tap (SM_STAGE_*)
// A point light's faces (a spot light's one cone on a CPU device): the tiles each resolves
// (light_tiles.h, listed by shadow_map_tiles.comp).
SHARED_CONST uint SM_RESOLVE_BINDING_TILES = 9u;
// The resolve's passes (shadow_map_resolve.glsl's kStage): whole on a GPU; on a CPU device with
// masking, every pixel listing those whose PCSS taps must run, that list's dispatch, the listed taps.
SHARED_CONST uint SM_STAGE_WHOLE = 0u;
SHARED_CONST uint SM_STAGE_LIST = 1u;
SHARED_CONST uint SM_STAGE_LIST_DISPATCH = 2u;
SHARED_CONST uint SM_STAGE_LISTED = 3u;
// PCSS's masking in the sm resolve: the depth map in blocks of kSmBlock² texels, each with the plane
// that fits its depths and the largest distance of a depth from it (a vec4: the depth at the block's
// centre, the slopes along x and y per texel, that distance; shadow_map_blocks.comp).
SHARED_CONST uint kSmBlock = 8u;
// The resolve's counts, per frame (summed over a point light's faces): facing receivers it resolved
// with a light size, and those of them whose PCSS taps ran (the blocks did not settle them).
SHARED_CONST uint SM_COUNTER_FACING = 0u;
SHARED_CONST uint SM_COUNTER_TAPPED = 1u;
SHARED_CONST uint SM_COUNTER_WORDS = 4u;

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
static_assert(sizeof(gpu_shared::ShadowMapResolveParams) == 2 * 64 + 128);
#endif
#endif
