#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_tiles.glsl"
#include "shadows/izb_group_reserve.glsl"
layout(local_size_x_id = 0) in;  // kIzbTileStepLanes

layout(push_constant) uniform Push { IzbComputePush push; };

// Compute trace / compute CSM, step 2 (see izb.h): kIzbTileStepRecords records side by side, a thread
// per tile (kIzbRecordsPerGroup such rounds per workgroup), keeps the (triangle, tile) pairs the
// triangle touches (the lit map: within its widened footprint, less the tiles it covers whole, which
// it bounds at once: lower_lit_tile) and, for the trace, is not behind every node of. A pair that
// does not fit the buffer is worked here.
void main() {
  uint group = IZB_ROW_DISPATCH_GROUP;
  uint mode = kIzbWork;
  uint count = record_count(mode);
  uint slot_counter = tile_pair_counter(mode);
  uint lanes = kIzbTileStepLanes / kIzbTileStepRecords;
  uint unit = gl_LocalInvocationIndex / lanes, lane = gl_LocalInvocationIndex % lanes;
  for (uint k = 0u; k < kIzbRecordsPerGroup; ++k) {
    uint record = (group * kIzbRecordsPerGroup + k) * kIzbTileStepRecords + unit;
    if (kIzbTileStepRecords == 1u && record >= count) break;  // uniform over the workgroup
    bool valid = record < count;
    uvec4 rec = valid ? records[record] : uvec4(0u, 0u, 1u, 0u);  // (an empty span)
    vec3 a = vec3(0.0), b = vec3(0.0), c = vec3(0.0);
    if (valid) load_grid_triangle(rec.x, a, b, c);
    float area = edge_fn(c.xy, a.xy, b.xy);
    for (uint x0 = 0u; x0 < kIzbRecordTiles; x0 += lanes) {
      if (kIzbTileStepRecords == 1u && rec.z + x0 > rec.w) break;  // uniform: one record
      uvec2 tile = uvec2(rec.z + x0 + lane, rec.y);
      bool keep = tile.x <= rec.w && tile_survives(tile, a, b, c, area, mode);
      // The lit map takes a triangle covering the whole tile at the tile level: no texel work.
      if (mode == IZB_WORK_LIT && keep && lit_covers_tile(tile, a, b, c, area)) {
        lower_lit_tile(tile, a, b, c, area);
        keep = false;
      }
      uint slot = reserve_group_slots(slot_counter, keep ? 1u : 0u, tile_pair_dispatch_at(mode), params.capacities.x,
                                      tile_pairs_per_group(mode));
      if (keep) {
        if (slot < params.capacities.x) tile_pairs[slot] = uvec2(rec.x, tile.y * tiles_per_side() + tile.x);
        else work_tile_here(tile, rec.x, a, b, c, area, mode);
      }
    }
  }
}
