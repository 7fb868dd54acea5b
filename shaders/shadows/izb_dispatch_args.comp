#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_chunk_work.glsl"
layout(local_size_x = 1) in;

layout(push_constant) uniform Push { IzbComputePush push; };

// Indirect dispatch arguments for the record workgroups (kIzbRecordsPerGroup records of push.mode's each) or
// the pair threads (IZB_ARGS_PAIRS), in rows of kIzbDispatchRow workgroups.
void main() {
  uint groups, at;
  if (push.mode == IZB_ARGS_PAIRS) {
    groups = (min(counters[IZB_COUNTER_PAIRS], params.limits.w) + kIzbPairGroup - 1u) / kIzbPairGroup;
    at = IZB_COUNTER_PAIR_DISPATCH;
  } else {
    groups = (chunk_records(push.mode) + kIzbRecordsPerGroup - 1u) / kIzbRecordsPerGroup;
    at = IZB_COUNTER_CHUNK_DISPATCH;
  }
  counters[at] = min(groups, kIzbDispatchRow);
  counters[at + 1u] = (groups + kIzbDispatchRow - 1u) / kIzbDispatchRow;
  counters[at + 2u] = 1u;
}
