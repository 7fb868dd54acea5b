#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_tiles.glsl"
layout(local_size_x = 64) in;

layout(push_constant) uniform Push { IzbComputePush push; };

// Compute trace / compute CSM, step 1 (see izb.h): a thread per caster triangle walks its rows of
// tiles and cuts each row's span into records of at most kIzbRecordTiles tiles (a subgroup reserves
// its records with one atomic). A record that does not fit the buffer is worked here, so nothing is
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
    bool useful = !is_csm_work(mode) || triangle_can_cover_a_texel(a, b, c, area);
    // (Edge-on to the light, |area| <= 1e-10: no trace tests it, so the lit map needs it neither.)
    if (abs(area) > 1.0e-10 && useful) rows = triangle_tile_rows(a, b, c, walk_slack(a, b, c, mode));
    if (mode == IZB_WORK_LIT && rows.x <= rows.y) {
      // A small triangle's texels, here: a tile's workgroup would leave most of its lanes idle (a CPU
      // device pays for them all). The same per-texel work, so the same map.
      float slack = walk_slack(a, b, c, mode);
      float last = float(izb_resolution()) - 1.0;
      vec2 lo = clamp(floor(min(min(a.xy, b.xy), c.xy) - slack), vec2(0.0), vec2(last + 1.0));
      vec2 hi = clamp(floor(max(max(a.xy, b.xy), c.xy) + slack), vec2(-1.0), vec2(last));
      if ((hi.x - lo.x + 1.0) * (hi.y - lo.y + 1.0) <= float(kIzbLitDirectTexels)) {
        for (int y = int(lo.y); y <= int(hi.y); ++y)
          for (int x = int(lo.x); x <= int(hi.x); ++x) lit_texel(ivec2(x, y), a, b, c, area);
        rows = ivec2(0, -1);
      }
    }
  }
  float slack = walk_slack(a, b, c, mode);
  uint count = 0u;
  for (int r = rows.x; r <= rows.y; ++r) {
    ivec2 span = triangle_tile_span(a, b, c, r, slack);
    if (span.x <= span.y) count += (uint(span.y - span.x) + kIzbRecordTiles) / kIzbRecordTiles;
  }
  uint offset = subgroupExclusiveAdd(count);
  uint total = subgroupAdd(count);
  uint base = 0u;
  if (subgroupElect() && total > 0u) base = atomicAdd(counters[record_counter(mode)], total);
  uint slot = subgroupBroadcastFirst(base) + offset;
  for (int r = rows.x; r <= rows.y && count > 0u; ++r) {
    ivec2 span = triangle_tile_span(a, b, c, r, slack);
    for (int x = span.x; x <= span.y; x += int(kIzbRecordTiles)) {
      int last = min(x + int(kIzbRecordTiles) - 1, span.y);
      if (slot < params.limits.z) {
        records[slot] = uvec4(t, uint(r), uint(x), uint(last));
      } else {
        for (int k = x; k <= last; ++k)
          if (tile_survives(uvec2(k, r), a, b, c, area, mode)) work_tile_here(uvec2(k, r), t, a, b, c, area, mode);
      }
      ++slot;
    }
  }
}
