#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_tiles.glsl"
layout(local_size_x_id = 0) in;  // kIzbTileStepLanes

layout(push_constant) uniform Push { IzbComputePush push; };

// Compute trace / compute CSM, step 2 (see izb.h): a thread per tile of kIzbRecordsPerGroup records
// keeps the (triangle, tile) pairs the triangle touches (the lit map: within its widened footprint)
// and, for the trace, is not behind every node of. A pair that does not fit the buffer is worked here.
void main() {
  uint group = gl_WorkGroupID.y * kIzbDispatchRow + gl_WorkGroupID.x;
  uint mode = push.mode;
  uint count = record_count(mode);
  uint slot_counter = tile_pair_counter(mode);
  for (uint k = 0u; k < kIzbRecordsPerGroup; ++k) {
    uint record = group * kIzbRecordsPerGroup + k;
    if (record >= count) break;  // uniform over the workgroup
    uvec4 rec = records[record];
    vec3 a, b, c;
    load_grid_triangle(rec.x, a, b, c);
    float area = edge_fn(c.xy, a.xy, b.xy);
    for (uint x = rec.z; x <= rec.w; x += kIzbTileStepLanes) {
      uvec2 tile = uvec2(x + gl_LocalInvocationID.x, rec.y);
      bool keep = tile.x <= rec.w && tile_survives(tile, a, b, c, area, mode);
      uint slot = reserve_slots(slot_counter, keep ? 1u : 0u);
      if (keep) {
        if (slot < params.capacities.x) tile_pairs[slot] = uvec2(rec.x, tile.y * tiles_per_side() + tile.x);
        else work_tile_here(tile, rec.x, a, b, c, area, mode);
      }
    }
  }
}
