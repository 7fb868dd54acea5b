#pragma once
#include <cstdint>

#include "frame.hpp"
#include "izb_state.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// What one IZB record runs: the backends (raster or compute, each timed under PassBackend::Auto),
// whether the CSM prepass and the lit map run, and the IZB_FLAG_* that specialize every pipeline.
struct IzbPlan {
  bool spot = false;  // a spot light's perspective grid (or one cone of a point light)
  bool run_csm = false;
  bool compute_trace = false;
  bool compute_csm = false;
  bool hardware = false;  // hardware conservative rasterization in the raster trace
  bool lit = false;       // known-lit culling by the lit map
  uint32_t step_one_shape = gpu_shared::kIzbStepOneWide;
  uint32_t debug = 0;  // izb_debug_code()
  uint32_t flags = 0;
  bool sorted = false;              // counting-sorted lists instead of linked ones
  bool all_triangles = false;       // few casters: every triangle set up, no cull of the draws
  bool triangles_in_trace = false;  // ... in the compute trace's first step
  bool cpu = false;
  bool direct_term = false;     // the build and trace write the term; no resolve
  bool listed_resolve = false;  // the resolve reads only the pixels with nodes
  bool face_tiles = false;      // a point light face (a spot light on a CPU device) builds over listed tiles (IZB_FLAG_FACE_TILES)
  bool fit_clears_grid = false;  // the fit empties the grid, not record_izb_reset (IZB_FLAG_FIT_CLEARS_GRID)
  bool constant_ray_w = false;
  bool bounded_fit = false;
  bool penumbra = false;  // the hybrid with a sun of some size: occluder heights and the penumbra pass
};

// The resolve's and the trace's debug view (izb_common.glsl).
uint32_t izb_debug_code(DebugView debug);
// 1 spp, no resolve needed (no hybrid range, no IZB debug view): the build and the trace write the term
// (IZB_FLAG_DIRECT_TERM). Not for a local light on a CPU device, whose build stores only zeros.
bool izb_direct_term(uint32_t samples, bool hybrid, float max_distance, uint32_t debug_code, bool cpu_local_light);

// Chooses the trace's and the CSM's backends, step 1's shape, the conservative rasterization and
// the lit map, taking each probe's pick in the order the probes expect (each is timed only once the
// ones before it have decided). `plan.run_csm` comes in from CsmPass::plan and may be taken back.
// Throws where the settings ask for what the device or the light cannot take.
void choose_izb_backends(IzbState& s, const Frame& frame, const IzbSettings& settings, bool hybrid, IzbPlan& plan);

// The shader flags for the choices made (IZB_FLAG_*, see izb_common.glsl).
void choose_izb_flags(const IzbState& s, const Frame& frame, const IzbSettings& settings, bool hybrid,
                      bool collect_stats, IzbPlan& plan);

}  // namespace shadows::detail
