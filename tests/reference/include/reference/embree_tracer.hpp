#pragma once
// Ground truth for sun shadows: an Embree scene of every shadow-casting triangle, queried with the
// same shading points and the same ray conventions (shared/shadow_common.h) the GPU techniques use.
//
// Rules of every visibility_* result (one float per pixel, index y * width + x):
//  * background pixel (position.w == 0)                       -> -1 (excluded from comparisons)
//  * covered pixel that does not face the light (ShadingPoints::faces: the G-buffer's decision,
//    gpu_shared::faces_light, for captured frames)            -> 0  (the GPU passes skip such
//    points)
//  * otherwise, visibility_1spp: one ray from gpu_shared::shadow_ray_origin(p, n, offset) towards the
//  light, offset = gpu_shared::shadow_ray_offset(p, ShadingPoints::eye);
//    occluded -> 0, else 1.
//  * otherwise, visibility_32spp: for each i < 32, s_i = gpu_shared::micro_quad_sample(vec2(x, y),
//    kSamplePattern[i], vec2(width, height), inv_view_proj, p, n); one ray from
//    shadow_ray_origin(s_i, n, offset) (the pixel's offset); the value is the unoccluded fraction k / 32.
// A ray (tnear = 0, tfar = inf) is occluded by any hit on either face of any triangle (no backface
// culling), except where an alpha-tested triangle (engine::alpha_tested: MASK, BLEND) is transparent:
// an occlusion filter reads its texture at the hit's texture coordinate with the rule every GPU
// technique uses (the nearest texel of the stored level, shared/material.h) and drops the hit when
// the alpha byte is below engine::alpha_threshold.
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "engine/core/ecs.hpp"
#include "reference/shading_points.hpp"

namespace reference {

// A spot or point light, by the conventions of shared/local_light.h.
struct LocalLight {
  glm::vec3 position{0.0f};
  float range = 1.0f;                           // > 0
  bool spot = false;                            // else a point light
  glm::vec3 spot_direction{0.0f, -1.0f, 0.0f};  // unit, the direction the light travels
  float cos_outer = -1.0f;                      // cosine of the spot's outer cone
};

// A reference of its own (EmbreeTracer::independent_visibility): what it needs, in double and in the
// tracer's coordinates (its `shift` applied), taken from the camera and the light themselves.
struct PinholeCamera {
  glm::dvec3 eye{0.0};
  // Vulkan NDC (x, y in [-1, 1], y down; either depth convention, a finite or infinite far plane) to
  // the tracer's coordinates; a perspective projection.
  glm::dmat4 inv_view_proj{1.0};
  uint32_t width = 0, height = 0;
};
struct TrueLight {
  bool sun = true;
  glm::dvec3 direction{0.0, -1.0, 0.0};  // sun: the direction light travels (need not be unit)
  glm::dvec3 position{0.0};              // spot and point
  double range = 1.0;                    // spot and point: > 0
  bool spot = false;
  glm::dvec3 spot_direction{0.0, -1.0, 0.0};  // the direction the spot shines (need not be unit)
  double outer_cone = 0.0;                    // spot: the outer cone's half angle in radians
};
// One pixel's true lit fraction, as the bounds the module's answer must fall within: lit_min counts
// the samples lit whatever the shadow ray's start within [own epsilon, offset band] off the surface,
// lit_max those not shadowed whatever that start. -1 both: the primary ray hit nothing.
struct TrueVisibility {
  float lit_min = -1.0f;
  float lit_max = -1.0f;
  glm::dvec3 point{0.0};   // the pixel centre's hit, in double
  glm::dvec3 normal{0.0};  // the hit triangle's unit normal, facing the eye
  bool covered() const { return lit_min >= 0.0f; }
};

class EmbreeTracer {
 public:
  // Takes every entity with Mesh + Transform, skipping those whose ShadowCaster says
  // casts_shadow = false (no ShadowCaster means it casts). Vertices go through Transform::world as
  // it stands: run the transform system first. `shift` is added to each world matrix's translation in
  // double first, as the renderer rebases a frame (engine::FrameView: Scene::origin minus the frame's
  // origin), so the reference traces the same float triangles the GPU draws, relative to the same
  // local origin. Throws std::runtime_error (one line) on an Embree error or a mesh index out of range.
  explicit EmbreeTracer(engine::Registry& registry, const glm::dvec3& shift = glm::dvec3(0.0));
  const glm::dvec3& shift() const;
  ~EmbreeTracer();
  EmbreeTracer(EmbreeTracer&&) noexcept;
  EmbreeTracer& operator=(EmbreeTracer&&) noexcept;
  EmbreeTracer(const EmbreeTracer&) = delete;
  EmbreeTracer& operator=(const EmbreeTracer&) = delete;

