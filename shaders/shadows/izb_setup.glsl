// The light frustum's fit (its second step) and the cull of the casters against it, run by the
// fit's last workgroup (izb_fit.comp) once every workgroup's bounds are in: one dispatch, not one
// for the fit and one for this single workgroup after it (on a CPU device, izb_setup.comp). Include after izb_prelude.glsl and the
// push constants, in a shader of kSetupThreads invocations that declares `bounds_partials`.

const uint kSetupThreads = 256u;
shared vec4 subgroup_bounds[256];
shared mat4 fitted_light_view_projection;
shared uint subgroup_sums[2 * 256];  // any subgroup size
shared uint running[2];

// Exclusive prefix sums of `v` over the workgroup (in the subgroup, then over the subgroups' sums);
// `total` gets the sums over every invocation. Every invocation calls it, in uniform control flow.
uvec2 workgroup_exclusive_add(uvec2 v, out uvec2 total) {
  uvec2 before = subgroupExclusiveAdd(v);
  uvec2 sums = subgroupAdd(v);
  if (subgroupElect()) {
    subgroup_sums[2u * gl_SubgroupID] = sums.x;
    subgroup_sums[2u * gl_SubgroupID + 1u] = sums.y;
  }
  barrier();
  total = uvec2(0u);
  for (uint s = 0u; s < gl_NumSubgroups; ++s) {
    uvec2 w = uvec2(subgroup_sums[2u * s], subgroup_sums[2u * s + 1u]);
    if (s < gl_SubgroupID) before += w;
    total += w;
  }
  barrier();  // every invocation has read subgroup_sums[]
  return before;
}

// Thread 0: the grid from the reduced bounds (the frame's IzbFrame, at the partials' buffer's start;
// also in fitted_light_view_projection for the workgroup).
void fit_grid(vec4 b) {
  for (uint i = 1u; i < gl_NumSubgroups; ++i) b = vec4(min(b.xy, subgroup_bounds[i].xy), max(b.zw, subgroup_bounds[i].zw));
  float lo_x = b.x;
  float lo_y = b.y;
  float hi_x = b.z;
  float hi_y = b.w;
  bool empty = !(hi_x >= lo_x && hi_y >= lo_y);
  if (empty) {
    lo_x = -1.0; lo_y = -1.0; hi_x = 1.0; hi_y = 1.0;
  }
  // Square texels: the same world size on both axes keeps the μQuad coverage isotropic.
  float size = max(max(hi_x - lo_x, hi_y - lo_y), 1.0e-4);
  float res = float(izb_resolution());
  float border = 2.0 * size / res;
  size += 2.0 * border;
  vec2 center = vec2(lo_x + hi_x, lo_y + hi_y) * 0.5;
  float near_d = params.depth_range.x;
  float far_d = params.depth_range.y;
  // Orthographic: x,y -> [-1,1] over the window; depth: distance along the light, 0 at near_d.
  mat4 ortho = mat4(1.0);
  ortho[0][0] = 2.0 / size;
  ortho[1][1] = 2.0 / size;
  ortho[3][0] = -2.0 * center.x / size;
  ortho[3][1] = -2.0 * center.y / size;
  // The light view looks down -z: distance d = -z.
  ortho[2][2] = -1.0 / (far_d - near_d);
  ortho[3][2] = -near_d / (far_d - near_d);
  fitted_light_view_projection = ortho * params.light_view;
  vec4 grid = vec4(res, 1.0 / res, size / res, empty ? 0.0 : 1.0);
  if (spot_light()) {
    // A spot light: a square perspective grid over its cone (x, y / depth within the tangent in
    // params.light_cone.y); depth 0 at the near plane, 1 at its range, and w the light-view depth, so
    // to_grid's divide leaves rays toward the light along the depth axis.
    float t = params.light_cone.y;
    mat4 perspective = mat4(0.0);
    perspective[0][0] = 1.0 / t;
    perspective[1][1] = 1.0 / t;
    perspective[2][2] = -far_d / (far_d - near_d);
    perspective[2][3] = -1.0;
    perspective[3][2] = -far_d * near_d / (far_d - near_d);
    fitted_light_view_projection = perspective * params.light_view;
    grid = vec4(res, 1.0 / res, 2.0 * t / res, empty ? 0.0 : 1.0);
  }
  // The overflow fallback's indirect dispatch: the build pass raises x as pixels overflow.
  counters[IZB_COUNTER_DISPATCH + 1u] = 1u;
  counters[IZB_COUNTER_DISPATCH + 2u] = 1u;
  counters[IZB_COUNTER_HYBRID + 2u] = 1u;
  counters[IZB_COUNTER_HYBRID + 3u] = 1u;
  // The frame opens the partials' buffer (izb.h, IzbFrame): its matrix's columns, then the grid.
  for (int i = 0; i < 4; ++i) bounds_partials[i] = fitted_light_view_projection[i];
  bounds_partials[4] = grid;
}

