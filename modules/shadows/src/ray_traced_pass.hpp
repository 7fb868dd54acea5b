#pragma once
#include <memory>

#include "gpu/resources.hpp"
#include "frame.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// The "rt" technique: one hard shadow ray per shading point (or per μQuad sample at 32 spp) through
// the ray tracing pipeline; at 1 spp, for a light with a size (View::light_tan_half_angle,
// light_radius), `light_samples` (Settings::rt_light_samples, 1..64) rays over the light instead, the
// term their lit fraction (shared/area_light.h). Bottom-level structures are built once per mesh of the scene; those of
// deformed slots (Instance::deformed) are refitted every frame they are drawn, to that frame's
// positions. The top level is rebuilt every frame from the casters' current transforms, so moving
// casters work.
class RayTracedPass {
 public:
  // Throws std::runtime_error (one line naming the missing extension) where the device cannot trace.
  explicit RayTracedPass(engine::gpu::Context& ctx);
  ~RayTracedPass();
  void record(Frame& frame, uint32_t samples_per_pixel, uint32_t light_samples, bool collect_stats);
  // One Stats per record of the slot's frame that collected statistics, in order.
  void after_frame(std::vector<Stats>& records, uint32_t slot);
  uint32_t records_so_far(uint32_t slot, uint64_t frame_index) const;
  // Forgets the bottom levels (the scene's geometry changed).
  void scene_changed();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shadows::detail
