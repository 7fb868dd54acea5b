#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows.h"
layout(local_size_x = 8, local_size_y = 8) in;  // a thread a block of kSmBlock² texels

// PCSS's masking in the sm resolve (shadow_map_resolve.glsl's pcss_settled): the map's depth blocks
// (depth_blocks.glsl). A thread a block, its texels in two loops: a workgroup a block summing through
// shared memory took lavapipe 51 ms for a 1024² map, its barriers being the cost, and summing by
// subgroups took the H200 0.018 ms at 4K against this one's 0.011.

layout(set = 0, binding = SM_RESOLVE_BINDING_PARAMS) uniform Params { ShadowMapResolveParams params; };
layout(set = 0, binding = SM_RESOLVE_BINDING_SHADOW_MAP) uniform sampler2D shadow_map;
layout(set = 0, binding = SM_RESOLVE_BINDING_BLOCKS, std430) writeonly buffer Blocks { vec4 blocks_out[]; };

float depth_block_texel(ivec2 texel) { return texelFetch(shadow_map, texel, 0).r; }
#define DEPTH_BLOCKS_FIT
#include "depth_blocks.glsl"

void main() {
  ivec2 size = ivec2(params.extent.zw);
  ivec2 blocks = (size + int(kSmBlock) - 1) / int(kSmBlock);
  ivec2 block = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(block, blocks))) return;
  blocks_out[block.y * blocks.x + block.x] = fit_depth_block(block, size);
}
