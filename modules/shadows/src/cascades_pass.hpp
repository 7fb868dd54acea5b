#pragma once
#include "gpu/resources.hpp"
#include "frame.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// Pixels a pass is restricted to: `entries` holds uvec4s whose x is the pixel (x | y << 16);
// `counters` holds, from word `count_word`, the entry count and then indirect dispatch arguments in
// workgroups of gpu_shared::kIzbHybridEntriesPerGroup entries. `nearest_view_depth`: no listed pixel
// lies nearer the camera than this view depth (0 where that is not known).
struct PixelList {
  VkBuffer entries = VK_NULL_HANDLE;
  VkBuffer counters = VK_NULL_HANDLE;
  uint32_t count_word = 0;
  float nearest_view_depth = 0.0f;
};

// Cascaded filtered shadow maps with computation masking and selective blur.
class CascadesPass {
 public:
  explicit CascadesPass(engine::gpu::Context& ctx);
  ~CascadesPass();
  // Writes the filtered visibility (1 lit .. 0 shadowed) of every covered pixel into `out` (a view of
  // an R32F storage image of the frame's size, GENERAL layout). Background pixels are left untouched.
  // With debug == Cascades or ExpensivePath, also draws that overlay into frame.overlay.
  // With `only`, filters just the listed pixels; the rest of `out` must hold a negative term (the caller
  // keeps it so), and the blur takes no neighbours from there; a cascade that ends before the list's
  // nearest view depth is not drawn (no listed pixel reads it).
  void record(Frame& frame, const CascadeSettings& settings, VkImageView out, DebugView debug,
              const PixelList* only = nullptr);
  // After the frame's fence: fills the cascade fields of `stats`.
  void after_frame(Stats& stats, uint32_t slot);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shadows::detail
