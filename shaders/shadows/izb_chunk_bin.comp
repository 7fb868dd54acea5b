#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_chunk_work.glsl"
layout(local_size_x = kIzbChunkLanes) in;

layout(push_constant) uniform Push { IzbComputePush push; };

// Compute trace / compute CSM, step 2: one workgroup per chunk record walks its texels. The CSM
// writes fully covered texels' depth bounds; the trace keeps the (triangle, texel) pairs that touch
// and survive the depth cull against the texel's farthest node, appended densely so the list walks
// of step 3 fill every lane. A pair that does not fit the buffer is traced here.
void main() {
  uint record = gl_WorkGroupID.y * kIzbDispatchRow + gl_WorkGroupID.x;
  uint mode = push.mode;
  if (record >= chunk_records(mode)) return;  // uniform over the workgroup
  uvec2 chunk = chunks[record];
  uint t = chunk.x;
  vec3 a, b, c;
  load_grid_triangle(t, a, b, c);
  float area = edge_fn(c.xy, a.xy, b.xy);
  TexelBox box = triangle_texel_box(a, b, c);
  uint last = min(chunk.y + kIzbChunkTexels, box_texels(box));
  uint touched_total = 0u, kept_total = 0u;
  for (uint first = chunk.y; first < last; first += kIzbChunkLanes) {
    uint i = first + gl_LocalInvocationID.x;
    bool keep = false, touched = false;
    if (i < last) {
      ivec2 texel = box_texel(box, i);
      if (mode != IZB_CHUNKS_FOR_TRACE) {
        csm_texel(texel, a, b, c, area, mode);
      } else {
        keep = trace_pair_survives(texel, a, b, c, area, touched);
      }
    }
    if (mode != IZB_CHUNKS_FOR_TRACE) continue;
    uint want = keep ? 1u : 0u;
    uint offset = subgroupExclusiveAdd(want);
    uint total = subgroupAdd(want);
    uint base = 0u;
    if (subgroupElect() && total > 0u) base = atomicAdd(counters[IZB_COUNTER_PAIRS], total);
    base = subgroupBroadcastFirst(base);
    if (keep) {
      ivec2 texel = box_texel(box, i);
      uint slot = base + offset;
      if (slot < params.limits.w) pairs[slot] = uvec2(t, texel_index(texel));
      else trace_texel_list(texel_index(texel), a, b, c, 1.0 / area);
    }
    touched_total += touched ? 1u : 0u;
    kept_total += want;
  }
  if (izb_flag(IZB_FLAG_STATS) && mode == IZB_CHUNKS_FOR_TRACE) {
    uint f = subgroupAdd(touched_total);
    uint k = subgroupAdd(kept_total);
    if (subgroupElect()) {
      if (f > 0u) atomicAdd(counters[IZB_COUNTER_FRAGMENTS], f);
      if (k > 0u) atomicAdd(counters[IZB_COUNTER_FRAGMENTS_KEPT], k);
    }
  }
}
