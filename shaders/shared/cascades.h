// Cascaded filtered shadow maps: structs, bindings and constants shared by C++ and GLSL.
#ifndef CASCADES_H
#define CASCADES_H
#include "shared_prelude.h"

SHARED_BEGIN

SHARED_CONST uint kMaxCascades = 4u;
SHARED_CONST uint kPoissonTaps = 12u;
SHARED_CONST uint kRotationTileSize = 32u;  // rotation texture is tiled over the screen

// 12 offsets in the unit disk, minimum spacing 0.47 (dart throwing, fixed seed).
#ifdef __cplusplus
inline constexpr vec2 kPoissonDisk[12] = {
#else
const vec2 kPoissonDisk[12] = vec2[12](
#endif
    vec2(-0.8475f, 0.1671f), vec2(0.2845f, 0.7622f), vec2(-0.2183f, -0.1384f), vec2(0.4637f, -0.1310f),
    vec2(0.8362f, 0.3996f), vec2(0.1858f, 0.3035f), vec2(-0.2741f, 0.4262f), vec2(-0.1529f, -0.6234f),
    vec2(0.9015f, -0.3691f), vec2(-0.6677f, -0.6579f), vec2(0.2504f, -0.8704f), vec2(-0.3691f, 0.8925f)
#ifdef __cplusplus
};
#else
);
#endif

// Mask modes (CascadeParams::mode.x), mirroring shadows::Masking.
SHARED_CONST uint CASCADE_MASKING_OFF = 0u;
SHARED_CONST uint CASCADE_MASKING_EDGE = 1u;
SHARED_CONST uint CASCADE_MASKING_DEPTH_EXTENT = 2u;
SHARED_CONST uint CASCADE_MASKING_PLANES = 3u;  // depth blocks' planes (depth_blocks.glsl): settles exactly, a mask level of kSmBlock texels

// Debug overlays (CascadeParams::mode.z).
SHARED_CONST uint CASCADE_DEBUG_NONE = 0u;
SHARED_CONST uint CASCADE_DEBUG_CASCADES = 1u;
SHARED_CONST uint CASCADE_DEBUG_EXPENSIVE = 2u;

// Counters in the host-readable stats buffer (uint indices), followed by indirect dispatch arguments.
SHARED_CONST uint CASCADE_COUNTER_EXPENSIVE = 0u;  // pixels that took the 12-tap path outside the kernel list (band
                                                   // stage; the classify stage where masking is off)
SHARED_CONST uint CASCADE_COUNTER_BLUR = 1u;       // flagged pixels appended to the blur list
SHARED_CONST uint CASCADE_COUNTER_FACING = 2u;     // covered pixels facing the light
SHARED_CONST uint CASCADE_COUNTER_KERNEL = 3u;     // pixels listed for the kernel in one cascade
SHARED_CONST uint CASCADE_COUNTER_BAND = 4u;       // pixels listed for two cascades (blend band)
// 3 uints each: vkCmdDispatchIndirect arguments.
SHARED_CONST uint CASCADE_COUNTER_DISPATCH_BLUR = 5u;
SHARED_CONST uint CASCADE_COUNTER_DISPATCH_KERNEL = 8u;
SHARED_CONST uint CASCADE_COUNTER_DISPATCH_BAND = 11u;
SHARED_CONST uint CASCADE_COUNTER_WORDS = 16u;

// Filter pipelines (specialization constant 0 of cascade_filter.comp).
SHARED_CONST uint CASCADE_STAGE_CLASSIFY = 0u;  // every pixel: mask test, one tap; lists the rest
SHARED_CONST uint CASCADE_STAGE_KERNEL = 1u;    // listed pixels: the kernel in one cascade
SHARED_CONST uint CASCADE_STAGE_BAND = 2u;      // listed pixels: two cascades of a blend band
SHARED_CONST uint CASCADE_STAGE_CLASSIFY_LIST = 3u;  // the classify stage over an input list of pixels
SHARED_CONST uint CASCADE_LIST_GROUP = 64u;     // list entries per workgroup (8x8)

SHARED_CONST uint CASCADE_BLUR_GROUP = 64u;

// Highest mask level: the mask pass keeps one footprint row (2^level texels, twice that at the end of
// a map whose size isn't a power of two, plus the border) in registers.
SHARED_CONST int CASCADE_MASK_MAX_LEVEL = 5;

// The empty depth range of a mask texel with no edge nearby (packed min 0xffff, max 0).
SHARED_CONST uint CASCADE_EXTENT_EMPTY = 0xffff0000u;

struct CascadeDepthPush {
  mat4 model;
  mat4 light_view_projection;
};

