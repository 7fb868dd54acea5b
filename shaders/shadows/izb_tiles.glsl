// The compute trace and compute CSM over light-space tiles (see izb.h), shared by their passes.
// Include after izb_prelude.glsl.
#include "csm.h"

layout(set = 0, binding = IZB_BINDING_RECORDS, std430) buffer Records { uvec4 records[]; };
layout(set = 0, binding = IZB_BINDING_TILE_PAIRS, std430) buffer TilePairs { uvec2 tile_pairs[]; };
layout(set = 0, binding = IZB_BINDING_PAIRS, std430) buffer Pairs { uvec2 pairs[]; };

layout(constant_id = 0) const uint kIzbTileStepLanes = 32u;
layout(constant_id = 1) const uint kIzbRecordsPerGroup = kIzbRecordsPerGroupGpu;
layout(constant_id = 2) const uint kIzbTilePairsPerGroup = kIzbTilePairsPerGroupGpu;
// Step 2's records worked side by side in a workgroup (kIzbTileStepLanes / this lanes each, at least
// kIzbRecordTiles when above 1): its workgroups reserve their pairs with one atomic.
layout(constant_id = 4) const uint kIzbTileStepRecords = 1u;
// The work (IZB_WORK_*) of steps 1-3: a pipeline each, so that each holds only its own work's code.
layout(constant_id = 5) const uint kIzbWork = IZB_WORK_TRACE;

bool is_csm_work(uint mode) { return mode == IZB_WORK_CSM_HERTEL || mode == IZB_WORK_CSM_BARYCENTRIC; }
// Each work's own request counters.
uint record_counter(uint mode) {
  return mode == IZB_WORK_TRACE ? IZB_COUNTER_RECORDS
                                : (mode == IZB_WORK_LIT ? IZB_COUNTER_LIT_RECORDS : IZB_COUNTER_RECORDS + 1u);
}
uint tile_pair_counter(uint mode) {
  return mode == IZB_WORK_TRACE ? IZB_COUNTER_TILE_PAIRS
                                : (mode == IZB_WORK_LIT ? IZB_COUNTER_LIT_TILE_PAIRS : IZB_COUNTER_TILE_PAIRS + 1u);
}
// Where each work's step 2 and step 3 dispatches live.
uint record_dispatch_at(uint mode) { return izb_step_dispatch_at(mode); }
uint tile_pair_dispatch_at(uint mode) { return izb_step_dispatch_at(mode) + 3u; }
uint record_count(uint mode) { return min(counters[record_counter(mode)], params.limits.z); }
uint tile_pair_count(uint mode) { return min(counters[tile_pair_counter(mode)], params.capacities.x); }
// Step 3's (triangle, tile) pairs per workgroup: the CSM and lit map work kIzbQuadPairsPerRound side
// by side, an invocation per 2x2 texels (izb_texel_bin.comp).
const uint kIzbQuadPairsPerRound = 4u;
bool works_texel_quads(uint mode) { return mode != IZB_WORK_TRACE; }
uint tile_pairs_per_group(uint mode) {
  return works_texel_quads(mode) ? max(kIzbTilePairsPerGroup, kIzbQuadPairsPerRound) : kIzbTilePairsPerGroup;
}

// The lit map takes every caster; the CSM those chosen for it this frame.
bool triangle_wanted(uint t, uint mode) {
  return !is_csm_work(mode) || (caster_draw_words[caster_draw(t)] & IZB_DRAW_IN_CSM) != 0u;
}

// How far (texels) the tile walk widens a triangle: more than the trace's and CSM's touch tests'
// slack and rounding, or the lit map's widened footprint.
float walk_slack(vec3 a, vec3 b, vec3 c, uint mode) {
  return mode == IZB_WORK_LIT ? lit_slack(a, b, c) + 1.0e-3 : 2.0e-3;
}

// CSM: a triangle that fully covers a texel contains the texel's inscribed circle (radius 1/2), so
// one whose own inscribed circle is smaller (radius 2 area / perimeter) can write no texel.
bool triangle_can_cover_a_texel(vec3 a, vec3 b, vec3 c, float area) {
  float perimeter = length(b.xy - a.xy) + length(c.xy - b.xy) + length(a.xy - c.xy);
  return abs(area) >= (0.5 - 1.0e-3) * perimeter;  // |area| here is twice the triangle's area
}

