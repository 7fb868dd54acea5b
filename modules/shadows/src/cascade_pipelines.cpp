#include "cascade_pipelines.hpp"

#include <type_traits>

#include "light_space.hpp"
#include "shared/cascades.h"

namespace shadows::detail {

using namespace engine::gpu;
namespace gs = gpu_shared;

CascadePipelines::CascadePipelines(Context& ctx) : ctx_(ctx) {
  PipelineFactory factory(ctx);
  for (int cull = 0; cull < 2; ++cull) {
    GraphicsPipelineDesc d;
    d.name = cull ? "cascade depth (front culled)" : "cascade depth";
    d.vertex_shader = "cascade_depth.vert";
    d.vertex_input = VertexInput::PositionOnly;
    d.push_constant_size = sizeof(gs::CascadeDepthPush);
    d.depth_format = kCascadeMapFormat;
    d.depth_compare = VK_COMPARE_OP_LESS_OR_EQUAL;
    // The light projection keeps y up, which mirrors winding in Vulkan's y-down framebuffer: faces
    // turned toward the light arrive clockwise, hence front = clockwise.
    d.front_face = VK_FRONT_FACE_CLOCKWISE;
    d.cull_mode = cull ? VK_CULL_MODE_FRONT_BIT : VK_CULL_MODE_NONE;
    d.depth_bias = true;
    depth[cull] = factory.graphics(d);
    if (!cull) alpha_depth = alpha_depth_pipeline(ctx, d);
  }
  for (uint32_t neighbourhoods = 0; neighbourhoods < 3; ++neighbourhoods)
    edges[neighbourhoods] =
        factory.compute({"cascade_edges.comp",
                         {{gs::CASCADE_MASK_BINDING_PARAMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},
                          {gs::CASCADE_MASK_BINDING_DEPTH, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
                          {gs::CASCADE_MASK_BINDING_MASKS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                          {gs::CASCADE_MASK_BINDING_NEIGHBOURHOODS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}},
                         sizeof(gs::CascadeMaskPush),
                         {{0, neighbourhoods}}});
  args = factory.compute(
      {"cascade_dispatch_args.comp", {{gs::CASCADE_ARGS_BINDING_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}}, 0});
  for (uint32_t apply = 0; apply < 2; ++apply)
    blur[apply] = factory.compute({"cascade_blur.comp",
                                   {{gs::CASCADE_BLUR_BINDING_WORLD_POSITION, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
                                    {gs::CASCADE_BLUR_BINDING_GEOMETRIC_NORMAL, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
                                    {gs::CASCADE_BLUR_BINDING_SHADOW_TERM, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
                                    {gs::CASCADE_BLUR_BINDING_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                                    {gs::CASCADE_BLUR_BINDING_BLUR_LIST, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
                                    {gs::CASCADE_BLUR_BINDING_BLURRED, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}},
                                   sizeof(gs::CascadeBlurPush),
                                   {{0, apply}}});
}

const Pipeline& CascadePipelines::filter(uint32_t stage, uint32_t masking, uint32_t debug, uint32_t pcss) {
  static_assert(std::extent_v<decltype(filters_), 1> == gs::CASCADE_MASKING_PLANES + 1, "a pipeline per masking mode");
  Pipeline& pipeline = filters_[stage][masking][debug][pcss];
  if (pipeline.valid()) return pipeline;
  PipelineFactory factory(ctx_);
  pipeline = factory.compute(
      {"cascade_filter.comp",
       {{gs::CASCADE_FILTER_BINDING_PARAMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},
        {gs::CASCADE_FILTER_BINDING_WORLD_POSITION, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
        {gs::CASCADE_FILTER_BINDING_GEOMETRIC_NORMAL, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
        {gs::CASCADE_FILTER_BINDING_DEPTH, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
        {gs::CASCADE_FILTER_BINDING_NEIGHBOURHOODS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
        {gs::CASCADE_FILTER_BINDING_ROTATION, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
        {gs::CASCADE_FILTER_BINDING_SHADOW_TERM, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
        {gs::CASCADE_FILTER_BINDING_OVERLAY, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
        {gs::CASCADE_FILTER_BINDING_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
        {gs::CASCADE_FILTER_BINDING_BLUR_LIST, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
        {gs::CASCADE_FILTER_BINDING_WORK_LIST, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
        {gs::CASCADE_FILTER_BINDING_INPUT_LIST, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
        {gs::CASCADE_FILTER_BINDING_INPUT_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
        {gs::CASCADE_FILTER_BINDING_RECEIVERS, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE}},
       0,
       {{0, stage}, {1, masking}, {2, debug}, {3, pcss}}});
  return pipeline;
}

}  // namespace shadows::detail
