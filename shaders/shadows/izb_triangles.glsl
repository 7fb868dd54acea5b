// Every caster triangle of the draws in the light frustum (izb_setup.glsl) into grid space (texels,
// light depth) once per frame, or with IZB_FLAG_ALL_TRIANGLES (few casters) every caster triangle,
// with no cull of the draws before; the CSM, both traces and the fallback read these. Those that reach
// the grid are listed: the compute passes and the fallback walk only the listed triangles. Run by
// izb_triangles.comp, or with IZB_FLAG_TRIANGLES_IN_TRACE by the compute trace's step 1
// (izb_records.comp). Include after izb_prelude.glsl and the push constants.
// A spot light: a triangle reaching behind its near plane (where the projection folds over) or within
// twice the light's radius of it is left out of the grid (degenerate, far outside it: every pass skips
// it) and listed after the grid triangles, from 3 * triangle_count on, with its grid bounds
// (pack_straddler_bound); it is ray-tested in world space (izb_straddlers.glsl). w: 1 / light-view depth per
// vertex, for perspective-correct texture coordinates.

// The grid bounds [lo, hi] of the part of a triangle reaching behind a local light's near plane that
// a candidate's shadow ray can meet; false when a cone of a half space bounds nothing. Every
// candidate's shadow ray runs inside the pyramid from the light through the fitted grid, and a point
// and the light share their projection, so a ray meets the triangle only where its grid position
// lies in these bounds. The triangle is clipped to light-view depth >= apex_depth first: a
// candidate's ray (inside the cone, at most the cone's half angle off the axis) is that near the apex
// only within apex_depth / cos(cone) < the light's bulb (local_light_bulb) of the light, the part of
// every ray that does not count (local_light.h). lo > hi: no part of it is that far out.
bool straddler_grid_bounds(vec3 v[3], float depth[3], out vec2 lo, out vec2 hi) {
  lo = vec2(1.0e30);
  hi = vec2(-1.0e30);
  float cos_cone = params.light_cone.x;
  if (cos_cone <= 1.0e-3) return false;
  float apex_depth = 0.99 * local_light_bulb(params.light_position.w) * cos_cone;
  for (int i = 0; i < 3; ++i) {
    int j = (i + 1) % 3;
    if (depth[i] >= apex_depth) {
      vec2 g = to_grid(v[i]).xy;
      lo = min(lo, g);
      hi = max(hi, g);
    }
    if ((depth[i] >= apex_depth) != (depth[j] >= apex_depth)) {
      vec3 crossing = mix(v[i], v[j], (apex_depth - depth[i]) / (depth[j] - depth[i]));
      vec2 g = to_grid(crossing).xy;
      lo = min(lo, g);
      hi = max(hi, g);
    }
  }
  return true;
}

// Whether bounds from straddler_grid_bounds lie wholly outside the grid (one texel of margin on each
// side): the triangle meets no candidate's ray.
bool outside_grid(vec2 lo, vec2 hi) {
  float res = float(izb_resolution());
  return hi.x < -1.0 || hi.y < -1.0 || lo.x > res + 1.0 || lo.y > res + 1.0;
}

// Whether a triangle's grid bounds reach the grid (widened by kIzbCullMargin texels).
bool reaches_grid(vec4 g0, vec4 g1, vec4 g2) {
  float res = float(izb_resolution());
  vec2 lo = min(min(g0.xy, g1.xy), g2.xy), hi = max(max(g0.xy, g1.xy), g2.xy);
  return all(greaterThanEqual(hi, vec2(-kIzbCullMargin))) && all(lessThanEqual(lo, vec2(res + kIzbCullMargin)));
}

