#include "gpu/resources.hpp"

#include <stdexcept>

namespace engine::gpu {

Buffer::Buffer(const Context& ctx, VkDeviceSize size, VkBufferUsageFlags usage, bool host_visible,
               const std::string& name)
    : ctx_(&ctx), size_(size) {
  // Storage buffers are bound whole, so one larger than the device's storage range could not be read
  // past it: refuse it with the figures rather than let the shader see a truncated buffer.
  const uint64_t storage_range = ctx.features().max_storage_buffer_range;
  if ((usage & VK_BUFFER_USAGE_STORAGE_BUFFER_BIT) && storage_range && size > storage_range)
    throw VulkanError("buffer '" + name + "' needs " + std::to_string(size) + " bytes, over " + ctx.device_name() +
                      "'s maxStorageBufferRange of " + std::to_string(storage_range) + " bytes");
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = size > 0 ? size : 4;
  info.usage = usage;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VK_CHECK(vkCreateBuffer(ctx.device(), &info, ctx.allocator(), &buffer_));
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(ctx.device(), buffer_, &req);
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  alloc.allocationSize = req.size;
  alloc.memoryTypeIndex = ctx.find_memory_type(
      req.memoryTypeBits, host_visible ? (VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)
                                       : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  // Buffers read through device addresses (acceleration structure inputs, shader binding tables).
  VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
  if (usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT) {
    flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
    alloc.pNext = &flags;
  }
  try {
    memory_ = ctx.allocate_memory(alloc, "buffer '" + name + "'");
  } catch (...) {
    vkDestroyBuffer(ctx.device(), buffer_, ctx.allocator());
    throw;
  }
  VK_CHECK(vkBindBufferMemory(ctx.device(), buffer_, memory_, 0));
  ctx.track_allocation(memory_, name, req.size);
  if (usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT) {
    VkBufferDeviceAddressInfo address{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
    address.buffer = buffer_;
    device_address_ = vkGetBufferDeviceAddress(ctx.device(), &address);
  }
  if (host_visible) VK_CHECK(vkMapMemory(ctx.device(), memory_, 0, VK_WHOLE_SIZE, 0, &mapped_));
  ctx.set_name(buffer_, VK_OBJECT_TYPE_BUFFER, name);
}

Buffer& Buffer::operator=(Buffer&& o) noexcept {
  if (this != &o) {
    reset();
    ctx_ = o.ctx_;
    buffer_ = std::exchange(o.buffer_, VK_NULL_HANDLE);
    texel_view_ = std::exchange(o.texel_view_, VK_NULL_HANDLE);
    memory_ = std::exchange(o.memory_, VK_NULL_HANDLE);
    size_ = std::exchange(o.size_, 0);
    mapped_ = std::exchange(o.mapped_, nullptr);
    device_address_ = std::exchange(o.device_address_, 0);
  }
  return *this;
}

void Buffer::make_texel_view(VkFormat format, VkDeviceSize elements, VkDeviceSize texel_bytes) {
  if (texel_view_) throw std::logic_error("Buffer::make_texel_view: the buffer has its view already");
  VkBufferViewCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
  info.buffer = buffer_;
  info.format = format;
  info.offset = 0;
  info.range = elements * texel_bytes;
  VK_CHECK(vkCreateBufferView(ctx_->device(), &info, ctx_->allocator(), &texel_view_));
}

void Buffer::reset() {
  if (!ctx_) return;
  const Context* ctx = ctx_;
  auto destroy = [ctx, buffer = buffer_, view = texel_view_, memory = memory_] {
    if (view) vkDestroyBufferView(ctx->device(), view, ctx->allocator());
    if (buffer) vkDestroyBuffer(ctx->device(), buffer, ctx->allocator());
    if (memory) {
      ctx->untrack_allocation(memory);
      ctx->free_memory(memory);
    }
  };
  // Frames still in flight may use it (Context::defer_releases).
  if (ctx->defers_releases() && (buffer_ || memory_)) ctx->defer_release(destroy);
  else destroy();
  buffer_ = VK_NULL_HANDLE;
  texel_view_ = VK_NULL_HANDLE;
  memory_ = VK_NULL_HANDLE;
  mapped_ = nullptr;
  size_ = 0;
  device_address_ = 0;
}

Buffer upload_buffer(const Context& ctx, const void* data, VkDeviceSize bytes, VkBufferUsageFlags usage,
                     const std::string& name) {
  Buffer staging(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true, name + " staging");
  if (bytes) staging.write(data, bytes);
  Buffer out(ctx, bytes, usage | VK_BUFFER_USAGE_TRANSFER_DST_BIT, false, name);
  if (bytes) {
    ctx.immediate_submit([&](VkCommandBuffer cmd) {
      VkBufferCopy copy{0, 0, bytes};
      vkCmdCopyBuffer(cmd, staging.handle(), out.handle(), 1, &copy);
    });
  }
  return out;
}

std::vector<uint8_t> read_buffer(const Context& ctx, const Buffer& buffer, VkDeviceSize bytes) {
  if (bytes == VK_WHOLE_SIZE) bytes = buffer.size();
  Buffer staging(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true, "readback staging");
  ctx.immediate_submit([&](VkCommandBuffer cmd) {
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    VkBufferCopy copy{0, 0, bytes};
    vkCmdCopyBuffer(cmd, buffer.handle(), staging.handle(), 1, &copy);
  });
  std::vector<uint8_t> out(bytes);
  std::memcpy(out.data(), staging.mapped(), bytes);
  return out;
}

bool is_depth_format(VkFormat format) {
  return format == VK_FORMAT_D32_SFLOAT || format == VK_FORMAT_D16_UNORM || format == VK_FORMAT_D24_UNORM_S8_UINT ||
         format == VK_FORMAT_D32_SFLOAT_S8_UINT;
}

Image::Image(const Context& ctx, VkExtent2D extent, VkFormat format, VkImageUsageFlags usage, const std::string& name,
             uint32_t mip_levels, uint32_t layers)
    : ctx_(&ctx), format_(format), usage_(usage), extent_(extent), mip_levels_(mip_levels), layers_(layers) {
  aspect_ = is_depth_format(format) ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT;
  const uint32_t max_side = ctx.properties().limits.maxImageDimension2D;
  if (extent.width > max_side || extent.height > max_side)
    throw VulkanError("image '" + name + "' of " + std::to_string(extent.width) + "x" + std::to_string(extent.height) +
                      " exceeds the " + std::to_string(max_side) + "-texel image side of " + ctx.device_name());
  VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  info.imageType = VK_IMAGE_TYPE_2D;
  info.format = format;
  info.extent = {extent.width, extent.height, 1};
  info.mipLevels = mip_levels;
  info.arrayLayers = layers;
  info.samples = VK_SAMPLE_COUNT_1_BIT;
  info.tiling = VK_IMAGE_TILING_OPTIMAL;
  info.usage = usage;
  info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  VK_CHECK(vkCreateImage(ctx.device(), &info, ctx.allocator(), &image_));
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(ctx.device(), image_, &req);
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  alloc.allocationSize = req.size;
  alloc.memoryTypeIndex = ctx.find_memory_type(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  try {
    memory_ = ctx.allocate_memory(alloc, "image '" + name + "'");
  } catch (...) {
    vkDestroyImage(ctx.device(), image_, ctx.allocator());
    throw;
  }
  VK_CHECK(vkBindImageMemory(ctx.device(), image_, memory_, 0));
  ctx.track_allocation(memory_, name, req.size);

  auto make_view = [&](uint32_t base_mip, uint32_t mips, uint32_t base_layer, uint32_t layer_count) {
    VkImageViewCreateInfo v{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    v.image = image_;
    v.viewType = layer_count > 1 ? VK_IMAGE_VIEW_TYPE_2D_ARRAY : VK_IMAGE_VIEW_TYPE_2D;
    v.format = format;
    v.subresourceRange = {aspect_, base_mip, mips, base_layer, layer_count};
    VkImageView view;
    VK_CHECK(vkCreateImageView(ctx.device(), &v, ctx.allocator(), &view));
    return view;
  };
  const VkImageUsageFlags viewable = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_STORAGE_BIT |
                                     VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT;
  if (!(usage & viewable)) {  // transfer-only images (readback staging) have no views
    ctx.set_name(image_, VK_OBJECT_TYPE_IMAGE, name);
    return;
  }
  view_ = make_view(0, mip_levels, 0, layers);
  if (mip_levels > 1)
    for (uint32_t m = 0; m < mip_levels; ++m) mip_views_.push_back(make_view(m, 1, 0, layers));
  if (layers > 1)
    for (uint32_t l = 0; l < layers; ++l) {
      VkImageViewCreateInfo v{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
      v.image = image_;
      v.viewType = VK_IMAGE_VIEW_TYPE_2D;
      v.format = format;
      v.subresourceRange = {aspect_, 0, 1, l, 1};
      VkImageView view;
      VK_CHECK(vkCreateImageView(ctx.device(), &v, ctx.allocator(), &view));
      layer_views_.push_back(view);
    }
  ctx.set_name(image_, VK_OBJECT_TYPE_IMAGE, name);
  ctx.set_name(view_, VK_OBJECT_TYPE_IMAGE_VIEW, name + " view");
}

Image& Image::operator=(Image&& o) noexcept {
  if (this != &o) {
    reset();
    ctx_ = o.ctx_;
    image_ = std::exchange(o.image_, VK_NULL_HANDLE);
    memory_ = std::exchange(o.memory_, VK_NULL_HANDLE);
    view_ = std::exchange(o.view_, VK_NULL_HANDLE);
    mip_views_ = std::move(o.mip_views_);
    layer_views_ = std::move(o.layer_views_);
    format_ = o.format_;
    usage_ = o.usage_;
    extent_ = o.extent_;
    aspect_ = o.aspect_;
    mip_levels_ = o.mip_levels_;
    layers_ = o.layers_;
    layout_ = o.layout_;
  }
  return *this;
}

void Image::reset() {
  if (!ctx_) return;
  const Context* ctx = ctx_;
  auto destroy = [ctx, mips = std::move(mip_views_), layers = std::move(layer_views_), view = view_, image = image_,
                  memory = memory_] {
    VkDevice d = ctx->device();
    for (VkImageView v : mips) vkDestroyImageView(d, v, ctx->allocator());
    for (VkImageView v : layers) vkDestroyImageView(d, v, ctx->allocator());
    if (view) vkDestroyImageView(d, view, ctx->allocator());
    if (image) vkDestroyImage(d, image, ctx->allocator());
    if (memory) {
      ctx->untrack_allocation(memory);
      ctx->free_memory(memory);
    }
  };
  // Frames still in flight may use it (Context::defer_releases).
  if (ctx->defers_releases() && (image_ || memory_)) ctx->defer_release(std::move(destroy));
  else destroy();
  mip_views_.clear();
  layer_views_.clear();
  view_ = VK_NULL_HANDLE;
  image_ = VK_NULL_HANDLE;
  memory_ = VK_NULL_HANDLE;
  layout_ = VK_IMAGE_LAYOUT_UNDEFINED;
}

void Image::transition(VkCommandBuffer cmd, VkImageLayout new_layout, VkPipelineStageFlags2 src_stage,
                       VkAccessFlags2 src_access, VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access) {
  VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
  b.srcStageMask = src_stage;
  b.srcAccessMask = src_access;
  b.dstStageMask = dst_stage;
  b.dstAccessMask = dst_access;
  b.oldLayout = layout_;
  b.newLayout = new_layout;
  b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image_;
  b.subresourceRange = {aspect_, 0, mip_levels_, 0, layers_};
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.imageMemoryBarrierCount = 1;
  dep.pImageMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &dep);
  layout_ = new_layout;
}

Sampler::Sampler(const Context& ctx, VkFilter filter, VkSamplerAddressMode address, const std::string& name,
                 bool depth_compare)
    : ctx_(&ctx) {
  VkSamplerCreateInfo info{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  info.magFilter = filter;
  info.minFilter = filter;
  info.mipmapMode = filter == VK_FILTER_LINEAR ? VK_SAMPLER_MIPMAP_MODE_LINEAR : VK_SAMPLER_MIPMAP_MODE_NEAREST;
  info.addressModeU = info.addressModeV = info.addressModeW = address;
  info.maxLod = VK_LOD_CLAMP_NONE;
  info.borderColor = VK_BORDER_COLOR_FLOAT_OPAQUE_WHITE;
  info.compareEnable = depth_compare;
  info.compareOp = VK_COMPARE_OP_GREATER_OR_EQUAL;
  VK_CHECK(vkCreateSampler(ctx.device(), &info, ctx.allocator(), &sampler_));
  ctx.set_name(sampler_, VK_OBJECT_TYPE_SAMPLER, name);
}

Sampler& Sampler::operator=(Sampler&& o) noexcept {
  if (this != &o) {
    reset();
    ctx_ = o.ctx_;
    sampler_ = std::exchange(o.sampler_, VK_NULL_HANDLE);
  }
  return *this;
}

void Sampler::reset() {
  if (ctx_ && sampler_) vkDestroySampler(ctx_->device(), sampler_, ctx_->allocator());
  sampler_ = VK_NULL_HANDLE;
}

void memory_barrier(VkCommandBuffer cmd, VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access,
                    VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access) {
  VkMemoryBarrier2 b{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
  b.srcStageMask = src_stage;
  b.srcAccessMask = src_access;
  b.dstStageMask = dst_stage;
  b.dstAccessMask = dst_access;
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.memoryBarrierCount = 1;
  dep.pMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &dep);
}

void full_barrier(VkCommandBuffer cmd) {
  memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
}

std::vector<uint8_t> read_image(const Context& ctx, Image& image, uint32_t texel_bytes) {
  const VkDeviceSize bytes = VkDeviceSize(image.extent().width) * image.extent().height * texel_bytes;
  Buffer staging(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true, "image readback");
  ctx.immediate_submit([&](VkCommandBuffer cmd) {
    const VkImageLayout original = image.layout();
    image.transition(cmd, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                     VK_ACCESS_2_MEMORY_WRITE_BIT, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    VkBufferImageCopy copy{};
    copy.imageSubresource = {image.aspect(), 0, 0, 1};
    copy.imageExtent = {image.extent().width, image.extent().height, 1};
    vkCmdCopyImageToBuffer(cmd, image.handle(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, staging.handle(), 1, &copy);
    if (original != VK_IMAGE_LAYOUT_UNDEFINED)
      image.transition(cmd, original, VK_PIPELINE_STAGE_2_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT,
                     VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
  });
  std::vector<uint8_t> out(bytes);
  std::memcpy(out.data(), staging.mapped(), bytes);
  return out;
}

}  // namespace engine::gpu
