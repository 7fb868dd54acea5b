#include "barriers.hpp"
#include "shadow_map_pass.hpp"

#include <algorithm>

#include "light_space.hpp"
#include "shared/local_light.h"
#include "shared/shadows.h"

namespace shadows::detail {

using namespace engine::gpu;

namespace {
constexpr VkFormat kMapFormat = VK_FORMAT_D32_SFLOAT;
// A list a pass appends to and a later one dispatches over, its count zeroed by a fill.
constexpr VkBufferUsageFlags kListUsage =
    VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;

// The PCSS fields of the resolve's parameters (pcss.glsl's PcssMap). `light_vp` is a projection
// times a rigid light view, so the norms of its rows' xyz are the projection's scales: a texel's size
// in map units from the first two, an orthographic map's depth range from the third.
void set_pcss_params(gpu_shared::ShadowMapResolveParams& p, const View& view, const glm::mat4& light_vp, uint32_t size) {
  const auto row_norm = [&](int i) { return glm::length(glm::vec3(light_vp[0][i], light_vp[1][i], light_vp[2][i])); };
  const bool perspective = view.local_light;
  p.light_plane_matrix = glm::transpose(glm::inverse(light_vp));
  // An orthographic map's world -> clip transform is affine, so a plane's slope in it does not depend on
  // the plane's offset: exact zeros, which the resolve relies on to read only nine values
  // (pcss_plane_gradient).
  if (!perspective) p.light_plane_matrix[3] = glm::vec4(0.0f, 0.0f, 0.0f, p.light_plane_matrix[3].w);
  p.pcss = glm::vec4(perspective ? view.light_radius : view.light_tan_half_angle, 1.0f / row_norm(2), 0.0f, 0.0f);
  if (perspective) p.pcss = glm::vec4(p.pcss.x, 0.0f, gpu_shared::local_light_bulb(view.light_range), view.light_range);
  p.pcss_texel = glm::vec4(2.0f / (row_norm(0) * float(size)), 2.0f / (row_norm(1) * float(size)),
                           gpu_shared::kPcssMaxTexels, perspective ? 1.0f : 0.0f);
}

// The depth blocks a side of a map of `size` texels (shadow_map_blocks.comp).
uint32_t blocks_per_side(uint32_t size) { return (size + gpu_shared::kSmBlock - 1) / gpu_shared::kSmBlock; }

// The depth blocks, a vec4 each: a storage buffer, and a texel view through
// which a CPU device reads them where it reaches them all (lavapipe loads a storage buffer's words
// lane by lane, each behind a branch; a texel fetch gathers them).
Buffer blocks_buffer(Context& ctx, VkDeviceSize bytes) {
  Buffer blocks(ctx, bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT, false,
                "sm depth blocks");
  blocks.make_texel_view(VK_FORMAT_R32G32B32A32_SFLOAT,
                         std::min<VkDeviceSize>(bytes / 16, ctx.properties().limits.maxTexelBufferElements), 16);
  return blocks;
}
}  // namespace

ShadowMapPass::ShadowMapPass(Context& ctx, bool cpu_paths) : ctx_(ctx), cpu_paths_(cpu_paths) {
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
  counters_ = Buffer(ctx, gpu_shared::SM_COUNTER_WORDS * 4,
                     VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                     false, "sm counters");
  // Placeholders that keep the resolve's bindings valid until a frame needs the real ones.
  blocks_ = blocks_buffer(ctx, 16);
  tap_list_ = Buffer(ctx, 16, kListUsage, false, "sm tap list");
  light_tiles_ = Buffer(ctx, 16, kListUsage, false, "sm light tiles");
}

const Pipeline& ShadowMapPass::resolve_pipeline(const ResolveVariant& v) {
  // Made on first use (the filtered ones serve the cascades' spot lights).
  Pipeline& pipeline = resolve_pipelines_[v.key()];
  if (pipeline.valid()) return pipeline;
  pipeline = PipelineFactory(ctx_).compute(
      {subgroup_shader(ctx_, "shadow_map_resolve"),
       {{gpu_shared::SM_RESOLVE_BINDING_PARAMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},
        {gpu_shared::SM_RESOLVE_BINDING_WORLD_POSITION, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
        {gpu_shared::SM_RESOLVE_BINDING_GEOMETRIC_NORMAL, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
        {gpu_shared::SM_RESOLVE_BINDING_SHADOW_MAP, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
        {gpu_shared::SM_RESOLVE_BINDING_SHADOW_TERM, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
        {gpu_shared::SM_RESOLVE_BINDING_RECEIVERS, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
        {gpu_shared::SM_RESOLVE_BINDING_BLOCKS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
        {gpu_shared::SM_RESOLVE_BINDING_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
        {gpu_shared::SM_RESOLVE_BINDING_LIST, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
        {gpu_shared::SM_RESOLVE_BINDING_TILES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
        {gpu_shared::SM_RESOLVE_BINDING_BLOCK_TEXELS, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER}},
       0,
       with_pixel_group({{0, v.pcss ? 1u : 0u}, {1, v.pcf ? 1u : 0u}, {2, v.masking ? 1u : 0u}, {3, v.count ? 1u : 0u},
                         {4, v.stage}, {5, v.local ? 1u : 0u}, {6, v.tiles ? 1u : 0u}, {7, cpu_paths_ ? 1u : 0u},
                         {8, v.block_fetch ? 1u : 0u}},
                        9, cpu_paths_)});
  return pipeline;
}

void ShadowMapPass::record_blocks(Frame& frame, uint32_t size) {
  VkCommandBuffer cmd = frame.cmd;
  const uint32_t blocks = blocks_per_side(size);
  const VkDeviceSize bytes = VkDeviceSize(blocks) * blocks * 16;
  if (blocks_.size() < bytes) blocks_ = blocks_buffer(ctx_, bytes);
  if (!blocks_pipeline_.valid())
    blocks_pipeline_ = PipelineFactory(ctx_).compute(
        {"shadow_map_blocks.comp",
         {{gpu_shared::SM_RESOLVE_BINDING_PARAMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},
          {gpu_shared::SM_RESOLVE_BINDING_SHADOW_MAP, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER},
          {gpu_shared::SM_RESOLVE_BINDING_BLOCKS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}}});
  ScopedGpuRegion region(ctx_, frame.profiler, cmd, "sm_blocks");
  blocks_pipeline_.bind(cmd);
  DescriptorWriter()
      .uniform_buffer(gpu_shared::SM_RESOLVE_BINDING_PARAMS, params_.handle())
      .sampled_image(gpu_shared::SM_RESOLVE_BINDING_SHADOW_MAP, map_.view(), sampler_.handle(), VK_IMAGE_LAYOUT_GENERAL)
      .storage_buffer(gpu_shared::SM_RESOLVE_BINDING_BLOCKS, blocks_.handle())
      .push(ctx_, cmd, blocks_pipeline_);
  vkCmdDispatch(cmd, (blocks + 7) / 8, (blocks + 7) / 8, 1);
  // The blocks' stores before the resolve's loads.
  pass_barrier(ctx_, cmd);
}

void ShadowMapPass::record_light_tiles(Frame& frame) {
  VkCommandBuffer cmd = frame.cmd;
  const VkExtent2D e = frame.view.extent;
  const VkDeviceSize bytes = VkDeviceSize(gpu_shared::light_tile_words(e.width, e.height)) * 4;
  if (light_tiles_.size() < bytes) light_tiles_ = Buffer(ctx_, bytes, kListUsage, false, "sm light tiles");
  if (!light_tiles_pipeline_.valid())
    light_tiles_pipeline_ = PipelineFactory(ctx_).compute(
        {"shadow_map_tiles.comp",
         {{gpu_shared::SM_RESOLVE_BINDING_PARAMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},
          {gpu_shared::SM_RESOLVE_BINDING_WORLD_POSITION, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
          {gpu_shared::SM_RESOLVE_BINDING_SHADOW_TERM, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE},
          {gpu_shared::SM_RESOLVE_BINDING_TILES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}},
         0,
         {{0, cpu_paths_ ? 1u : 0u}}});
  ScopedGpuRegion region(ctx_, frame.profiler, cmd, "sm_light_tiles");
  // The lists' counts and dispatches zeroed (the fill before the listing's atomics).
  vkCmdFillBuffer(cmd, light_tiles_.handle(), 0, VkDeviceSize(gpu_shared::kLightTilesAt) * 4, 0);
  pass_barrier(ctx_, cmd);
  light_tiles_pipeline_.bind(cmd);
  DescriptorWriter()
      .uniform_buffer(gpu_shared::SM_RESOLVE_BINDING_PARAMS, params_.handle())
      .storage_image(gpu_shared::SM_RESOLVE_BINDING_WORLD_POSITION, frame.gbuffer.world_position)
      .storage_image(gpu_shared::SM_RESOLVE_BINDING_SHADOW_TERM, frame.shadow_term.view())
      .storage_buffer(gpu_shared::SM_RESOLVE_BINDING_TILES, light_tiles_.handle())
      .push(ctx_, cmd, light_tiles_pipeline_);
  const uint32_t block = gpu_shared::light_tile_listing_block(cpu_paths_);
  vkCmdDispatch(cmd, groups(e.width, block), groups(e.height, block), 1);
  // The lists and the term's stores before the faces' indirect dispatches and resolves.
  pass_barrier(ctx_, cmd);
}

void ShadowMapPass::ensure_map(VkCommandBuffer cmd, uint32_t size) {
  if (map_.valid() && map_.extent().width == size) return;
  map_ = Image(ctx_, {size, size}, kMapFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
               "sm depth map");
  to_general(ctx_, cmd, map_);
}

void ShadowMapPass::record(Frame& frame, const ShadowMapSettings& settings, float filter_texels, bool count) {
  ensure_map(frame.cmd, settings.size);
  VkCommandBuffer cmd = frame.cmd;
  const glm::mat4 light_vp = frame.view.local_light ? spot_view_projection(frame.view) : [&] {
    const glm::mat4 light_view = light_view_matrix(frame.view.light_direction);
    const Aabb bounds = caster_bounds(frame);
    return fit_orthographic(light_view, bounds, 0.01f * glm::length(bounds.extent())) * light_view;
  }();
  // A point light's faces count into one total: zeroed before the first, read after the last.
  const bool first_map = !frame.view.light_face || frame.view.first_light_face();
  const bool last_map = !frame.view.light_face || frame.view.last_light_face;
  if (count && first_map) vkCmdFillBuffer(cmd, counters_.handle(), 0, VK_WHOLE_SIZE, 0);

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
  gpu_shared::ShadowMapResolveParams p{};
  p.light_view_projection = light_vp;
  p.light_direction = glm::vec4(frame.view.light_direction, 0.0f);
  if (frame.view.local_light) {
    p.light_position = glm::vec4(frame.view.light_position, frame.view.light_range);
    p.light_cone = glm::vec4(frame.view.light_cos_outer, 0.0f, frame.view.light_face ? 1.0f : 0.0f,
                             frame.view.light_face ? float(frame.view.light_face_index) : 0.0f);
  }
  p.bias = glm::vec4(settings.constant_bias, filter_texels, 0.0f, 0.0f);
  p.extent = glm::uvec4(frame.view.extent.width, frame.view.extent.height, settings.size, settings.size);
  p.camera_position = glm::vec4(frame.view.camera_position, 1.0f);
  set_pcss_params(p, frame.view, light_vp, settings.size);
  record_update(ctx_, cmd, params_, &p, sizeof(p));
  const bool sized = (frame.view.local_light ? frame.view.light_radius : frame.view.light_tan_half_angle) > 0.0f;
  // (Under the sun: a local light's search spans kPcssMaxTexels either way, wider than the blocks
  // a pixel's settling reads, and its map is left unmasked.)
  const bool masking = sized && settings.masking && !frame.view.local_light;
  if (masking) record_blocks(frame, settings.size);
  const bool split = masking && cpu_paths_;
  const VkDeviceSize list_bytes = (VkDeviceSize(frame.view.extent.width) * frame.view.extent.height + 4) * 4;
  if (split && tap_list_.size() < list_bytes)
    tap_list_ = Buffer(ctx_, list_bytes, kListUsage, false, "sm tap list");
  // A point light's faces each resolve the tiles their cones reach, not the whole frame; so does a spot
  // light on a CPU device, which would pay for every pixel outside its cone too.
  const bool tiles = settings.local_light_tiles && (frame.view.light_face || (frame.view.local_light && cpu_paths_));
  if (tiles && first_map) record_light_tiles(frame);
  const uint64_t blocks = blocks_per_side(settings.size);
  const bool block_fetch = cpu_paths_ && masking && blocks * blocks <= ctx_.properties().limits.maxTexelBufferElements;
  record_resolve(frame,
                 {sized, filter_texels > 0.0f, masking, count && sized, gpu_shared::SM_STAGE_WHOLE, frame.view.local_light, tiles,
                  block_fetch},
                 split);
  // The counts are read on the host once this frame has completed.
  if (count && last_map)
    readback_.record_copy(frame, counters_, gpu_shared::SM_COUNTER_WORDS * 4, pass_shader_stages(ctx_),
                          VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, "sm counters readback");
}

void ShadowMapPass::record_resolve(Frame& frame, ResolveVariant variant, bool split) {
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(ctx_, frame.profiler, cmd, "sm_resolve");
  const auto bind = [&](const ResolveVariant& v) {
    const Pipeline& resolve = resolve_pipeline(v);
    resolve.bind(cmd);
    DescriptorWriter()
        .uniform_buffer(gpu_shared::SM_RESOLVE_BINDING_PARAMS, params_.handle())
        .storage_image(gpu_shared::SM_RESOLVE_BINDING_WORLD_POSITION, frame.gbuffer.world_position)
        .storage_image(gpu_shared::SM_RESOLVE_BINDING_GEOMETRIC_NORMAL, frame.gbuffer.geometric_normal)
        .sampled_image(gpu_shared::SM_RESOLVE_BINDING_SHADOW_MAP, map_.view(), sampler_.handle(), VK_IMAGE_LAYOUT_GENERAL)
        .storage_image(gpu_shared::SM_RESOLVE_BINDING_SHADOW_TERM, frame.shadow_term.view())
        .storage_image(gpu_shared::SM_RESOLVE_BINDING_RECEIVERS, frame.gbuffer.albedo)
        .storage_buffer(gpu_shared::SM_RESOLVE_BINDING_BLOCKS, blocks_.handle())
        .storage_buffer(gpu_shared::SM_RESOLVE_BINDING_COUNTERS, counters_.handle())
        .storage_buffer(gpu_shared::SM_RESOLVE_BINDING_LIST, tap_list_.handle())
        .storage_buffer(gpu_shared::SM_RESOLVE_BINDING_TILES, light_tiles_.handle())
        .uniform_texel_buffer(gpu_shared::SM_RESOLVE_BINDING_BLOCK_TEXELS, blocks_.texel_view())
        .push(ctx_, cmd, resolve);
  };
  const auto over_frame = [&] {
    if (variant.tiles) {
      const uint32_t list = frame.view.light_face ? frame.view.light_face_index : 0;
      vkCmdDispatchIndirect(cmd, light_tiles_.handle(), VkDeviceSize(4 * list + 1) * 4);
      return;
    }
    const VkExtent2D covering = pixel_groups(frame.view.extent, cpu_paths_);
    vkCmdDispatch(cmd, covering.width, covering.height, 1);
  };
  if (!split) {
    bind(variant);
    over_frame();
    return;
  }
  // The list's count zeroed (its transfer write before the listing pass's atomics).
  vkCmdFillBuffer(cmd, tap_list_.handle(), 0, 16, 0);
  pass_barrier(ctx_, cmd);
  variant.stage = gpu_shared::SM_STAGE_LIST;
  bind(variant);
  over_frame();
  pass_barrier(ctx_, cmd);  // the list's stores before its dispatch's sizing
  variant.stage = gpu_shared::SM_STAGE_LIST_DISPATCH;
  variant.count = false;
  bind(variant);
  vkCmdDispatch(cmd, 1, 1, 1);
  pass_barrier(ctx_, cmd);  // the dispatch's words before the indirect read, the list before its loads
  variant.stage = gpu_shared::SM_STAGE_LISTED;
  bind(variant);
  vkCmdDispatchIndirect(cmd, tap_list_.handle(), 4);
}

void ShadowMapPass::after_frame(Stats& stats, uint32_t slot) {
  const Buffer* readback = readback_.take(slot);
  if (!readback) return;
  const uint32_t* c = readback->as<uint32_t>();
  stats.expensive_path_pixels = c[gpu_shared::SM_COUNTER_TAPPED];
  const uint64_t facing = c[gpu_shared::SM_COUNTER_FACING];
  stats.expensive_path_fraction = facing ? double(stats.expensive_path_pixels) / double(facing) : 0.0;
}

}  // namespace shadows::detail