// How many texels past its own a texel's pairs reach up and right: 1 for the trace with anchored
// nodes (IZB_FLAG_ANCHORED_NODES: a node's samples lie in the 2x2 block from its texel), else 0. The
// tile walk reaches as far back from the triangle's lower bounds.
float trace_reach(uint mode) { return mode == IZB_WORK_TRACE && izb_flag(IZB_FLAG_ANCHORED_NODES) ? 1.0 : 0.0; }

// The rows of tiles [first, last] a triangle's bounds touch, reaching `reach` texels back (empty when
// first > last).
ivec2 triangle_tile_rows(vec3 a, vec3 b, vec3 c, float slack, float reach) {
  float tile = float(kIzbTile);
  float lo = floor((min(min(a.y, b.y), c.y) - slack - reach) / tile);
  float hi = floor((max(max(a.y, b.y), c.y) + slack) / tile);
  return ivec2(clamp(lo, 0.0, float(tiles_per_side())), clamp(hi, -1.0, float(tiles_per_side()) - 1.0));
}

// The tiles [first, last] of tile row `row` the triangle may touch: its exact x-extent over the row's
// band (vertices inside it, edges crossing its two lines), widened by `slack` (walk_slack()) and
// rounding, the band and the extent's low end by `reach` (trace_reach()). Empty when first > last.
ivec2 triangle_tile_span(vec3 a, vec3 b, vec3 c, int row, float slack, float reach) {
  float tile = float(kIzbTile);
  float y0 = float(row) * tile - slack, y1 = float(row + 1) * tile + slack + reach;
  vec2 p[3] = vec2[3](a.xy, b.xy, c.xy);
  float x_lo = 1.0e30, x_hi = -1.0e30;
  for (int i = 0; i < 3; ++i) {
    if (p[i].y >= y0 && p[i].y <= y1) {
      x_lo = min(x_lo, p[i].x);
      x_hi = max(x_hi, p[i].x);
    }
    vec2 e0 = p[i], e1 = p[(i + 1) % 3];
    if (e0.y == e1.y) continue;
    for (int k = 0; k < 2; ++k) {
      float y = k == 0 ? y0 : y1;
      if ((e0.y - y) * (e1.y - y) > 0.0) continue;
      float x = e0.x + (y - e0.y) * (e1.x - e0.x) / (e1.y - e0.y);
      x_lo = min(x_lo, x);
      x_hi = max(x_hi, x);
    }
  }
  if (x_lo > x_hi) return ivec2(0, -1);
  float widen = slack + 1.0e-6 * max(abs(x_lo), abs(x_hi));
  float last = float(tiles_per_side()) - 1.0;
  return ivec2(clamp(floor((x_lo - widen - reach) / tile), 0.0, last + 1.0),
               clamp(floor((x_hi + widen) / tile), -1.0, last));
}

// The texel rectangle [lo, hi) of a tile, clipped to the grid.
void tile_rect(uvec2 tile, out vec2 lo, out vec2 hi) {
  lo = vec2(tile * kIzbTile);
  hi = min(lo + float(kIzbTile), vec2(float(izb_resolution())));
}

// CSM: whether the triangle may fully cover some texel of the rectangle of texels [lo, hi). A fully
// covered texel's centre lies in [lo + 1/2, hi - 1/2] and at least half a texel inside every edge,
// so a rectangle none of whose points is that far inside some edge holds no such texel.
bool rect_may_hold_covered_texel(vec2 lo, vec2 hi, vec3 a, vec3 b, vec3 c, float orientation) {
  return rect_depth_inside(lo + 0.5, hi - 0.5, a, b, c, orientation) >= 0.5 - 1.0e-3;
}

// Step 2: whether the triangle may touch the tile and, for the trace, lie in front of its farthest
// node somewhere (an empty tile holds 0 and culls everything), or, for the CSM, fully cover a texel.
bool tile_survives(uvec2 tile, vec3 a, vec3 b, vec3 c, float area, uint mode) {
  vec2 lo, hi;
  tile_rect(tile, lo, hi);
  if (mode == IZB_WORK_LIT) return rect_touches_triangle_within(lo, hi, a, b, c, sign(area), lit_slack(a, b, c));
  if (mode != IZB_WORK_TRACE) return rect_may_hold_covered_texel(lo, hi, a, b, c, sign(area));
  hi += trace_reach(mode);  // its anchors' blocks
  if (!izb_flag(IZB_FLAG_NO_DEPTH_CULL)) {
    float farthest_node = uintBitsToFloat(farthest[tile_farthest_index(tile.y * tiles_per_side() + tile.x)]);
    if (farthest_node <= 0.0 || triangle_nearest_depth(lo, hi, a, b, c, area) >= farthest_node) return false;
  }
  return rect_touches_triangle(lo, hi, a, b, c, sign(area));
}

