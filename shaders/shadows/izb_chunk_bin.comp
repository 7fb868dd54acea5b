#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_chunk_work.glsl"
layout(local_size_x_id = 0) in;  // kIzbRecordLanes

layout(push_constant) uniform Push { IzbComputePush push; };

// Compute trace / compute CSM, step 2: a workgroup takes kIzbRecordsPerGroup row records, a thread
// per texel. The CSM writes fully covered texels' depth bounds; the trace keeps the (triangle, texel)
// pairs that touch and survive the depth cull against the texel's farthest node, appended densely so
// the list walks of step 3 fill every lane. A pair that does not fit the buffer is traced here.
void main() {
  uint group = gl_WorkGroupID.y * kIzbDispatchRow + gl_WorkGroupID.x;
  uint mode = push.mode;
  uint records = chunk_records(mode);
  uint fragments = 0u, kept = 0u;
  for (uint k = 0u; k < kIzbRecordsPerGroup; ++k) {
    uint record = group * kIzbRecordsPerGroup + k;
    if (record >= records) break;  // uniform over the workgroup
    uvec4 rec = chunks[record];
    vec3 a, b, c;
    load_grid_triangle(rec.x, a, b, c);
    float area = edge_fn(c.xy, a.xy, b.xy);
    for (uint x = rec.z; x <= rec.w; x += kIzbRecordLanes) {
      uint xi = x + gl_LocalInvocationID.x;
      bool inside = xi <= rec.w;
      ivec2 texel = ivec2(int(xi), int(rec.y));
      if (mode != IZB_CHUNKS_FOR_TRACE) {
        if (inside) csm_texel(texel, a, b, c, area, mode);
        continue;
      }
      uint outcome = inside ? trace_pair_outcome(texel, a, b, c, area) : IZB_PAIR_OUTSIDE;
      bool keep = outcome == IZB_PAIR_KEPT;
      uint want = keep ? 1u : 0u;
      uint offset = subgroupExclusiveAdd(want);
      uint total = subgroupAdd(want);
      uint base = 0u;
      if (subgroupElect() && total > 0u) base = atomicAdd(counters[IZB_COUNTER_PAIRS], total);
      base = subgroupBroadcastFirst(base);
      if (keep) {
        uint slot = base + offset;
        if (slot < params.limits.w) pairs[slot] = uvec2(rec.x, texel_index(texel));
        else trace_texel_list(texel_index(texel), a, b, c, 1.0 / area);
      }
      fragments += outcome != IZB_PAIR_OUTSIDE ? 1u : 0u;
      kept += want;
    }
  }
  if (izb_flag(IZB_FLAG_STATS) && mode == IZB_CHUNKS_FOR_TRACE) {
    uint f = subgroupAdd(fragments);
    uint k = subgroupAdd(kept);
    if (subgroupElect()) {
      if (f > 0u) atomicAdd(counters[IZB_COUNTER_FRAGMENTS], f);
      if (k > 0u) atomicAdd(counters[IZB_COUNTER_FRAGMENTS_KEPT], k);
    }
  }
}
