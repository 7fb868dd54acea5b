#pragma once
#include "engine/gpu/resources.hpp"
#include "shadows/shadows.hpp"

namespace shadows::detail {

// Cascaded filtered shadow maps with computation masking and selective blur.
class CascadesPass {
 public:
  explicit CascadesPass(engine::gpu::Context& ctx);
  ~CascadesPass();
  // Writes the filtered visibility (1 lit .. 0 shadowed) of every covered pixel into `out` (R32F
  // storage image of the frame's size, GENERAL layout). Background pixels are left untouched.
  // With debug == Cascades or ExpensivePath, also draws that overlay into frame.overlay.
  void record(engine::FrameContext& frame, const CascadeSettings& settings, engine::gpu::Image& out, DebugView debug);
  // After the frame's fence: fills the cascade fields of `stats`.
  void after_frame(Stats& stats);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shadows::detail
