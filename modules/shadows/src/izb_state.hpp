#pragma once
#include <memory>
#include <string>
#include <vector>

#include "backend_probe.hpp"
#include "csm_pass.hpp"
#include "frame.hpp"
#include "izb_casters.hpp"
#include "izb_pipelines.hpp"
#include "izb_resources.hpp"
#include "shared/izb.h"

namespace shadows::detail {

struct IzbBatch;

// The IZB's timed choices. Each compares the IZB's own passes, timed by these regions.
struct IzbProbes {
  static std::vector<std::string> izb_regions() {
    return {"light_frustum", "lit_map", "csm", "izb_build", "frustum_trace", "izb_fallback", "izb_resolve"};
  }
  BackendProbe trace{"frustum_trace"};
  BackendProbe csm{"csm"};
  // Known-lit culling under LitCulling::Auto: the IZB's own passes timed with the lit map ("on", the
  // probe's raster slot) and without ("off", its compute slot: the choice without timestamps).
  BackendProbe lit{izb_regions(), {"on", "off"}};
  // Step 1's shape on a GPU (izb.h): the same passes timed "wide" (the raster slot) and "narrow".
  BackendProbe shape{izb_regions(), {"wide", "narrow"}};
  // IzbSettings::csm_timed: the same passes timed with the automatic CSM prepass ("run", the raster
  // slot) and without it ("skip").
  BackendProbe csm_run{izb_regions(), {"run", "skip"}};

  // A frame slowed by an overflow does not speak for any of them.
  void discard_pending(uint32_t slot) {
    trace.discard_pending(slot);
    csm.discard_pending(slot);
    lit.discard_pending(slot);
    csm_run.discard_pending(slot);
    shape.discard_pending(slot);
  }
};

// What the last record() ran, for the statistics and the snapshots.
struct IzbLastRecord {
  bool compute_trace = false;
  bool compute_csm = false;
  bool lit = false;
  bool hardware = false;
  bool csm = false;
  bool penumbra = false;  // IzbPlan::penumbra
};

// Everything the IZB's steps share, and the ways they record a pass: every pass binds the same
// descriptors (push_all) and takes an IzbComputePush.
struct IzbState {
  IzbState(engine::gpu::Context& c, bool cpu_paths);

  void push_all(VkCommandBuffer cmd, const Frame& frame, const engine::gpu::Pipeline& pipeline);
  void bind_compute(VkCommandBuffer cmd, const Frame& frame, const engine::gpu::Pipeline& pipeline,
                    const gpu_shared::IzbComputePush& push);
  void dispatch(VkCommandBuffer cmd, const Frame& frame, const engine::gpu::Pipeline& pipeline,
                gpu_shared::IzbComputePush push, uint32_t x, uint32_t y = 1);
  // One invocation per pixel of the view, in workgroups of IzbPipelineCache::with_pixel_group.
  void dispatch_pixels(VkCommandBuffer cmd, const Frame& frame, const engine::gpu::Pipeline& pipeline,
                       gpu_shared::IzbComputePush push);
  // The dispatch's size from counter `counter` (IZB_COUNTER_*), which an earlier pass raised.
  void dispatch_indirect(VkCommandBuffer cmd, const Frame& frame, const engine::gpu::Pipeline& pipeline,
                         gpu_shared::IzbComputePush push, uint32_t counter);
  // A point light's face, or a spot light on a CPU device (IZB_FLAG_FACE_TILES): a workgroup of 8x8 a
  // tile of the face's list (izb_face_tiles.comp; a spot light's is list 0).
  void dispatch_face_tiles(VkCommandBuffer cmd, const Frame& frame, const engine::gpu::Pipeline& pipeline,
                           gpu_shared::IzbComputePush push);
  // A CPU device: the dispatch over list `which` (IZB_LIST_*) from its length, visible to what follows.
  void size_list_dispatch(VkCommandBuffer cmd, const Frame& frame, gpu_shared::IzbComputePush push, uint32_t which);
  // Compute trace / compute CSM / lit map, steps 1-3 (see izb.h) for `mode` (IZB_WORK_*), each step
  // for every record of `batch` before the barrier after it; with `time_steps`
  // (IzbSettings::step_timings) each step in a nested profiler region "<region>_records",
  // "<region>_tiles", "<region>_texels".
  void record_tile_work(VkCommandBuffer cmd, IzbBatch& batch, uint32_t mode, const std::string& region,
                        bool time_steps);
  // The light view-projection the last frame's fit wrote (izb_fit.comp), for the snapshots.
  glm::mat4 read_light_view_projection() const;

  engine::gpu::Context& ctx;
  IzbPipelineCache pipelines;
  IzbPipelines* p = nullptr;  // this frame's
  IzbResources res;
  IzbCasters casters;
  IzbProbes probes;
  std::unique_ptr<CsmPass> csm;
  IzbLastRecord last;
};

}  // namespace shadows::detail