// Whether a caster draw's world bounds reach the fitted grid (widened by kIzbCullMargin texels). A
// spot light's perspective grid folds over behind the light, so there every draw is kept.
bool draw_in_frustum(IzbDrawBounds b, mat4 light_view_projection) {
  if (spot_light() || any(greaterThan(b.lo.xyz, b.hi.xyz))) return true;
  // An affine map's range over the box: its value at the centre +- |its linear part| times the
  // half extent, per grid axis.
  vec3 centre = 0.5 * (b.lo.xyz + b.hi.xyz), half_extent = 0.5 * (b.hi.xyz - b.lo.xyz);
  mat4 m = light_view_projection;
  vec2 mid = vec2(dot(vec3(m[0][0], m[1][0], m[2][0]), centre) + m[3][0],
                  dot(vec3(m[0][1], m[1][1], m[2][1]), centre) + m[3][1]);
  vec2 reach = vec2(dot(abs(vec3(m[0][0], m[1][0], m[2][0])), half_extent),
                    dot(abs(vec3(m[0][1], m[1][1], m[2][1])), half_extent));
  float res = float(izb_resolution());
  vec2 lo = ((mid - reach) * 0.5 + 0.5) * res, hi = ((mid + reach) * 0.5 + 0.5) * res;
  return all(greaterThanEqual(hi, vec2(-kIzbCullMargin))) && all(lessThanEqual(lo, vec2(res + kIzbCullMargin)));
}

IzbDrawBounds load_draw_bounds(uint draw) {
  uint w = draw_bounds_word(draw);
  IzbDrawBounds b;
  b.lo = vec4(uintBitsToFloat(caster_draw_words[w]), uintBitsToFloat(caster_draw_words[w + 1u]),
              uintBitsToFloat(caster_draw_words[w + 2u]), uintBitsToFloat(caster_draw_words[w + 3u]));
  b.hi = vec4(uintBitsToFloat(caster_draw_words[w + 4u]), uintBitsToFloat(caster_draw_words[w + 5u]),
              uintBitsToFloat(caster_draw_words[w + 6u]), uintBitsToFloat(caster_draw_words[w + 7u]));
  return b;
}

const uint kDrawsPerThread = 4u;  // fewer rounds of the workgroup's scan

