#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"

// Raster frustum trace: one fragment per (caster triangle, light texel it touches) that survived the
// early depth test against the texel's farthest node (the rasterizer's depth is biased to the
// triangle's nearest depth over the texel). Tests the triangle against every node in the texel's list
// and ORs the shadowed samples into the pixel's mask. With kCountOnly, only counts the fragments.
layout(early_fragment_tests) in;
layout(constant_id = 0) const uint kSoftware = 1u;
layout(constant_id = 1) const uint kCountOnly = 0u;
layout(push_constant) uniform Push { IzbDrawPush draw; };

void main() {
  ivec2 texel = ivec2(gl_FragCoord.xy);
  uint triangle = draw.first_triangle + uint(gl_PrimitiveID);
  vec3 a, b, c;
  load_grid_triangle(triangle, a, b, c);
  float area = edge_fn(c.xy, a.xy, b.xy);
  uint fragment = 0u, tests = 0u;
  if (abs(area) > 1.0e-10 &&
      (kSoftware == 0u || rect_touches_triangle(vec2(texel), vec2(texel) + 1.0, a, b, c, sign(area)))) {
    fragment = 1u;
    if (kCountOnly == 0u) tests = trace_texel_list(texel_index(texel), triangle, a, b, c, 1.0 / area);
  }
  if (izb_flag(IZB_FLAG_STATS)) {
    uint seed = (uint(gl_FragCoord.x) / 8u) * 7u + (uint(gl_FragCoord.y) / 8u) * 13u;
    add_sharded(kCountOnly != 0u ? IZB_COUNTER_FRAGMENTS : IZB_COUNTER_FRAGMENTS_KEPT, fragment, seed);
    add_sharded(IZB_COUNTER_TRIANGLE_TESTS, tests, seed);
  }
}