// Outside the grid, or no node's depth raised its farthest bound (trace_pair_outcome culls it).
bool texel_without_nodes(ivec2 texel) {
  return !all(lessThan(uvec2(texel), uvec2(izb_resolution()))) || uintBitsToFloat(farthest[texel_index(texel)]) <= 0.0;
}

// Trace: what becomes of a (triangle, texel) pair. The cheap depth cull against the texel's farthest
// node runs first; the touch test after it, or first when statistics count the fragments before the
// cull.
const uint IZB_PAIR_OUTSIDE = 0u;  // the triangle does not touch the texel
const uint IZB_PAIR_CULLED = 1u;   // touches, but lies behind every node of the texel
const uint IZB_PAIR_KEPT = 2u;
// With anchored nodes the texel stands for its 2x2 block (trace_reach).
uint trace_pair_outcome(ivec2 texel, vec3 a, vec3 b, vec3 c, float area) {
  vec2 lo = vec2(texel);
  vec2 hi = lo + 1.0 + trace_reach(IZB_WORK_TRACE);
  bool counting = izb_flag(IZB_FLAG_STATS);
  if (counting && !rect_touches_triangle(lo, hi, a, b, c, sign(area))) return IZB_PAIR_OUTSIDE;
  if (!izb_flag(IZB_FLAG_NO_DEPTH_CULL)) {
    float farthest_node = uintBitsToFloat(farthest[texel_index(texel)]);
    if (farthest_node <= 0.0 || triangle_nearest_depth(lo, hi, a, b, c, area) >= farthest_node)
      return IZB_PAIR_CULLED;
  }
  if (!counting && !rect_touches_triangle(lo, hi, a, b, c, sign(area))) return IZB_PAIR_OUTSIDE;
  return IZB_PAIR_KEPT;
}

// The trace on a CPU device: triangle `t` against the `width` (at most 32) texels of a row from
// `first`, a thread's, each kept pair taking its slot with one atomic (no workgroup barrier). Without
// statistics (which count the texels a triangle touches) a texel without nodes is culled whatever the
// triangle: the row's farthest depths are read first, straight through (no loop control a texel), into
// a mask of the texels left, so a batch tests a texel only where some lane has nodes in one (lavapipe,
// lamps' point light at 1280x720: step 3 26.2 -> 18.4 ms scanning texel by texel, 13.5-13.8 with the
// mask). Returns the touched texels (fragments) and the kept pairs, for the statistics.
uvec2 trace_texel_row(ivec2 first, uint width, uint t, vec3 a, vec3 b, vec3 c, float area) {
  uint todo = width == 32u ? 0xffffffffu : (1u << width) - 1u;
  if (!izb_flag(IZB_FLAG_STATS) && !izb_flag(IZB_FLAG_NO_DEPTH_CULL))
    for (uint x = 0u; x < width; ++x)
      if (texel_without_nodes(first + ivec2(x, 0))) todo &= ~(1u << x);
  uvec2 counts = uvec2(0u);
  while (todo != 0u) {
    ivec2 texel = first + ivec2(findLSB(todo), 0);
    todo &= todo - 1u;
    bool inside = all(lessThan(uvec2(texel), uvec2(izb_resolution())));
    uint outcome = inside ? trace_pair_outcome(texel, a, b, c, area) : IZB_PAIR_OUTSIDE;
    counts.x += outcome != IZB_PAIR_OUTSIDE ? 1u : 0u;
    if (outcome != IZB_PAIR_KEPT) continue;
    ++counts.y;
    uint slot = reserve_slots_raising(IZB_COUNTER_PAIRS, 1u, true, IZB_COUNTER_PAIR_DISPATCH, params.limits.w, kIzbPairGroup);
    if (slot < params.limits.w) pairs[slot] = uvec2(t, texel_index(texel));
    else trace_texel_list(texel_index(texel), t, a, b, c, 1.0 / area);
  }
  return counts;
}

// CSM at one corner of a texel: its barycentric weights (each against the test's slack: true when the
// corner is inside) and the triangle's plane depth there.
bool csm_corner(vec2 corner, vec3 a, vec3 b, vec3 c, float area, out float depth) {
  float w0 = edge_fn(corner, b.xy, c.xy) / area;
  float w1 = edge_fn(corner, c.xy, a.xy) / area;
  float w2 = 1.0 - w0 - w1;
  depth = w0 * a.z + w1 * b.z + w2 * c.z;
  return !(w0 < kCsmBarycentricSlack || w1 < kCsmBarycentricSlack || w2 < kCsmBarycentricSlack);
}

