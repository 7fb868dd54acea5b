#include "barriers.hpp"
#include "izb_pass.hpp"

#include <algorithm>
#include <stdexcept>

#include "izb_build.hpp"
#include "izb_csm_prepass.hpp"
#include "izb_frustum.hpp"
#include "izb_hybrid.hpp"
#include "izb_lit_map.hpp"
#include "izb_plan.hpp"
#include "izb_resolve.hpp"
#include "izb_state.hpp"
#include "izb_stats.hpp"
#include "izb_trace.hpp"

namespace shadows::detail {

using namespace engine::gpu;

uint32_t izb_grid_resolution(const View& view, const IzbSettings& settings) {
  if (!view.light_face) return settings.resolution;
  // Each face holds about a sixth of the light's points, and every face pays its grid's fills (list
  // heads and farthest depths) again: at three quarters a side the fills take 56 % of the whole grid's
  // while the lists stay short (BENCHMARKS.md, local lights: a quarter, five eighths and the whole
  // grid measured).
  const uint32_t tile = gpu_shared::kIzbTile;
  const uint32_t scaled = (settings.resolution * kPointFaceGridEighths / 8 + tile - 1) / tile * tile;
  return std::clamp(scaled, std::min(settings.resolution, tile), settings.resolution);
}

IzbPass::IzbPass(Context& ctx, bool cpu_paths) : state_(std::make_unique<IzbState>(ctx, cpu_paths)) {}
IzbPass::~IzbPass() = default;

bool IzbPass::hardware_raster_available() const { return state_->pipelines.hardware_trace_available(); }

bool IzbPass::csm_test_supported(CsmTest test, std::string* why) const { return state_->csm->supported(test, why); }

void IzbPass::record(Frame& frame, const IzbSettings& settings, DebugView debug, bool hybrid, bool collect_stats) {
  IzbState& s = *state_;
  if (settings.resolution == 0 || settings.resolution > 16384)
    throw std::invalid_argument("IZB resolution must be in 1..16384");
  s.res.ensure_buffers(frame, settings, izb_grid_resolution(frame.view, settings));
  // A point light's faces count in slices of one buffer, read back together after the last.
  s.res.counter_slice = frame.view.light_face ? std::min(frame.view.light_face_order, IzbResources::kCounterSlices - 1) : 0;
  s.res.ensure_hybrid(frame.cmd, frame.view.extent, hybrid, settings.max_distance > 0.0f);
  s.casters.update(frame, s.pipelines);
  IzbPlan plan;
  plan.run_csm = s.csm->plan(frame, settings, s.res.resolution);
  s.csm->prepare(frame.cmd, plan.run_csm ? s.res.resolution : 1);
  choose_izb_backends(s, frame, settings, hybrid, plan);
  s.res.ensure_work_lists(plan.compute_trace || plan.compute_csm || plan.lit, s.casters.triangle_count);
  if (plan.compute_csm) upload_csm_draw_flags(s, frame);
  const IzbLightView light = izb_light_view(frame);
  plan.debug = izb_debug_code(debug);
  choose_izb_flags(s, frame, settings, hybrid, collect_stats, plan);
  s.last.penumbra = plan.penumbra;
  s.res.ensure_resolve_list(frame.view.extent, plan.listed_resolve, plan.face_tiles);
  s.p = &s.pipelines.set(s.res.samples, plan.flags);  // specialized for every flag of the plan
  const gpu_shared::IzbComputePush push{hybrid ? 1u : 0u, plan.debug, s.casters.triangle_count, 0u};

  record_izb_reset(s, frame, plan, izb_params(s, frame, settings, plan, light));
  record_light_frustum(s, frame, settings, plan, push);
  pass_barrier(frame.ctx, frame.cmd);
  if (plan.lit) record_lit_map(s, frame, settings, push);
  if (plan.run_csm) record_csm_prepass(s, frame, settings, plan, push, collect_stats);
  record_izb_build(s, frame, settings, plan, push);
  const IzbRasterTrace raster = prepare_raster_trace(s, frame, settings, plan, light.light_view);
  record_frustum_trace(s, frame, settings, plan, raster, push);
  pass_barrier(frame.ctx, frame.cmd);
  record_overflow_fallback(s, frame, plan, push);
  record_izb_resolve(s, frame, plan, hybrid, push);
  if (collect_stats) record_izb_stats(s, frame, plan, raster, push);
  // A point light's faces: every face's counters at once, after the last.
  if (!frame.view.light_face || frame.view.last_light_face) record_counters_readback(s, frame);
}

bool IzbPass::writes_every_pixel(const IzbSettings& settings, float max_distance, DebugView debug, bool hybrid) const {
  return !state_->pipelines.cpu_device() &&
         izb_direct_term(izb_sample_count(settings), hybrid, max_distance, izb_debug_code(debug), false);
}

engine::gpu::Image& IzbPass::soft_term() { return state_->res.soft_term; }

PixelList IzbPass::hybrid_list() const { return izb_hybrid_list(state_->res); }

void IzbPass::record_hybrid_blend(Frame& frame) { detail::record_hybrid_blend(*state_, frame); }

void IzbPass::record_hybrid_penumbra(Frame& frame, bool step_timings) {
  if (state_->last.penumbra) detail::record_hybrid_penumbra(*state_, frame, step_timings);
}

CsmSnapshot IzbPass::read_csm() { return detail::read_csm(*state_); }

LitMapSnapshot IzbPass::read_lit_map() { return detail::read_lit_map(*state_); }

void IzbPass::after_frame(std::vector<Stats>& records, uint32_t slot) { read_izb_counters(*state_, records, slot); }

uint32_t IzbPass::records_so_far(uint32_t slot, uint64_t frame_index) const {
  return state_->res.counters_readback.recorded(slot, frame_index);
}

}  // namespace shadows::detail
