#pragma once
// Per-frame cascade fitting on the CPU: split distances, one light-space orthographic projection
// per cascade sized by its slice's bounding sphere and snapped to whole texels.
#include <array>
#include <cstdint>
#include <glm/glm.hpp>

#include "scene_types.hpp"
#include "frame.hpp"
#include "shadows/settings.hpp"

namespace shadows::detail {

inline constexpr uint32_t kMaxCascadeCount = 4;

struct CascadeFit {
  uint32_t count = 0;
  std::array<float, kMaxCascadeCount + 1> splits{};  // view depth; splits[0] = near, splits[count] = max
  std::array<float, kMaxCascadeCount> blend_start{};  // view depth where cascade c starts blending out
  glm::mat4 light_view{1.0f};                          // rotation only
  std::array<glm::mat4, kMaxCascadeCount> light_view_projection{};
  std::array<float, kMaxCascadeCount> radius{};       // bounding sphere radius (world)
  std::array<float, kMaxCascadeCount> texel_world{};  // world units per texel
  std::array<float, kMaxCascadeCount> depth_range{};  // world units covered by light depth 0..1
  // Light-view xy of the map's corner texel edge; a multiple of texel_world in both axes.
  std::array<glm::vec2, kMaxCascadeCount> grid_origin{};
};

// Fits `settings.count` cascades to `view`'s frustum up to settings.max_distance. `casters` (world
// bounds of every shadow caster) pulls each cascade's near depth toward the light so no caster is clipped.
CascadeFit fit_cascades(const View& view, const CascadeSettings& settings, const Aabb& casters);

}  // namespace shadows::detail
