#pragma once
// The module's SPIR-V compiled into the library (source generated at build time from shaders/shadows/
// by cmake/embed_spirv.cmake). Registered with engine::gpu before the first pipeline is created.
#include <span>

#include "gpu/pipeline.hpp"

namespace shadows::detail {

std::span<const engine::gpu::EmbeddedShader> embedded_shaders();

}  // namespace shadows::detail
