#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_chunk_work.glsl"
layout(local_size_x = 64) in;

layout(push_constant) uniform Push { IzbComputePush push; };

// The texels of one record, worked by this thread (when the record buffer is full).
void work_record_here(uint mode, vec3 a, vec3 b, vec3 c, float area, int row, int first, int last) {
  for (int x = first; x <= last; ++x) {
    ivec2 texel = ivec2(x, row);
    if (mode != IZB_CHUNKS_FOR_TRACE) csm_texel(texel, a, b, c, area, mode);
    else if (trace_pair_outcome(texel, a, b, c, area) == IZB_PAIR_KEPT)
      trace_texel_list(texel_index(texel), a, b, c, 1.0 / area);
  }
}

// Compute trace / compute CSM, step 1: one thread per caster triangle walks its rows, cuts each row's
// span into records of at most kIzbRecordTexels texels and reserves them (a subgroup reserves its
// records with one atomic). A record that does not fit the buffer is worked here, so nothing is
// dropped; the request count grows the buffer for the next frame.
void main() {
  uint t = gl_GlobalInvocationID.x;
  uint mode = push.mode;
  vec3 a = vec3(0.0), b = vec3(0.0), c = vec3(0.0);
  float area = 0.0;
  ivec2 rows = ivec2(0, -1);
  if (t < push.triangle_count && triangle_wanted(t, mode)) {
    load_grid_triangle(t, a, b, c);
    area = edge_fn(c.xy, a.xy, b.xy);
    if (abs(area) > 1.0e-10) rows = triangle_rows(a, b, c);
  }
  uint count = 0u;
  for (int r = rows.x; r <= rows.y; ++r) {
    ivec2 span = triangle_row_span(a, b, c, r);
    if (span.x <= span.y) count += (uint(span.y - span.x) + kIzbRecordTexels) / kIzbRecordTexels;
  }
  uint offset = subgroupExclusiveAdd(count);
  uint total = subgroupAdd(count);
  uint base = 0u;
  if (subgroupElect() && total > 0u) base = atomicAdd(counters[chunk_counter(mode)], total);
  uint slot = subgroupBroadcastFirst(base) + offset;
  uint capacity = params.limits.z;
  for (int r = rows.x; r <= rows.y && count > 0u; ++r) {
    ivec2 span = triangle_row_span(a, b, c, r);
    for (int x = span.x; x <= span.y; x += int(kIzbRecordTexels)) {
      int last = min(x + int(kIzbRecordTexels) - 1, span.y);
      if (slot < capacity) chunks[slot] = uvec4(t, uint(r), uint(x), uint(last));
      else work_record_here(mode, a, b, c, area, r, x, last);
      ++slot;
    }
  }
}
