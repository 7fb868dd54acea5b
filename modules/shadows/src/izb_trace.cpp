#include "barriers.hpp"
#include "izb_trace.hpp"

#include "izb_batch.hpp"

#include <algorithm>

#include "gpu/profiler.hpp"
#include "light_space.hpp"

namespace shadows::detail {

using namespace engine::gpu;

namespace {

// Light-space box around every point that can hold a node (the view, up to the IZB's range, within
// the scene): a caster wholly beside it shadows none of them.
glm::mat4 receiver_region(const Frame& frame, const IzbSettings& settings, const glm::mat4& light_view) {
  const float reach = settings.max_distance > 0.0f ? std::min(settings.max_distance, frame.view.far_plane)
                                                   : frame.view.far_plane;
  glm::vec3 corners[8];
  view_slice_corners(frame.view, frame.view.near_plane, reach, corners);
  Aabb box;
  for (const glm::vec3& c : corners) box.extend(c);
  const Aabb scene = scene_bounds(frame);
  if (scene.valid()) box = {glm::max(box.min, scene.min), glm::min(box.max, scene.max)};
  if (!box.valid()) return glm::mat4(0.0f);  // nothing to receive: every caster culled
  // The shadow-ray offset and rounding may carry a node slightly outside.
  // fit_orthographic gives the projection alone: the clip matrix is it after the light's view.
  return fit_orthographic(light_view, box, 1e-3f * glm::length(box.extent()) + 1e-3f) * light_view;
}

// Each texel's farthest node depth becomes the depth the early test compares against (0 for an empty
// texel: nothing passes). The build keeps them in [0,1], where float order is bit order, so the
// buffer copies as it is; a full-screen depth-writing draw costs a CPU driver far more.
void copy_farthest_to_depth(IzbState& s, Frame& frame) {
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 0, 1};
  region.imageExtent = {s.res.resolution, s.res.resolution, 1};
  vkCmdCopyBufferToImage(frame.cmd, s.res.farthest.handle(), s.res.trace_depth.handle(), VK_IMAGE_LAYOUT_GENERAL, 1,
                         &region);
  pass_barrier(frame.ctx, frame.cmd);
}

}  // namespace

IzbRasterTrace prepare_raster_trace(IzbState& s, const Frame& frame, const IzbSettings& settings,
                                    const IzbPlan& plan, const glm::mat4& light_view) {
  IzbRasterTrace trace;
  trace.receiver_region = receiver_region(frame, settings, light_view);
  // The raster trace draws the opaque casters with pipelines whose node test has no alpha-test code
  // (a CPU device runs both sides of a branch), then the alpha-tested ones with it.
  trace.alpha = (plan.flags & gpu_shared::IZB_FLAG_ALPHA) != 0;
  trace.opaque = trace.alpha ? &s.pipelines.opaque_trace(s.res.samples, plan.flags) : &s.p->trace;
  trace.alpha_tested = &s.p->trace;
  trace.hardware = plan.hardware;  // the raster trace runs only without the compute one
  return trace;
}

void draw_raster_trace(IzbState& s, Frame& frame, const IzbRasterTrace& trace, bool count_only, VkCompareOp compare,
                       bool fill_depth) {
  VkCommandBuffer cmd = frame.cmd;
  if (fill_depth) copy_farthest_to_depth(s, frame);
  begin_depth_rendering(cmd, s.res.trace_depth.view(), {s.res.resolution, s.res.resolution}, false);
  for (const CasterSet set : {trace.alpha ? CasterSet::Opaque : CasterSet::All, CasterSet::AlphaTested}) {
    if (set == CasterSet::AlphaTested && !trace.alpha) break;
    const IzbTracePipelines& tp = set == CasterSet::AlphaTested ? *trace.alpha_tested : *trace.opaque;
    const Pipeline& pipeline = count_only ? (trace.hardware ? tp.count_hardware : tp.count_software)
                                          : (trace.hardware ? tp.hardware : tp.software);
    pipeline.bind(cmd);
    vkCmdSetDepthBias(cmd, -1.0f, 0.0f, -1.0f);
    vkCmdSetDepthCompareOp(cmd, compare);
    s.push_all(cmd, frame, pipeline);
    draw_casters(
        cmd, frame,
        [&](const DrawItem& d, const MeshRange& range) {
          gpu_shared::IzbDrawPush dp{d.world, range.first_index, range.vertex_offset,
                                     s.casters.first_triangle[size_t(&d - frame.draws.data())], 0u};
          pipeline.push_constants(cmd, dp);
        },
        set,
        // Rasterizing a caster costs a CPU driver per triangle even where it covers no node.
        [&](const DrawItem& d) { return d.bounds.outside_clip(trace.receiver_region); });
  }
  vkCmdEndRendering(cmd);
}

void record_frustum_trace(IzbState& s, IzbBatch& batch, const IzbSettings& settings) {
  Frame& frame = batch.frame();
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(s.ctx, frame.profiler, cmd, "frustum_trace");
  if (batch.plan().compute_trace) {
    // Tiles' farthest nodes -> (triangle, tile) pairs not culled -> (triangle, texel) pairs that touch
    // and survive the texel's cull -> one thread per pair walks the texel's list.
    s.record_tile_work(cmd, batch, gpu_shared::IZB_WORK_TRACE, "trace", settings.step_timings);
    pass_barrier(frame.ctx, cmd);
    OptionalGpuRegion step(settings.step_timings, s.ctx, frame.profiler, cmd, "trace_pairs");
    for_each_record(s, batch, [&](IzbRecord& r) {
      s.dispatch_indirect(cmd, *r.frame, s.p->trace_compute, r.push, gpu_shared::IZB_COUNTER_PAIR_DISPATCH);
    });
  } else {
    // (The raster trace has one depth image: its records are the sun's, one a batch.)
    select_record(s, batch.records.front());
    draw_raster_trace(s, frame, batch.records.front().raster, false,
                      settings.depth_cull ? VK_COMPARE_OP_LESS : VK_COMPARE_OP_ALWAYS, true);
  }
}

}  // namespace shadows::detail
