#include "barriers.hpp"
#include "izb_resolve.hpp"

#include "izb_batch.hpp"

#include "gpu/profiler.hpp"

namespace shadows::detail {

using namespace engine::gpu;

void record_overflow_fallback(IzbState& s, IzbBatch& batch) {
  // With a node per pixel in a pool of one per pixel (IZB_FLAG_DIRECT_NODES) no pixel overflows.
  if ((batch.plan().flags & gpu_shared::IZB_FLAG_DIRECT_NODES) != 0) return;
  Frame& frame = batch.frame();
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(s.ctx, frame.profiler, cmd, "izb_fallback");
  for_each_record(s, batch, [&](IzbRecord& r) {
    s.dispatch_indirect(cmd, *r.frame, s.p->fallback, r.push, gpu_shared::IZB_COUNTER_DISPATCH);
  });
  pass_barrier(frame.ctx, cmd);
}

void record_izb_resolve(IzbState& s, IzbBatch& batch, bool hybrid) {
  const IzbPlan& plan = batch.plan();
  // A direct term needs none: the build also tests a local light's casters across its near plane.
  if (plan.direct_term) return;
  Frame& frame = batch.frame();
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(s.ctx, frame.profiler, cmd, "izb_resolve");
  const Pipeline& resolve = s.pipelines.resolve(s.res.samples, plan.flags, plan.debug, hybrid);
  for_each_record(s, batch, [&](IzbRecord& r) {
    // With face tiles, over the tiles the build ran over.
    if (plan.face_tiles) s.dispatch_face_tiles(cmd, *r.frame, resolve, r.push);
    else if (plan.listed_resolve)
      s.dispatch_indirect(cmd, *r.frame, resolve, r.push, gpu_shared::IZB_COUNTER_RESOLVE_LIST + 1);
    else s.dispatch_pixels(cmd, *r.frame, resolve, r.push);
  });
  pass_barrier(frame.ctx, cmd);
  if (hybrid && plan.cpu) s.size_list_dispatch(cmd, frame, batch.records.front().push, gpu_shared::IZB_LIST_HYBRID);
}

}  // namespace shadows::detail
