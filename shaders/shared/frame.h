// Per-frame data and the G-buffer/lighting bindings, shared by C++ and GLSL.
#ifndef FRAME_H
#define FRAME_H
#include "shared_prelude.h"

SHARED_BEGIN

// A spot or point light of the lighting pass (engine::FrameLight).
struct LocalLightUniforms {
  vec4 position_range;   // xyz world position, w range
  vec4 direction_kind;   // xyz spot direction (travel), w: 0 spot, 1 point
  vec4 radiance;         // rgb colour * intensity
  vec4 cone;             // x cos(outer), y cos(inner)
};

SHARED_CONST uint kMaxLocalLights = 3u;

struct FrameUniforms {
  mat4 view;
  mat4 projection;
  mat4 view_projection;
  mat4 inverse_view_projection;  // NDC (y down, reversed depth) -> world
  vec4 camera_position;          // xyz
  vec4 light_direction;          // xyz: direction the light travels, unit
  vec4 light_radiance;           // rgb: colour * intensity
  vec4 ambient;                  // rgb: sky fill light; w: sky background brightness (1 day)
  uvec4 extent;                  // x, y: render size in pixels; z: frame index; w: FRAME_FLAG_*
  LocalLightUniforms local_lights[kMaxLocalLights];
  uvec4 local_light_count;       // x
};

// Push constants of one mesh draw in the G-buffer pass.
struct DrawPush {
  mat4 model;
  vec4 base_color;
  uint first_index;   // of the mesh in the scene index buffer, to fetch the triangle for its face normal
  int vertex_offset;
  uint flags;         // DRAW_FLAG_*
  uint alpha_threshold;  // engine::alpha_threshold: 0 opaque, else the least alpha byte kept
  uint base_color_texture;  // index into the material textures, or kNoTexture
  uint pad0, pad1, pad2;
};

SHARED_CONST uint DRAW_FLAG_RECEIVES_SHADOW = 2u;

// frame.extent.w bits.
SHARED_CONST uint FRAME_FLAG_SMOOTH_TERMINATOR = 1u;  // shading points take the terminator offset

// G-buffer pass bindings.
SHARED_CONST uint GBUFFER_BINDING_FRAME = 0u;
SHARED_CONST uint GBUFFER_BINDING_VERTICES = 1u;
SHARED_CONST uint GBUFFER_BINDING_INDICES = 2u;
SHARED_CONST uint GBUFFER_BINDING_TEXTURES = 3u;

// Shading-point pass: depth -> world position.
SHARED_CONST uint SHADING_POINTS_BINDING_FRAME = 0u;
SHARED_CONST uint SHADING_POINTS_BINDING_DEPTH = 1u;
SHARED_CONST uint SHADING_POINTS_BINDING_WORLD_POSITION = 2u;
SHARED_CONST uint SHADING_POINTS_BINDING_TERMINATOR_OFFSET = 3u;

// Lighting pass.
SHARED_CONST uint LIGHTING_BINDING_FRAME = 0u;
SHARED_CONST uint LIGHTING_BINDING_ALBEDO = 1u;
SHARED_CONST uint LIGHTING_BINDING_NORMAL = 2u;
SHARED_CONST uint LIGHTING_BINDING_WORLD_POSITION = 3u;
SHARED_CONST uint LIGHTING_BINDING_SHADOW = 4u;
SHARED_CONST uint LIGHTING_BINDING_OVERLAY = 5u;
SHARED_CONST uint LIGHTING_BINDING_OUTPUT = 6u;
SHARED_CONST uint LIGHTING_BINDING_LOCAL_SHADOW = 7u;  // kMaxLocalLights bindings from here

SHARED_CONST uint kVertexFloats = 8u;  // engine::Vertex: position(3) normal(3) uv(2)

SHARED_END

#ifdef __cplusplus
static_assert(sizeof(gpu_shared::FrameUniforms) == 4 * 64 + 5 * 16 + 3 * 64 + 16);
static_assert(sizeof(gpu_shared::DrawPush) == 112);
#endif
#endif
