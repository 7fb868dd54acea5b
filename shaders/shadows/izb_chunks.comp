#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_chunk_work.glsl"
layout(local_size_x = 64) in;

layout(push_constant) uniform Push { IzbComputePush push; };

// Compute trace / compute CSM, step 1: one thread per caster triangle cuts its texel box into chunks
// of kIzbChunkTexels and reserves one record per chunk (a subgroup reserves its records with one
// atomic). A record that does not fit the buffer is worked here, serially, so nothing is dropped;
// the request count grows the buffer for the next frame.
void main() {
  uint t = gl_GlobalInvocationID.x;
  uint mode = push.mode;
  vec3 a = vec3(0.0), b = vec3(0.0), c = vec3(0.0);
  float area = 0.0;
  TexelBox box;
  box.lo = ivec2(0);
  box.size = ivec2(0);
  if (t < push.triangle_count && triangle_wanted(t, mode)) {
    load_grid_triangle(t, a, b, c);
    area = edge_fn(c.xy, a.xy, b.xy);
    if (abs(area) > 1.0e-10) box = triangle_texel_box(a, b, c);
  }
  uint texels = box_texels(box);
  uint count = (texels + kIzbChunkTexels - 1u) / kIzbChunkTexels;
  uint offset = subgroupExclusiveAdd(count);
  uint total = subgroupAdd(count);
  uint base = 0u;
  if (subgroupElect() && total > 0u) base = atomicAdd(counters[chunk_counter(mode)], total);
  base = subgroupBroadcastFirst(base);
  uint capacity = params.limits.z;
  for (uint k = 0u; k < count; ++k) {
    uint slot = base + offset + k;
    uint first = k * kIzbChunkTexels;
    if (slot < capacity) {
      chunks[slot] = uvec2(t, first);
      continue;
    }
    uint last = min(first + kIzbChunkTexels, texels);
    for (uint i = first; i < last; ++i) {
      ivec2 texel = box_texel(box, i);
      if (mode != IZB_CHUNKS_FOR_TRACE) {
        csm_texel(texel, a, b, c, area, mode);
        continue;
      }
      bool touched;
      if (trace_pair_survives(texel, a, b, c, area, touched))
        trace_texel_list(texel_index(texel), a, b, c, 1.0 / area);
    }
  }
}
