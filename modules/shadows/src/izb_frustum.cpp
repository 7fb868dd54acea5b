#include "barriers.hpp"
#include "izb_frustum.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/gtc/matrix_transform.hpp>

#include "gpu/profiler.hpp"
#include "izb_corner_rays.hpp"
#include "light_space.hpp"
#include "shared/local_light.h"

namespace shadows::detail {

using namespace engine::gpu;

namespace {

// A spot light: its view from its position, near where a ray inside its cone is within the light's
// radius (so what lies nearer never counts, local_light.h), far at its range (no point it reaches is
// farther, nor anything between such a point and the light).
void fit_spot_light(const Frame& frame, IzbLightView& light) {
  light.light_view = light.light_view * glm::translate(glm::mat4(1.0f), -frame.view.light_position);
  const float cos_outer = std::clamp(frame.view.light_cos_outer, 0.05f, 1.0f);
  // The near plane sits at 1/64 of the range, not at the bulb: a perspective depth in [0, 1] keeps
  // about far / near ulps of relative precision, and a bulb-sized near plane left the node test's depths
  // of a room-scale light (tens of units) too coarse for its shadow-ray offsets (speckled false
  // shadow). The few casters nearer than it are ray-tested in world space (izb_triangles.comp).
  light.near_depth = std::max(gpu_shared::local_light_bulb(frame.view.light_range) * cos_outer,
                              frame.view.light_range * gpu_shared::kLocalLightNearPerRange);
  light.far_depth = frame.view.light_range;
  // The cone's rim inside the grid; a point light's face shadows only its cube face's pyramid (its
  // points, light_tiles.glsl's point_light_face_of), whose sides lie at tangent 1 along the grid's
  // axes (light_view_matrix keeps an axis's right and up on the other axes): a grid half as wide.
  light.tan_half_angle = (frame.view.light_face ? 1.0f : std::tan(std::acos(cos_outer))) * 1.02f;
}

// The sun: the depth range of the scene's box (casters and receivers) along the light.
void fit_sun_depth(const Aabb& depth_box, IzbLightView& light) {
  float lo = std::numeric_limits<float>::max(), hi = -lo;
  for (int i = 0; i < 8; ++i) {
    glm::vec3 corner((i & 1) ? depth_box.max.x : depth_box.min.x, (i & 2) ? depth_box.max.y : depth_box.min.y,
                     (i & 4) ? depth_box.max.z : depth_box.min.z);
    const float d = -(light.light_view * glm::vec4(corner, 1.0f)).z;
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  const float margin = 0.01f * (hi - lo) + 1e-3f;
  light.near_depth = lo - margin;
  light.far_depth = hi + margin;
}

}  // namespace

IzbLightView izb_light_view(const Frame& frame) {
  IzbLightView light;
  light.light_view = light_view_matrix(frame.view.light_direction);
  const Aabb depth_box = scene_bounds(frame);  // casters and receivers
  if (frame.view.local_light) fit_spot_light(frame, light);
  else if (depth_box.valid()) fit_sun_depth(depth_box, light);
  return light;
}

gpu_shared::IzbParams izb_params(IzbState& s, const Frame& frame, const IzbSettings& settings, const IzbPlan& plan,
                                 const IzbLightView& light) {
  const IzbResources& r = s.res;
  gpu_shared::IzbParams p{};
  p.light_view = light.light_view;
  p.inverse_view_projection = frame.view.inverse_view_projection;
  p.light_direction = glm::vec4(frame.view.light_direction, 0.0f);
  p.camera_position = glm::vec4(frame.view.camera_position, settings.max_distance);
  p.depth_range = glm::vec4(light.near_depth, light.far_depth, 0.0f, 0.0f);
  p.extent = glm::uvec4(frame.view.extent.width, frame.view.extent.height, r.resolution, r.samples);
  p.limits = glm::uvec4(uint32_t(std::min<uint64_t>(r.pool_size, UINT32_MAX)), plan.flags,
                        uint32_t(std::min<uint64_t>(r.records.capacity, UINT32_MAX)),
                        uint32_t(std::min<uint64_t>(r.pairs.capacity, UINT32_MAX)));
  p.capacities = glm::uvec4(uint32_t(std::min<uint64_t>(r.tile_pairs.capacity, UINT32_MAX)), r.tiles_per_side,
                            s.casters.caster_draws, plan.step_one_shape);
  if (plan.spot) {
    p.light_position = glm::vec4(frame.view.light_position, frame.view.light_range);
    p.light_cone = glm::vec4(frame.view.light_cos_outer, light.tan_half_angle, frame.view.light_face ? 1.0f : 0.0f, 0.0f);
  }
  p.view_projection = frame.view.view_projection;
  p.penumbra = glm::vec4(plan.penumbra ? frame.view.light_tan_half_angle : 0.0f,
                         2.0f * frame.view.tan_half_fov.y / float(std::max(frame.view.extent.height, 1u)), 0.0f, 0.0f);
  const glm::mat4& inverse_vp = frame.view.inverse_view_projection;
  if (plan.constant_ray_w) set_ray_scales(p, inverse_vp);
  if (plan.bounded_fit) set_corner_rays(p, inverse_vp, frame.view.extent);
  return p;
}

void record_light_frustum(IzbState& s, IzbBatch& batch, const IzbSettings& settings) {
  Frame& frame = batch.frame();
  const IzbPlan& plan = batch.plan();
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(s.ctx, frame.profiler, cmd, "light_frustum");
  {
    // The last of its workgroups also fits the grid and (with many casters) lists the caster draws
    // whose bounds reach it; on a CPU device a dispatch of its own does (IZB_FLAG_CPU_DEVICE).
    // A spot light's grid spans its whole cone whatever the points' bounds (izb_setup.glsl): one
    // workgroup that reads no pixel sets it up.
    OptionalGpuRegion step(settings.step_timings, s.ctx, frame.profiler, cmd, "light_frustum_fit");
    for_each_record(s, batch, [&](IzbRecord& r) {
      if (plan.spot) s.dispatch(cmd, *r.frame, s.p->fit, r.push, 1, 1);
      else
        s.dispatch(cmd, *r.frame, s.p->fit, r.push, fit_columns(frame.view.extent.width),
                   fit_rows(frame.view.extent.height));
    });
  }
  if (plan.cpu) {
    pass_barrier(frame.ctx, cmd);
    OptionalGpuRegion step(settings.step_timings, s.ctx, frame.profiler, cmd, "light_frustum_cull");
    for_each_record(s, batch, [&](IzbRecord& r) { s.dispatch(cmd, *r.frame, s.p->setup, r.push, 1); });
  }
  // The triangles into grid space, listed where they reach it: those of the listed draws, or with
  // few casters every one (where nothing before the compute trace reads them, in its step 1).
  if (!plan.triangles_in_trace) {
    pass_barrier(frame.ctx, cmd);
    OptionalGpuRegion step(settings.step_timings, s.ctx, frame.profiler, cmd, "light_frustum_triangles");
    for_each_record(s, batch, [&](IzbRecord& r) {
      if (plan.all_triangles) {
        const uint32_t groups = (s.casters.triangle_count + 63) / 64;
        if (groups > 0) s.dispatch(cmd, *r.frame, s.p->grid_setup, r.push, groups);
      } else {
        s.dispatch_indirect(cmd, *r.frame, s.p->grid_setup, r.push, gpu_shared::IZB_COUNTER_GRID_SETUP_DISPATCH);
      }
    });
  }
}

}  // namespace shadows::detail
