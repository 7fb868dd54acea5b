#include "barriers.hpp"
#include "izb_pass.hpp"

#include <algorithm>
#include <stdexcept>

#include "izb_batch.hpp"
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

namespace {

// Plans one record: sizes what it binds, chooses its backends and flags, and fills its parameters.
IzbRecord plan_izb_record(IzbState& s, Frame& frame, const IzbSettings& settings, DebugView debug, bool hybrid,
                          bool collect_stats) {
  if (settings.resolution == 0 || settings.resolution > 16384)
    throw std::invalid_argument("IZB resolution must be in 1..16384");
  IzbRecord r;
  r.frame = &frame;
  s.res.ensure_buffers(frame, settings, izb_grid_resolution(frame.view, settings));
  // A point light's faces count in slices of one buffer, read back together after the last.
  r.counter_slice = frame.view.light_face ? std::min(frame.view.light_face_order, IzbResources::kCounterSlices - 1) : 0;
  s.res.ensure_hybrid(frame.cmd, frame.view.extent, hybrid, settings.max_distance > 0.0f);
  s.casters.update(frame, s.pipelines);
  IzbPlan& plan = r.plan;
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
  r.pipelines = &s.pipelines.set(s.res.samples, plan.flags);  // specialized for every flag of the plan
  s.p = r.pipelines;  // (the raster trace's pipelines come from it)
  r.push = gpu_shared::IzbComputePush{hybrid ? 1u : 0u, plan.debug, s.casters.triangle_count, 0u};
  r.params = izb_params(s, frame, settings, plan, light);
  r.raster = prepare_raster_trace(s, frame, settings, plan, light.light_view);
  return r;
}

void record_izb_batch(IzbState& s, IzbBatch& batch, const IzbSettings& settings, bool hybrid, bool collect_stats) {
  Frame& frame = batch.frame();
  const IzbPlan& plan = batch.plan();
  record_izb_reset(s, batch);
  record_face_tiles(s, batch);
  record_light_frustum(s, batch, settings);
  pass_barrier(frame.ctx, frame.cmd);
  if (plan.lit) record_lit_map(s, batch, settings);
  if (plan.run_csm) record_csm_prepass(s, batch, settings, collect_stats);
  record_izb_build(s, batch, settings);
  record_frustum_trace(s, batch, settings);
  pass_barrier(frame.ctx, frame.cmd);
  record_overflow_fallback(s, batch);
  record_izb_resolve(s, batch, hybrid);
  if (collect_stats) record_izb_stats(s, batch);
  // A point light's faces: every face's counters at once, after the last.
  const IzbRecord& last = batch.records.back();
  if (!last.frame->view.light_face || last.frame->view.last_light_face)
    record_counters_readback(s, frame, last.counter_slice + 1);
}

// Whether a point light's planned faces can record together: one plan for all (one set of pipelines),
// and nothing they write outside their own slices and pixels. That takes a node per pixel (a pool
// shared by counters per face would hand out the same nodes twice), a term the build and trace write
// (a resolve reads each pixel's state, which every face's build writes over its tiles, the other
// faces' pixels marked as theirs) and neither the CSM nor the lit map (one depth image or buffer a
// grid) nor sorted lists (one prefix sum a grid).
bool faces_record_together(const IzbBatch& faces) {
  const IzbPlan& first = faces.plan();
  if (faces.records.size() < 2 || !first.compute_trace || !first.direct_term || first.run_csm || first.lit ||
      first.sorted || (first.flags & gpu_shared::IZB_FLAG_DIRECT_NODES) == 0)
    return false;
  return std::all_of(faces.records.begin(), faces.records.end(), [&](const IzbRecord& r) {
    return r.plan.flags == first.flags && r.pipelines == faces.records.front().pipelines;
  });
}

}  // namespace

void IzbPass::record(Frame& frame, const IzbSettings& settings, DebugView debug, bool hybrid, bool collect_stats) {
  IzbBatch batch;
  batch.records.push_back(plan_izb_record(*state_, frame, settings, debug, hybrid, collect_stats));
  record_izb_batch(*state_, batch, settings, hybrid, collect_stats);
}

void IzbPass::record_faces(std::vector<Frame>& faces, const IzbSettings& settings, DebugView debug,
                           bool collect_stats) {
  IzbState& s = *state_;
  // The CSM keeps state from one record to the next (its choices per record): faces that may run it
  // are planned and recorded one at a time.
  if (settings.csm || faces.size() < 2) {
    for (Frame& face : faces) {
      record(face, settings, debug, false, collect_stats);
      pass_barrier(face.ctx, face.cmd);
    }
    return;
  }
  IzbBatch all;
  for (Frame& face : faces) all.records.push_back(plan_izb_record(s, face, settings, debug, false, collect_stats));
  if (!faces_record_together(all)) {
    for (IzbRecord& r : all.records) {
      IzbBatch one{{r}};
      record_izb_batch(s, one, settings, false, collect_stats);
      pass_barrier(r.frame->ctx, r.frame->cmd);
    }
    return;
  }
  const uint32_t slices = uint32_t(all.records.size());
  s.res.ensure_grid_slices(slices);
  s.casters.ensure_grid_sections(slices);
  for (uint32_t k = 0; k < slices; ++k) {
    all.records[k].grid_slice = k;
    all.records[k].params.face_sections.x = s.casters.face_section_words(k);
  }
  record_izb_batch(s, all, settings, false, collect_stats);
  pass_barrier(all.frame().ctx, all.frame().cmd);
}

bool IzbPass::writes_every_pixel(const IzbSettings& settings, float max_distance, DebugView debug, bool hybrid,
                                 bool directional) const {
  return (directional || !state_->pipelines.cpu_device()) &&
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
