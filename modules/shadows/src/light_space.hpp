#pragma once
// Light-space helpers shared by the module's passes.
#include <cstddef>
#include <type_traits>

#include <glm/glm.hpp>

#include "engine/core/components.hpp"
#include "engine/gpu/pipeline.hpp"
#include "engine/render/renderer.hpp"

namespace shadows::detail {

// Rotation-only view matrix looking along `light_direction` (the direction light travels).
glm::mat4 light_view_matrix(const glm::vec3& light_direction);

// Orthographic projection (Vulkan depth 0..1, 0 nearest the light) enclosing `box` seen through
// `light_view`, with `margin` world units of slack on every side.
glm::mat4 fit_orthographic(const glm::mat4& light_view, const engine::Aabb& box, float margin = 0.0f);

// World bounds of every shadow-casting draw.
engine::Aabb caster_bounds(const engine::FrameContext& frame);
// Bounds of everything drawn (every receiver lies inside).
engine::Aabb scene_bounds(const engine::FrameContext& frame);
// The eight corners of the camera frustum between view depths d0 and d1 (near quad first).
void view_slice_corners(const engine::FrameView& view, float d0, float d1, glm::vec3 corners[8]);

// Issues one indexed draw per shadow-casting item; `push` is called before each with its model matrix.
// Draws every caster; with `cull`, only those it keeps (the raster trace needs all of them, in
// order, to find a fragment's triangle).
template <typename PushFn, typename CullFn = std::nullptr_t>
void draw_casters(VkCommandBuffer cmd, const engine::FrameContext& frame, PushFn&& push, CullFn&& cull = nullptr) {
  VkDeviceSize offset = 0;
  VkBuffer vb = frame.geometry.vertices().handle();
  vkCmdBindVertexBuffers(cmd, 0, 1, &vb, &offset);
  vkCmdBindIndexBuffer(cmd, frame.geometry.indices().handle(), 0, VK_INDEX_TYPE_UINT32);
  for (const auto& d : frame.draws) {
    if (!d.shadow.casts_shadow) continue;
    if constexpr (!std::is_same_v<std::decay_t<CullFn>, std::nullptr_t>)
      if (cull(d)) continue;
    const auto& range = frame.geometry.mesh(d.mesh);
    if (range.index_count == 0) continue;
    push(d, range);
    vkCmdDrawIndexed(cmd, range.index_count, 1, range.first_index, range.vertex_offset, 0);
  }
}

void set_viewport(VkCommandBuffer cmd, VkExtent2D extent);

// Begins depth-only dynamic rendering into `depth` (GENERAL layout) over `extent` and sets the
// viewport; with `clear` the target starts at depth 1 (far), else its contents are kept.
// `area` (optional) limits the clear and the rasterization to texels that are read afterwards.
void begin_depth_rendering(VkCommandBuffer cmd, VkImageView depth, VkExtent2D extent, bool clear,
                           const VkRect2D* area = nullptr);

}  // namespace shadows::detail
