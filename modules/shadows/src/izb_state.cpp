#include "barriers.hpp"
#include "izb_state.hpp"

#include "izb_batch.hpp"

#include <cstring>

#include "gpu/profiler.hpp"

namespace shadows::detail {

using namespace engine::gpu;

namespace {
// Refuses a device without what the IZB's shaders need, before anything is made on it.
Context& with_izb_features(Context& c) {
  if (!c.features().subgroup_arithmetic_compute_fragment)
    throw VulkanError("the IZB needs subgroup arithmetic and ballot operations in compute and fragment shaders, "
                      "which " + c.device_name() + " lacks");
  if (!c.features().depth_clamp)
    throw VulkanError("the IZB trace needs the depthClamp feature, which " + c.device_name() + " lacks");
  return c;
}
}  // namespace

IzbState::IzbState(Context& c, bool cpu_paths)
    : ctx(with_izb_features(c)), pipelines(c, cpu_paths), res(c), casters(c), csm(std::make_unique<CsmPass>(c)) {}

void IzbState::push_all(VkCommandBuffer cmd, const Frame& frame, const Pipeline& pipeline) {
  DescriptorWriter()
      .uniform_buffer(gpu_shared::IZB_BINDING_PARAMS, res.params.handle(), res.slice_at(res.params_stride),
                      sizeof(gpu_shared::IzbParams))
      .uniform_buffer(gpu_shared::IZB_BINDING_FRAME, res.frame_data.handle(), res.slice_at(res.frame_stride),
                      sizeof(gpu_shared::IzbFrame))
      .storage_buffer(gpu_shared::IZB_BINDING_COUNTERS, res.counters.handle(), res.counter_slice_offset(),
                      IzbResources::counter_bytes())
      .storage_buffer(gpu_shared::IZB_BINDING_HEADS, res.heads.handle(), res.slice_at(res.heads_stride()),
                      res.slice_range(res.heads, res.heads_stride()))
      .storage_buffer(gpu_shared::IZB_BINDING_FARTHEST, res.farthest.handle(), res.slice_at(res.farthest_stride()),
                      res.slice_range(res.farthest, res.farthest_stride()))
      .storage_buffer(gpu_shared::IZB_BINDING_NODES, res.nodes.handle())
      .storage_buffer(gpu_shared::IZB_BINDING_MASK, res.mask.handle())
      .storage_buffer(gpu_shared::IZB_BINDING_PIXEL_STATE, res.pixel_state.handle())
      .storage_buffer(gpu_shared::IZB_BINDING_QUADS, res.quads.handle())
      .storage_image(gpu_shared::IZB_BINDING_WORLD_POSITION, frame.gbuffer.world_position)
      .storage_image(gpu_shared::IZB_BINDING_GEOMETRIC_NORMAL, frame.gbuffer.geometric_normal)
      .storage_image(gpu_shared::IZB_BINDING_ALBEDO, frame.gbuffer.albedo)
      .storage_buffer(gpu_shared::IZB_BINDING_HYBRID_LIST, res.hybrid_list.handle())
      .storage_image(gpu_shared::IZB_BINDING_SOFT_TERM, res.soft_term.view())
      .storage_image(gpu_shared::IZB_BINDING_SHADOW_TERM, frame.shadow_term.view())
      .storage_image(gpu_shared::IZB_BINDING_OVERLAY, frame.overlay.view())
      .storage_buffer(gpu_shared::IZB_BINDING_TRIANGLES, casters.triangles.handle())
      .storage_buffer(gpu_shared::IZB_BINDING_OVERFLOW_LIST, res.overflow_list.handle())
      .storage_buffer(gpu_shared::IZB_BINDING_OCCLUDER_DISTANCE, res.occluder_distance.handle())
      .storage_buffer(gpu_shared::IZB_BINDING_GRID_TRIANGLES, casters.grid_triangles.handle(),
                      res.slice_at(casters.grid_triangle_stride()), casters.grid_triangle_stride())
      .storage_buffer(gpu_shared::IZB_BINDING_RECORDS, res.records.buffer.handle(), res.slice_at(res.records.stride),
                      res.records.stride)
      .storage_buffer(gpu_shared::IZB_BINDING_TILE_PAIRS, res.tile_pairs.buffer.handle(),
                      res.slice_at(res.tile_pairs.stride), res.tile_pairs.stride)
      .storage_buffer(gpu_shared::IZB_BINDING_PAIRS, res.pairs.buffer.handle(), res.slice_at(res.pairs.stride),
                      res.pairs.stride)
      .uniform_texel_buffer(gpu_shared::IZB_BINDING_LIT_WORDS, res.csm_texels.texel_view())
      .storage_buffer(gpu_shared::IZB_BINDING_LIST_COUNTS, res.list_counts.handle())
      .storage_buffer(gpu_shared::IZB_BINDING_LIST_CURSOR, res.list_cursor.handle())
      .storage_buffer(gpu_shared::IZB_BINDING_RESOLVE_LIST, res.resolve_list.handle())
      .storage_buffer(gpu_shared::IZB_BINDING_BOUNDS_PARTIALS, res.frame_data.handle(), res.slice_at(res.frame_stride),
                      res.frame_stride)
      .storage_buffer(gpu_shared::IZB_BINDING_MATERIAL_TEXTURES, frame.geometry.textures().handle())
      .storage_buffer(gpu_shared::IZB_BINDING_CASTER_DRAWS, casters.caster_draw_words.handle())
      .storage_buffer(gpu_shared::IZB_BINDING_CSM_TEXELS, res.csm_texels.handle())
      .sampled_image(gpu_shared::IZB_BINDING_CSM_DEPTH, csm->depth_view(), res.nearest.handle(), VK_IMAGE_LAYOUT_GENERAL)
      .push(ctx, cmd, pipeline);
}

void IzbState::bind_compute(VkCommandBuffer cmd, const Frame& frame, const Pipeline& pipeline,
                            const gpu_shared::IzbComputePush& push) {
  pipeline.bind(cmd);
  push_all(cmd, frame, pipeline);
  pipeline.push_constants(cmd, push);
}

void IzbState::dispatch(VkCommandBuffer cmd, const Frame& frame, const Pipeline& pipeline,
                        gpu_shared::IzbComputePush push, uint32_t x, uint32_t y) {
  bind_compute(cmd, frame, pipeline, push);
  vkCmdDispatch(cmd, x, y, 1);
}

void IzbState::dispatch_pixels(VkCommandBuffer cmd, const Frame& frame, const Pipeline& pipeline,
                               gpu_shared::IzbComputePush push) {
  const VkExtent2D covering = pixel_groups(frame.view.extent, pipelines.cpu_device());
  dispatch(cmd, frame, pipeline, push, covering.width, covering.height);
}

void IzbState::size_list_dispatch(VkCommandBuffer cmd, const Frame& frame, gpu_shared::IzbComputePush push,
                                  uint32_t which) {
  push.mode = which;
  dispatch(cmd, frame, p->list_dispatch, push, 1);
  pass_barrier(frame.ctx, cmd);
}

void IzbState::dispatch_indirect(VkCommandBuffer cmd, const Frame& frame, const Pipeline& pipeline,
                                 gpu_shared::IzbComputePush push, uint32_t counter) {
  bind_compute(cmd, frame, pipeline, push);
  vkCmdDispatchIndirect(cmd, res.counters.handle(), res.counter_at(counter));
}

void IzbState::dispatch_face_tiles(VkCommandBuffer cmd, const Frame& frame, const Pipeline& pipeline,
                                   gpu_shared::IzbComputePush push) {
  bind_compute(cmd, frame, pipeline, push);
  vkCmdDispatchIndirect(cmd, res.resolve_list.handle(), VkDeviceSize(4 * frame.view.light_face_index + 1) * 4);
}

void IzbState::record_tile_work(VkCommandBuffer cmd, IzbBatch& batch, uint32_t mode, const std::string& region,
                                bool time_steps) {
  const Frame& frame = batch.frame();
  // The dispatches of steps 2 and 3 (and the trace's step 4) are raised by the steps before them as
  // they append (izb_group_reserve.glsl): no pass between sizes them.
  const uint32_t records_dispatch = gpu_shared::izb_step_dispatch_at(mode);
  const auto step = [&](const char* name, Pipeline IzbPipelines::TileWork::*pipeline, uint32_t counter) {
    OptionalGpuRegion timed(time_steps, ctx, frame.profiler, cmd, region + name);
    for_each_record(*this, batch, [&](IzbRecord& r) {
      gpu_shared::IzbComputePush push = r.push;
      push.mode = mode;
      dispatch_indirect(cmd, *r.frame, pipelines.tile_work(*p, mode).*pipeline, push, counter);
    });
  };
  // Over the frustum's triangles: the listed ones are fewer (izb_triangles.comp).
  step("_records", &IzbPipelines::TileWork::records, gpu_shared::IZB_COUNTER_STEP_ONE_DISPATCH);
  pass_barrier(frame.ctx, cmd);
  step("_tiles", &IzbPipelines::TileWork::tile_bin, records_dispatch);
  pass_barrier(frame.ctx, cmd);
  step("_texels", &IzbPipelines::TileWork::texel_bin, records_dispatch + 3u);
}

glm::mat4 IzbState::read_light_view_projection() const {
  const auto bytes = read_buffer(ctx, res.frame_data);
  gpu_shared::IzbFrame frame;
  std::memcpy(&frame, bytes.data(), sizeof(frame));
  return frame.light_view_projection;
}

}  // namespace shadows::detail
