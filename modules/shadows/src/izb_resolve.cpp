#include "barriers.hpp"
#include "izb_resolve.hpp"

#include "gpu/profiler.hpp"

namespace shadows::detail {

using namespace engine::gpu;

void record_overflow_fallback(IzbState& s, Frame& frame, const IzbPlan& plan, const gpu_shared::IzbComputePush& push) {
  // With a node per pixel in a pool of one per pixel (IZB_FLAG_DIRECT_NODES) no pixel overflows.
  if ((plan.flags & gpu_shared::IZB_FLAG_DIRECT_NODES) != 0) return;
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(s.ctx, frame.profiler, cmd, "izb_fallback");
  s.dispatch_indirect(cmd, frame, s.p->fallback, push, gpu_shared::IZB_COUNTER_DISPATCH);
  pass_barrier(frame.ctx, cmd);
}

void record_izb_resolve(IzbState& s, Frame& frame, const IzbPlan& plan, bool hybrid,
                        const gpu_shared::IzbComputePush& push) {
  // A direct term needs none: the build also tests a local light's casters across its near plane.
  if (plan.direct_term) return;
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(s.ctx, frame.profiler, cmd, "izb_resolve");
  const Pipeline& resolve = s.pipelines.resolve(s.res.samples, plan.flags, plan.debug, hybrid);
  // With face tiles, over the tiles the build ran over.
  if (plan.face_tiles) s.dispatch_face_tiles(cmd, frame, resolve, push);
  else if (plan.listed_resolve) s.dispatch_indirect(cmd, frame, resolve, push, gpu_shared::IZB_COUNTER_RESOLVE_LIST + 1);
  else s.dispatch_pixels(cmd, frame, resolve, push);
  pass_barrier(frame.ctx, cmd);
  if (hybrid && plan.cpu) s.size_list_dispatch(cmd, frame, push, gpu_shared::IZB_LIST_HYBRID);
}

}  // namespace shadows::detail
