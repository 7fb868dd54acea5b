#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_pixel.glsl"
layout(local_size_x = 8, local_size_y = 8) in;

// Light frustum fit, step 1: light-view x/y bounds of every lit candidate's ray origin (and, at 32
// spp, its μQuad corners), reduced per subgroup then with atomics.
void main() {
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  bool inside = all(lessThan(uvec2(pixel), params.extent.xy));
  vec2 lo = vec2(1.0e30), hi = vec2(-1.0e30);
  if (inside) {
    PixelPoint p = load_pixel(pixel);
    if (p.candidate) {
      if (izb_samples() == 32u) {
        vec3 c[4];
        micro_quad_corners(pixel, p, c);
        for (int i = 0; i < 4; ++i) {
          vec2 v = (params.light_view * vec4(c[i], 1.0)).xy;
          lo = min(lo, v);
          hi = max(hi, v);
        }
      } else {
        vec2 v = (params.light_view * vec4(shadow_ray_origin(p.position, p.normal), 1.0)).xy;
        lo = v;
        hi = v;
      }
    }
  }
  lo = subgroupMin(lo);
  hi = subgroupMax(hi);
  if (subgroupElect() && hi.x >= lo.x) {
    atomicMin(counters[IZB_COUNTER_BOUNDS + 0u], float_to_ordered(lo.x));
    atomicMin(counters[IZB_COUNTER_BOUNDS + 1u], float_to_ordered(lo.y));
    atomicMax(counters[IZB_COUNTER_BOUNDS + 2u], float_to_ordered(hi.x));
    atomicMax(counters[IZB_COUNTER_BOUNDS + 3u], float_to_ordered(hi.y));
  }
}
