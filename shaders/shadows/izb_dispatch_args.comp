#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_tiles.glsl"
layout(local_size_x = 1) in;

layout(push_constant) uniform Push { IzbComputePush push; };

// Indirect dispatch arguments for one step of the compute trace/CSM (push.debug: IZB_ARGS_*, for the
// work push.mode), in rows of kIzbDispatchRow workgroups.
void main() {
  uint groups, at;
  if (push.debug == IZB_ARGS_RECORDS) {
    groups = (record_count(push.mode) + kIzbRecordsPerGroup - 1u) / kIzbRecordsPerGroup;
    at = IZB_COUNTER_RECORD_DISPATCH;
  } else if (push.debug == IZB_ARGS_TILE_PAIRS) {
    groups = (tile_pair_count(push.mode) + kIzbTilePairsPerGroup - 1u) / kIzbTilePairsPerGroup;
    at = IZB_COUNTER_TILE_PAIR_DISPATCH;
  } else {
    groups = (min(counters[IZB_COUNTER_PAIRS], params.limits.w) + kIzbPairGroup - 1u) / kIzbPairGroup;
    at = IZB_COUNTER_PAIR_DISPATCH;
  }
  write_row_dispatch(at, groups);
}
