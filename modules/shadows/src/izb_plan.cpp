#include "izb_plan.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace shadows::detail {

using namespace engine::gpu;

bool izb_direct_term(uint32_t samples, bool hybrid, float max_distance, uint32_t debug_code, bool cpu_local_light) {
  return samples == 1 && !(hybrid && max_distance > 0.0f) && debug_code == 0 && !cpu_local_light;
}

uint32_t izb_debug_code(DebugView debug) {
  switch (debug) {
    case DebugView::VisibilityMask: return 1;
    case DebugView::ListLength: return 2;
    case DebugView::CsmCoverage: return 4;
    default: return 0;
  }
}

namespace {

// Raster or compute, per pass. The timing of either depends on the sizes, the scene and the mode.
// The render size counts in half-octaves of pixels, so dynamic resolution's small steps do not
// restart the probe every few frames; the CSM setting counts, not whether the adaptive CSM ran
// this frame (that alternates). The grid counts as IzbSettings::resolution, not a record's own (a
// point light's faces take a smaller one, izb_grid_resolution): the probes time whole frames, the
// faces' regions with the other lights' of the frame.
uint64_t probe_key(const IzbState& s, const Frame& frame, const IzbSettings& settings, bool hybrid) {
  const double pixels = double(frame.view.extent.width) * frame.view.extent.height;
  uint64_t key = mix_key(0, settings.resolution);
  for (uint64_t v : {uint64_t(std::lround(2.0 * std::log2(std::max(pixels, 1.0)))), uint64_t(s.res.samples),
                     uint64_t(s.casters.triangle_count), uint64_t(settings.csm), uint64_t(settings.csm_test),
                     uint64_t(settings.depth_cull), uint64_t(settings.progressive_removal), uint64_t(hybrid),
                     uint64_t(settings.lit_culling), uint64_t(settings.csm_timed),
                     uint64_t(settings.step_one_shape), uint64_t(settings.anchored_nodes)})
    key = mix_key(key, v);
  return key;
}

// A probe's pick for this record, within its frame (every record of a frame gets the frame's choice).
PassBackend pick_for_frame(BackendProbe& probe, PassBackend requested, bool raster_ok, bool compute_ok, uint64_t key,
                           const Frame& frame) {
  return probe.pick(requested, raster_ok, compute_ok, key, frame.profiler, frame.slot, frame.view.frame_index,
                    frame.slots);
}

// A spot light's perspective grid is traced and culled by the compute passes, which read the
// grid-space triangles (the raster passes' geometry stage assumes the sun's orthographic one).
void choose_trace_backend(IzbState& s, const Frame& frame, const IzbSettings& settings, uint64_t key, IzbPlan& plan) {
  const bool raster_trace_available = s.pipelines.raster_trace_available();
  if (plan.spot &&
      (settings.trace == PassBackend::Raster || (plan.run_csm && settings.csm_backend == PassBackend::Raster)))
    throw std::runtime_error("spot lights take the compute IZB trace and CSM (IzbSettings trace/csm_backend raster)");
  if (plan.spot && plan.run_csm && !CsmPass::compute_available(settings.csm_test))
    throw std::runtime_error("spot lights take the compute CSM, which CSM test " + csm_test_name(settings.csm_test) +
                             " does not have");
  plan.compute_trace =
      plan.spot ||
      pick_for_frame(s.probes.trace, settings.trace, raster_trace_available, true, key, frame) == PassBackend::Compute;
  if (!plan.compute_trace && !raster_trace_available)
    throw std::runtime_error("the raster IZB trace needs geometry shaders, which " + s.ctx.device_name() +
                             " lacks (use the compute trace)");
}

void choose_csm_backend(IzbState& s, const Frame& frame, const IzbSettings& settings, uint64_t key, IzbPlan& plan) {
  if (!plan.run_csm) return;
  const bool raster_ok = s.csm->raster_available(settings.csm_test);
  const bool compute_ok = CsmPass::compute_available(settings.csm_test);
  if (settings.csm_backend == PassBackend::Compute && !compute_ok)
    throw std::runtime_error("CSM test " + csm_test_name(settings.csm_test) + " has no compute pass");
  if (settings.csm_backend == PassBackend::Raster && !raster_ok)
    throw std::runtime_error("CSM test " + csm_test_name(settings.csm_test) + " has no raster pass on " +
                             s.ctx.device_name() + " (it needs geometry shaders)");
  plan.compute_csm =
      plan.spot ||
      pick_for_frame(s.probes.csm, settings.csm_backend, raster_ok, compute_ok, key, frame) == PassBackend::Compute;
}

// Step 1's shape (izb.h, kIzbStepOne*): on a GPU timed both ways once the backends are chosen, where
// the compute trace or CSM runs its tile work.
void choose_step_one_shape(IzbState& s, const Frame& frame, const IzbSettings& settings, uint64_t key,
                           bool backends_chosen, IzbPlan& plan) {
  plan.step_one_shape = gpu_shared::kIzbStepOneWide;
  if (settings.step_one_shape != StepOneShape::Auto) {
    if (settings.step_one_shape == StepOneShape::Narrow) plan.step_one_shape = gpu_shared::kIzbStepOneNarrow;
  } else if (s.pipelines.cpu_device()) {
    plan.step_one_shape = gpu_shared::kIzbStepOneCpu;
  } else if (backends_chosen && (plan.compute_trace || plan.compute_csm) &&
             pick_for_frame(s.probes.shape, PassBackend::Auto, true, true, key, frame) == PassBackend::Compute) {
    plan.step_one_shape = gpu_shared::kIzbStepOneNarrow;
  }
}

// Whether the automatic prepass pays for itself here: timed once the above are chosen.
void time_csm_prepass(IzbState& s, const Frame& frame, const IzbSettings& settings, uint64_t key,
                      bool backends_chosen, IzbPlan& plan) {
  if (plan.run_csm && settings.csm_timed && s.csm->automatic_only() && backends_chosen && !s.probes.shape.probing() &&
      pick_for_frame(s.probes.csm_run, PassBackend::Auto, true, true, key, frame) == PassBackend::Compute) {
    s.csm->skip("skipped: the IZB's passes timed faster without it (IzbSettings::csm_timed)");
    plan.run_csm = false;
    plan.compute_csm = false;
  }
}

void choose_conservative_raster(const IzbState& s, const IzbSettings& settings, IzbPlan& plan) {
  const bool use_hardware = settings.raster == ConservativeRaster::Hardware ||
                            (settings.raster == ConservativeRaster::Auto && s.pipelines.hardware_trace_available());
  if (!plan.compute_trace) {
    if (use_hardware && !s.ctx.features().conservative_rasterization)
      throw std::runtime_error("hardware conservative rasterization requested but " + s.ctx.device_name() +
                               " lacks VK_EXT_conservative_rasterization");
    if (use_hardware && !s.ctx.features().geometry_shader)
      throw std::runtime_error("the hardware conservative trace reads gl_PrimitiveID, which needs geometry shaders, "
                               "which " + s.ctx.device_name() + " lacks");
    if (!use_hardware && !s.ctx.features().geometry_shader)
      throw std::runtime_error("software conservative rasterization needs geometry shaders, which " +
                               s.ctx.device_name() + " lacks");
  }
  plan.hardware = use_hardware && !plan.compute_trace;
}

// Known-lit culling: the lit map is the sun's alone. Auto probes it once the trace's and the CSM's
// choices are made, so the frames it compares differ in nothing else.
void choose_lit_culling(IzbState& s, const Frame& frame, const IzbSettings& settings, uint64_t key,
                        bool backends_chosen, IzbPlan& plan) {
  plan.lit = false;
  if (plan.spot) return;
  if (settings.lit_culling == LitCulling::On) {
    plan.lit = true;
  } else if (settings.lit_culling == LitCulling::Auto && backends_chosen && !s.probes.shape.probing() &&
             !s.probes.csm_run.probing()) {
    plan.lit = pick_for_frame(s.probes.lit, PassBackend::Auto, true, true, key, frame) == PassBackend::Raster;
  }
}

// What the lists, culling and trace do (IZB_FLAG_*).
uint32_t work_flags(const IzbState& s, const Frame& frame, const IzbSettings& settings, bool hybrid,
                    bool collect_stats, IzbPlan& plan) {
  uint32_t flags = collect_stats ? gpu_shared::IZB_FLAG_STATS : 0u;
  if (!settings.depth_cull) flags |= gpu_shared::IZB_FLAG_NO_DEPTH_CULL;
  if (plan.compute_csm) flags |= gpu_shared::IZB_FLAG_CSM_BUFFER;
  plan.sorted = settings.lists == ListLayout::Sorted;
  if (plan.sorted) flags |= gpu_shared::IZB_FLAG_SORTED_LISTS;
  if (plan.run_csm) flags |= gpu_shared::IZB_FLAG_CSM;
  // At 32 spp also unasked: a pixel's 32 samples are often all shadowed long before its last node is
  // tested (Sponza v1 4K: the trace 0.49 -> 0.44 ms on an H100). Not where the hybrid keeps occluder
  // heights: a pixel would keep the nearest occluder among those tested before it was covered, which
  // depends on the order the trace tests them in, so the penumbrae around it would differ between
  // the raster and compute traces and with known-lit culling on or off (lavapipe, atrium v0, 256²,
  // hybrid+csm at 32 spp: 7 pixels).
  plan.penumbra = hybrid && !plan.spot && frame.view.light_tan_half_angle > 0.0f;
  const bool gaps = plan.penumbra;
  if (settings.progressive_removal || (s.res.samples == 32 && !gaps)) flags |= gpu_shared::IZB_FLAG_PROGRESSIVE;
  if (plan.lit) flags |= gpu_shared::IZB_FLAG_LIT;
  if (std::any_of(frame.draws.begin(), frame.draws.end(),
                  [](const DrawItem& d) { return d.shadow.casts_shadow && d.alpha_tested(); }))
    flags |= gpu_shared::IZB_FLAG_ALPHA;
  if (gaps) flags |= gpu_shared::IZB_FLAG_GAPS;
  if (s.res.samples == 1 && !plan.sorted &&
      s.res.pool_size >= uint64_t(frame.view.extent.width) * frame.view.extent.height)
    flags |= gpu_shared::IZB_FLAG_DIRECT_NODES;
  if ((flags & gpu_shared::IZB_FLAG_DIRECT_NODES) && !s.pipelines.cpu_device())
    flags |= gpu_shared::IZB_FLAG_ROW_RUNS;
  plan.all_triangles = s.casters.triangle_count <= gpu_shared::kIzbAllTrianglesLimit;
  if (plan.all_triangles) flags |= gpu_shared::IZB_FLAG_ALL_TRIANGLES;
  plan.triangles_in_trace = plan.all_triangles && plan.compute_trace && !plan.run_csm && !plan.lit && !plan.spot;
  if (plan.triangles_in_trace) flags |= gpu_shared::IZB_FLAG_TRIANGLES_IN_TRACE;
  plan.cpu = s.pipelines.cpu_device();
  if (plan.cpu) flags |= gpu_shared::IZB_FLAG_CPU_DEVICE;
  if (plan.cpu && plan.lit && s.res.lit_view_whole()) flags |= gpu_shared::IZB_FLAG_LIT_FETCH;
  return flags;
}

// Where the term is written and how the camera rays are made (IZB_FLAG_*).
uint32_t output_flags(const IzbState& s, const Frame& frame, const IzbSettings& settings, bool hybrid, IzbPlan& plan) {
  uint32_t flags = 0;
  // The resolve is needed only to count samples (32 spp), list the hybrid's fade band toward the
  // cascades (a limited range) or draw a debug view. With a direct term the build ray-tests a local
  // light's casters that straddle its near plane (izb_straddlers.glsl) before it gives a point a node.
  plan.direct_term = izb_direct_term(s.res.samples, hybrid, settings.max_distance, plan.debug,
                                     plan.spot && s.pipelines.cpu_device());
  if (plan.direct_term) flags |= gpu_shared::IZB_FLAG_DIRECT_TERM;
  // A point light's faces: each face's build (and resolve, where one runs) over the tiles its cone
  // reaches, listed once; on a CPU device, which runs every workgroup it is given whole, a spot
  // light's too.
  plan.face_tiles = frame.view.light_face || (plan.spot && s.pipelines.cpu_device());
  if (plan.face_tiles) flags |= gpu_shared::IZB_FLAG_FACE_TILES;
  // The fit empties the grid where it runs many workgroups on a GPU (a spot light's runs one).
  plan.fit_clears_grid = !plan.spot && !plan.cpu;
  if (plan.fit_clears_grid) flags |= gpu_shared::IZB_FLAG_FIT_CLEARS_GRID;
  // Otherwise, for the sun with no debug view, the build settles every pixel without a node and the
  // resolve reads only the others.
  plan.listed_resolve = !plan.direct_term && plan.debug == 0 && !plan.spot;
  if (plan.listed_resolve) flags |= gpu_shared::IZB_FLAG_LISTED_RESOLVE;
  if (hybrid) flags |= gpu_shared::IZB_FLAG_HYBRID;
  if (plan.spot) flags |= gpu_shared::IZB_FLAG_SPOT;
  if (plan.compute_trace) flags |= gpu_shared::IZB_FLAG_TILE_FARTHEST;
  // Every camera ray's points share their w where the inverse view-projection's w row ignores x and y
  // (exactly: then its products with them add zeros), so the μQuad corners take 1 / w from here.
  const glm::mat4& inverse_vp = frame.view.inverse_view_projection;
  plan.constant_ray_w = inverse_vp[0][3] == 0.0f && inverse_vp[1][3] == 0.0f;
  if (plan.constant_ray_w) flags |= gpu_shared::IZB_FLAG_CONSTANT_RAY_W;
  // 32 spp and the sun: the fit bounds each μQuad from fast corners (izb_pixel.glsl, bound_micro_quad).
  plan.bounded_fit = plan.constant_ray_w && s.res.samples == 32 && !plan.spot;
  if (plan.bounded_fit) flags |= gpu_shared::IZB_FLAG_BOUNDED_FIT;
  // 32 spp and the compute trace: a node per 2x2 block of texels a pixel's samples fill (izb.h).
  if (s.res.samples == 32 && plan.compute_trace && settings.anchored_nodes) flags |= gpu_shared::IZB_FLAG_ANCHORED_NODES;
  return flags;
}

}  // namespace