// Writes triangle t's grid-space vertices (also left in `grid`); whether it is to be listed.
bool set_up_triangle(uint t, out vec3 grid[3]) {
  grid = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
  vec3 v[3] = vec3[3](casters[t].p0.xyz, casters[t].p1.xyz, casters[t].p2.xyz);
  vec3 inv_w = vec3(1.0);
  // (Trace step 1's copy leaves the spot light's code out: it sets up the sun's alone.)
  if (!izb_flag(IZB_FLAG_TRIANGLES_IN_TRACE) && spot_light()) {
    bool apart = false, behind = true;
    float depth[3];
    for (int i = 0; i < 3; ++i) {
      float d = -(params.light_view * vec4(v[i], 1.0)).z;
      depth[i] = d;
      apart = apart || d < params.depth_range.x || distance(v[i], params.light_position.xyz) < 2.0 * local_light_bulb(params.light_position.w);
      behind = behind && d < 0.0;
      inv_w[i] = 1.0 / max(d, 1.0e-30);
    }
    // No shadow ray meets a triangle wholly behind the light's plane (the cone, at most a half space,
    // lies in front), wholly outside its range (a ray runs from a point within range to the light,
    // inside the range ball) or, reaching behind the near plane, outside the pyramid of the rays: it
    // is left out, as degenerate, and never listed. Its bounding box bounds its distance.
    vec3 lo = min(min(v[0], v[1]), v[2]), hi = max(max(v[0], v[1]), v[2]);
    vec3 nearest = clamp(params.light_position.xyz, lo, hi);
    bool unreached = behind || distance(nearest, params.light_position.xyz) > params.light_position.w;
    vec2 grid_lo = vec2(0.0), grid_hi = vec2(0.0);
    bool bounded = false;
    if (apart && !unreached) {
      bounded = straddler_grid_bounds(v, depth, grid_lo, grid_hi);
      unreached = bounded && outside_grid(grid_lo, grid_hi);
    }
    if (apart || unreached) {
      for (uint i = 0u; i < 3u; ++i) grid_triangles[3u * t + i] = vec4(-1.0e9, -1.0e9, 2.0, 1.0);
      if (unreached) return false;
      uint k = atomicAdd(counters[IZB_COUNTER_STRADDLERS], 1u);
      // (Unbounded: zero bounds words, which straddler_samples reads as "test every ray".)
      grid_triangles[3u * push.triangle_count + k] =
          vec4(uintBitsToFloat(t), uintBitsToFloat(bounded ? pack_straddler_bound(grid_lo, -kStraddlerBoundsMargin) : 0u),
               uintBitsToFloat(bounded ? pack_straddler_bound(grid_hi, kStraddlerBoundsMargin) : 0u), 0.0);
      return false;
    }
  }
  vec4 g[3];
  for (uint i = 0u; i < 3u; ++i) {
    g[i] = vec4(to_grid(v[i]), inv_w[i]);
    grid_triangles[3u * t + i] = g[i];
    grid[i] = g[i].xyz;
  }
  return reaches_grid(g[0], g[1], g[2]);
}

// The caster triangle at `slot` among the frustum draws' triangles: its draw is the last listed one
// whose first slot is at most `slot`.
uint frustum_triangle(uint slot) {
  uint lo = 0u, hi = counters[IZB_COUNTER_FRUSTUM_DRAWS] - 1u;
  while (lo < hi) {
    uint mid = (lo + hi + 1u) / 2u;
    if (caster_draw_words[frustum_draw_word(mid) + 1u] <= slot) lo = mid;
    else hi = mid - 1u;
  }
  uint w = frustum_draw_word(lo);
  return caster_draw_words[w] + (slot - caster_draw_words[w + 1u]);
}

// Lists the triangle (one atomic per subgroup) when its grid bounds reach the grid: one wholly beside
// it touches no texel, so no pass would find work in it. With every triangle set up (no cull wrote
// step 1's dispatch over the frustum's), step 1's dispatch is raised over the listed ones here.
void list_triangle(bool listed, uint t) {
  bool raise = izb_flag(IZB_FLAG_ALL_TRIANGLES) && !izb_flag(IZB_FLAG_TRIANGLES_IN_TRACE);
  uint slot = reserve_slots_raising(IZB_COUNTER_LISTED_TRIANGLES, listed ? 1u : 0u, raise,
                                    IZB_COUNTER_STEP_ONE_DISPATCH, 0xffffffffu, step_one_triangles());
  if (listed) caster_draw_words[listed_triangle_word(slot)] = t;
}

// The triangle at `slot` (of the frustum's, or with IZB_FLAG_ALL_TRIANGLES of every caster's): set
// up and listed. Every invocation of the subgroup calls it together.
void set_up_triangle_slot(uint slot) {
  // A draw the cull would leave out has no triangle that reaches the grid: every triangle set up
  // lists the same ones as the frustum's.
  bool all = izb_flag(IZB_FLAG_ALL_TRIANGLES);
  bool in_range = slot < (all ? push.triangle_count : counters[IZB_COUNTER_FRUSTUM_TRIANGLES]);
  uint t = in_range ? (all ? slot : frustum_triangle(slot)) : 0u;
  bool listed = false;
  vec3 grid[3];
  if (in_range) listed = set_up_triangle(t, grid);
  list_triangle(listed, t);
}
