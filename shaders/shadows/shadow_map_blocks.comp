#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "shadows.h"
// A GPU: a workgroup a block, a thread a texel, summed by subgroups. A CPU device (kThreadPerBlock): a
// thread a block, its texels in two loops (a workgroup a block took lavapipe 51 ms for a 1024² map,
// its barriers being the cost; on the H200 a thread a block took 0.011 ms at that size, its 128
// fetches in a row).
layout(local_size_x = 8, local_size_y = 8) in;
layout(constant_id = 0) const bool kThreadPerBlock = false;

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

// Offsets from the block's centre: -3.5 .. 3.5 along each axis. Least squares over a full grid: the
// mean, and each slope the moment over the sum of u² (the block's kSmBlock columns of
// 2 * (0.5² + 1.5² + 2.5² + 3.5²) = 42 each).
const float kHalfSpan = 0.5 * float(kSmBlock - 1u);
const float kSquares = float(kSmBlock) * float(kSmBlock * (kSmBlock * kSmBlock - 1u)) / 12.0;
const float kNotPlanar = 3.0e38;  // a block reaching past the map's edge

vec4 fitted(vec3 moments) {
  return vec4(moments.x / float(kSmBlock * kSmBlock), moments.yz / kSquares, 0.0);
}
float deviation(vec4 plane, float depth, vec2 u) { return abs(depth - (plane.x + dot(plane.yz, u))); }

void thread_per_block() {
  ivec2 size = ivec2(params.extent.zw);
  ivec2 blocks = (size + int(kSmBlock) - 1) / int(kSmBlock);
  ivec2 block = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(block, blocks))) return;
  ivec2 origin = block * int(kSmBlock);
  uint index = uint(block.y * blocks.x + block.x);
  if (any(greaterThan(origin + int(kSmBlock), size))) {
    blocks_out[index] = vec4(0.0, 0.0, 0.0, kNotPlanar);
    return;
  }
  vec3 moments = vec3(0.0);
  for (int y = 0; y < int(kSmBlock); ++y)
    for (int x = 0; x < int(kSmBlock); ++x) {
      float depth = texelFetch(shadow_map, origin + ivec2(x, y), 0).r;
      moments += vec3(depth, (vec2(x, y) - kHalfSpan) * depth);
    }
  vec4 plane = fitted(moments);
  for (int y = 0; y < int(kSmBlock); ++y)
    for (int x = 0; x < int(kSmBlock); ++x)
      plane.w = max(plane.w, deviation(plane, texelFetch(shadow_map, origin + ivec2(x, y), 0).r, vec2(x, y) - kHalfSpan));
  blocks_out[index] = plane;
}

shared vec4 subgroup_partials[kSmBlock * kSmBlock];  // one a subgroup

void workgroup_per_block() {
  ivec2 size = ivec2(params.extent.zw);
  ivec2 origin = ivec2(gl_WorkGroupID.xy) * int(kSmBlock);
  vec2 u = vec2(gl_LocalInvocationID.xy) - kHalfSpan;
  float depth = texelFetch(shadow_map, min(origin + ivec2(gl_LocalInvocationID.xy), size - 1), 0).r;
  vec3 moments = subgroupAdd(vec3(depth, u * depth));
  if (subgroupElect()) subgroup_partials[gl_SubgroupID] = vec4(moments, 0.0);
  barrier();
  moments = vec3(0.0);
  for (uint k = 0u; k < gl_NumSubgroups; ++k) moments += subgroup_partials[k].xyz;
  vec4 plane = fitted(moments);
  float farthest = subgroupMax(deviation(plane, depth, u));
  barrier();  // every subgroup's moments read before the deviations overwrite them
  if (subgroupElect()) subgroup_partials[gl_SubgroupID].w = farthest;
  barrier();
  if (gl_LocalInvocationIndex != 0u) return;
  for (uint k = 0u; k < gl_NumSubgroups; ++k) plane.w = max(plane.w, subgroup_partials[k].w);
  if (any(greaterThan(origin + int(kSmBlock), size))) plane.w = kNotPlanar;
  blocks_out[gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x] = plane;
}

void main() {
  if (kThreadPerBlock) thread_per_block();
  else workgroup_per_block();
}