void choose_izb_backends(IzbState& s, const Frame& frame, const IzbSettings& settings, bool hybrid, IzbPlan& plan) {
  const uint64_t key = probe_key(s, frame, settings, hybrid);
  plan.spot = frame.view.local_light;
  choose_trace_backend(s, frame, settings, key, plan);
  plan.compute_csm = false;
  choose_csm_backend(s, frame, settings, key, plan);
  const bool backends_chosen = !s.probes.trace.probing() && !(plan.run_csm && s.probes.csm.probing());
  choose_step_one_shape(s, frame, settings, key, backends_chosen, plan);
  time_csm_prepass(s, frame, settings, key, backends_chosen, plan);
  choose_conservative_raster(s, settings, plan);
  s.last.hardware = plan.hardware;
  s.last.compute_trace = plan.compute_trace;
  s.last.compute_csm = plan.compute_csm;
  s.last.csm = plan.run_csm;
  choose_lit_culling(s, frame, settings, key, backends_chosen, plan);
  s.last.lit = plan.lit;
}

void choose_izb_flags(const IzbState& s, const Frame& frame, const IzbSettings& settings, bool hybrid,
                      bool collect_stats, IzbPlan& plan) {
  plan.flags = work_flags(s, frame, settings, hybrid, collect_stats, plan) |
               output_flags(s, frame, settings, hybrid, plan);
}

}  // namespace shadows::detail
