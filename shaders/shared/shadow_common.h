// The geometric conventions every shadow technique and the Embree reference share, defined once.
#ifndef SHADOW_COMMON_H
#define SHADOW_COMMON_H
#include "shared_prelude.h"

SHARED_BEGIN

// How far a shading point's shadow rays start off its surface, along the geometric normal (the side
// facing the camera): 1/8192 of the point's largest coordinate plus its largest coordinate offset from
// the camera `eye` (both in the frame's coordinates, relative to FrameDesc::origin). The first term
// covers float's spacing at the point (some thousand ulps), the second the depth buffer's and the
// reconstruction's error, which grow with the distance from the camera. So the offset follows the
// precision at hand, not a world-unit constant: a scene in centimetres gets offsets 100 times longer,
// a scene far from the frame's origin longer ones than one near it. Every technique and the reference
// start their rays at shadow_ray_origin() with this offset, one per pixel (its μQuad samples share it),
// and count any hit with t > 0 as an occluder.
SHARED_CONST float kShadowOffsetPerUnit = 1.0f / 8192.0f;

SHARED_INLINE float shadow_ray_offset(SHARED_IN(vec3) position, SHARED_IN(vec3) eye) {
  SHARED_PRECISE vec3 from_eye = abs(position - eye);
  vec3 size = abs(position);
  SHARED_PRECISE float reach = max(max(size.x, size.y), size.z) + max(max(from_eye.x, from_eye.y), from_eye.z);
  SHARED_PRECISE float offset = reach * kShadowOffsetPerUnit;
  return offset;
}

SHARED_INLINE vec3 shadow_ray_origin(SHARED_IN(vec3) position, SHARED_IN(vec3) geometric_normal, float offset) {
  SHARED_PRECISE vec3 origin = position + geometric_normal * offset;
  return origin;
}

// Whether a shading point faces the light; a point turned away is shadowed without a ray. The
// G-buffer decides once per pixel (gbuffer.frag) and stores the answer in the geometric normal's w
// (1 facing, 0 not): with the smooth terminator on, from the shading normal, since the point has
// been lifted onto the smooth surface that normal describes and a ray toward a light it faces leaves
// that surface outward, clear of the flat facets under it; otherwise from the geometric normal.
// Every technique and the reference read the stored answer.
SHARED_INLINE bool faces_light(SHARED_IN(vec4) geometric_normal_texel) { return geometric_normal_texel.w > 0.5f; }

// 32 sample offsets inside a pixel, in [0,1)^2, for the 32-samples-per-pixel mode: a jittered 8x4 grid
// (one sample per cell, fixed jitter) so coverage is well stratified.
SHARED_CONST uint kSamplesPerPixel = 32u;
#ifdef __cplusplus
inline constexpr vec2 kSamplePattern[32] = {
#else
const vec2 kSamplePattern[32] = vec2[32](
#endif
    vec2(0.0703f, 0.1641f), vec2(0.1797f, 0.0391f), vec2(0.3047f, 0.2109f), vec2(0.4297f, 0.0859f),
    vec2(0.5547f, 0.1953f), vec2(0.6797f, 0.0547f), vec2(0.8047f, 0.2266f), vec2(0.9297f, 0.1016f),
    vec2(0.0234f, 0.3359f), vec2(0.1641f, 0.4609f), vec2(0.2891f, 0.3203f), vec2(0.4141f, 0.4766f),
    vec2(0.5391f, 0.3516f), vec2(0.6641f, 0.4453f), vec2(0.7891f, 0.2891f), vec2(0.9141f, 0.4141f),
    vec2(0.1016f, 0.5859f), vec2(0.2266f, 0.7109f), vec2(0.3516f, 0.5547f), vec2(0.4766f, 0.6797f),
    vec2(0.6016f, 0.5391f), vec2(0.7266f, 0.6641f), vec2(0.8516f, 0.5703f), vec2(0.9766f, 0.7266f),
    vec2(0.0547f, 0.8203f), vec2(0.1953f, 0.9453f), vec2(0.3203f, 0.7891f), vec2(0.4453f, 0.9141f),
    vec2(0.5703f, 0.8047f), vec2(0.6953f, 0.9297f), vec2(0.8203f, 0.7734f), vec2(0.9453f, 0.8984f)
#ifdef __cplusplus
};
#else
);
#endif

