#pragma once
#include <memory>

#include "engine/gpu/resources.hpp"
#include "shadows/shadows.hpp"

namespace shadows::detail {

class CsmPass;

// The frustum-traced irregular z-buffer: light frustum fit, (CSM culling), IZB build, conservative
// frustum trace, overflow fallback and resolve into the shadow term. One object owns all of it; the
// stages live in their own shaders and are recorded in order by record().
class IzbPass {
 public:
  explicit IzbPass(engine::gpu::Context& ctx);
  ~IzbPass();
  // hybrid: the term already holds the cascades; the IZB overwrites its range and fades at the limit.
  // collect_stats adds the statistics passes (fragment count before culling, list lengths).
  // hybrid with soft_distance > 0 also blends toward the cascades by occluder distance.
  void record(engine::FrameContext& frame, const IzbSettings& settings, DebugView debug, bool hybrid,
              bool collect_stats, float soft_distance = 0.0f);
  void after_frame(Stats& stats);
  bool hardware_raster_available() const;
  bool csm_test_supported(CsmTest test, std::string* why) const;
  ShadowModule::CsmSnapshot read_csm();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shadows::detail