struct CascadeParams {
  mat4 light_view_projection[4];
  mat4 light_normal_matrix[4];  // world normal -> light clip space (inverse transpose of the linear part)
  vec4 split_far;               // view depth where each cascade ends
  vec4 blend_start;             // view depth where each cascade starts blending into the next
  vec4 texel_world;             // world units per map texel
  vec4 kernel_texels;           // PCF radius in texels
  vec4 depth_bias;              // constant bias in light depth units
  vec4 normal_offset;           // world units along the geometric normal
  vec4 edge_threshold;          // light depth step between neighbours that counts as an edge
  ivec4 mask_level;             // mask mip level matching the kernel width
  ivec4 mask_rect[4];           // mask texels built this frame (inclusive, at mask_level); empty: none
  uvec4 mask_offset;            // each cascade's first texel in the mask buffers (rows of mask_rect's width)
  vec4 camera_position;         // xyz
  vec4 camera_forward;          // xyz, unit
  vec4 light_direction;         // xyz: travel direction, unit
  uvec4 extent;                 // xy frame size, z map size, w cascade count
  uvec4 mode;                   // x masking, y blur on, z debug view, w the input list's count word (CASCADE_STAGE_CLASSIFY_LIST)
  vec4 depth_range;             // world units from light depth 0 to 1 (PCSS)
  vec4 pcss;                    // x the sun's tan of its angular radius (0: no PCSS), y the widest PCSS radius in texels
};

struct CascadeMaskPush {
  uint cascade;       // the layer built by this dispatch, at its mask_level
  uint depth_extent;  // also write the depth extent
  uint pad0;
  uint pad1;
};

struct CascadeBlurPush {
  vec4 camera_position;  // xyz
  uvec4 extent;          // xy frame size
};

SHARED_CONST uint CASCADE_MASK_BINDING_PARAMS = 0u;
SHARED_CONST uint CASCADE_MASK_BINDING_DEPTH = 1u;
SHARED_CONST uint CASCADE_MASK_BINDING_MASKS = 2u;
SHARED_CONST uint CASCADE_MASK_BINDING_NEIGHBOURHOODS = 3u;

SHARED_CONST uint CASCADE_FILTER_BINDING_PARAMS = 0u;
SHARED_CONST uint CASCADE_FILTER_BINDING_WORLD_POSITION = 1u;
SHARED_CONST uint CASCADE_FILTER_BINDING_GEOMETRIC_NORMAL = 2u;
SHARED_CONST uint CASCADE_FILTER_BINDING_DEPTH = 3u;
SHARED_CONST uint CASCADE_FILTER_BINDING_NEIGHBOURHOODS = 4u;
SHARED_CONST uint CASCADE_FILTER_BINDING_ROTATION = 5u;
SHARED_CONST uint CASCADE_FILTER_BINDING_SHADOW_TERM = 6u;
SHARED_CONST uint CASCADE_FILTER_BINDING_OVERLAY = 7u;
SHARED_CONST uint CASCADE_FILTER_BINDING_COUNTERS = 8u;
SHARED_CONST uint CASCADE_FILTER_BINDING_BLUR_LIST = 9u;
SHARED_CONST uint CASCADE_FILTER_BINDING_WORK_LIST = 10u;
SHARED_CONST uint CASCADE_FILTER_BINDING_INPUT_LIST = 11u;      // CASCADE_STAGE_CLASSIFY_LIST: uvec4, x the pixel
SHARED_CONST uint CASCADE_FILTER_BINDING_INPUT_COUNTERS = 12u;  // word CascadeParams::mode.w: entries in the input list
SHARED_CONST uint CASCADE_FILTER_BINDING_RECEIVERS = 13u;       // RGBA8, a > 0.5: receives shadows

SHARED_CONST uint CASCADE_ARGS_BINDING_COUNTERS = 0u;

SHARED_CONST uint CASCADE_BLUR_BINDING_WORLD_POSITION = 0u;
SHARED_CONST uint CASCADE_BLUR_BINDING_GEOMETRIC_NORMAL = 1u;
SHARED_CONST uint CASCADE_BLUR_BINDING_SHADOW_TERM = 2u;
SHARED_CONST uint CASCADE_BLUR_BINDING_COUNTERS = 3u;
SHARED_CONST uint CASCADE_BLUR_BINDING_BLUR_LIST = 4u;
SHARED_CONST uint CASCADE_BLUR_BINDING_BLURRED = 5u;

// The entry of mask texel `id` (at its cascade's mask level, inside that cascade's mask_rect `rect`)
// in the mask buffers, where each cascade's rectangle lies in rows of its width from its `offset`
// (CascadeParams::mask_offset).
SHARED_INLINE uint cascade_mask_entry(SHARED_IN(ivec4) rect, uint offset, SHARED_IN(ivec2) id) {
  return offset + uint((id.y - rect.y) * (rect.z - rect.x + 1) + (id.x - rect.x));
}

// Packs a light-depth range into one uint, rounding outwards so the packed range contains it.
SHARED_INLINE uint cascade_pack_extent(float lo, float hi) {
  uint a = uint(clamp(floor(lo * 65535.0f), 0.0f, 65535.0f));
  uint b = uint(clamp(ceil(hi * 65535.0f), 0.0f, 65535.0f));
  return (a << 16u) | b;
}

SHARED_END

#ifdef __cplusplus
static_assert(sizeof(gpu_shared::CascadeDepthPush) == 128);
static_assert(sizeof(gpu_shared::CascadeParams) == 8 * 64 + 20 * 16);
static_assert(sizeof(gpu_shared::CascadeMaskPush) == 16);
static_assert(sizeof(gpu_shared::CascadeBlurPush) == 32);
#endif
#endif
