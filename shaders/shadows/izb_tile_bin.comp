#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_tiles.glsl"
layout(local_size_x_id = 0) in;  // kIzbTileStepLanes

layout(push_constant) uniform Push { IzbComputePush push; };

shared uint subgroup_slot_offsets[256];
shared uint group_slot_base;

// Reserves the invocation's `count` tile pairs with one atomic for the whole workgroup (atomics on one
// address serialize; a GPU's workgroup works several records at once). Every invocation calls it
// together.
uint reserve_tile_pairs(uint counter, uint count) {
  if (gl_NumSubgroups == 1u) return reserve_slots(counter, count);
  uint offset = subgroupExclusiveAdd(count);
  uint total = subgroupAdd(count);
  barrier();  // the previous call's reads are done
  if (subgroupElect()) subgroup_slot_offsets[gl_SubgroupID] = total;
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    uint sum = 0u;
    for (uint i = 0u; i < gl_NumSubgroups; ++i) {
      uint t = subgroup_slot_offsets[i];
      subgroup_slot_offsets[i] = sum;
      sum += t;
    }
    group_slot_base = sum > 0u ? atomicAdd(counters[counter], sum) : 0u;
  }
  barrier();
  return group_slot_base + subgroup_slot_offsets[gl_SubgroupID] + offset;
}

// Compute trace / compute CSM, step 2 (see izb.h): kIzbTileStepRecords records side by side, a thread
// per tile (kIzbRecordsPerGroup such rounds per workgroup), keeps the (triangle, tile) pairs the
// triangle touches (the lit map: within its widened footprint) and, for the trace, is not behind
// every node of. A pair that does not fit the buffer is worked here.
void main() {
  uint group = gl_WorkGroupID.y * kIzbDispatchRow + gl_WorkGroupID.x;
  uint mode = push.mode;
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
      uint slot = reserve_tile_pairs(slot_counter, keep ? 1u : 0u);
      if (keep) {
        if (slot < params.capacities.x) tile_pairs[slot] = uvec2(rec.x, tile.y * tiles_per_side() + tile.x);
        else work_tile_here(tile, rec.x, a, b, c, area, mode);
      }
    }
  }
}