  uint32_t triangle_count() const;

  // True when the ray origin + t * dir_to_light, t in [0, inf), hits either face of any triangle.
  bool occluded(glm::vec3 origin, glm::vec3 dir_to_light) const;
  // The same for t in [0, distance] along the normalised direction: an occluder within `distance`.
  bool occluded_within(glm::vec3 origin, glm::vec3 dir_to_light, float distance) const;

  // light_direction: the direction light travels (from the sun into the scene); need not be unit.
  // Throws std::invalid_argument when it is zero or the buffers do not match width * height.
  std::vector<float> visibility_1spp(const ShadingPoints& points, glm::vec3 light_direction) const;
  std::vector<float> visibility_32spp(const ShadingPoints& points, glm::vec3 light_direction) const;

  // The same for a spot or point light (shared/local_light.h): a covered pixel the light does not
  // reach (range, cone), or whose geometric normal turns away from it, is 0 (tested at its shading
  // point); otherwise each ray runs from shadow_ray_origin(sample, n) toward the light's position and
  // is occluded by a hit within local_shadow_ray_length. The G-buffer's sun-facing decision is not used.
  std::vector<float> visibility_1spp(const ShadingPoints& points, const LocalLight& light) const;
  std::vector<float> visibility_32spp(const ShadingPoints& points, const LocalLight& light) const;

  // Soft shadows: the fraction of a light with a size that a pixel's shading point sees, from `rays`
  // (>= 1; 256 or more for figures worth quoting) rays per pixel. The pixels' rules are visibility_1spp's
  // (-1 background; 0 for a point that does not face the light or, for a local light, that it does not
  // reach, both decided toward the light's centre), and every ray starts at the same
  // shadow_ray_origin(p, n, shadow_ray_offset(p, eye)); the value is lit rays / rays. The rays are
  // stratified over the light: the unit square cut into `rays` cells of equal area (a sqrt(rays) x
  // sqrt(rays) grid when rays is a square), one point jittered in each cell by a hash of the pixel and
  // the sample (so a result is reproducible), mapped onto the unit disc by the concentric map (which
  // keeps areas). A light of size 0 gives exactly visibility_1spp's answer.
  // The sun: `angular_diameter_degrees` (0 to < 180) is its disc's angular diameter; a disc sample of
  // squared radius u goes to the direction at 1 - cos(angle) = u (1 - cos(half the diameter)) from the
  // direction toward the sun, so the rays are uniform in the cone's solid angle. Throws
  // std::invalid_argument on a bad direction, size or ray count, or mismatched buffers.
  std::vector<float> area_visibility(const ShadingPoints& points, glm::vec3 light_direction,
                                     float angular_diameter_degrees, uint32_t rays) const;
  // A spot or point light taken as the disc of `radius` (world units, >= 0) centred at its position
  // and perpendicular to the direction from the ray origin toward it: a ray toward each disc sample,
  // occluded by a hit within local_shadow_ray_length(origin, sample, range) (it ends short of the
  // sample by the bulb, as the ray toward the centre does; a length <= 0 is lit).
  std::vector<float> area_visibility(const ShadingPoints& points, const LocalLight& light, float radius,
                                     uint32_t rays) const;

  // The same truth computed without the module's shader code (of shared/*.h only the documented
  // sample positions, kSamplePattern, are read): for each pixel a
  // primary ray from the eye through the pixel's centre finds the triangle it shows, and its hit,
  // normal, light facing and light reach (range, the spot's cone) are recomputed in double from that
  // triangle's vertices. Samples (1, or 32: the rays through the pixel's corners meet the centre's
  // plane, and each sample is the bilinear blend of those four points at its kSamplePattern position)
  // start their shadow rays at two heights along the normal: 2^-16 of
  // the largest coordinate of the sample and its triangle (the least Embree's float needs), and
  // `offset_band` times reach = |q|inf + |q - eye|inf (what the module may use: its documented offset
  // is 1/8192 of that reach). A ray toward a local light stops 1/1000 of the range short of it (the
  // documented bulb). Decisions within 1e-6 of their threshold (facing, range, cone) and points seen
  // within 1e-6 of edge-on are left open (lit_min 0, lit_max from the rays). Throws
  // std::invalid_argument on a zero size, samples other than 1 or 32, or a non-positive band.
  std::vector<TrueVisibility> independent_visibility(const PinholeCamera& camera, const TrueLight& light,
                                                     uint32_t samples, double offset_band) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace reference
