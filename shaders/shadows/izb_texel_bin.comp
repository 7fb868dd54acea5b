#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_tiles.glsl"
#include "shadows/izb_group_reserve.glsl"
layout(local_size_x = kIzbTile, local_size_y = kIzbTile) in;

layout(push_constant) uniform Push { IzbComputePush push; };

// The CSM and lit map: kIzbQuadPairsPerRound pairs side by side, an invocation per 2x2 texels of its
// pair's tile (a texel's corners are its neighbours': evaluated once).
void quad_pairs(uint group, uint mode, uint count) {
  uint per_group = tile_pairs_per_group(mode);
  uint lanes = kIzbTile * kIzbTile / 4u;
  uint unit = gl_LocalInvocationIndex / lanes, lane = gl_LocalInvocationIndex % lanes;
  ivec2 offset = 2 * ivec2(lane % (kIzbTile / 2u), lane / (kIzbTile / 2u));
  for (uint k = 0u; k < per_group; k += kIzbQuadPairsPerRound) {
    if (group * per_group + k >= count) break;  // uniform over the workgroup
    uint index = group * per_group + k + unit;
    if (index >= count) break;
    uvec2 pair = tile_pairs[index];
    vec3 a, b, c;
    load_grid_triangle(pair.x, a, b, c);
    float area = edge_fn(c.xy, a.xy, b.xy);
    uvec2 tile = uvec2(pair.y % tiles_per_side(), pair.y / tiles_per_side());
    ivec2 first = ivec2(tile * kIzbTile) + offset;
    if (mode == IZB_WORK_LIT) lit_texel_quad(first, a, b, c, area);
    else csm_texel_quad(first, a, b, c, area, mode);
  }
}

// The trace on a CPU device: a thread per row of a pair's tile (kIzbTilePairsPerGroup pairs of
// kIzbTile rows fill the workgroup), its kIzbTile texels one after another (trace_texel_row): the pair
// and its triangle are read and set up once a row, not once a texel, and a kept pair takes its slot
// with one atomic, no barrier (lavapipe runs a workgroup's invocations in batches and pays a barrier
// with a switch through all of them). The same outcomes and pairs as a thread a texel (below), in
// another order.
void trace_tile_rows(uint group, uint count) {
  uint unit = gl_LocalInvocationIndex / kIzbTile, row = gl_LocalInvocationIndex % kIzbTile;
  uint index = group * kIzbTilePairsPerGroup + unit;
  bool valid = unit < kIzbTilePairsPerGroup && index < count;
  uvec2 pair = valid ? tile_pairs[index] : uvec2(0u);
  vec3 a = vec3(0.0), b = vec3(0.0), c = vec3(0.0);
  if (valid) load_grid_triangle(pair.x, a, b, c);
  float area = edge_fn(c.xy, a.xy, b.xy);
  uvec2 tile = uvec2(pair.y % tiles_per_side(), pair.y / tiles_per_side());
  uvec2 counts = valid ? trace_texel_row(ivec2(tile * kIzbTile + uvec2(0u, row)), kIzbTile, pair.x, a, b, c, area) : uvec2(0u);
  if (izb_flag(IZB_FLAG_STATS)) {
    add_sharded(IZB_COUNTER_FRAGMENTS, counts.x, IZB_SHARD_SEED);
    add_sharded(IZB_COUNTER_FRAGMENTS_KEPT, counts.y, IZB_SHARD_SEED);
  }
}

// Compute trace / compute CSM, step 3 (see izb.h): a thread per texel of kIzbTilePairsPerGroup
// (triangle, tile) pairs (the CSM and lit map: per 2x2 texels of tile_pairs_per_group pairs). The CSM writes
// fully covered texels' depth bounds, the lit map touched texels' nearest-depth bounds; the trace
// keeps the (triangle, texel) pairs that touch and survive the texel's farthest-node cull, appended
// densely so the list walks of step 4 fill every lane. A pair that does not fit the buffer is traced
// here.
void main() {
  uint group = IZB_ROW_DISPATCH_GROUP;
  uint mode = kIzbWork;
  uint count = tile_pair_count(mode);
  if (works_texel_quads(mode)) {  // a specialization constant
    quad_pairs(group, mode, count);
    return;
  }
  if (izb_flag(IZB_FLAG_CPU_DEVICE) && mode == IZB_WORK_TRACE && kIzbTilePairsPerGroup == kIzbTile) {  // (a CPU device's 16)
    trace_tile_rows(group, count);
    return;
  }
  uint fragments = 0u, kept = 0u;
  for (uint k = 0u; k < kIzbTilePairsPerGroup; ++k) {
    uint index = group * kIzbTilePairsPerGroup + k;
    if (index >= count) break;  // uniform over the workgroup
    uvec2 pair = tile_pairs[index];
    vec3 a, b, c;
    load_grid_triangle(pair.x, a, b, c);
    float area = edge_fn(c.xy, a.xy, b.xy);
    uvec2 tile = uvec2(pair.y % tiles_per_side(), pair.y / tiles_per_side());
    ivec2 texel = ivec2(tile * kIzbTile + gl_LocalInvocationID.xy);
    bool inside = all(lessThan(uvec2(texel), uvec2(izb_resolution())));
    uint outcome = inside ? trace_pair_outcome(texel, a, b, c, area) : IZB_PAIR_OUTSIDE;
    bool keep = outcome == IZB_PAIR_KEPT;
    uint want = keep ? 1u : 0u;
    uint slot = reserve_group_slots(IZB_COUNTER_PAIRS, want, IZB_COUNTER_PAIR_DISPATCH, params.limits.w, kIzbPairGroup);
    if (keep) {
      if (slot < params.limits.w) pairs[slot] = uvec2(pair.x, texel_index(texel));
      else trace_texel_list(texel_index(texel), pair.x, a, b, c, 1.0 / area);
    }
    fragments += outcome != IZB_PAIR_OUTSIDE ? 1u : 0u;
    kept += want;
  }
  if (izb_flag(IZB_FLAG_STATS) && mode == IZB_WORK_TRACE) {
    add_sharded(IZB_COUNTER_FRAGMENTS, fragments, IZB_SHARD_SEED);
    add_sharded(IZB_COUNTER_FRAGMENTS_KEPT, kept, IZB_SHARD_SEED);
  }
}
