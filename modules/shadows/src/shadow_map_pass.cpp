#include "barriers.hpp"
#include "shadow_map_pass.hpp"

#include "light_space.hpp"
#include "shared/local_light.h"
#include "shared/shadows.h"

namespace shadows::detail {

using namespace engine::gpu;

namespace {
constexpr VkFormat kMapFormat = VK_FORMAT_D32_SFLOAT;

// The PCSS fields of the resolve's parameters (pcss.glsl's PcssMap). `light_vp` is a projection
// times a rigid light view, so the norms of its rows' xyz are the projection's scales: a texel's size
// in map units from the first two, an orthographic map's depth range from the third.
void set_pcss_params(gpu_shared::ShadowMapResolveParams& p, const View& view, const glm::mat4& light_vp, uint32_t size) {
  const auto row_norm = [&](int i) { return glm::length(glm::vec3(light_vp[0][i], light_vp[1][i], light_vp[2][i])); };
  const bool perspective = view.local_light;
  p.light_plane_matrix = glm::transpose(glm::inverse(light_vp));
  p.pcss = glm::vec4(perspective ? view.light_radius : view.light_tan_half_angle, 1.0f / row_norm(2), 0.0f, 0.0f);
  if (perspective) p.pcss = glm::vec4(p.pcss.x, 0.0f, gpu_shared::local_light_bulb(view.light_range), view.light_range);
  p.pcss_texel = glm::vec4(2.0f / (row_norm(0) * float(size)), 2.0f / (row_norm(1) * float(size)),
                           gpu_shared::kPcssMaxTexels, perspective ? 1.0f : 0.0f);
}
}  // namespace

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
  depth_pipeline_ = factory.graphics(d);
  alpha_depth_pipeline_ = alpha_depth_pipeline(ctx, d);
}

const Pipeline& ShadowMapPass::resolve_pipeline(bool pcss, bool pcf) {
  // Made on first use: a frame needs one of the four (the filtered ones serve the cascades' spot lights).
  Pipeline& pipeline = resolve_pipelines_[(pcss ? 1 : 0) | (pcf ? 2 : 0)];
  if (pipeline.valid()) return pipeline;
  pipeline = PipelineFactory(ctx_).compute(
      {"shadow_map_resolve.comp",
       {{gpu_shared::SM_RESOLVE_BINDING_PARAMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},
        {gpu_shared::SM_RESOLVE_BINDING_WORLD_POSITION, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
        {gpu_shared::SM_RESOLVE_BINDING_GEOMETRIC_NORMAL, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
        {gpu_shared::SM_RESOLVE_BINDING_SHADOW_MAP, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
        {gpu_shared::SM_RESOLVE_BINDING_SHADOW_TERM, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
        {gpu_shared::SM_RESOLVE_BINDING_RECEIVERS, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE}},
       0,
       {{0, pcss ? 1u : 0u}, {1, pcf ? 1u : 0u}}});
  return pipeline;
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
    set_pcss_params(p, frame.view, light_vp, settings.size);
    record_update(ctx_, cmd, params_, &p, sizeof(p));
    const bool sized = (frame.view.local_light ? frame.view.light_radius : frame.view.light_tan_half_angle) > 0.0f;
    const Pipeline& resolve = resolve_pipeline(sized, filter_texels > 0.0f);
    resolve.bind(cmd);
    DescriptorWriter()
        .uniform_buffer(gpu_shared::SM_RESOLVE_BINDING_PARAMS, params_.handle())
        .storage_image(gpu_shared::SM_RESOLVE_BINDING_WORLD_POSITION, frame.gbuffer.world_position)
        .storage_image(gpu_shared::SM_RESOLVE_BINDING_GEOMETRIC_NORMAL, frame.gbuffer.geometric_normal)
        .sampled_image(gpu_shared::SM_RESOLVE_BINDING_SHADOW_MAP, map_.view(), sampler_.handle(), VK_IMAGE_LAYOUT_GENERAL)
        .storage_image(gpu_shared::SM_RESOLVE_BINDING_SHADOW_TERM, frame.shadow_term.view())
        .storage_image(gpu_shared::SM_RESOLVE_BINDING_RECEIVERS, frame.gbuffer.albedo)
        .push(ctx_, cmd, resolve);
    vkCmdDispatch(cmd, (frame.view.extent.width + 7) / 8, (frame.view.extent.height + 7) / 8, 1);
  }
}

}  // namespace shadows::detail
