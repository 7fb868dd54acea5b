#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"

// Frustum trace: one fragment per (caster triangle, light texel it touches) that survived the early
// depth test against the texel's farthest node (the rasterizer's depth is biased to the triangle's
// nearest depth over the texel). Tests the triangle against every node in the texel's list and ORs
// the shadowed samples into the pixel's mask. With kCountOnly, only counts the fragments.
layout(early_fragment_tests) in;
layout(constant_id = 0) const uint kSoftware = 1u;
layout(constant_id = 1) const uint kCountOnly = 0u;
layout(push_constant) uniform Push { IzbDrawPush draw; };

vec3 fetch_grid_vertex(uint corner) {
  uint v = uint(int(indices[draw.first_index + 3u * uint(gl_PrimitiveID) + corner]) + draw.vertex_offset);
  vec3 p = vec3(vertex_floats[v * kVertexFloats], vertex_floats[v * kVertexFloats + 1u],
                vertex_floats[v * kVertexFloats + 2u]);
  return to_grid((draw.model * vec4(p, 1.0)).xyz);
}

// Separating-axis test of the texel square against the triangle (inclusive, with a little slack so
// a sample exactly on a texel border is never lost).
bool texel_touches_triangle(vec2 lo, vec2 hi, vec3 a, vec3 b, vec3 c, float orientation) {
  const float slack = 1.0e-3;
  vec2 tmin = min(min(a.xy, b.xy), c.xy);
  vec2 tmax = max(max(a.xy, b.xy), c.xy);
  if (any(lessThan(tmax, lo - slack)) || any(greaterThan(tmin, hi + slack))) return false;
  vec2 p[3] = vec2[3](a.xy, b.xy, c.xy);
  for (int i = 0; i < 3; ++i) {
    vec2 e0 = p[i];
    vec2 e1 = p[(i + 1) % 3];
    float best = -1.0e30;
    best = max(best, orientation * edge_fn(vec2(lo.x, lo.y), e0, e1));
    best = max(best, orientation * edge_fn(vec2(hi.x, lo.y), e0, e1));
    best = max(best, orientation * edge_fn(vec2(lo.x, hi.y), e0, e1));
    best = max(best, orientation * edge_fn(vec2(hi.x, hi.y), e0, e1));
    if (best < -slack * length(e1 - e0)) return false;
  }
  return true;
}

void main() {
  ivec2 texel = ivec2(gl_FragCoord.xy);
  // Fetched by primitive id rather than passed as flat varyings: on the CPU driver the fetch is far
  // cheaper than geometry-shader varyings.
  vec3 a = fetch_grid_vertex(0u);
  vec3 b = fetch_grid_vertex(1u);
  vec3 c = fetch_grid_vertex(2u);
  float area = edge_fn(c.xy, a.xy, b.xy);
  uint fragment = 0u, tests = 0u;
  if (abs(area) > 1.0e-10 &&
      (kSoftware == 0u || texel_touches_triangle(vec2(texel), vec2(texel) + 1.0, a, b, c, sign(area)))) {
    fragment = 1u;
    if (kCountOnly == 0u) {
      float inv_area = 1.0 / area;
      uint full = full_mask();
      bool progressive = izb_flag(IZB_FLAG_PROGRESSIVE);
      for (uint node = heads[texel_index(texel)]; node != kIzbEndOfList;) {
        uvec2 n = nodes[node];
        node = n.x;
        uint current = visibility_mask[n.y];
        if (progressive && current == full) continue;
        ++tests;
        float gap = 1.0e30;
        uint bits = occluded_samples(n.y, a, b, c, inv_area, gap);
        if ((bits & ~current) != 0u) atomicOr(visibility_mask[n.y], bits);
        if (bits != 0u) note_occluder_gap(n.y, gap);
      }
    }
  }
  if (izb_flag(IZB_FLAG_STATS)) {
    uint f = subgroupAdd(fragment);
    uint s = subgroupAdd(tests);
    if (subgroupElect()) {
      if (f > 0u) atomicAdd(counters[kCountOnly != 0u ? IZB_COUNTER_FRAGMENTS : IZB_COUNTER_FRAGMENTS_KEPT], f);
      if (s > 0u) atomicAdd(counters[IZB_COUNTER_TRIANGLE_TESTS], s);
    }
  }
}
