#include "barriers.hpp"
#include "izb_hybrid.hpp"

#include "gpu/profiler.hpp"

namespace shadows::detail {

using namespace engine::gpu;

void IzbResources::ensure_hybrid(VkCommandBuffer cmd, VkExtent2D e, bool hybrid, bool limited_range) {
  // A frame may shadow the sun with the hybrid and then a local light with the plain IZB: the
  // hybrid's images stay until the extent or the range changes.
  if (!hybrid && soft_term.valid()) return;
  const VkExtent2D want = hybrid ? e : VkExtent2D{1, 1};
  // The soft term and the list's pixels serve a limited range alone (the cascades' share of the
  // blend); with none the list holds the penumbra pass's tiles alone (3840x2160: 37 MB, not 170).
  const bool limited = hybrid && limited_range;
  if (soft_term.valid() && want.width == hybrid_extent.width && want.height == hybrid_extent.height &&
      limited == hybrid_limited)
    return;
  hybrid_extent = want;
  hybrid_limited = limited;
  soft_term = Image(ctx, limited ? want : VkExtent2D{1, 1}, VK_FORMAT_R32_SFLOAT,
                    VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, "izb hybrid soft term");
  // -1 (not filtered) everywhere; the blend restores that after each frame (izb_hybrid_blend.comp).
  to_general(ctx, cmd, soft_term);
  const VkClearColorValue unfiltered{{-1.0f, 0.0f, 0.0f, 0.0f}};
  const VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdClearColorImage(cmd, soft_term.handle(), VK_IMAGE_LAYOUT_GENERAL, &unfiltered, 1, &range);
  pass_barrier(ctx, cmd);
  hybrid_list = Buffer(ctx, VkDeviceSize(gpu_shared::izb_hybrid_list_entries(want.width, want.height, limited)) * 16,
                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false, "izb hybrid pixel list");
}

PixelList izb_hybrid_list(const IzbResources& res) {
  return {res.hybrid_list.handle(), res.counters.handle(), uint32_t(res.counter_at(gpu_shared::IZB_COUNTER_HYBRID) / 4)};
}

void record_hybrid_blend(IzbState& s, Frame& frame) {
  VkCommandBuffer cmd = frame.cmd;
  const Pipeline& blend = s.pipelines.hybrid_blend();
  ScopedGpuRegion region(s.ctx, frame.profiler, cmd, "hybrid_blend");
  blend.bind(cmd);
  s.push_all(cmd, frame, blend);
  vkCmdDispatchIndirect(cmd, s.res.counters.handle(), s.res.counter_at(gpu_shared::IZB_COUNTER_HYBRID + 1));
}

void record_hybrid_penumbra(IzbState& s, Frame& frame, bool step_timings) {
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(s.ctx, frame.profiler, cmd, "hybrid_penumbra");
  const gpu_shared::IzbComputePush push{};
  const uint32_t tiles_x = gpu_shared::penumbra_tiles_x(frame.view.extent.width);
  const uint32_t tiles_y = gpu_shared::penumbra_tiles_y(frame.view.extent.height);
  const auto step = [&](const char* name, auto&& record) {
    OptionalGpuRegion timed(step_timings, s.ctx, frame.profiler, cmd, name);
    record();
    pass_barrier(s.ctx, cmd);
  };
  constexpr uint32_t summary_tiles = gpu_shared::kPenumbraSummaryTiles;  // a workgroup's, side by side
  step("penumbra_tiles", [&] {
    s.dispatch(cmd, frame, s.pipelines.penumbra(0), push, (tiles_x + summary_tiles - 1) / summary_tiles, tiles_y);
  });
  step("penumbra_dilate",  // a thread a tile, 8x8 a workgroup
       [&] { s.dispatch(cmd, frame, s.pipelines.penumbra(1), push, (tiles_x + 7) / 8, (tiles_y + 7) / 8); });
  step("penumbra_filter", [&] {
    s.dispatch_indirect(cmd, frame, s.pipelines.penumbra(2), push, gpu_shared::IZB_COUNTER_PENUMBRA_TILES + 1);
  });
  OptionalGpuRegion timed(step_timings, s.ctx, frame.profiler, cmd, "penumbra_apply");
  s.dispatch_indirect(cmd, frame, s.pipelines.penumbra(3), push, gpu_shared::IZB_COUNTER_PENUMBRA_TILES + 1);
}

}  // namespace shadows::detail
