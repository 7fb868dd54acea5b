#include "barriers.hpp"
#include "izb_csm_prepass.hpp"

#include "izb_batch.hpp"

#include <cstring>

namespace shadows::detail {

using namespace engine::gpu;

void upload_csm_draw_flags(IzbState& s, const Frame& frame) {
  const auto& chosen = s.csm->chosen_draws();
  std::vector<uint32_t> flags;
  flags.reserve(s.casters.caster_draws);
  for (const uint32_t i : s.casters.caster_items)
    flags.push_back(i < chosen.size() && chosen[i] ? gpu_shared::IZB_DRAW_IN_CSM : 0u);
  // In the command stream: each frame in flight reads its own flags.
  if (!flags.empty())
    record_update(s.ctx, frame.cmd, s.casters.caster_draw_words, flags.data(), flags.size() * sizeof(uint32_t));
}

void record_csm_prepass(IzbState& s, IzbBatch& batch, const IzbSettings& settings, bool collect_stats) {
  Frame& frame = batch.frame();
  const IzbPlan& plan = batch.plan();
  if (plan.compute_csm) {
    const uint32_t mode = settings.csm_test == CsmTest::Hertel ? gpu_shared::IZB_WORK_CSM_HERTEL
                                                               : gpu_shared::IZB_WORK_CSM_BARYCENTRIC;
    s.csm->record(
        frame, settings, s.res.frame_data, s.res.resolution, collect_stats,
        [&](VkCommandBuffer c) {
          vkCmdFillBuffer(c, s.res.csm_texels.handle(), 0, s.res.texel_word_bytes(), 0x3f800000u);  // 1.0: nothing stored
          pass_barrier(frame.ctx, c);
          s.record_tile_work(c, batch, mode, "csm", settings.step_timings);
        },
        &s.res.csm_texels);
  } else {
    s.csm->record(frame, settings, s.res.frame_data, s.res.resolution, collect_stats);
  }
  pass_barrier(frame.ctx, frame.cmd);
}

CsmSnapshot read_csm(IzbState& s) {
  CsmSnapshot snapshot;
  if (!s.last.csm) return snapshot;
  const uint32_t resolution = s.res.resolution;
  snapshot.resolution = resolution;
  if (s.last.compute_csm) {
    const auto bytes = read_buffer(s.ctx, s.res.csm_texels);
    snapshot.depth.resize(size_t(resolution) * resolution);
    std::memcpy(snapshot.depth.data(), bytes.data(), snapshot.depth.size() * sizeof(float));
  } else {
    snapshot.depth = s.csm->read_depth();
  }
  snapshot.light_view_projection = s.read_light_view_projection();
  return snapshot;
}

}  // namespace shadows::detail
