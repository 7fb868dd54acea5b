#pragma once
// Barriers between the module's own passes. Each names the stages the passes run on this device
// (geometry and ray tracing stages only where enabled) and the accesses they make; none is an
// ALL_COMMANDS barrier.
#include <string>
#include <vector>

#include "gpu/context.hpp"
#include "gpu/pipeline.hpp"

namespace shadows::detail {

// Shader stages the module's passes use on this device.
VkPipelineStageFlags2 pass_shader_stages(const engine::gpu::Context& ctx);

// Whether the module takes its CPU-device paths (a CPU device pays a store or an atomic for every lane
// of a SIMD row, and a transfer clear is a memset there): on a CPU device, unless the environment
// variable SHADOWS_GPU_PATHS is 1, which makes it take the paths a GPU takes (for tests: both must give
// the same pixels). Read once, when a module is created (its passes, made later, take that answer).
bool takes_cpu_paths(const engine::gpu::Context& ctx);

// Workgroups of `size` that cover `n`.
constexpr uint32_t groups(uint32_t n, uint32_t size) { return (n + size - 1) / size; }

// The per-pixel passes' workgroup of 64 invocations (sm's resolve; the IZB's build, scatter and
// resolve): 8 wide (8x8) on a GPU, 64 wide (a row) with the CPU-device paths, where lavapipe ran a row
// about a tenth (the IZB's build) to a fifth (sm's resolve) faster; and the workgroups that cover a
// view of `extent` pixels in that shape.
constexpr uint32_t pixel_group_width(bool cpu_paths) { return cpu_paths ? 64u : 8u; }
// `constants` and that workgroup's width and height as specialization constants `first_id` and the
// next.
inline std::vector<engine::gpu::SpecializationConstant> with_pixel_group(
    std::vector<engine::gpu::SpecializationConstant> constants, uint32_t first_id, bool cpu_paths) {
  constants.push_back({first_id, pixel_group_width(cpu_paths)});
  constants.push_back({first_id + 1, 64u / pixel_group_width(cpu_paths)});
  return constants;
}
inline VkExtent2D pixel_groups(VkExtent2D extent, bool cpu_paths) {
  const uint32_t width = pixel_group_width(cpu_paths);
  return {groups(extent.width, width), groups(extent.height, 64u / width)};
}

// The compute shader `stem` (e.g. "shadow_map_resolve") for this device: `stem`.comp, or on a device
// without subgroup arithmetic and ballot operations its variant without them, `stem`_portable.comp
// (only the passes every technique or the plain shadow map needs have one).
std::string subgroup_shader(const engine::gpu::Context& ctx, const std::string& stem);

// Every earlier pass's writes (shader storage, depth and colour attachments, copies and fills) before
// every later pass's reads and writes (shaders, indirect arguments, vertex and index fetch, depth
// tests, copies and fills).
void pass_barrier(const engine::gpu::Context& ctx, VkCommandBuffer cmd);

}  // namespace shadows::detail

namespace engine::gpu {
class Image;
}

namespace shadows::detail {

// A new image (UNDEFINED) into GENERAL, in the frame's command stream, before any pass uses it.
void to_general(const engine::gpu::Context& ctx, VkCommandBuffer cmd, engine::gpu::Image& image);

}  // namespace shadows::detail

namespace engine::gpu {
class Buffer;
}

namespace shadows::detail {

// Writes `bytes` of `data` into `buffer` at `offset` in the command stream (vkCmdUpdateBuffer, at
// most 65536 bytes), so frames in flight each read their own values: earlier passes' reads finish
// before the write, and the write is visible to every later pass's uniform and storage reads.
// `buffer` must be created with VK_BUFFER_USAGE_TRANSFER_DST_BIT.
void record_update(const engine::gpu::Context& ctx, VkCommandBuffer cmd, const engine::gpu::Buffer& buffer,
                   const void* data, VkDeviceSize bytes, VkDeviceSize offset = 0);

}  // namespace shadows::detail
