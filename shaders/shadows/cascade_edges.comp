#version 460
#extension GL_GOOGLE_include_directive : require
#include "cascades.h"
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = CASCADE_MASK_BINDING_PARAMS) uniform Params { CascadeParams params; };
layout(set = 0, binding = CASCADE_MASK_BINDING_DEPTH) uniform sampler2DArray depth_map;
layout(set = 0, binding = CASCADE_MASK_BINDING_EDGE_DST, r32ui) writeonly uniform uimage2DArray edge_dst;
layout(set = 0, binding = CASCADE_MASK_BINDING_EXTENT_DST, r32ui) writeonly uniform uimage2DArray extent_dst;

// Level 0 of both masks. A texel is an edge when any 3x3 neighbour's depth differs by more than a
// slope of two texels per texel could explain; both sides of a step are flagged. The depth extent is
// the 3x3 neighbourhood's [min, max] at every texel, so a footprint's range covers all its texels.
void main() {
  ivec3 id = ivec3(gl_GlobalInvocationID);
  int size = int(params.extent.z);
  if (id.x >= size || id.y >= size || id.z >= int(params.extent.w)) return;
  float centre = texelFetch(depth_map, id, 0).r;
  float lo = centre, hi = centre;
  bool edge = false;
  float threshold = params.edge_threshold[id.z];
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      ivec2 t = clamp(id.xy + ivec2(dx, dy), ivec2(0), ivec2(size - 1));
      float d = texelFetch(depth_map, ivec3(t, id.z), 0).r;
      lo = min(lo, d);
      hi = max(hi, d);
      edge = edge || abs(d - centre) > threshold;
    }
  }
  imageStore(edge_dst, id, uvec4(edge ? 1u : 0u));
  imageStore(extent_dst, id, uvec4(cascade_pack_extent(lo, hi)));
}
