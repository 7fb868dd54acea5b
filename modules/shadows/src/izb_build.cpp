#include "barriers.hpp"
#include "izb_build.hpp"

#include <algorithm>

#include "gpu/profiler.hpp"

namespace shadows::detail {

using namespace engine::gpu;

namespace {

// Counting sort: counts (the build's) -> prefix sum -> scatter into contiguous ranges.
void record_counting_sort(IzbState& s, Frame& frame, const gpu_shared::IzbComputePush& push) {
  VkCommandBuffer cmd = frame.cmd;
  const uint32_t blocks = s.res.scan_blocks;
  for (uint32_t step = 0; step < 3; ++step) {
    pass_barrier(frame.ctx, cmd);
    gpu_shared::IzbComputePush scan_push = push;
    scan_push.mode = step;
    const uint32_t rows = (blocks + gpu_shared::kIzbDispatchRow - 1) / gpu_shared::kIzbDispatchRow;
    if (step == 1) s.dispatch(cmd, frame, s.p->scan, scan_push, 1);
    else s.dispatch(cmd, frame, s.p->scan, scan_push, std::min(blocks, gpu_shared::kIzbDispatchRow), rows);
  }
  pass_barrier(frame.ctx, cmd);
  s.dispatch_pixels(cmd, frame, s.p->scatter, push);
}

// Whether the batch lists a point light's face tiles (or a CPU device's spot light's): once, before
// its first face.
bool lists_face_tiles(IzbBatch& batch) { return batch.plan().face_tiles && batch.frame().view.first_light_face(); }

}  // namespace

void record_face_tiles(IzbState& s, IzbBatch& batch) {
  if (!lists_face_tiles(batch)) return;
  Frame& frame = batch.frame();
  select_record(s, batch.records.front());
  ScopedGpuRegion region(s.ctx, frame.profiler, frame.cmd, "point_light_tiles");
  const uint32_t block = gpu_shared::light_tile_listing_block(s.pipelines.cpu_device());
  s.dispatch(frame.cmd, frame, s.p->face_tiles, batch.records.front().push, groups(frame.view.extent.width, block),
             groups(frame.view.extent.height, block));
}

void record_izb_reset(IzbState& s, IzbBatch& batch) {
  Frame& frame = batch.frame();
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(s.ctx, frame.profiler, cmd, "izb_reset");
  // The previous record's shader reads and its readback's copy before these transfer writes (its
  // writes were made visible by the barrier after it).
  engine::gpu::memory_barrier(cmd, pass_shader_stages(s.ctx) | VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, 0,
                              VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, 0);
  // The face tiles' lists start empty (their counts and dispatches; record_face_tiles).
  if (lists_face_tiles(batch))
    vkCmdFillBuffer(cmd, s.res.resolve_list.handle(), 0, VkDeviceSize(gpu_shared::kLightTilesAt) * 4, 0);
  for_each_record(s, batch, [&](const IzbRecord& r) {
    const IzbResources& res = s.res;
    vkCmdUpdateBuffer(cmd, res.params.handle(), res.slice_at(res.params_stride), sizeof(r.params), &r.params);
    vkCmdFillBuffer(cmd, res.counters.handle(), res.counter_slice_offset(), IzbResources::counter_bytes(), 0);
    // (With IZB_FLAG_FIT_CLEARS_GRID the fit empties the grid: izb_fit.comp.)
    if (r.plan.fit_clears_grid) return;
    if (r.plan.sorted) vkCmdFillBuffer(cmd, res.list_counts.handle(), 0, res.texel_word_bytes(), 0);
    else
      vkCmdFillBuffer(cmd, res.heads.handle(), res.slice_at(res.heads_stride()), res.texel_word_bytes(),
                      gpu_shared::kIzbEndOfList);
    vkCmdFillBuffer(cmd, res.farthest.handle(), res.slice_at(res.farthest_stride()), res.farthest_bytes(), 0);
  });
  // Transfer writes before the fit's shader reads and writes (the parameters' uniform reads too); the
  // previous light's shader reads of the grid before the fit's stores into it.
  pass_barrier(frame.ctx, cmd);
}

void record_izb_build(IzbState& s, IzbBatch& batch, const IzbSettings& settings) {
  Frame& frame = batch.frame();
  const IzbPlan& plan = batch.plan();
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(s.ctx, frame.profiler, cmd, "izb_build");
  {
    OptionalGpuRegion step(settings.step_timings, s.ctx, frame.profiler, cmd, "build_classify");
    for_each_record(s, batch, [&](IzbRecord& r) {
      if (plan.face_tiles) s.dispatch_face_tiles(cmd, *r.frame, s.p->build, r.push);
      else s.dispatch_pixels(cmd, *r.frame, s.p->build, r.push);
    });
  }
  if (plan.sorted) for_each_record(s, batch, [&](IzbRecord& r) { record_counting_sort(s, *r.frame, r.push); });
  pass_barrier(frame.ctx, cmd);
  // A CPU device sizes the lists' dispatches in a pass of their own (izb_list_dispatch.comp), then
  // inserts the listed pixels' nodes where the build runs in two steps. (The sun's alone.)
  if (plan.listed_resolve && plan.cpu) {
    IzbRecord& r = batch.records.front();
    select_record(s, r);
    OptionalGpuRegion step(settings.step_timings, s.ctx, frame.profiler, cmd, "build_insert");
    s.size_list_dispatch(cmd, frame, r.push, gpu_shared::IZB_LIST_RESOLVE);
    if (s.p->build_insert.valid()) {
      s.dispatch_indirect(cmd, frame, s.p->build_insert, r.push, gpu_shared::IZB_COUNTER_RESOLVE_LIST + 1);
      pass_barrier(frame.ctx, cmd);
    }
  }
}

}  // namespace shadows::detail
