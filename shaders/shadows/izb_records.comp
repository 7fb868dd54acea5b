#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_tiles.glsl"
#include "shadows/izb_group_reserve.glsl"
layout(local_size_x = 64) in;

layout(push_constant) uniform Push { IzbComputePush push; };
#include "shadows/izb_triangles.glsl"

// The workgroup's work laid end to end, a thread per item: each thread's triangle, its direct texels
// (a rectangle) and its first tile row, and where its texels and its rows start (exclusive prefix sums;
// [64] holds the totals).
shared uint walk_triangle[64];
shared vec4 walk_a[64], walk_b[64], walk_c[64];  // its grid-space vertices (w of a: the signed area), read here once
shared ivec4 walk_direct[64];
shared int walk_first_row[64];
shared uint walk_texel_start[65];
shared uint walk_row_start[65];
shared uvec2 walk_subgroup_sums[64];

// Thread `owner`'s triangle, from shared memory.
void walked_triangle(uint owner, out vec3 a, out vec3 b, out vec3 c, out float area) {
  a = walk_a[owner].xyz;
  b = walk_b[owner].xyz;
  c = walk_c[owner].xyz;
  area = walk_a[owner].w;
}

// Item j's thread: the last whose items start at or before it.
uint walk_owner(uint j, bool rows) {
  uint lo = 0u, hi = 63u;
  while (lo < hi) {
    uint mid = (lo + hi + 1u) / 2u;
    if ((rows ? walk_row_start[mid] : walk_texel_start[mid]) <= j) lo = mid;
    else hi = mid - 1u;
  }
  return lo;
}

// The trace on a CPU device, without statistics (which count every texel a triangle touches): the
// small triangles' texels a row of a rectangle a thread, as izb_texel_bin.comp's trace_tile_rows
// walks a tile's (trace_texel_row: only the row's texels with nodes tested, a kept pair taking its
// slot with one atomic). (A thread a texel paid the walk's search and loads for every texel of the
// rectangles, and tested each twice: counting, then writing.) The same pairs, in another order.
bool walks_direct_rows(uint mode) {
  return izb_flag(IZB_FLAG_CPU_DEVICE) && mode == IZB_WORK_TRACE && !izb_flag(IZB_FLAG_STATS);
}
void trace_direct_rows(uint total_rows) {
  for (uint j = gl_LocalInvocationIndex; j < total_rows; j += 64u) {
    uint owner = walk_owner(j, false);
    ivec4 d = walk_direct[owner];
    vec3 a, b, c;
    float area;
    walked_triangle(owner, a, b, c, area);
    int y = d.y + int(j - walk_texel_start[owner]);
    for (int x0 = d.x; x0 <= d.z; x0 += 32)
      trace_texel_row(ivec2(x0, y), uint(min(d.z - x0 + 1, 32)), walk_triangle[owner], a, b, c, area);
  }
}

