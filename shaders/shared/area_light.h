// Where shadow rays toward a light with a size go: over the sun's disc (a cone of directions around
// the direction toward the sun) or over a spot or point light's sphere, taken as the disc it shows the
// shading point (centred at the light, perpendicular to the point-to-light direction). Shared by the
// techniques that sample a light and by the tests that check them. The hash is exact on both sides;
// the float functions may round differently on a GPU (their users compare lit fractions, not bits).
#ifndef AREA_LIGHT_H
#define AREA_LIGHT_H
#include "shared_prelude.h"

SHARED_BEGIN

// pi (3 - sqrt(5)): consecutive spiral samples turn by it, so no two line up however many there are.
SHARED_CONST float kAreaLightGoldenAngle = 2.39996323f;
SHARED_CONST float kAreaLightTwoPi = 6.28318531f;

// An integer hash of a pixel (well mixed: neighbouring pixels get unrelated values). The same on the
// CPU and the GPU (32-bit unsigned arithmetic wraps in both).
SHARED_INLINE uint area_light_hash(SHARED_IN(uvec2) pixel) {
  uint h = pixel.x * 0x9e3779b1u + pixel.y * 0x85ebca77u + 0x165667b1u;
  h = (h ^ (h >> 16u)) * 0x7feb352du;
  h = (h ^ (h >> 15u)) * 0x846ca68bu;
  return h ^ (h >> 16u);
}

// The per-pixel turn of the sample pattern, radians in [0, 2 pi): fixed for a pixel (no flicker from
// frame to frame); neighbours differ, so the few-ray error is noise rather than banding.
SHARED_INLINE float area_light_rotation(SHARED_IN(uvec2) pixel) {
  return float(area_light_hash(pixel) >> 8u) * (kAreaLightTwoPi / 16777216.0f);
}

// Sample k (< n) of n on the unit disc: a golden-angle spiral whose radius sqrt((k + 0.5) / n) gives
// every sample an equal share of the disc's area, turned by `rotation` radians.
SHARED_INLINE vec2 area_light_disc_sample(uint k, uint n, float rotation) {
  float radius = sqrt((float(k) + 0.5f) / float(n));
  float angle = float(k) * kAreaLightGoldenAngle + rotation;
  return vec2(radius * cos(angle), radius * sin(angle));
}

// Two unit vectors perpendicular to the unit `axis` and to each other, continuous everywhere but where
// axis.z changes sign, without a normalisation.
SHARED_INLINE vec3 area_light_tangent(SHARED_IN(vec3) axis) {
  float s = axis.z >= 0.0f ? 1.0f : -1.0f;
  float a = -1.0f / (s + axis.z);
  return vec3(1.0f + s * axis.x * axis.x * a, s * axis.x * axis.y * a, -s * axis.x);
}
SHARED_INLINE vec3 area_light_bitangent(SHARED_IN(vec3) axis) {
  float s = axis.z >= 0.0f ? 1.0f : -1.0f;
  float a = -1.0f / (s + axis.z);
  return vec3(axis.x * axis.y * a, s + axis.y * axis.y * a, -axis.y);
}

// 1 - cos of the sun's angular radius, from its tangent (View::light_tan_half_angle), without the
// cancellation of 1 - cos for a small sun: (1 - c)(1 + c) = sin^2 = tan^2 c^2.
SHARED_INLINE float area_light_cone(float tan_half_angle) {
  float t2 = tan_half_angle * tan_half_angle;
  float c = 1.0f / sqrt(1.0f + t2);
  return t2 * c * c / (1.0f + c);
}

// The direction of disc sample `disc` (on the unit disc) within the cone of 1 - cos(half angle) =
// `cone` around the unit `axis`: uniform in solid angle for samples uniform on the disc (|disc|^2 is
// the share of the cone's solid angle inside the sample's ring). Unit length.
SHARED_INLINE vec3 area_light_cone_direction(SHARED_IN(vec3) axis, float cone, SHARED_IN(vec2) disc) {
  float h = (disc.x * disc.x + disc.y * disc.y) * cone;  // 1 - cos of the sample's angle to the axis
  float side = sqrt(max(cone * (2.0f - h), 0.0f));        // sin of that angle / |disc|
  vec3 d = axis * (1.0f - h) + (area_light_tangent(axis) * disc.x + area_light_bitangent(axis) * disc.y) * side;
  return normalize(d);
}

// The point of disc sample `disc` (on the unit disc) on the disc of radius `radius` centred at
// `center`, perpendicular to the unit `axis` (the shading point's direction toward the light).
SHARED_INLINE vec3 area_light_disc_point(SHARED_IN(vec3) center, SHARED_IN(vec3) axis, float radius,
                                         SHARED_IN(vec2) disc) {
  return center + (area_light_tangent(axis) * disc.x + area_light_bitangent(axis) * disc.y) * radius;
}

SHARED_END
#endif
