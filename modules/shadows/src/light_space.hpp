#pragma once
// Light-space helpers shared by the module's passes.
#include <cstddef>
#include <functional>
#include <type_traits>

#include <glm/glm.hpp>

#include "scene_types.hpp"
#include "gpu/pipeline.hpp"
#include "frame.hpp"

namespace shadows::detail {

// Rotation-only view matrix looking along `light_direction` (the direction light travels).
glm::mat4 light_view_matrix(const glm::vec3& light_direction);

// Orthographic projection (Vulkan depth 0..1, 0 nearest the light) enclosing `box` seen through
// `light_view`, with `margin` world units of slack on every side.
glm::mat4 fit_orthographic(const glm::mat4& light_view, const Aabb& box, float margin = 0.0f);
// A spot light's world -> Vulkan clip transform (depth 0 near .. 1 at its range): a square perspective
// frustum from its position along its direction that holds its outer cone. Casters nearer than the
// near plane (a thousandth of the range, at least the light's radius) are clipped.
glm::mat4 spot_view_projection(const View& view);

// World bounds of every shadow-casting draw.
Aabb caster_bounds(const Frame& frame);
// Bounds of everything drawn (every receiver lies inside).
Aabb scene_bounds(const Frame& frame);
// The eight corners of the camera frustum between view depths d0 and d1 (near quad first).
void view_slice_corners(const View& view, float d0, float d1, glm::vec3 corners[8]);

// A lower bound on the view depth (along the camera's forward axis) of any point the camera sees at
// `distance` or farther from it: `distance` times the cosine of the widest angle a frustum corner
// makes with that axis. 0 where the projection is not a perspective one.
float nearest_view_depth_at(const View& view, float distance);

// A point light's six cones around the axes, in the order they are recorded (+x, -x, +y, -y, +z, -z;
// the face numbers of light_tiles.glsl's point_light_face_of), each just wider than a cube face's (half angle acos(1/sqrt 3) =
// 54.7 degrees, plus half a degree): each holds its cube face's pyramid, whose points alone its passes
// shadow (light_tiles.glsl's point_light_face_of), with half a degree to spare.
inline constexpr glm::vec3 kPointLightFaceAxes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
float point_light_face_cos_outer();

// Whether a point within `range` of `apex` and inside the cone about `axis` (unit) whose half angle has
// the cosine `cos_half_angle` can lie in the view frustum of `view_projection` (Vulkan clip space:
// |x|, |y| <= w, 0 <= z <= w). False only where one of the frustum's planes has that whole part of the
// ball on its outer side, by more than the points' rounding: a cone no visible point lies in.
bool cone_may_reach_view(const glm::mat4& view_projection, glm::vec3 apex, glm::vec3 axis, float cos_half_angle,
                         float range);

// Which shadow-casting draws draw_casters issues.
enum class CasterSet { All, Opaque, AlphaTested };

inline bool in_caster_set(const DrawItem& d, CasterSet set) {
  if (!d.shadow.casts_shadow) return false;
  if (set == CasterSet::Opaque) return !d.alpha_tested();
  if (set == CasterSet::AlphaTested) return d.alpha_tested();
  return true;
}

// Issues one indexed draw per shadow-casting item of `set`; `push` is called before each with its
// model matrix. With `cull`, only those it keeps (the raster trace needs all of them, in order, to
// find a fragment's triangle).
template <typename PushFn, typename CullFn = std::nullptr_t>
void draw_casters(VkCommandBuffer cmd, const Frame& frame, PushFn&& push, CasterSet set = CasterSet::All,
                  CullFn&& cull = nullptr) {
  VkDeviceSize offset = 0;
  VkBuffer vb = frame.geometry.vertices().handle();
  vkCmdBindVertexBuffers(cmd, 0, 1, &vb, &offset);
  vkCmdBindIndexBuffer(cmd, frame.geometry.indices().handle(), 0, VK_INDEX_TYPE_UINT32);
  for (const auto& d : frame.draws) {
    if (!in_caster_set(d, set)) continue;
    if constexpr (!std::is_same_v<std::decay_t<CullFn>, std::nullptr_t>)
      if (cull(d)) continue;
    const auto& range = frame.geometry.mesh(d.mesh);
    if (range.index_count == 0) continue;
    push(d, range);
    vkCmdDrawIndexed(cmd, range.index_count, 1, range.first_index, range.vertex_offset, 0);
  }
}

void set_viewport(VkCommandBuffer cmd, VkExtent2D extent);

// The depth pipeline for alpha-tested casters of a shadow-map pass: `opaque` with the alpha-testing
// shaders (shadow_depth_alpha.*: position and texture coordinate in, the material's alpha test,
// material_textures.glsl) and no face culling (cut-out cards are single quads seen from either side).
engine::gpu::Pipeline alpha_depth_pipeline(const engine::gpu::Context& ctx, engine::gpu::GraphicsPipelineDesc opaque);

// Draws the alpha-tested casters with `pipeline` (from alpha_depth_pipeline) into the bound depth
// target through `light_view_projection`; the caller has set the depth bias.
// `cull` (optional) skips the draws it returns true for.
void draw_alpha_casters(const engine::gpu::Context& ctx, VkCommandBuffer cmd, const Frame& frame,
                        const engine::gpu::Pipeline& pipeline, const glm::mat4& light_view_projection,
                        const std::function<bool(const DrawItem&)>& cull = {});

// Begins depth-only dynamic rendering into `depth` (GENERAL layout) over `extent` and sets the
// viewport; with `clear` the target starts at depth 1 (far), else its contents are kept.
// `area` (optional) limits the clear and the rasterization to texels that are read afterwards.
void begin_depth_rendering(VkCommandBuffer cmd, VkImageView depth, VkExtent2D extent, bool clear,
                           const VkRect2D* area = nullptr);

}  // namespace shadows::detail
