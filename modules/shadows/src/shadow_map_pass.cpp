#include "barriers.hpp"
#include "shadow_map_pass.hpp"

#include "light_space.hpp"
#include "shared/shadows.h"

namespace shadows::detail {

using namespace engine::gpu;

namespace {
constexpr VkFormat kMapFormat = VK_FORMAT_D32_SFLOAT;
}

ShadowMapPass::ShadowMapPass(Context& ctx) : ctx_(ctx) {
  params_ = Buffer(ctx, sizeof(gpu_shared::ShadowMapResolveParams),
                   VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, false, "sm resolve params");
  sampler_ = Sampler(ctx, VK_FILTER_NEAREST, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, "sm sampler");
  PipelineFactory factory(ctx);
  GraphicsPipelineDesc d;
  d.name = "sm depth";
  d.vertex_shader = "shadow_map.vert";
  d.vertex_input = engine::gpu::VertexInput::PositionOnly;
  d.push_constant_size = sizeof(gpu_shared::ShadowMapPush);
  d.depth_format = kMapFormat;
  d.depth_compare = VK_COMPARE_OP_LESS_OR_EQUAL;
  d.cull_mode = VK_CULL_MODE_NONE;
  d.depth_bias = true;
  resolve_pipeline_ = factory.compute({"shadow_map_resolve.comp",
                                       {{gpu_shared::SM_RESOLVE_BINDING_PARAMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},
                                        {gpu_shared::SM_RESOLVE_BINDING_WORLD_POSITION, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
                                        {gpu_shared::SM_RESOLVE_BINDING_GEOMETRIC_NORMAL, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
                                        {gpu_shared::SM_RESOLVE_BINDING_SHADOW_MAP, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
                                        {gpu_shared::SM_RESOLVE_BINDING_SHADOW_TERM, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
                                        {gpu_shared::SM_RESOLVE_BINDING_RECEIVERS, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE}},
                                       0});
  depth_pipeline_ = factory.graphics(d);
  alpha_depth_pipeline_ = alpha_depth_pipeline(ctx, d);
}

void ShadowMapPass::ensure_map(VkCommandBuffer cmd, uint32_t size) {
  if (map_.valid() && map_.extent().width == size) return;
  map_ = Image(ctx_, {size, size}, kMapFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
               "sm depth map");
  to_general(ctx_, cmd, map_);
}

void ShadowMapPass::record(Frame& frame, const ShadowMapSettings& settings, float filter_texels) {
  ensure_map(frame.cmd, settings.size);
  VkCommandBuffer cmd = frame.cmd;
  const glm::mat4 light_vp = frame.view.local_light ? spot_view_projection(frame.view) : [&] {
    const glm::mat4 light_view = light_view_matrix(frame.view.light_direction);
    const Aabb bounds = caster_bounds(frame);
    return fit_orthographic(light_view, bounds, 0.01f * glm::length(bounds.extent())) * light_view;
  }();

  {
    ScopedGpuRegion region(ctx_, frame.profiler, cmd, "sm_depth");
    begin_depth_rendering(cmd, map_.view(), map_.extent(), true);
    vkCmdSetDepthBias(cmd, 0.0f, 0.0f, settings.slope_bias);
    depth_pipeline_.bind(cmd);
    draw_casters(cmd, frame, [&](const DrawItem& d, const MeshRange&) {
      gpu_shared::ShadowMapPush push{d.world, light_vp};
      depth_pipeline_.push_constants(cmd, push);
    }, CasterSet::Opaque);
    draw_alpha_casters(ctx_, cmd, frame, alpha_depth_pipeline_, light_vp);
    vkCmdEndRendering(cmd);
  }
  pass_barrier(ctx_, cmd);
  {
    ScopedGpuRegion region(ctx_, frame.profiler, cmd, "sm_resolve");
    gpu_shared::ShadowMapResolveParams p{};
    p.light_view_projection = light_vp;
    p.light_direction = glm::vec4(frame.view.light_direction, 0.0f);
    if (frame.view.local_light) {
      p.light_position = glm::vec4(frame.view.light_position, frame.view.light_range);
      p.light_cone = glm::vec4(frame.view.light_cos_outer, 0.0f, frame.view.light_face ? 1.0f : 0.0f, 0.0f);
    }
    p.bias = glm::vec4(settings.constant_bias, filter_texels, 0.0f, 0.0f);
    p.extent = glm::uvec4(frame.view.extent.width, frame.view.extent.height, settings.size, settings.size);
    p.camera_position = glm::vec4(frame.view.camera_position, 1.0f);
    record_update(ctx_, cmd, params_, &p, sizeof(p));
    resolve_pipeline_.bind(cmd);
    DescriptorWriter()
        .uniform_buffer(gpu_shared::SM_RESOLVE_BINDING_PARAMS, params_.handle())
        .storage_image(gpu_shared::SM_RESOLVE_BINDING_WORLD_POSITION, frame.gbuffer.world_position)
        .storage_image(gpu_shared::SM_RESOLVE_BINDING_GEOMETRIC_NORMAL, frame.gbuffer.geometric_normal)
        .sampled_image(gpu_shared::SM_RESOLVE_BINDING_SHADOW_MAP, map_.view(), sampler_.handle(), VK_IMAGE_LAYOUT_GENERAL)
        .storage_image(gpu_shared::SM_RESOLVE_BINDING_SHADOW_TERM, frame.shadow_term.view())
        .storage_image(gpu_shared::SM_RESOLVE_BINDING_RECEIVERS, frame.gbuffer.albedo)
        .push(ctx_, cmd, resolve_pipeline_);
    vkCmdDispatch(cmd, (frame.view.extent.width + 7) / 8, (frame.view.extent.height + 7) / 8, 1);
  }
}

}  // namespace shadows::detail