// CSM, Hertel's test: whether the texel's centre lies far enough inside every edge.
bool csm_hertel_covers(ivec2 texel, vec3 a, vec3 b, vec3 c, float area) {
  vec2 centre = vec2(texel) + 0.5;
  vec2 p[3] = vec2[3](a.xy, b.xy, c.xy);
  for (int i = 0; i < 3; ++i) {
    vec2 e0 = p[i];
    vec2 e1 = p[(i + 1) % 3];
    float distance_in = sign(area) * edge_fn(centre, e0, e1) / length(e1 - e0);
    if (distance_in < 0.70710678 + kCsmDistanceSlack) return false;
  }
  return true;
}

// CSM: lowers the texel's stored bound to `far_depth` (depths in [0,1]: float order is bit order).
void csm_store(ivec2 texel, float far_depth) {
  lower_stored_bits(texel_index(texel), floatBitsToUint(clamp(far_depth, 0.0, 1.0)));
}

// CSM: where the triangle fully covers the texel (Hertel's or the barycentric test, the same
// arithmetic as csm.frag), the nearest bound so far of its farthest depth over the texel, from its
// four corners' csm_corner (in the order (0,0), (1,0), (0,1), (1,1)).
void csm_texel_from_corners(ivec2 texel, bool inside[4], float depth[4], vec3 a, vec3 b, vec3 c, float area,
                            uint test) {
  if (test == IZB_WORK_CSM_HERTEL && !csm_hertel_covers(texel, a, b, c, area)) return;
  float far_depth = -1.0e30;
  for (int i = 0; i < 4; ++i) {
    if (test == IZB_WORK_CSM_BARYCENTRIC && !inside[i]) return;
    far_depth = max(far_depth, depth[i]);
  }
  csm_store(texel, far_depth);
}

void csm_texel(ivec2 texel, vec3 a, vec3 b, vec3 c, float area, uint test) {
  bool inside[4];
  float depth[4];
  for (int i = 0; i < 4; ++i) inside[i] = csm_corner(vec2(texel + ivec2(i & 1, i >> 1)), a, b, c, area, depth[i]);
  csm_texel_from_corners(texel, inside, depth, a, b, c, area, test);
}

// csm_texel over the 2x2 texels from `first` (those inside the grid), each of their 9 corners
// evaluated once: the same arithmetic per corner, so the same bounds.
void csm_texel_quad(ivec2 first, vec3 a, vec3 b, vec3 c, float area, uint test) {
  float depth[9];
  bool inside[9];
  for (int i = 0; i < 9; ++i) inside[i] = csm_corner(vec2(first + ivec2(i % 3, i / 3)), a, b, c, area, depth[i]);
  for (int k = 0; k < 4; ++k) {
    ivec2 texel = first + ivec2(k & 1, k >> 1);
    if (any(greaterThanEqual(uvec2(texel), uvec2(izb_resolution())))) continue;
    int corner = (k >> 1) * 3 + (k & 1);  // its lower-left corner among the 9
    int corners[4] = int[4](corner, corner + 1, corner + 3, corner + 4);
    bool texel_inside[4];
    float texel_depth[4];
    for (int i = 0; i < 4; ++i) {
      texel_inside[i] = inside[corners[i]];
      texel_depth[i] = depth[corners[i]];
    }
    csm_texel_from_corners(texel, texel_inside, texel_depth, a, b, c, area, test);
  }
}

// Lit map: where the triangle touches the texel widened by `slack` (lit_slack), lowers the texel's
// bound to the triangle's and `least` with it (its tile's least texel bound is the caller's to lower);
// whether it touched.
bool lower_lit_texel(ivec2 texel, vec3 a, vec3 b, vec3 c, float area, float slack, inout uint least) {
  vec2 lo = vec2(texel);
  if (!rect_touches_triangle_within(lo, lo + 1.0, a, b, c, sign(area), slack)) return false;
  uint bits = ordered_depth_bits(lit_nearest_depth(lo, lo + 1.0, a, b, c, area, slack));
  lower_stored_bits(lit_map_index(texel_index(texel)), bits);
  least = min(least, bits);
  return true;
}

