#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 256) in;

layout(push_constant) uniform Push { IzbComputePush push; };

shared uint subgroup_sums[2 * 256];  // any subgroup size
shared uint running[2];

// Whether a caster draw's world bounds reach the fitted grid (widened by kIzbCullMargin texels). A
// spot light's perspective grid folds over behind the light, so there every draw is kept.
bool draw_in_frustum(IzbDrawBounds b) {
  if (spot_light() || any(greaterThan(b.lo.xyz, b.hi.xyz))) return true;
  float res = float(izb_resolution());
  vec2 lo = vec2(1.0e30), hi = vec2(-1.0e30);
  for (int i = 0; i < 8; ++i) {
    vec3 corner = vec3((i & 1) != 0 ? b.hi.x : b.lo.x, (i & 2) != 0 ? b.hi.y : b.lo.y, (i & 4) != 0 ? b.hi.z : b.lo.z);
    vec2 g = to_grid(corner).xy;
    lo = min(lo, g);
    hi = max(hi, g);
  }
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

// The light-frustum cull, after the fit: one workgroup lists, in draw order, the caster draws whose
// bounds reach the grid with the first slot of their triangles among all such draws' (a running
// prefix sum, so izb_triangles.comp finds a slot's draw by binary search), and writes the dispatch
// over those triangles. The passes after it touch only them: the frame's cost follows the casters
// near the view, not the scene's size.
void main() {
  if (gl_LocalInvocationIndex == 0u) {
    running[0] = 0u;
    running[1] = 0u;
  }
  barrier();
  for (uint first = 0u; first < caster_draw_count(); first += gl_WorkGroupSize.x) {
    uint draw = first + gl_LocalInvocationIndex;
    uint kept = 0u, triangles = 0u, first_triangle = 0u;
    if (draw < caster_draw_count()) {
      IzbDrawBounds b = load_draw_bounds(draw);
      first_triangle = floatBitsToUint(b.lo.w);
      if (draw_in_frustum(b)) {
        kept = 1u;
        triangles = floatBitsToUint(b.hi.w);
      }
    }
    // Exclusive prefix sums over the workgroup: in the subgroup, then over the subgroups' sums.
    uvec2 before = uvec2(subgroupExclusiveAdd(kept), subgroupExclusiveAdd(triangles));
    uvec2 sums = uvec2(subgroupAdd(kept), subgroupAdd(triangles));
    if (subgroupElect()) {
      subgroup_sums[2u * gl_SubgroupID] = sums.x;
      subgroup_sums[2u * gl_SubgroupID + 1u] = sums.y;
    }
    barrier();
    uvec2 base = uvec2(running[0], running[1]);
    uvec2 total = uvec2(0u);
    for (uint s = 0u; s < gl_NumSubgroups; ++s) {
      uvec2 v = uvec2(subgroup_sums[2u * s], subgroup_sums[2u * s + 1u]);
      if (s < gl_SubgroupID) before += v;
      total += v;
    }
    if (kept != 0u) {
      uint w = frustum_draw_word(base.x + before.x);
      caster_draw_words[w] = first_triangle;
      caster_draw_words[w + 1u] = base.y + before.y;
    }
    barrier();  // every thread has read running[] and subgroup_sums[]
    if (gl_LocalInvocationIndex == 0u) {
      running[0] = base.x + total.x;
      running[1] = base.y + total.y;
    }
    barrier();
  }
  if (gl_LocalInvocationIndex == 0u) {
    counters[IZB_COUNTER_FRUSTUM_DRAWS] = running[0];
    counters[IZB_COUNTER_FRUSTUM_TRIANGLES] = running[1];
    write_row_dispatch(IZB_COUNTER_GRID_SETUP_DISPATCH, (running[1] + 63u) / 64u);
  }
}
