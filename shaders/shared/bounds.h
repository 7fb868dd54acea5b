// Axis-aligned box tests shared by the engine's and the shadow module's own box types, so that both
// cull with the same arithmetic.
#ifndef BOUNDS_H
#define BOUNDS_H
#include "shared_prelude.h"

SHARED_BEGIN

// Corner i of the box [lo, hi]: bit 0 of i picks hi.x, bit 1 hi.y, bit 2 hi.z.
SHARED_INLINE vec3 box_corner(SHARED_IN(vec3) lo, SHARED_IN(vec3) hi, uint i) {
  return vec3((i & 1u) != 0u ? hi.x : lo.x, (i & 2u) != 0u ? hi.y : lo.y, (i & 4u) != 0u ? hi.z : lo.z);
}

// True when the box lies wholly on the far side of one plane of the clip-space volume
// x/w in [ndc.x, ndc.z], y/w in [ndc.y, ndc.w], w >= min_w: nothing of it can reach that view.
// Each test is a half-space in world space, so it holds for corners behind a perspective camera too.
SHARED_INLINE bool box_outside_clip(SHARED_IN(mat4) clip, SHARED_IN(vec3) lo, SHARED_IN(vec3) hi, SHARED_IN(vec4) ndc,
                                    float min_w) {
  // Bit k set: every corner so far lies beyond plane k (left, right, bottom, top, near).
  uint beyond_all = 0x1fu;
  for (uint i = 0u; i < 8u && beyond_all != 0u; ++i) {
    vec4 c = clip * vec4(box_corner(lo, hi, i), 1.0f);
    uint beyond = (c.x < ndc.x * c.w ? 1u : 0u) | (c.x > ndc.z * c.w ? 2u : 0u) | (c.y < ndc.y * c.w ? 4u : 0u) |
                  (c.y > ndc.w * c.w ? 8u : 0u) | (c.w < min_w ? 16u : 0u);
    beyond_all &= beyond;
  }
  return beyond_all != 0u;
}

SHARED_END
#endif