// Lit map: where the triangle touches the widened texel, lowers the texel's bound, its tile's least
// and its corners' planes to the triangle's.
void lit_texel(ivec2 texel, vec3 a, vec3 b, vec3 c, float area) {
  uint least = 0xffffffffu;
  if (!lower_lit_texel(texel, a, b, c, area, lit_slack(a, b, c), least)) return;
  lower_stored_bits(lit_tile_record(uvec2(texel) / kIzbTile) + kLitTileLeast, least);
  lower_lit_corners(texel, a, b, c, area);
}

// lit_texel over the 2x2 texels from `first` (those inside the grid; `first` even, so all four lie
// in one tile, whose least bound is lowered once): each of their 9 corners is lowered once where a
// touched texel of the four has it, to the same bound.
void lit_texel_quad(ivec2 first, vec3 a, vec3 b, vec3 c, float area) {
  float slack = lit_slack(a, b, c);
  uint touched = 0u, least = 0xffffffffu;
  for (int k = 0; k < 4; ++k) {
    ivec2 texel = first + ivec2(k & 1, k >> 1);
    if (all(lessThan(uvec2(texel), uvec2(izb_resolution()))) && lower_lit_texel(texel, a, b, c, area, slack, least))
      touched |= 1u << k;
  }
  if (touched == 0u) return;
  lower_stored_bits(lit_tile_record(uvec2(first) / kIzbTile) + kLitTileLeast, least);
  LitPlane q = lit_plane(a, b, c, area);
  for (int corner = 0; corner < 9; ++corner) {
    int i = corner % 3, j = corner / 3;
    uint adjacent = 0u;  // the texels of the four that have this corner
    for (int k = 0; k < 4; ++k)
      if ((k & 1) <= i && i <= (k & 1) + 1 && (k >> 1) <= j && j <= (k >> 1) + 1) adjacent |= 1u << k;
    if ((touched & adjacent) != 0u) lower_lit_corner(first + ivec2(i, j), a, q);
  }
}

// Lit map, step 2: whether the triangle covers all of the tile (its four corners inside every edge).
// Rounding may err either way; that only moves the triangle between the map's two levels, both sound.
bool lit_covers_tile(uvec2 tile, vec3 a, vec3 b, vec3 c, float area) {
  vec2 lo, hi;
  tile_rect(tile, lo, hi);
  float orientation = sign(area);
  for (int k = 0; k < 4; ++k) {
    vec2 p = vec2((k & 1) != 0 ? hi.x : lo.x, (k & 2) != 0 ? hi.y : lo.y);
    if (orientation * edge_fn(p, a.xy, b.xy) < 0.0 || orientation * edge_fn(p, b.xy, c.xy) < 0.0 ||
        orientation * edge_fn(p, c.xy, a.xy) < 0.0)
      return false;
  }
  return true;
}

// Lit map, tile level (lit_tile_record): lowers the tile's bound and its own four corners' planes to the
// triangle's, as lower_lit_texel and lower_lit_corner do for a texel.
void lower_lit_tile(uvec2 tile, vec3 a, vec3 b, vec3 c, float area) {
  vec2 lo, hi;
  tile_rect(tile, lo, hi);
  uint record = lit_tile_record(tile);
  lower_stored_bits(record + kLitTileBound,
                    ordered_depth_bits(lit_nearest_depth(lo, hi, a, b, c, area, lit_slack(a, b, c))));
  LitPlane q = lit_plane(a, b, c, area);
  for (uint k = 0u; k < 4u; ++k) {
    uvec2 corner = tile + uvec2(k & 1u, k >> 1u);
    lower_lit_plane_at(lit_tile_corner_point(corner), record + kLitTileCorners + k, a, q);
  }
}

// Step 3 for one texel of a kept tile, done serially where a buffer overflowed.
void work_texel_here(ivec2 texel, uint t, vec3 a, vec3 b, vec3 c, float area, uint mode) {
  if (any(greaterThanEqual(uvec2(texel), uvec2(izb_resolution())))) return;
  if (mode == IZB_WORK_LIT) lit_texel(texel, a, b, c, area);
  else if (mode != IZB_WORK_TRACE) csm_texel(texel, a, b, c, area, mode);
  else if (trace_pair_outcome(texel, a, b, c, area) == IZB_PAIR_KEPT)
    trace_texel_list(texel_index(texel), t, a, b, c, 1.0 / area);
}

void work_tile_here(uvec2 tile, uint t, vec3 a, vec3 b, vec3 c, float area, uint mode) {
  for (uint i = 0u; i < kIzbTile * kIzbTile; ++i)
    work_texel_here(ivec2(tile * kIzbTile + uvec2(i % kIzbTile, i / kIzbTile)), t, a, b, c, area, mode);
}
