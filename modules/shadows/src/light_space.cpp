#include "light_space.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "shared/local_light.h"
#include "shared/shadows.h"

namespace shadows::detail {

glm::mat4 light_view_matrix(const glm::vec3& light_direction) {
  const glm::vec3 forward = glm::normalize(light_direction);
  // Any up vector not parallel to the light works; the choice only rotates the grid about the light.
  const glm::vec3 up = std::abs(forward.y) > 0.99f ? glm::vec3(0.0f, 0.0f, 1.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
  return glm::lookAtRH(glm::vec3(0.0f), forward, up);
}

glm::mat4 spot_view_projection(const View& view) {
  const glm::mat4 rotation = light_view_matrix(view.light_direction);
  const glm::mat4 light_view = rotation * glm::translate(glm::mat4(1.0f), -view.light_position);
  // The cone's half angle from its cosine, widened a little so its rim is inside the map.
  const float half_angle = std::acos(std::clamp(view.light_cos_outer, -1.0f, 1.0f)) * 1.02f;
  const float near_plane = gpu_shared::local_light_bulb(view.light_range);
  return glm::perspectiveRH_ZO(2.0f * std::min(half_angle, 1.55f), 1.0f, near_plane, view.light_range) * light_view;
}

glm::mat4 fit_orthographic(const glm::mat4& light_view, const Aabb& box, float margin) {
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (int i = 0; i < 8; ++i) {
    glm::vec3 corner((i & 1) ? box.max.x : box.min.x, (i & 2) ? box.max.y : box.min.y,
                     (i & 4) ? box.max.z : box.min.z);
    glm::vec3 v = glm::vec3(light_view * glm::vec4(corner, 1.0f));
    lo = glm::min(lo, v);
    hi = glm::max(hi, v);
  }
  lo -= glm::vec3(margin);
  hi += glm::vec3(margin);
  // View space looks down -Z: the nearest point to the light has the largest z.
  return glm::orthoRH_ZO(lo.x, hi.x, lo.y, hi.y, -hi.z, -lo.z);
}

float nearest_view_depth_at(const View& view, float distance) {
  const glm::mat4& proj = view.projection;
  if (proj[3][3] != 0.0f || proj[2][3] == 0.0f) return 0.0f;
  // In view space the camera is at the origin looking down -Z: every corner ray starts there.
  const glm::mat4 inverse_projection = glm::inverse(proj);
  float cos_widest = 1.0f;
  for (int i = 0; i < 4; ++i) {
    const glm::vec4 h = inverse_projection * glm::vec4((i & 1) ? 1.0f : -1.0f, (i & 2) ? 1.0f : -1.0f, 0.5f, 1.0f);
    const glm::vec3 ray = glm::vec3(h) / h.w;
    const float len = glm::length(ray);
    if (!(len > 0.0f) || !(-ray.z > 0.0f)) return 0.0f;
    cos_widest = std::min(cos_widest, -ray.z / len);
  }
  // A thousandth less: the pixels' own distances and depths are rounded in float.
  return std::max(distance * cos_widest * 0.999f, 0.0f);
}

Aabb caster_bounds(const Frame& frame) {
  Aabb bounds;
  for (const auto& d : frame.draws)
    if (d.shadow.casts_shadow) bounds.extend(d.bounds);
  return bounds;
}

Aabb scene_bounds(const Frame& frame) {
  Aabb bounds;
  for (const auto& d : frame.draws) bounds.extend(d.bounds);
  return bounds;
}

void view_slice_corners(const View& view, float d0, float d1, glm::vec3 corners[8]) {
  const glm::mat4& v = view.view;
  const glm::vec3 right(v[0][0], v[1][0], v[2][0]), up(v[0][1], v[1][1], v[2][1]);
  const glm::vec3 forward = -glm::vec3(v[0][2], v[1][2], v[2][2]);
  for (int i = 0; i < 8; ++i) {
    const float depth = (i >> 2) ? d1 : d0;
    corners[i] = view.camera_position + forward * depth +
                 right * (((i & 1) ? 1.0f : -1.0f) * depth * view.tan_half_fov.x) +
                 up * (((i & 2) ? 1.0f : -1.0f) * depth * view.tan_half_fov.y);
  }
}

void set_viewport(VkCommandBuffer cmd, VkExtent2D extent) {
  VkViewport viewport{0, 0, float(extent.width), float(extent.height), 0.0f, 1.0f};
  VkRect2D scissor{{0, 0}, extent};
  vkCmdSetViewport(cmd, 0, 1, &viewport);
  vkCmdSetScissor(cmd, 0, 1, &scissor);
}

void begin_depth_rendering(VkCommandBuffer cmd, VkImageView depth, VkExtent2D extent, bool clear,
                           const VkRect2D* area) {
  VkRenderingAttachmentInfo attachment{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  attachment.imageView = depth;
  attachment.imageLayout = VK_IMAGE_LAYOUT_GENERAL;
  attachment.loadOp = clear ? VK_ATTACHMENT_LOAD_OP_CLEAR : VK_ATTACHMENT_LOAD_OP_LOAD;
  attachment.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  attachment.clearValue.depthStencil = {1.0f, 0};
  VkRenderingInfo info{VK_STRUCTURE_TYPE_RENDERING_INFO};
  info.renderArea = area ? *area : VkRect2D{{0, 0}, extent};
  info.layerCount = 1;
  info.pDepthAttachment = &attachment;
  vkCmdBeginRendering(cmd, &info);
  set_viewport(cmd, extent);
  if (area) vkCmdSetScissor(cmd, 0, 1, area);
}

engine::gpu::Pipeline alpha_depth_pipeline(const engine::gpu::Context& ctx, engine::gpu::GraphicsPipelineDesc opaque) {
  opaque.name += " (alpha-tested)";
  opaque.vertex_shader = "shadow_depth_alpha.vert";
  opaque.fragment_shader = "shadow_depth_alpha.frag";
  opaque.vertex_input = engine::gpu::VertexInput::StandardVertex;
  opaque.bindings = {{gpu_shared::ALPHA_DEPTH_BINDING_TEXTURES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}};
  opaque.push_constant_size = sizeof(gpu_shared::AlphaDepthPush);
  opaque.cull_mode = VK_CULL_MODE_NONE;
  return engine::gpu::PipelineFactory(ctx).graphics(opaque);
}

void draw_alpha_casters(const engine::gpu::Context& ctx, VkCommandBuffer cmd, const Frame& frame,
                        const engine::gpu::Pipeline& pipeline, const glm::mat4& light_view_projection,
                        const std::function<bool(const DrawItem&)>& cull) {
  bool bound = false;
  draw_casters(
      cmd, frame,
      [&](const DrawItem& d, const MeshRange&) {
        if (!bound) {
          pipeline.bind(cmd);
          engine::gpu::DescriptorWriter()
              .storage_buffer(gpu_shared::ALPHA_DEPTH_BINDING_TEXTURES, frame.geometry.textures().handle())
              .push(ctx, cmd, pipeline);
          bound = true;
        }
        gpu_shared::AlphaDepthPush push{light_view_projection * d.world, d.base_color_texture, d.alpha_threshold, 0u, 0u};
        pipeline.push_constants(cmd, push);
      },
      CasterSet::AlphaTested, [&](const DrawItem& d) { return cull && cull(d); });
}

float point_light_face_cos_outer() { return std::cos(std::acos(1.0f / std::sqrt(3.0f)) + glm::radians(0.5f)); }

bool cone_may_reach_view(const glm::mat4& view_projection, glm::vec3 apex, glm::vec3 axis, float cos_half_angle,
                         float range) {
  const glm::dmat4 m(view_projection);
  const auto row = [&](int i) { return glm::dvec4(m[0][i], m[1][i], m[2][i], m[3][i]); };
  // Inside: each plane's value (its xyz dot a point, plus w) >= 0.
  const glm::dvec4 planes[6] = {row(3) + row(0), row(3) - row(0), row(3) + row(1),
                                row(3) - row(1), row(2),          row(3) - row(2)};
  const glm::dvec3 a = glm::normalize(glm::dvec3(axis)), p(apex);
  const double half_angle = std::acos(std::clamp(double(cos_half_angle), -1.0, 1.0));
  for (const glm::dvec4& plane : planes) {
    const double length = glm::length(glm::dvec3(plane));
    if (!(length > 0.0)) continue;  // no bound (a reversed-Z infinite far plane)
    const glm::dvec3 n = glm::dvec3(plane) / length;
    const double offset = plane.w / length;
    // The largest value of n . u over the cone's unit directions u.
    const double to_axis = std::acos(std::clamp(glm::dot(n, a), -1.0, 1.0));
    const double reach = std::cos(std::max(to_axis - half_angle, 0.0));
    const double highest = glm::dot(n, p) + offset + double(range) * std::max(reach, 0.0);
    if (highest < -1.0e-4 * (std::abs(glm::dot(n, p)) + std::abs(offset) + double(range))) return false;
  }
  return true;
}

}  // namespace shadows::detail
