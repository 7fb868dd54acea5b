#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_tiles.glsl"
layout(local_size_x = 64) in;

layout(push_constant) uniform Push { IzbComputePush push; };

// The workgroup's tile rows laid end to end: each thread's triangle, its first row, and where its
// rows start (an exclusive prefix sum; [64] holds the total).
shared uint walk_triangle[64];
shared int walk_first_row[64];
shared uint walk_row_start[65];

// The trace's (triangle, texel) pairs of the texels [direct.xy, direct.zw] that touch and survive
// the texel's cull, appended to step 4's pairs (one atomic per subgroup). The first 32 texels' outcomes
// are kept as bits (a GPU's few texels are tested once), any more tested again to write. A pair that
// does not fit is traced here.
void trace_pairs_here(uint t, ivec4 direct, vec3 a, vec3 b, vec3 c, float area) {
  uint kept = 0u, fragments = 0u, kept_bits = 0u;
  int width = direct.z - direct.x + 1;
  for (int y = direct.y; y <= direct.w; ++y) {
    for (int x = direct.x; x <= direct.z; ++x) {
      uint outcome = trace_pair_outcome(ivec2(x, y), a, b, c, area);
      int i = (y - direct.y) * width + (x - direct.x);
      if (outcome == IZB_PAIR_KEPT) {
        ++kept;
        if (i < 32) kept_bits |= 1u << uint(i);
      }
      fragments += outcome != IZB_PAIR_OUTSIDE ? 1u : 0u;
    }
  }
  uint slot = reserve_pairs(kept);
  if (izb_flag(IZB_FLAG_STATS)) {
    add_sharded(IZB_COUNTER_FRAGMENTS, fragments, IZB_SHARD_SEED);
    add_sharded(IZB_COUNTER_FRAGMENTS_KEPT, kept, IZB_SHARD_SEED);
  }
  for (int y = direct.y; y <= direct.w && kept > 0u; ++y) {
    for (int x = direct.x; x <= direct.z; ++x) {
      ivec2 texel = ivec2(x, y);
      int i = (y - direct.y) * width + (x - direct.x);
      bool keep = i < 32 ? (kept_bits & (1u << uint(i))) != 0u : trace_pair_outcome(texel, a, b, c, area) == IZB_PAIR_KEPT;
      if (!keep) continue;
      if (slot < params.limits.w) pairs[slot] = uvec2(t, texel_index(texel));
      else trace_texel_list(texel_index(texel), t, a, b, c, 1.0 / area);
      ++slot;
    }
  }
}

// Compute trace / compute CSM, step 1 (see izb.h): a thread per listed caster triangle finds its rows
// of tiles; then the workgroup walks all its triangles' rows together, a thread per row (a large
// triangle's many rows would otherwise serialize its one thread), cutting each row's span into records
// of at most kIzbRecordTiles tiles (a subgroup reserves its records with one atomic). A record that
// does not fit the buffer is worked here, so nothing is dropped; the request count grows the buffer
// for the next frame.
void main() {
  uint index = row_dispatch_index(gl_WorkGroupID, gl_LocalInvocationIndex, 64u);
  bool in_range = index < listed_triangle_count();
  uint t = in_range ? listed_triangle(index) : 0u;
  uint mode = push.mode;
  vec3 a = vec3(0.0), b = vec3(0.0), c = vec3(0.0);
  float area = 0.0;
  ivec2 rows = ivec2(0, -1);
  ivec4 direct = ivec4(0, 0, -1, -1);  // texels [xy, zw] worked here (the trace: its pairs listed)
  if (in_range && triangle_wanted(t, mode)) {
    load_grid_triangle(t, a, b, c);
    area = edge_fn(c.xy, a.xy, b.xy);
    bool useful = !is_csm_work(mode) || triangle_can_cover_a_texel(a, b, c, area);
    // (Edge-on to the light, |area| <= 1e-10: no trace tests it, so the lit map needs it neither.)
    if (abs(area) > 1.0e-10 && useful) rows = triangle_tile_rows(a, b, c, walk_slack(a, b, c, mode));
    if (rows.x <= rows.y) {
      // A small triangle's texels, here: a tile's workgroup would leave most of its lanes idle (a CPU
      // device pays for them all), and a record its tiles' workgroups. The same per-texel work, so the
      // same map, CSM and trace pairs (the trace's pairs after the others, in no particular order).
      float slack = walk_slack(a, b, c, mode);
      float last = float(izb_resolution()) - 1.0;
      vec2 lo = clamp(floor(min(min(a.xy, b.xy), c.xy) - slack), vec2(0.0), vec2(last + 1.0));
      vec2 hi = clamp(floor(max(max(a.xy, b.xy), c.xy) + slack), vec2(-1.0), vec2(last));
      if ((hi.x - lo.x + 1.0) * (hi.y - lo.y + 1.0) <= float(kIzbDirectTexels)) {
        direct = ivec4(lo, hi);
        rows = ivec2(0, -1);
        if (mode != IZB_WORK_TRACE)
          for (int y = direct.y; y <= direct.w; ++y)
            for (int x = direct.x; x <= direct.z; ++x) work_texel_here(ivec2(x, y), t, a, b, c, area, mode);
      }
    }
  }
  if (mode == IZB_WORK_TRACE) trace_pairs_here(t, direct, a, b, c, area);

  uint lane = gl_LocalInvocationIndex;
  walk_triangle[lane] = t;
  walk_first_row[lane] = rows.x;
  walk_row_start[lane + 1u] = rows.x <= rows.y ? uint(rows.y - rows.x + 1) : 0u;
  barrier();
  if (lane == 0u) {
    walk_row_start[0] = 0u;
    for (uint i = 1u; i <= 64u; ++i) walk_row_start[i] += walk_row_start[i - 1u];
  }
  barrier();
  uint total_rows = walk_row_start[64];
  for (uint first = 0u; first < total_rows; first += 64u) {
    uint j = first + lane;
    uint row_triangle = 0u;
    int r = 0;
    ivec2 span = ivec2(0, -1);
    uint count = 0u;
    if (j < total_rows) {
      // The thread whose rows hold row j: the last whose rows start at or before it.
      uint lo = 0u, hi = 63u;
      while (lo < hi) {
        uint mid = (lo + hi + 1u) / 2u;
        if (walk_row_start[mid] <= j) lo = mid;
        else hi = mid - 1u;
      }
      row_triangle = walk_triangle[lo];
      r = walk_first_row[lo] + int(j - walk_row_start[lo]);
      load_grid_triangle(row_triangle, a, b, c);
      area = edge_fn(c.xy, a.xy, b.xy);
      span = triangle_tile_span(a, b, c, r, walk_slack(a, b, c, mode));
      if (span.x <= span.y) count = (uint(span.y - span.x) + kIzbRecordTiles) / kIzbRecordTiles;
    }
    uint slot = reserve_slots_dispatched(record_counter(mode), count, record_dispatch_at(mode), params.limits.z,
                                         kIzbRecordsPerGroup * kIzbTileStepRecords);
    for (int x = span.x; x <= span.y; x += int(kIzbRecordTiles)) {
      int last = min(x + int(kIzbRecordTiles) - 1, span.y);
      if (slot < params.limits.z) {
        records[slot] = uvec4(row_triangle, uint(r), uint(x), uint(last));
      } else {
        for (int k = x; k <= last; ++k)
          if (tile_survives(uvec2(k, r), a, b, c, area, mode))
            work_tile_here(uvec2(k, r), row_triangle, a, b, c, area, mode);
      }
      ++slot;
    }
  }
}