// The light-frustum cull, after the fit: the workgroup lists the caster draws whose bounds reach the
// grid, each with the first slot of its triangles among all such draws' (slots and triangle slots
// from one running prefix sum, both ascending, so izb_triangles.comp finds a slot's draw by binary
// search), and writes the dispatch over those triangles. The passes after it touch only them: the
// frame's cost follows the casters near the view, not the scene's size.
void cull_draws(mat4 light_view_projection) {
  uint draws = uniform_branch(caster_draw_count());
  for (uint first = 0u; first < draws; first += kSetupThreads * kDrawsPerThread) {
    uint draw0 = first + gl_LocalInvocationIndex * kDrawsPerThread;
    uint kept = 0u, triangles = 0u, kept_bits = 0u;
    uint first_triangle[kDrawsPerThread], draw_triangles[kDrawsPerThread];
    for (uint k = 0u; k < kDrawsPerThread; ++k) {
      first_triangle[k] = 0u;
      draw_triangles[k] = 0u;
      if (draw0 + k >= draws) continue;
      IzbDrawBounds b = load_draw_bounds(draw0 + k);
      if (!draw_in_frustum(b, light_view_projection)) continue;
      first_triangle[k] = floatBitsToUint(b.lo.w);
      draw_triangles[k] = floatBitsToUint(b.hi.w);
      kept_bits |= 1u << k;
      ++kept;
      triangles += draw_triangles[k];
    }
    uvec2 base = uvec2(running[0], running[1]);
    uvec2 total;
    uvec2 before = workgroup_exclusive_add(uvec2(kept, triangles), total);
    uvec2 at = base + before;  // this thread's first slot and first triangle slot
    for (uint k = 0u; k < kDrawsPerThread; ++k) {
      if ((kept_bits & (1u << k)) == 0u) continue;
      uint w = frustum_draw_word(at.x);
      caster_draw_words[w] = first_triangle[k];
      caster_draw_words[w + 1u] = at.y;
      at += uvec2(1u, draw_triangles[k]);
    }
    if (gl_LocalInvocationIndex == 0u) {  // (every invocation read running[] before the scan's last barrier)
      running[0] = base.x + total.x;
      running[1] = base.y + total.y;
    }
    barrier();
  }
  if (gl_LocalInvocationIndex == 0u) {
    counters[IZB_COUNTER_FRUSTUM_DRAWS] = running[0];
    counters[IZB_COUNTER_FRUSTUM_TRIANGLES] = running[1];
    write_row_dispatch(IZB_COUNTER_GRID_SETUP_DISPATCH, (running[1] + 63u) / 64u);
    uint per_group = step_one_triangles();
    write_row_dispatch(IZB_COUNTER_STEP_ONE_DISPATCH, (running[1] + per_group - 1u) / per_group);
  }
}

// Light frustum fit, step 2, and the cull of the casters against it: reduces the fit's per-workgroup
// bounds, builds an orthographic projection whose x/y window covers them plus a border (so no point
// sits on the grid's edge), and whose depth range spans the casters (from the CPU, which knows their
// bounds); then lists the caster draws whose bounds reach the grid. The fit's last workgroup runs it.
void set_up_frustum() {
  // One per fit workgroup (a spot light's fit runs one).
  uint partials = uniform_branch(spot_light() ? 1u
                                              : ((params.extent.x + kIzbFitBlockWidth - 1u) / kIzbFitBlockWidth) *
                                                    ((params.extent.y + kIzbFitBlockHeight - 1u) / kIzbFitBlockHeight));
  vec4 b = vec4(1.0e30, 1.0e30, -1.0e30, -1.0e30);
  for (uint i = gl_LocalInvocationIndex; i < partials; i += kSetupThreads) {
    vec4 p = bounds_partials[kIzbPartialsAt + i];
    b = vec4(min(b.xy, p.xy), max(b.zw, p.zw));
  }
  b = vec4(subgroupMin(b.xy), subgroupMax(b.zw));
  if (subgroupElect()) subgroup_bounds[gl_SubgroupID] = b;
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    fit_grid(b);
    running[0] = 0u;
    running[1] = 0u;
  }
  barrier();  // the grid's transform, in shared memory, for every thread
  // With every caster triangle set up (IZB_FLAG_ALL_TRIANGLES), nothing reads the frustum's draws.
  if (!izb_flag(IZB_FLAG_ALL_TRIANGLES)) cull_draws(fitted_light_view_projection);
  // The trace's step 1 sets up every caster triangle itself (IZB_FLAG_TRIANGLES_IN_TRACE).
  if (izb_flag(IZB_FLAG_TRIANGLES_IN_TRACE) && gl_LocalInvocationIndex == 0u) {
    uint per_group = step_one_triangles();
    write_row_dispatch(IZB_COUNTER_STEP_ONE_DISPATCH, (push.triangle_count + per_group - 1u) / per_group);
  }
}
