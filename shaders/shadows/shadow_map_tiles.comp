#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows.h"
#include "shadow_common.h"
#include "local_light.h"
layout(local_size_x = 16, local_size_y = 16) in;

// Before a point light's first face map is resolved (on a CPU device, a spot light's map too), with
// that map's parameters: lists the 8x8 tiles holding a covered point of each face (light_tiles.glsl's
// local_light_faces: within the range and the face's pyramid) and writes 0 where a covered
// point lies beyond the light's range (a spot light's: outside its cone too), as each face's resolve
// would have. Each face's resolve then runs over its tiles alone (shadow_map_resolve.glsl's kTiles),
// six times a frame's pixels no longer.
layout(constant_id = 0) const bool kCpuDevice = false;

layout(set = 0, binding = SM_RESOLVE_BINDING_PARAMS) uniform Params { ShadowMapResolveParams params; };
layout(set = 0, binding = SM_RESOLVE_BINDING_WORLD_POSITION, rgba32f) readonly uniform image2D world_position;
layout(set = 0, binding = SM_RESOLVE_BINDING_SHADOW_TERM, r32f) writeonly uniform image2D shadow_term;
layout(set = 0, binding = SM_RESOLVE_BINDING_TILES, std430) buffer TileLists { uint tile_lists[]; };
#define LIGHT_TILES_LIST tile_lists
#include "shadows/light_tiles.glsl"

uint light_tile_faces(ivec2 pixel) {
  if (any(greaterThanEqual(uvec2(pixel), params.extent.xy))) return 0u;
  vec4 p = imageLoad(world_position, pixel);
  if (p.w == 0.0) return 0u;  // not covered: the resolve writes nothing there
  uint faces = local_light_faces(params.light_position.xyz, params.light_position.w, params.light_direction.xyz,
                                 params.light_cone.x, params.light_cone.z > 0.0, p.xyz);
  if (faces == 0u) imageStore(shadow_term, pixel, vec4(0.0));
  return faces;
}
#define LIGHT_TILES_LISTING
#include "shadows/light_tiles.glsl"

void main() { list_light_tiles(kCpuDevice, params.extent.xy); }
