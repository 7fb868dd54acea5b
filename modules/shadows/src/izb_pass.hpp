#pragma once
#include <memory>
#include <vector>

#include "cascades_pass.hpp"
#include "gpu/resources.hpp"
#include "frame.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

struct IzbState;

// A point light's face takes this many eighths of IzbSettings::resolution a side.
constexpr uint32_t kPointFaceGridEighths = 6;
// The grid a record of `view`'s light takes: IzbSettings::resolution, or for one of a point light's
// faces kPointFaceGridEighths of it (rounded up to whole kIzbTile tiles).
uint32_t izb_grid_resolution(const View& view, const IzbSettings& settings);

// The frustum-traced irregular z-buffer: light frustum fit, (lit map and CSM culling), IZB build,
// conservative frustum trace, overflow fallback and resolve into the shadow term. Each step lives in
// its own shaders (izb_*) and its own source file (izb_frustum, izb_lit_map, izb_csm_prepass,
// izb_build, izb_trace, izb_resolve, izb_hybrid, izb_stats); record() plans the frame (izb_plan) and
// records them in order over the state they share (izb_state).
class IzbPass {
 public:
  // `cpu_paths`: the module's takes_cpu_paths (barriers.hpp), decided when the module was created.
  IzbPass(engine::gpu::Context& ctx, bool cpu_paths);
  ~IzbPass();
  // collect_stats adds the statistics passes (fragment count before culling, list lengths).
  // hybrid: writes the hard term and, with a sun of some size, each shadowed pixel's occluder height
  // for record_hybrid_penumbra(); with a limited range it lists the pixels that take some of the
  // cascades' term (beyond the IZB's range and in its last tenth), which the cascades then filter
  // into soft_term(), and record_hybrid_blend() mixes them into the term.
  void record(Frame& frame, const IzbSettings& settings, DebugView debug, bool hybrid,
              bool collect_stats);
  // A point light's faces (View::light_face, in the order recorded, each writing only its own points):
  // where nothing they write is shared, each step for all faces before the barrier after it, each
  // face's grid, parameters and work lists in slices of their own (IzbResources::grid_slice); else
  // one face after another. Leaves every face's writes visible to what follows.
  void record_faces(std::vector<Frame>& faces, const IzbSettings& settings, DebugView debug, bool collect_stats);
  // Whether record() with these settings (`max_distance`: the range it is given) writes every pixel of
  // the term for a light (`directional`: the sun), so that it need not start lit: where the build
  // stores each pixel's 1 or 0 (a direct term), for any light on a GPU (a point light's faces
  // together: each writes its own points, light_tiles.glsl's point_light_face_of) and for the sun on
  // a CPU device, whose build runs over the whole frame.
  bool writes_every_pixel(const IzbSettings& settings, float max_distance, DebugView debug, bool hybrid,
                          bool directional) const;
  engine::gpu::Image& soft_term();
  PixelList hybrid_list() const;
  void record_hybrid_blend(Frame& frame);
  // After a hybrid record with a sun of some size: its penumbrae into the term (else nothing); with
  // `step_timings` (IzbSettings::step_timings) each step in a region of its own.
  void record_hybrid_penumbra(Frame& frame, bool step_timings);
  // The frame recorded in frame-in-flight slot `slot` has completed.
  // One Stats per IZB record of the slot's frame (one per light, six for a point light), in order; the
  // CSM's statistics go into the last.
  void after_frame(std::vector<Stats>& records, uint32_t slot);
  // How many IZB records the slot's frame `frame_index` has made so far.
  uint32_t records_so_far(uint32_t slot, uint64_t frame_index) const;
  bool hardware_raster_available() const;
  bool csm_test_supported(CsmTest test, std::string* why) const;
  CsmSnapshot read_csm();
  LitMapSnapshot read_lit_map();

 private:
  std::unique_ptr<IzbState> state_;
};

}  // namespace shadows::detail
