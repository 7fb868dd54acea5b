#pragma once
// RAII owners of Vulkan buffers, images, samplers and query pools. Each allocates its own memory:
// the engine's resource count is small (tens), so a sub-allocator would buy nothing here.
#include <cstring>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "gpu/context.hpp"

namespace engine::gpu {

class Buffer {
 public:
  Buffer() = default;
  // host_visible: mapped persistently (uploads, readbacks, small uniform data).
  Buffer(const Context& ctx, VkDeviceSize size, VkBufferUsageFlags usage, bool host_visible,
         const std::string& name);
  ~Buffer() { reset(); }
  Buffer(Buffer&& o) noexcept { *this = std::move(o); }
  Buffer& operator=(Buffer&& o) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  void reset();
  VkBuffer handle() const { return buffer_; }
  VkDeviceSize size() const { return size_; }
  void* mapped() const { return mapped_; }
  // Nonzero only for buffers created with VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT.
  VkDeviceAddress device_address() const { return device_address_; }
  bool valid() const { return buffer_ != VK_NULL_HANDLE; }
  template <typename T>
  T* as() const { return static_cast<T*>(mapped_); }
  void write(const void* data, size_t bytes, size_t offset = 0) { std::memcpy(static_cast<char*>(mapped_) + offset, data, bytes); }
  VkDescriptorBufferInfo descriptor() const { return {buffer_, 0, VK_WHOLE_SIZE}; }
  // A texel view of the buffer's first `elements` texels of `format` (the buffer must have a texel
  // buffer usage); it lives as long as the buffer. VK_NULL_HANDLE until made.
  void make_texel_view(VkFormat format, VkDeviceSize elements, VkDeviceSize texel_bytes);
  VkBufferView texel_view() const { return texel_view_; }

 private:
  const Context* ctx_ = nullptr;
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkBufferView texel_view_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  VkDeviceSize size_ = 0;
  void* mapped_ = nullptr;
  VkDeviceAddress device_address_ = 0;
};

// Creates a device-local buffer and fills it with `bytes` through a staging copy.
Buffer upload_buffer(const Context& ctx, const void* data, VkDeviceSize bytes, VkBufferUsageFlags usage,
                     const std::string& name);

// Copies a device buffer back to the host (waits for the queue).
std::vector<uint8_t> read_buffer(const Context& ctx, const Buffer& buffer, VkDeviceSize bytes = VK_WHOLE_SIZE);

class Image {
 public:
  Image() = default;
  Image(const Context& ctx, VkExtent2D extent, VkFormat format, VkImageUsageFlags usage, const std::string& name,
        uint32_t mip_levels = 1, uint32_t layers = 1);
  ~Image() { reset(); }
  Image(Image&& o) noexcept { *this = std::move(o); }
  Image& operator=(Image&& o) noexcept;
  Image(const Image&) = delete;
  Image& operator=(const Image&) = delete;

  void reset();
  VkImage handle() const { return image_; }
  VkImageView view() const { return view_; }
  // A view of one mip level (for storage writes into a mip chain).
  VkImageView mip_view(uint32_t level) const { return mip_views_.empty() ? view_ : mip_views_[level]; }
  VkImageView layer_view(uint32_t layer) const { return layer_views_.empty() ? view_ : layer_views_[layer]; }
  VkFormat format() const { return format_; }
  VkImageUsageFlags usage() const { return usage_; }  // as created
  VkExtent2D extent() const { return extent_; }
  uint32_t mip_levels() const { return mip_levels_; }
  uint32_t layers() const { return layers_; }
  VkImageAspectFlags aspect() const { return aspect_; }
  bool valid() const { return image_ != VK_NULL_HANDLE; }

  // Tracks the layout the image was last transitioned to by transition().
  VkImageLayout layout() const { return layout_; }
  void transition(VkCommandBuffer cmd, VkImageLayout new_layout, VkPipelineStageFlags2 src_stage,
                  VkAccessFlags2 src_access, VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access);

 private:
  const Context* ctx_ = nullptr;
  VkImage image_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  VkImageView view_ = VK_NULL_HANDLE;
  std::vector<VkImageView> mip_views_;
  std::vector<VkImageView> layer_views_;
  VkFormat format_ = VK_FORMAT_UNDEFINED;
  VkImageUsageFlags usage_ = 0;
  VkExtent2D extent_{};
  VkImageAspectFlags aspect_ = VK_IMAGE_ASPECT_COLOR_BIT;
  uint32_t mip_levels_ = 1;
  uint32_t layers_ = 1;
  VkImageLayout layout_ = VK_IMAGE_LAYOUT_UNDEFINED;
};

class Sampler {
 public:
  Sampler() = default;
  Sampler(const Context& ctx, VkFilter filter, VkSamplerAddressMode address, const std::string& name,
          bool depth_compare = false);
  ~Sampler() { reset(); }
  Sampler(Sampler&& o) noexcept { *this = std::move(o); }
  Sampler& operator=(Sampler&& o) noexcept;
  Sampler(const Sampler&) = delete;
  Sampler& operator=(const Sampler&) = delete;
  void reset();
  VkSampler handle() const { return sampler_; }

 private:
  const Context* ctx_ = nullptr;
  VkSampler sampler_ = VK_NULL_HANDLE;
};

// `value` rounded up to a multiple of `alignment` (0: unchanged).
inline VkDeviceSize align_up(VkDeviceSize value, VkDeviceSize alignment) {
  return alignment ? (value + alignment - 1) / alignment * alignment : value;
}

// Memory barrier helpers (synchronization2).
void memory_barrier(VkCommandBuffer cmd, VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access,
                    VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access);
// The common "compute/fragment wrote it, anything reads it next" full barrier, used between passes.
void full_barrier(VkCommandBuffer cmd);

bool is_depth_format(VkFormat format);

// Reads back a 2D image (level 0, layer 0) whose texels are `texel_bytes` wide into host memory.
// The image must be in GENERAL or TRANSFER_SRC layout and is left in its original layout.
std::vector<uint8_t> read_image(const Context& ctx, Image& image, uint32_t texel_bytes);

// The same, typed: one T per texel (T's size is the texel size).
template <typename T>
std::vector<T> read_image_as(const Context& ctx, Image& image) {
  const auto bytes = read_image(ctx, image, sizeof(T));
  std::vector<T> out(bytes.size() / sizeof(T));
  std::memcpy(out.data(), bytes.data(), out.size() * sizeof(T));
  return out;
}

}  // namespace engine::gpu
