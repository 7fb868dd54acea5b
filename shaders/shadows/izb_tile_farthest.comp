#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_tiles.glsl"
layout(local_size_x = kIzbTile, local_size_y = kIzbTile) in;

shared uint subgroup_farthest[kIzbTile * kIzbTile];

// Each tile's farthest node depth (0: no node), for the compute trace's tile-level cull.
void main() {
  uvec2 texel = gl_GlobalInvocationID.xy;
  uint res = izb_resolution();
  uint depth = all(lessThan(texel, uvec2(res))) ? farthest[texel.y * res + texel.x] : 0u;
  depth = subgroupMax(depth);
  if (subgroupElect()) subgroup_farthest[gl_SubgroupID] = depth;
  barrier();
  if (gl_LocalInvocationIndex != 0u) return;
  for (uint i = 1u; i < gl_NumSubgroups; ++i) depth = max(depth, subgroup_farthest[i]);
  tile_farthest[gl_WorkGroupID.y * tiles_per_side() + gl_WorkGroupID.x] = depth;
}
