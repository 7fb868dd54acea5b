#pragma once
// Checks of host-described resources at the API boundary: each failure is one shadows::Error line
// naming the argument, thrown before anything is recorded.
#include <initializer_list>
#include <optional>
#include <string>

#include "shadows/context.hpp"

namespace shadows::detail {

inline constexpr std::initializer_list<VkImageLayout> kReadLayouts = {
    VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_IMAGE_LAYOUT_DEPTH_READ_ONLY_OPTIMAL,
    VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL, VK_IMAGE_LAYOUT_READ_ONLY_OPTIMAL, VK_IMAGE_LAYOUT_GENERAL};

// `minimum` bytes must fit in the region; `half_aligned`: a 2-byte offset is enough (16-bit indices).
void check_buffer(const BufferInput& buffer, const std::string& name, VkDeviceSize minimum, bool half_aligned = false);
void check_image(const ImageInput& image, const std::string& name, std::initializer_list<VkFormat> formats,
                 VkImageUsageFlags usage, std::initializer_list<VkImageLayout> layouts,
                 std::optional<VkExtent2D> extent);
std::string format_name(VkFormat format);
// Instance::deformed, present: format, stride, vertex_count (the mesh's), region and bounds.
void check_deformed(const DeformedPositions& deformed, const std::string& name, uint32_t mesh_vertex_count);

}  // namespace shadows::detail
