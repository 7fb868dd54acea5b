#include "barriers.hpp"

#include <algorithm>
#include <cstdlib>
#include <string_view>

#include "gpu/resources.hpp"

namespace shadows::detail {

bool takes_cpu_paths(const engine::gpu::Context& ctx) {
  const char* gpu_paths = std::getenv("SHADOWS_GPU_PATHS");
  const bool forced = gpu_paths && std::string_view(gpu_paths) == "1";
  return ctx.properties().deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU && !forced;
}

std::string subgroup_shader(const engine::gpu::Context& ctx, const std::string& stem) {
  return stem + (ctx.features().subgroup_arithmetic_compute_fragment ? ".comp" : "_portable.comp");
}

VkPipelineStageFlags2 pass_shader_stages(const engine::gpu::Context& ctx) {
  VkPipelineStageFlags2 stages = VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT |
                                 VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT;
  if (ctx.features().geometry_shader) stages |= VK_PIPELINE_STAGE_2_GEOMETRY_SHADER_BIT;
  if (ctx.features().ray_tracing_pipeline) stages |= VK_PIPELINE_STAGE_2_RAY_TRACING_SHADER_BIT_KHR;
  return stages;
}

namespace {

struct Scope {
  VkPipelineStageFlags2 stages;
  VkAccessFlags2 access;
};

// Every later pass's use: shaders, indirect arguments, vertex and index fetch, depth tests, copies and fills.
Scope pass_uses(const engine::gpu::Context& ctx) {
  VkPipelineStageFlags2 build = 0;
  VkAccessFlags2 build_access = 0;
  if (ctx.features().acceleration_structure) {
    build = VK_PIPELINE_STAGE_2_ACCELERATION_STRUCTURE_BUILD_BIT_KHR;
    build_access = VK_ACCESS_2_ACCELERATION_STRUCTURE_READ_BIT_KHR | VK_ACCESS_2_ACCELERATION_STRUCTURE_WRITE_BIT_KHR;
  }
  return {pass_shader_stages(ctx) | VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_2_VERTEX_INPUT_BIT |
              VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT |
              VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT | build,
          VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_SAMPLED_READ_BIT | VK_ACCESS_2_UNIFORM_READ_BIT |
              VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT |
              VK_ACCESS_2_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_2_INDEX_READ_BIT |
              VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT |
              VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT |
              VK_ACCESS_2_TRANSFER_READ_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT | build_access};
}

}  // namespace

void to_general(const engine::gpu::Context& ctx, VkCommandBuffer cmd, engine::gpu::Image& image) {
  const Scope uses = pass_uses(ctx);
  image.transition(cmd, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0, uses.stages, uses.access);
}

void pass_barrier(const engine::gpu::Context& ctx, VkCommandBuffer cmd) {
  const VkPipelineStageFlags2 shaders = pass_shader_stages(ctx);
  VkPipelineStageFlags2 build = 0;
  VkAccessFlags2 build_write = 0;
  if (ctx.features().acceleration_structure) {
    build = VK_PIPELINE_STAGE_2_ACCELERATION_STRUCTURE_BUILD_BIT_KHR;
    build_write = VK_ACCESS_2_ACCELERATION_STRUCTURE_WRITE_BIT_KHR;
  }
  const VkPipelineStageFlags2 writers = shaders | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT |
                                        VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT | build;
  const VkAccessFlags2 writes = VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT |
                                VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT | build_write;
  const Scope uses = pass_uses(ctx);
  engine::gpu::memory_barrier(cmd, writers, writes, uses.stages, uses.access);
}

}  // namespace shadows::detail

namespace shadows::detail {

void record_update(const engine::gpu::Context& ctx, VkCommandBuffer cmd, const engine::gpu::Buffer& buffer,
                   const void* data, VkDeviceSize bytes, VkDeviceSize offset) {
  const VkPipelineStageFlags2 shaders = pass_shader_stages(ctx);
  engine::gpu::memory_barrier(cmd, shaders, 0, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, 0);
  const auto* bytes_in = static_cast<const uint8_t*>(data);
  for (VkDeviceSize done = 0; done < bytes;) {
    const VkDeviceSize chunk = std::min<VkDeviceSize>(bytes - done, 65536);
    vkCmdUpdateBuffer(cmd, buffer.handle(), offset + done, chunk, bytes_in + done);
    done += chunk;
  }
  engine::gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT, shaders,
                              VK_ACCESS_2_UNIFORM_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
}

}  // namespace shadows::detail
