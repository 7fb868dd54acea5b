// The conventions of spot and point light shadows, shared by every technique that shadows them and
// by the Embree reference: which points a light reaches, which face it, and where a shadow ray toward
// it ends.
#ifndef LOCAL_LIGHT_H
#define LOCAL_LIGHT_H
#include "shared_prelude.h"

SHARED_BEGIN

// Occluders closer to the light's position than its bulb (along the ray) do not count: the light's own
// bulb and housing, and what keeps a light-space near plane finite. The bulb is this fraction of the
// light's range (a range of 10 units: 0.01), so it scales with the world's units.
SHARED_CONST float kLocalLightBulbPerRange = 1.0e-3f;
SHARED_INLINE float local_light_bulb(float range) { return range * kLocalLightBulbPerRange; }
// The IZB's perspective grid of a spot light (or a point light's face) starts this fraction of the
// range from the light: casters nearer than that are ray-tested in world space instead.
SHARED_CONST float kLocalLightNearPerRange = 1.0f / 64.0f;

// Whether a light at `light_position` (range `range` > 0; for a spot light, `spot` set, travelling
// along the unit `spot_direction` with outer-cone cosine `cos_outer`) reaches `point`. A point it does
// not reach is 0 (unlit by this light) in every technique and the reference.
SHARED_INLINE bool local_light_reaches(SHARED_IN(vec3) light_position, float range, SHARED_IN(vec3) spot_direction,
                                       float cos_outer, bool spot, SHARED_IN(vec3) point) {
  SHARED_PRECISE vec3 from_light = point - light_position;
  SHARED_PRECISE float distance_squared = shared_dot(from_light, from_light);
  if (!(distance_squared <= range * range)) return false;
  if (!spot) return true;
  // cos(angle) >= cos_outer without a division or square root of its own: dot >= cos_outer * |v|.
  SHARED_PRECISE float along = shared_dot(from_light, spot_direction);
  return along >= cos_outer * sqrt(distance_squared);
}

// Whether the surface at `point` with geometric normal `geometric_normal` (facing the camera) faces
// the light; a point that does not is 0 (the G-buffer's sun-facing decision does not apply).
SHARED_INLINE bool faces_local_light(SHARED_IN(vec3) geometric_normal, SHARED_IN(vec3) point,
                                     SHARED_IN(vec3) light_position) {
  SHARED_PRECISE float facing = shared_dot(geometric_normal, light_position - point);
  return facing > 0.0f;
}

// The shadow ray toward a local light of range `range` from `origin` (shadow_ray_origin of the
// sample): it is occluded by a hit at t in [0, local_shadow_ray_length] along
// normalize(light_position - origin); nothing occludes when that length is <= 0.
SHARED_INLINE float local_shadow_ray_length(SHARED_IN(vec3) origin, SHARED_IN(vec3) light_position, float range) {
  return length(light_position - origin) - local_light_bulb(range);
}

SHARED_END
#endif