// Compute trace / compute CSM, step 1 (see izb.h): a thread per listed caster triangle finds its few
// texels (a small triangle) or its rows of tiles; then the workgroup works all its triangles' texels
// and rows together, a thread per texel or row (a triangle's many would otherwise serialize its one
// thread, and its subgroup with it), cutting each row's span into records
// of at most kIzbRecordTiles tiles (the workgroup reserves its records with one atomic). A record that
// does not fit the buffer is worked here, so nothing is dropped; the request count grows the buffer
// for the next frame.
void main() {
  // The workgroup's triangles, a thread each; the other threads only help walk.
  uint per_group = step_one_triangles();
  uint index = row_dispatch_index(gl_WorkGroupID, gl_LocalInvocationIndex, per_group);
  uint mode = kIzbWork;
  vec3 a = vec3(0.0), b = vec3(0.0), c = vec3(0.0);
  bool in_range;
  uint t;
  if (izb_flag(IZB_FLAG_TRIANGLES_IN_TRACE) && mode == IZB_WORK_TRACE) {
    // Every caster triangle, set up and listed here (IZB_FLAG_TRIANGLES_IN_TRACE); those that do not
    // reach the grid are left.
    in_range = gl_LocalInvocationIndex < per_group && index < push.triangle_count;
    t = in_range ? index : 0u;
    vec3 grid[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
    if (in_range) in_range = set_up_triangle(t, grid);
    list_triangle(in_range, t);
    a = grid[0];
    b = grid[1];
    c = grid[2];
  } else {
    in_range = gl_LocalInvocationIndex < per_group && index < listed_triangle_count();
    t = in_range ? listed_triangle(index) : 0u;
    if (in_range && triangle_wanted(t, mode)) load_grid_triangle(t, a, b, c);
  }
  float area = 0.0;
  ivec2 rows = ivec2(0, -1);
  ivec4 direct = ivec4(0, 0, -1, -1);  // texels [xy, zw] worked here (the trace: its pairs listed)
  if (in_range && triangle_wanted(t, mode)) {
    area = edge_fn(c.xy, a.xy, b.xy);
    bool useful = !is_csm_work(mode) || triangle_can_cover_a_texel(a, b, c, area);
    // (Edge-on to the light, |area| <= 1e-10: no trace tests it, so the lit map needs it neither.)
    if (abs(area) > 1.0e-10 && useful) rows = triangle_tile_rows(a, b, c, walk_slack(a, b, c, mode), trace_reach(mode));
    if (rows.x <= rows.y) {
      // A small triangle's texels, here: a tile's workgroup would leave most of its lanes idle (a CPU
      // device pays for them all), and a record its tiles' workgroups. The same per-texel work, so the
      // same map, CSM and trace pairs (the trace's pairs after the others, in no particular order).
      float slack = walk_slack(a, b, c, mode);
      float last = float(izb_resolution()) - 1.0;
      vec2 lo = clamp(floor(min(min(a.xy, b.xy), c.xy) - slack - trace_reach(mode)), vec2(0.0), vec2(last + 1.0));
      vec2 hi = clamp(floor(max(max(a.xy, b.xy), c.xy) + slack), vec2(-1.0), vec2(last));
      if ((hi.x - lo.x + 1.0) * (hi.y - lo.y + 1.0) <= float(step_one_texel_bound())) {
        direct = ivec4(lo, hi);
        rows = ivec2(0, -1);
      }
    }
  }
  uint lane = gl_LocalInvocationIndex;
  walk_triangle[lane] = t;
  walk_a[lane] = vec4(a, area);
  walk_b[lane] = vec4(b, 0.0);
  walk_c[lane] = vec4(c, 0.0);
  walk_direct[lane] = direct;
  walk_first_row[lane] = rows.x;
  // Where each thread's texels and rows start: inclusive sums in the subgroup, plus the subgroups'
  // before it (subgroups of any size that divides 64).
  // (walks_direct_rows: a direct rectangle's rows, not its texels.)
  uint direct_items = walks_direct_rows(mode) ? uint(direct.w - direct.y + 1)
                                              : uint((direct.z - direct.x + 1) * (direct.w - direct.y + 1));
  uvec2 items = uvec2(direct.x <= direct.z ? direct_items : 0u, rows.x <= rows.y ? uint(rows.y - rows.x + 1) : 0u);
  uvec2 through = subgroupInclusiveAdd(items);
  if (gl_SubgroupInvocationID == gl_SubgroupSize - 1u) walk_subgroup_sums[gl_SubgroupID] = through;
  barrier();
  for (uint s = 0u; s < gl_SubgroupID; ++s) through += walk_subgroup_sums[s];
  walk_texel_start[lane + 1u] = through.x;
  walk_row_start[lane + 1u] = through.y;
  if (lane == 0u) {
    walk_texel_start[0] = 0u;
    walk_row_start[0] = 0u;
  }
  barrier();

  // The small triangles' texels: the lit map and CSM write them, the trace lists its pairs for step 4
  // (counted first, so that the workgroup reserves them with one atomic, then written).
  // (The count's outcomes of a thread's first 32 texels are kept for the write, as bits.)
  uint total_texels = walk_texel_start[64];
  uint kept_total = 0u, fragments = 0u, kept_bits = 0u;
  if (walks_direct_rows(mode)) trace_direct_rows(total_texels);
  else for (uint pass = mode == IZB_WORK_TRACE ? 0u : 1u; pass < 2u; ++pass) {  // trace: count, then write
    uint slot = 0u;
    if (pass == 1u && mode == IZB_WORK_TRACE)
      slot = reserve_group_slots(IZB_COUNTER_PAIRS, kept_total, IZB_COUNTER_PAIR_DISPATCH, params.limits.w, kIzbPairGroup);
    for (uint j = lane, round = 0u; j < total_texels; j += 64u, ++round) {
      uint owner = walk_owner(j, false);
      uint texel_triangle = walk_triangle[owner];
      ivec4 d = walk_direct[owner];
      uint i = j - walk_texel_start[owner];
      uint width = uint(d.z - d.x + 1);
      ivec2 texel = d.xy + ivec2(i % width, i / width);
      walked_triangle(owner, a, b, c, area);
      if (mode != IZB_WORK_TRACE) {
        work_texel_here(texel, texel_triangle, a, b, c, area, mode);
        continue;
      }
      uint outcome;
      if (pass == 1u && round < 32u) outcome = (kept_bits & (1u << round)) != 0u ? IZB_PAIR_KEPT : IZB_PAIR_CULLED;
      else outcome = trace_pair_outcome(texel, a, b, c, area);
      if (pass == 0u) {
        kept_total += outcome == IZB_PAIR_KEPT ? 1u : 0u;
        fragments += outcome != IZB_PAIR_OUTSIDE ? 1u : 0u;
        if (outcome == IZB_PAIR_KEPT && round < 32u) kept_bits |= 1u << round;
        continue;
      }
      if (outcome != IZB_PAIR_KEPT) continue;
      if (slot < params.limits.w) pairs[slot] = uvec2(texel_triangle, texel_index(texel));
      else trace_texel_list(texel_index(texel), texel_triangle, a, b, c, 1.0 / area);
      ++slot;
    }
  }
  if (izb_flag(IZB_FLAG_STATS) && mode == IZB_WORK_TRACE) {
    add_sharded(IZB_COUNTER_FRAGMENTS, fragments, IZB_SHARD_SEED);
    add_sharded(IZB_COUNTER_FRAGMENTS_KEPT, kept_total, IZB_SHARD_SEED);
  }

  // The larger triangles' tile rows, cut into records (counted, reserved, then written likewise).
  uint total_rows = walk_row_start[64];
  uint record_total = 0u;
  for (uint pass = 0u; pass < 2u; ++pass) {
    uint slot = 0u;
    if (pass == 1u)
      slot = reserve_group_slots(record_counter(mode), record_total, record_dispatch_at(mode), params.limits.z,
                                 kIzbRecordsPerGroup * kIzbTileStepRecords);
    for (uint j = lane; j < total_rows; j += 64u) {
      uint owner = walk_owner(j, true);
      uint row_triangle = walk_triangle[owner];
      int r = walk_first_row[owner] + int(j - walk_row_start[owner]);
      walked_triangle(owner, a, b, c, area);
      ivec2 span = triangle_tile_span(a, b, c, r, walk_slack(a, b, c, mode), trace_reach(mode));
      if (span.x > span.y) continue;
      if (pass == 0u) {
        record_total += (uint(span.y - span.x) + kIzbRecordTiles) / kIzbRecordTiles;
        continue;
      }
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
}
