#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows.h"
layout(local_size_x = 8, local_size_y = 8) in;  // a thread a block of kSmBlock² texels (or of blocks)
// Two dispatches: the blocks from the map's texels, then the coarse blocks from the blocks.
layout(constant_id = 0) const bool kCoarse = false;

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
layout(set = 0, binding = SM_RESOLVE_BINDING_BLOCKS, std430) buffer Blocks { vec4 blocks_out[]; };

// (A thread a block, its texels in two loops: a workgroup a block summing through shared memory took
// lavapipe 51 ms for a 1024² map, its barriers being the cost, and summing by subgroups took the
// H200 0.018 ms at 4K against this one's 0.011.)
void fit_block() {
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
  // Offsets from the block's centre: -3.5 .. 3.5 along each axis. The depths are fetched once.
  float half_span = 0.5 * float(kSmBlock - 1u);
  float depths[kSmBlock * kSmBlock];
  vec3 moments = vec3(0.0);
  for (int y = 0; y < int(kSmBlock); ++y)
    for (int x = 0; x < int(kSmBlock); ++x) {
      float depth = texelFetch(shadow_map, origin + ivec2(x, y), 0).r;
      depths[y * int(kSmBlock) + x] = depth;
      moments += vec3(depth, (vec2(x, y) - half_span) * depth);
    }
  // Least squares over a full grid: the mean, and each slope the moment over the sum of u² (the
  // block's kSmBlock columns of 2 * (0.5² + 1.5² + 2.5² + 3.5²) = 42 each).
  float u_squares = float(kSmBlock) * float(kSmBlock * (kSmBlock * kSmBlock - 1u)) / 12.0;
  float centre = moments.x / float(kSmBlock * kSmBlock);
  vec2 slope = moments.yz / u_squares;
  float distance = 0.0;
  for (int y = 0; y < int(kSmBlock); ++y)
    for (int x = 0; x < int(kSmBlock); ++x)
      distance = max(distance, abs(depths[y * int(kSmBlock) + x] - (centre + dot(slope, vec2(x, y) - half_span))));
  blocks_out[index] = vec4(centre, slope, distance);
}

// A coarse block from its kSmCoarseBlocks² blocks: the plane through their centres' depths by least
// squares (each block's mean is its plane's depth at its centre; offsets -12, -4, 4, 12 texels), and
// the largest of each block's deviation plus the most its plane parts from the coarse one over its
// texels (at their rectangle's corners: the two planes' difference is linear). A block reaching past
// the map's edge leaves its coarse block unsettling.
void fit_coarse_block() {
  int blocks = (int(params.extent.z) + int(kSmBlock) - 1) / int(kSmBlock);
  int coarse = (blocks + int(kSmCoarseBlocks) - 1) / int(kSmCoarseBlocks);
  ivec2 at = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(at, ivec2(coarse)))) return;
  uint index = uint(blocks * blocks + at.y * coarse + at.x);
  ivec2 first = at * int(kSmCoarseBlocks);
  if (any(greaterThan(first + int(kSmCoarseBlocks), ivec2(blocks)))) {
    blocks_out[index] = vec4(0.0, 0.0, 0.0, 3.0e38);
    return;
  }
  float span = float(kSmBlock), half_count = 0.5 * float(kSmCoarseBlocks - 1u);
  vec3 moments = vec3(0.0);
  for (int y = 0; y < int(kSmCoarseBlocks); ++y)
    for (int x = 0; x < int(kSmCoarseBlocks); ++x) {
      float depth = blocks_out[(first.y + y) * blocks + first.x + x].x;
      moments += vec3(depth, (vec2(x, y) - half_count) * span * depth);
    }
  float n = float(kSmCoarseBlocks);
  float u_squares = n * span * span * n * (n * n - 1.0) / 12.0;
  vec4 plane = vec4(moments.x / (n * n), moments.yz / u_squares, 0.0);
  float half_span = 0.5 * float(kSmBlock - 1u);
  for (int y = 0; y < int(kSmCoarseBlocks); ++y)
    for (int x = 0; x < int(kSmCoarseBlocks); ++x) {
      vec4 block = blocks_out[(first.y + y) * blocks + first.x + x];
      vec2 offset = (vec2(x, y) - half_count) * span;  // the block's centre from the coarse one's
      float apart = block.x - plane.x - dot(plane.yz, offset);  // the planes' difference at its centre
      vec2 slope = block.yz - plane.yz;
      plane.w = max(plane.w, block.w + abs(apart) + (abs(slope.x) + abs(slope.y)) * half_span);
    }
  blocks_out[index] = plane;
}

void main() {
  if (kCoarse) fit_coarse_block();
  else fit_block();
}
