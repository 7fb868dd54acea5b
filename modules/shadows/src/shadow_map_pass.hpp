#pragma once
#include "gpu/resources.hpp"
#include "frame.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// The "sm" baseline: one depth map fitted to the casters' bounds, resolved with one tap; a light with a
// size (View::light_tan_half_angle, light_radius) is resolved with PCSS (pcss.glsl) wherever its
// penumbra is at least half a texel wide (and wider than `filter_texels`), with one tap elsewhere.
class ShadowMapPass {
 public:
  explicit ShadowMapPass(engine::gpu::Context& ctx);
  // `filter_texels` > 0: percentage-closer filtering over a disk of that radius in map texels (a spot
  // light's counterpart of the cascades' filtered term; with a light size, the narrowest PCSS filter);
  // 0: one tap.
  void record(Frame& frame, const ShadowMapSettings& settings, float filter_texels = 0.0f);

 private:
  void ensure_map(VkCommandBuffer cmd, uint32_t size);
  // The resolve for a light with a size (PCSS) and/or a fixed filter (`filter_texels` > 0).
  const engine::gpu::Pipeline& resolve_pipeline(bool pcss, bool pcf);
  engine::gpu::Context& ctx_;
  engine::gpu::Image map_;
  engine::gpu::Buffer params_;
  engine::gpu::Sampler sampler_;
  engine::gpu::Pipeline depth_pipeline_;
  engine::gpu::Pipeline alpha_depth_pipeline_;  // alpha-tested casters
  engine::gpu::Pipeline resolve_pipelines_[4];  // [PCSS + 2 * fixed filter], each made on first use
};

}  // namespace shadows::detail
