#pragma once
#include <cstdint>

#include "gpu/pipeline.hpp"

namespace shadows::detail {

// The cascades' depth maps' format.
inline constexpr VkFormat kCascadeMapFormat = VK_FORMAT_D32_SFLOAT;

// The cascades' pipelines: the depth pass, the masks, the filter's stages (per masking, debug view and
// PCSS, made on first use), the dispatch sizes and the blur.
class CascadePipelines {
 public:
  explicit CascadePipelines(engine::gpu::Context& ctx);
  const engine::gpu::Pipeline& filter(uint32_t stage, uint32_t masking, uint32_t debug, uint32_t pcss);

  engine::gpu::Pipeline depth[2];  // [cull_front_faces]
  engine::gpu::Pipeline alpha_depth;  // alpha-tested casters, either culling setting
  engine::gpu::Pipeline edges[3];  // masks, their neighbourhoods; the planes (cascade_edges.comp)
  engine::gpu::Pipeline args;
  engine::gpu::Pipeline blur[2];  // [apply]

 private:
  engine::gpu::Context& ctx_;
  engine::gpu::Pipeline filters_[4][4][3][2];  // [stage][masking: CASCADE_MASKING_*][debug][pcss]
};

}  // namespace shadows::detail
