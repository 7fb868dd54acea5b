#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
// 64 invocations a workgroup, 8x8 or a row of 64 pixels (IzbPipelineCache::with_pixel_group).
layout(local_size_x = 8, local_size_y = 8, local_size_x_id = 20, local_size_y_id = 21) in;

// Sorted lists (counting sort), step 3: each candidate pixel that was counted places its nodes at its
// texels' fill cursors (which start at each list's first node after the prefix sum).
void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (any(greaterThanEqual(pixel, params.extent.xy))) return;
  uint index = pixel.y * params.extent.x + pixel.x;
  uint state = pixel_state[index];
  // A pixel the lit map proved lit, or past the pool, has no node (nor stored points).
  if ((state & IZB_PIXEL_CANDIDATE) == 0u || (state & (IZB_PIXEL_OVERFLOW | IZB_PIXEL_LIT_CULLED)) != 0u) return;
  vec3 g[4];
  for (uint i = 0u; i < (izb_samples() == 1u ? 1u : 4u); ++i) g[i] = quad_point(index, i);
  uint texels[32];
  uint count = node_texels(g, visibility_mask[index], texels);  // the mask holds only the CSM's bits yet
  for (uint k = 0u; k < count; ++k) nodes[atomicAdd(list_cursor[texels[k]], 1u)] = uvec2(0u, index);
}
