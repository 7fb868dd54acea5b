#pragma once
#include <map>

#include "gpu/resources.hpp"
#include "frame.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// The "sm" baseline: one depth map fitted to the casters' bounds, resolved with one tap; a light with a
// size (View::light_tan_half_angle, light_radius) is resolved with PCSS (pcss.glsl) wherever its
// penumbra is at least half a texel wide (and wider than `filter_texels`), with one tap elsewhere.
class ShadowMapPass {
 public:
  // `cpu_paths`: the module's takes_cpu_paths (barriers.hpp), decided when the module was created (this
  // pass is made on first use, when the environment may say otherwise).
  ShadowMapPass(engine::gpu::Context& ctx, bool cpu_paths);
  // `filter_texels` > 0: percentage-closer filtering over a disk of that radius in map texels (a spot
  // light's counterpart of the cascades' filtered term; with a light size, the narrowest PCSS filter);
  // 0: one tap.
  // `count`: the resolve counts its pixels for Stats (after_frame).
  void record(Frame& frame, const ShadowMapSettings& settings, float filter_texels = 0.0f, bool count = false);
  // Once the frame in `slot` has completed: the counts of its PCSS resolves (expensive_path_*: the
  // pixels whose taps ran, of those resolved with a light size), when it counted.
  void after_frame(Stats& stats, uint32_t slot);

 private:
  void ensure_map(VkCommandBuffer cmd, uint32_t size);
  // The resolve for a light with a size (PCSS) and/or a fixed filter (`filter_texels` > 0).
  // The resolve's pipelines, one per combination, each made on first use.
  struct ResolveVariant {
    bool pcss = false;     // the light has a size
    bool pcf = false;      // a fixed filter
    bool masking = false;  // PCSS's masking (ShadowMapSettings::masking)
    bool count = false;    // the counts for Stats
    uint32_t stage = 0;    // SM_STAGE_*
    bool local = false;    // a spot light or a point light's face (a perspective map), not the sun
    bool tiles = false;    // over the tiles of the light's list (record_light_tiles), not the frame
    bool block_fetch = false;  // the blocks read through their texel view (a CPU device, the view whole)
    uint32_t key() const {
      return uint32_t(pcss) | uint32_t(pcf) << 1 | uint32_t(masking) << 2 | uint32_t(count) << 3 | uint32_t(local) << 4 |
             uint32_t(tiles) << 5 | uint32_t(block_fetch) << 6 | stage << 7;
    }
  };
  const engine::gpu::Pipeline& resolve_pipeline(const ResolveVariant& variant);
  // The resolve's passes over the frame (a CPU device with masking: listing, then the listed taps).
  void record_resolve(Frame& frame, ResolveVariant variant, bool split);
  // PCSS's masking: the depth map's block planes (shadow_map_blocks.comp), before the resolve.
  void record_blocks(Frame& frame, uint32_t size);
  // Before a point light's first face is resolved (on a CPU device, a spot light's map too): the tiles
  // holding each face's points (shadow_map_tiles.comp), and the term of the points beyond the range.
  void record_light_tiles(Frame& frame);
  engine::gpu::Context& ctx_;
  engine::gpu::Image map_;
  engine::gpu::Buffer params_;
  engine::gpu::Sampler sampler_;
  engine::gpu::Pipeline depth_pipeline_;
  engine::gpu::Pipeline alpha_depth_pipeline_;  // alpha-tested casters
  std::map<uint32_t, engine::gpu::Pipeline> resolve_pipelines_;  // by ResolveVariant::key
  bool cpu_paths_ = false;         // a CPU device: the resolve split where it masks
  engine::gpu::Buffer tap_list_;   // the split resolve's list (SM_STAGE_*)
  engine::gpu::Buffer light_tiles_;  // a local light's tile lists (light_tiles.h)
  engine::gpu::Pipeline light_tiles_pipeline_;
  engine::gpu::Pipeline blocks_pipeline_;
  engine::gpu::Buffer blocks_;    // vec4 per kSmBlock² block of the map
  engine::gpu::Buffer counters_;  // SM_COUNTER_*
  ReadbackRing readback_;
};

}  // namespace shadows::detail
