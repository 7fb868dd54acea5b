#pragma once
// Barriers between the module's own passes. Each names the stages the passes run on this device
// (geometry and ray tracing stages only where enabled) and the accesses they make; none is an
// ALL_COMMANDS barrier.
#include "engine/gpu/context.hpp"

namespace shadows::detail {

// Shader stages the module's passes use on this device.
VkPipelineStageFlags2 pass_shader_stages(const engine::gpu::Context& ctx);

// Every earlier pass's writes (shader storage, depth and colour attachments, copies and fills) before
// every later pass's reads and writes (shaders, indirect arguments, vertex and index fetch, depth
// tests, copies and fills).
void pass_barrier(const engine::gpu::Context& ctx, VkCommandBuffer cmd);

}  // namespace shadows::detail
