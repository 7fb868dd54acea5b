#version 460
#extension GL_GOOGLE_include_directive : require
#include "cascades.h"
layout(local_size_x = CASCADE_BLUR_GROUP) in;

// Two pipelines: kApply 0 blurs each listed pixel into `blurred`, reading the filter's output in the
// shadow term; kApply 1 then writes those values back. Blurring in place would read neighbours that
// are already blurred; this way the filter needs no frame-sized unblurred copy.
layout(constant_id = 0) const uint kApply = 0u;

layout(push_constant) uniform Push { CascadeBlurPush push; };
layout(set = 0, binding = CASCADE_BLUR_BINDING_WORLD_POSITION, rgba32f) readonly uniform image2D world_position;
layout(set = 0, binding = CASCADE_BLUR_BINDING_GEOMETRIC_NORMAL, rgba16f) readonly uniform image2D geometric_normal;
layout(set = 0, binding = CASCADE_BLUR_BINDING_SHADOW_TERM, r32f) uniform image2D shadow_term;
layout(set = 0, binding = CASCADE_BLUR_BINDING_COUNTERS) readonly buffer Counters { uint counters[]; };
layout(set = 0, binding = CASCADE_BLUR_BINDING_BLUR_LIST) readonly buffer BlurList { uint blur_list[]; };
layout(set = 0, binding = CASCADE_BLUR_BINDING_BLURRED) buffer Blurred { float blurred[]; };

// 5x5 binomial blur of the unfiltered term, only on pixels whose taps disagreed. Neighbours on another
// surface (normal turned, or off the centre's tangent plane) get no weight, so shadows don't bleed
// across silhouettes and creases.
void main() {
  uint index = gl_GlobalInvocationID.x;
  if (index >= counters[CASCADE_COUNTER_BLUR]) return;
  uint packed_pixel = blur_list[index];
  ivec2 pixel = ivec2(packed_pixel & 0xffffu, packed_pixel >> 16u);
  if (kApply != 0u) {
    imageStore(shadow_term, pixel, vec4(blurred[index]));
    return;
  }
  vec3 p = imageLoad(world_position, pixel).xyz;
  vec3 n = imageLoad(geometric_normal, pixel).xyz;
  float tolerance = 0.01 * distance(p, push.camera_position.xyz) + 1.0e-3;
  const float w1[5] = float[5](1.0, 4.0, 6.0, 4.0, 1.0);
  float sum = 0.0, weight = 0.0;
  for (int dy = -2; dy <= 2; ++dy) {
    for (int dx = -2; dx <= 2; ++dx) {
      ivec2 q = pixel + ivec2(dx, dy);
      if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(uvec2(q), push.extent.xy))) continue;
      vec4 pq = imageLoad(world_position, q);
      if (pq.w == 0.0) continue;  // background
      float v = imageLoad(shadow_term, q).r;
      if (v < 0.0) continue;  // not filtered this frame (a pass restricted to a pixel list)
      vec3 nq = imageLoad(geometric_normal, q).xyz;
      if (dot(n, nq) < 0.9 || abs(dot(n, pq.xyz - p)) > tolerance) continue;
      float w = w1[dx + 2] * w1[dy + 2];
      sum += w * v;
      weight += w;
    }
  }
  blurred[index] = weight > 0.0 ? sum / weight : imageLoad(shadow_term, pixel).r;
}
