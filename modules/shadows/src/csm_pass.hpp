#pragma once
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>

#include "gpu/resources.hpp"
#include "frame.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

// Decides whether an entity's mesh belongs in the CSM: only triangles large enough to cover whole
// texels can ever write a depth, so a mesh of small triangles costs raster time and culls nothing.
// The measure: of the mesh's area projected along the light, the share that lies at least a
// circumscribed texel radius (√2/2 texel) inside its triangle's edges — the area that can be fully
// covered. `texel_size` is the world size of one CSM texel. The module measures on the GPU
// (csm_measure.comp, the same formula in float); this CPU version (object-space positions and a
// triangle list of indices into them) is the tests' reference.
struct CsmChoiceMeasure {
  double coverable_share = 0.0;
  double projected_area = 0.0;
  uint64_t triangles = 0;
};
CsmChoiceMeasure measure_csm_suitability(std::span<const glm::vec3> positions, std::span<const uint32_t> indices,
                                         const glm::mat4& world,
                                         const glm::vec3& light_direction, float texel_size);
// Entities whose coverable share reaches this enter the CSM under CsmChoice::Auto.
// A fifth is enough: a mesh's CSM raster cost is small next to the trace work each culled point saves.
inline constexpr double kCsmAutoThreshold = 0.2;
// Instances measured per frame at most (the rest wait for the next frames).
inline constexpr size_t kMaxMeasuresPerFrame = 4096;

// Under CsmChoice::Auto the prepass must pay for itself: when the last frame it ran culled fewer
// than this share of the candidate points, it is skipped, and probed again every kCsmReprobeFrames
// frames or as soon as the light, the grid or a choice changes.
inline constexpr double kCsmMinimumYield = 0.01;
inline constexpr uint32_t kCsmReprobeFrames = 30;

class CsmPass {
 public:
  explicit CsmPass(engine::gpu::Context& ctx);
  ~CsmPass();
  // Sizes the CSM for `resolution`; call before recording anything that binds depth_view().
  void prepare(VkCommandBuffer cmd, uint32_t resolution);
  VkImageView depth_view() const;
  bool supported(CsmTest test, std::string* why) const;
  // Whether `test` exists as a raster pass (the hardware tests always; Hertel and barycentric through
  // a geometry shader) and as a compute pass (Hertel and barycentric).
  bool raster_available(CsmTest test) const;
  static bool compute_available(CsmTest test) { return test == CsmTest::Hertel || test == CsmTest::Barycentric; }
  // Per draw of the frame: whether it enters the CSM (valid after plan()).
  const std::vector<bool>& chosen_draws() const;
  // Chooses the casters for this frame and decides whether the prepass runs at all (see
  // kCsmMinimumYield); call once per frame before prepare(). Records the measures the automatic
  // choice still needs into frame.cmd; they count from the frame after the one that took them.
  bool plan(const Frame& frame, const IzbSettings& settings, uint32_t resolution);
  // Whether every caster plan() put in the CSM was chosen automatically (none by CsmChoice::On).
  bool automatic_only() const;
  // Takes back plan()'s decision to run this frame (the caller timed the frames without the prepass
  // faster): the prepass records nothing and no yield is noted; `why` becomes the status.
  void skip(const std::string& why);
  // The culling rate the IZB measured with the prepass of IZB record `record` (0 for the first light,
  // counting each cone of a point light) of the frame recorded in slot `slot`; it counts only when that
  // prepass ran under the record's current choice of casters, light and resolution.
  void note_yield(uint32_t slot, uint32_t record, double culling_rate);
  // Renders the CSM of the chosen casters with the GPU-fitted light projection in `izb_frame`. With
  // `compute_fill`, that callback records compute work leaving the depths (float bits, [0,1]) in
  // `compute_texels` instead, which the IZB build reads directly; only statistics (the covered-texel
  // count, with `collect_stats`) copy them into the map.
  void record(Frame& frame, const IzbSettings& settings, const engine::gpu::Buffer& izb_frame,
              uint32_t resolution, bool collect_stats, const std::function<void(VkCommandBuffer)>& compute_fill = {},
              const engine::gpu::Buffer* compute_texels = nullptr);
  // The frame recorded in frame-in-flight slot `slot` has completed: its measures count from now.
  void frame_completed(uint32_t slot);
  void after_frame(Stats& stats, uint32_t slot);
  std::vector<float> read_depth();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shadows::detail
