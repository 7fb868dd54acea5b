#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 1) in;

layout(push_constant) uniform Push { IzbComputePush push; };

void write_args(uint at, uvec3 groups) {
  counters[at] = groups.x;
  counters[at + 1u] = groups.y;
  counters[at + 2u] = groups.z;
}

// A CPU device (IZB_FLAG_CPU_DEVICE): the per-pixel passes append to their lists with an atomic a
// lane and leave the dispatches over them to this pass, since raising them in every lane's code costs
// a CPU driver more than a dispatch of one invocation. push.mode IZB_LIST_RESOLVE, after the build:
// the resolve's, one entry a thread in rows of kIzbDispatchRow workgroups of 64; IZB_LIST_HYBRID,
// after the resolve: the hybrid list's, kIzbHybridEntriesPerGroup entries a workgroup.
void main() {
  if (push.mode == IZB_LIST_RESOLVE) {
    uint groups = (counters[IZB_COUNTER_RESOLVE_LIST] + 63u) / 64u;
    write_args(IZB_COUNTER_RESOLVE_LIST + 1u,
               uvec3(min(groups, kIzbDispatchRow), (groups + kIzbDispatchRow - 1u) / kIzbDispatchRow, 1u));
  } else {
    uint groups = (counters[IZB_COUNTER_HYBRID] + kIzbHybridEntriesPerGroup - 1u) / kIzbHybridEntriesPerGroup;
    write_args(IZB_COUNTER_HYBRID + 1u, uvec3(groups, 1u, 1u));
  }
}