// The μQuad: the pixel's footprint on the tangent plane of its shading point. Its four corners are
// where the camera rays through the pixel's corners meet that plane; sample `sample_offset` (in
// [0,1]^2 of the pixel) is the bilinear blend of those corners, so a trace pass can rebuild all 32
// samples from the corners alone. `inv_view_proj` maps NDC (Vulkan, y down, reversed depth in [0,1])
// to world; `viewport` is the render size in pixels.
// A μQuad corner in two steps: the camera ray through a pixel corner (its origin on the near plane,
// its direction toward a point farther along, not normalized), which the four pixels around the corner
// share, and where that ray meets the pixel's tangent plane.
struct CameraRay {
  vec3 origin;
  vec3 direction;
};
// The ray's two homogeneous points, before their divide.
struct HomogeneousRay {
  vec4 near_point;
  vec4 far_point;
};
SHARED_INLINE HomogeneousRay pixel_corner_points(SHARED_IN(vec2) pixel_corner, SHARED_IN(vec2) viewport,
                                                 SHARED_IN(mat4) inv_view_proj) {
  SHARED_PRECISE vec2 ndc = shared_divide(pixel_corner, viewport) * 2.0f - 1.0f;
  HomogeneousRay h;
  h.near_point = shared_transform(inv_view_proj, vec4(ndc.x, ndc.y, 1.0f, 1.0f));  // reversed depth: 1 is near
  h.far_point = shared_transform(inv_view_proj, vec4(ndc.x, ndc.y, 0.5f, 1.0f));
  return h;
}
// The ray from its points and their reciprocal w (`near_scale` = 1 / near_point.w, correctly rounded,
// and `far_scale` likewise): products alone, correctly rounded on CPU and GPU alike.
SHARED_INLINE CameraRay camera_ray_scaled(SHARED_IN(HomogeneousRay) h, float near_scale, float far_scale) {
  SHARED_PRECISE vec3 ray_origin = vec3(h.near_point) * near_scale;
  SHARED_PRECISE vec3 ray_dir = vec3(h.far_point) * far_scale - ray_origin;
  CameraRay ray;
  ray.origin = ray_origin;
  ray.direction = ray_dir;
  return ray;
}
// One exact quotient a homogeneous point, then products: five of shared_divide's corrected quotients a
// corner, not nine.
SHARED_INLINE CameraRay camera_ray(SHARED_IN(HomogeneousRay) h) {
  return camera_ray_scaled(h, shared_divide(1.0f, h.near_point.w), shared_divide(1.0f, h.far_point.w));
}
SHARED_INLINE CameraRay pixel_corner_ray(SHARED_IN(vec2) pixel_corner, SHARED_IN(vec2) viewport,
                                         SHARED_IN(mat4) inv_view_proj) {
  return camera_ray(pixel_corner_points(pixel_corner, viewport, inv_view_proj));
}
SHARED_INLINE vec3 micro_quad_corner_on(SHARED_IN(CameraRay) ray, SHARED_IN(vec3) plane_point,
                                        SHARED_IN(vec3) plane_normal) {
  SHARED_PRECISE float denom = shared_dot(plane_normal, ray.direction);
  // A plane seen edge-on: keep the shading point rather than shoot to infinity.
  if (abs(denom) < 1.0e-12f) return plane_point;
  SHARED_PRECISE float t = shared_divide(shared_dot(plane_normal, plane_point - ray.origin), denom);
  SHARED_PRECISE vec3 corner = ray.origin + ray.direction * t;
  return corner;
}
SHARED_INLINE vec3 micro_quad_corner(SHARED_IN(vec2) pixel_corner, SHARED_IN(vec2) viewport,
                                     SHARED_IN(mat4) inv_view_proj, SHARED_IN(vec3) plane_point,
                                     SHARED_IN(vec3) plane_normal) {
  return micro_quad_corner_on(pixel_corner_ray(pixel_corner, viewport, inv_view_proj), plane_point, plane_normal);
}

SHARED_INLINE vec3 micro_quad_blend(SHARED_IN(vec3) c00, SHARED_IN(vec3) c10, SHARED_IN(vec3) c01,
                                    SHARED_IN(vec3) c11, SHARED_IN(vec2) offset) {
  // mix() written out (x (1 - a) + y a, as GLSL defines it and GLM computes it), so no compiler may
  // evaluate it another way.
  SHARED_PRECISE vec3 top = c00 * (1.0f - offset.x) + c10 * offset.x;
  SHARED_PRECISE vec3 bottom = c01 * (1.0f - offset.x) + c11 * offset.x;
  SHARED_PRECISE vec3 sample_point = top * (1.0f - offset.y) + bottom * offset.y;
  return sample_point;
}

SHARED_INLINE vec3 micro_quad_sample(SHARED_IN(vec2) pixel, SHARED_IN(vec2) sample_offset,
                                     SHARED_IN(vec2) viewport, SHARED_IN(mat4) inv_view_proj,
                                     SHARED_IN(vec3) plane_point, SHARED_IN(vec3) plane_normal) {
  vec3 c00 = micro_quad_corner(pixel, viewport, inv_view_proj, plane_point, plane_normal);
  vec3 c10 = micro_quad_corner(pixel + vec2(1.0f, 0.0f), viewport, inv_view_proj, plane_point, plane_normal);
  vec3 c01 = micro_quad_corner(pixel + vec2(0.0f, 1.0f), viewport, inv_view_proj, plane_point, plane_normal);
  vec3 c11 = micro_quad_corner(pixel + vec2(1.0f, 1.0f), viewport, inv_view_proj, plane_point, plane_normal);
  return micro_quad_blend(c00, c10, c01, c11, sample_offset);
}

SHARED_END
#endif
