#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows.h"
layout(local_size_x = 8, local_size_y = 8) in;  // a thread a block of kSmBlock² texels

// PCSS's masking in the sm resolve (shadow_map_resolve.comp's pcss_settled): per block of kSmBlock²
// texels of the depth map, the plane that fits its depths best (least squares over the texels'
// centres) and the largest distance of a stored depth from it. A receiver's taps compare its own
// tangent plane with the stored depths; where that plane lies below (above) a block's plane by more
// than the distance and the bias over every tap texel of the block, each of those taps is lit
// (shadowed) without being read. A planar surface's block fits it to a rounding step, so a receiver
// on it settles; a block crossing an occluder's edge or a crease fits loosely and settles nothing.
// A block reaching past the map's edge holds an infinite distance: it settles nothing.

layout(set = 0, binding = SM_RESOLVE_BINDING_PARAMS) uniform Params { ShadowMapResolveParams params; };
layout(set = 0, binding = SM_RESOLVE_BINDING_SHADOW_MAP) uniform sampler2D shadow_map;
layout(set = 0, binding = SM_RESOLVE_BINDING_BLOCKS, std430) writeonly buffer Blocks { vec4 blocks_out[]; };

// (A thread a block, its texels in two loops: a workgroup a block summing through shared memory took
// lavapipe 51 ms for a 1024² map, its barriers being the cost, and summing by subgroups took the
// H200 0.018 ms at 4K against this one's 0.011.)
void main() {
  ivec2 size = ivec2(params.extent.zw);
  ivec2 blocks = (size + int(kSmBlock) - 1) / int(kSmBlock);
  ivec2 block = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(block, blocks))) return;
  ivec2 origin = block * int(kSmBlock);
  uint index = uint(block.y * blocks.x + block.x);
  if (any(greaterThan(origin + int(kSmBlock), size))) {
    blocks_out[index] = vec4(0.0, 0.0, 0.0, 3.0e38);
    return;
  }
  // Offsets from the block's centre: -3.5 .. 3.5 along each axis.
  float half_span = 0.5 * float(kSmBlock - 1u);
  vec3 moments = vec3(0.0);
  for (int y = 0; y < int(kSmBlock); ++y)
    for (int x = 0; x < int(kSmBlock); ++x) {
      float depth = texelFetch(shadow_map, origin + ivec2(x, y), 0).r;
      moments += vec3(depth, (vec2(x, y) - half_span) * depth);
    }
  // Least squares over a full grid: the mean, and each slope the moment over the sum of u² (the
  // block's kSmBlock columns of 2 * (0.5² + 1.5² + 2.5² + 3.5²) = 42 each).
  float u_squares = float(kSmBlock) * float(kSmBlock * (kSmBlock * kSmBlock - 1u)) / 12.0;
  float centre = moments.x / float(kSmBlock * kSmBlock);
  vec2 slope = moments.yz / u_squares;
  float distance = 0.0;
  for (int y = 0; y < int(kSmBlock); ++y)
    for (int x = 0; x < int(kSmBlock); ++x) {
      float depth = texelFetch(shadow_map, origin + ivec2(x, y), 0).r;
      distance = max(distance, abs(depth - (centre + dot(slope, vec2(x, y) - half_span))));
    }
  blocks_out[index] = vec4(centre, slope, distance);
}
