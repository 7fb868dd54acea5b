#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_tiles.glsl"
layout(local_size_x = kIzbPairGroup) in;

// Compute trace, step 3: one thread per surviving (triangle, texel) pair walks the texel's list with
// the same exact node test as the raster trace.
void main() {
  uint index = IZB_ROW_DISPATCH_GROUP * kIzbPairGroup + gl_LocalInvocationID.x;
  uint tests = 0u;
  // The pair is loaded beside the count (within the buffer, a stale one is read and left): one round
  // trip to memory before the walk, not two.
  uvec2 pair = index < params.limits.w ? pairs[index] : uvec2(0u);
  if (index < min(counters[IZB_COUNTER_PAIRS], params.limits.w)) {
    vec3 a, b, c;
    load_grid_triangle(pair.x, a, b, c);
    tests = trace_texel_list(pair.y, pair.x, a, b, c, 1.0 / edge_fn(c.xy, a.xy, b.xy));
  }
  if (izb_flag(IZB_FLAG_STATS)) add_sharded(IZB_COUNTER_TRIANGLE_TESTS, tests, IZB_SHARD_SEED);
}
