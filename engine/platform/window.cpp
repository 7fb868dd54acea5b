#include "engine/platform/window.hpp"

#include <algorithm>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#define GLFW_INCLUDE_NONE
#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_vulkan.h>

#include "gpu/profiler.hpp"
#include "gpu/resources.hpp"

namespace engine::platform {

namespace {

// GLFW is process-global: the static extension query and every window share one initialisation,
// and it is torn down only when the last user lets go.
int g_glfw_users = 0;

std::string glfw_error_text() {
  const char* description = nullptr;
  glfwGetError(&description);
  std::string text = description ? description : "unknown error";
  // Callers promise one-line errors.
  std::replace(text.begin(), text.end(), '\n', ' ');
  return text;
}

void acquire_glfw() {
  if (g_glfw_users == 0 && glfwInit() != GLFW_TRUE)
    throw std::runtime_error("cannot open a window: GLFW initialisation failed (" + glfw_error_text() + ")");
  ++g_glfw_users;
}

void release_glfw() {
  if (g_glfw_users > 0 && --g_glfw_users == 0) glfwTerminate();
}

void check_imgui_vk(VkResult result) {
  if (result < 0) gpu::throw_vk_error(result, "ImGui Vulkan backend", __FILE__, __LINE__);
}

void image_barrier(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to,
                   VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access, VkPipelineStageFlags2 dst_stage,
                   VkAccessFlags2 dst_access) {
  VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
  b.srcStageMask = src_stage;
  b.srcAccessMask = src_access;
  b.dstStageMask = dst_stage;
  b.dstAccessMask = dst_access;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.imageMemoryBarrierCount = 1;
  dep.pImageMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &dep);
}

constexpr VkImageUsageFlags kSwapchainUsage =
    VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;

}  // namespace

struct Window::Impl {
  GLFWwindow* window = nullptr;
  bool glfw_acquired = false;
  float render_scale = 1.0f;
  gpu::Context* ctx = nullptr;

  VkSurfaceKHR surface = VK_NULL_HANDLE;
  VkSwapchainKHR swapchain = VK_NULL_HANDLE;
  VkSurfaceFormatKHR surface_format{};
  VkExtent2D extent{};
  uint32_t min_image_count = 2;
  std::vector<VkImage> images;
  std::vector<VkImageView> views;
  std::vector<VkFramebuffer> framebuffers;
  // Presentation may still be reading a render-finished semaphore until its image is acquired again,
  // so there is one per swapchain image; acquisition uses one per frame in flight.
  std::vector<VkSemaphore> render_finished;
  // One per frame in flight (the renderer's count): frame N records into slot N % count after
  // waiting for the slot's fence, i.e. for frame N - count.
  struct Slot {
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    VkFence fence = VK_NULL_HANDLE;  // created signalled: a slot never submitted does not block
    VkSemaphore image_available = VK_NULL_HANDLE;
  };
  std::vector<Slot> slots;
  uint64_t frames_submitted = 0;
  VkCommandPool command_pool = VK_NULL_HANDLE;
  bool swapchain_dirty = false;

  // ImGui 1.86's Vulkan backend only knows render passes.
  VkRenderPass ui_pass = VK_NULL_HANDLE;
  VkDescriptorPool ui_descriptors = VK_NULL_HANDLE;
  ImGuiContext* imgui = nullptr;
  bool imgui_glfw = false;
  bool imgui_vulkan = false;

  // A frame drawn after capture_next_frame is copied here (a presented image's contents cannot be
  // read back later); other frames skip the copy, a full-window readback a CPU device pays per frame.
  gpu::Buffer capture;
  VkExtent2D capture_extent{};
  bool capture_valid = false;
  bool capture_requested = false;
  // The slot of the latest submitted frame that copies into `capture`, until its fence is waited for.
  std::optional<size_t> capture_slot;

  VkDevice device() const { return ctx->device(); }
  // ImGui's backend keeps one vertex/index buffer set per "image" and reuses it that many frames
  // later, so both counts cover the most frames a renderer may have in flight.
  uint32_t ui_min_image_count() const { return std::max(min_image_count, Renderer::kMaxFramesInFlight); }

  void choose_surface_format();
  bool create_swapchain();
  void destroy_swapchain_views();
  void create_ui_pass();
  void init_imgui();
  void shutdown();
  void create_slots(uint32_t count);
  void destroy_slots();
  // Waits for the slot's last frame; the capture it made becomes readable.
  void wait_slot(size_t index);
  void record_present_part(VkCommandBuffer cmd, Renderer& renderer, uint32_t image_index, bool copy_to_capture);
};

void Window::Impl::create_slots(uint32_t count) {
  destroy_slots();
  slots.resize(count);
  for (Slot& slot : slots) {
    VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    alloc.commandPool = command_pool;
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = 1;
    VK_CHECK(vkAllocateCommandBuffers(device(), &alloc, &slot.cmd));
    VkSemaphoreCreateInfo sem_info{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    VK_CHECK(vkCreateSemaphore(device(), &sem_info, nullptr, &slot.image_available));
    VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    fence_info.flags = VK_FENCE_CREATE_SIGNALED_BIT;
    VK_CHECK(vkCreateFence(device(), &fence_info, nullptr, &slot.fence));
  }
  frames_submitted = 0;
}

// Only with the device idle.
void Window::Impl::destroy_slots() {
  for (Slot& slot : slots) {
    if (slot.cmd) vkFreeCommandBuffers(device(), command_pool, 1, &slot.cmd);
    if (slot.fence) vkDestroyFence(device(), slot.fence, nullptr);
    if (slot.image_available) vkDestroySemaphore(device(), slot.image_available, nullptr);
  }
  slots.clear();
  if (capture_slot) capture_valid = true;  // the device is idle: the copy landed
  capture_slot.reset();
}

void Window::Impl::wait_slot(size_t index) {
  VK_CHECK(vkWaitForFences(device(), 1, &slots[index].fence, VK_TRUE, UINT64_MAX));
  if (capture_slot == index) {
    capture_valid = true;
    capture_slot.reset();
  }
}

void Window::Impl::choose_surface_format() {
  VkPhysicalDevice gpu = ctx->physical_device();
  uint32_t count = 0;
  VK_CHECK(vkGetPhysicalDeviceSurfaceFormatsKHR(gpu, surface, &count, nullptr));
  std::vector<VkSurfaceFormatKHR> formats(count);
  VK_CHECK(vkGetPhysicalDeviceSurfaceFormatsKHR(gpu, surface, &count, formats.data()));
  // UNORM, not sRGB: the renderer's output is already display-encoded and the blit copies it as is.
  for (VkFormat wanted : {VK_FORMAT_B8G8R8A8_UNORM, VK_FORMAT_R8G8B8A8_UNORM}) {
    for (const auto& f : formats) {
      if (f.format != wanted || f.colorSpace != VK_COLOR_SPACE_SRGB_NONLINEAR_KHR) continue;
      VkFormatProperties props;
      vkGetPhysicalDeviceFormatProperties(gpu, f.format, &props);
      const VkFormatFeatureFlags need = VK_FORMAT_FEATURE_BLIT_DST_BIT | VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BLEND_BIT;
      if ((props.optimalTilingFeatures & need) != need) continue;
      surface_format = f;
      return;
    }
  }
  throw std::runtime_error("window surface offers neither B8G8R8A8_UNORM nor R8G8B8A8_UNORM");
}

// Returns false when the surface currently has no area (minimised); the caller retries later.
bool Window::Impl::create_swapchain() {
  VkPhysicalDevice gpu = ctx->physical_device();
  VkSurfaceCapabilitiesKHR caps;
  VK_CHECK(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(gpu, surface, &caps));
  VkExtent2D size = caps.currentExtent;
  if (size.width == UINT32_MAX) {
    int w = 0, h = 0;
    glfwGetFramebufferSize(window, &w, &h);
    size.width = std::clamp(uint32_t(std::max(w, 0)), caps.minImageExtent.width, caps.maxImageExtent.width);
    size.height = std::clamp(uint32_t(std::max(h, 0)), caps.minImageExtent.height, caps.maxImageExtent.height);
  }
  if (size.width == 0 || size.height == 0) return false;
  if ((caps.supportedUsageFlags & kSwapchainUsage) != kSwapchainUsage)
    throw std::runtime_error("window surface does not support transfer and colour-attachment use of its images");

  uint32_t image_count = std::max(caps.minImageCount + 1, 2u);
  if (caps.maxImageCount > 0) image_count = std::min(image_count, caps.maxImageCount);

  VkSwapchainCreateInfoKHR info{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
  info.surface = surface;
  info.minImageCount = image_count;
  info.imageFormat = surface_format.format;
  info.imageColorSpace = surface_format.colorSpace;
  info.imageExtent = size;
  info.imageArrayLayers = 1;
  info.imageUsage = kSwapchainUsage;
  info.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
  info.preTransform = caps.currentTransform;
  info.compositeAlpha = (caps.supportedCompositeAlpha & VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR)
                            ? VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR
                            : VkCompositeAlphaFlagBitsKHR(caps.supportedCompositeAlpha & -caps.supportedCompositeAlpha);
  info.presentMode = VK_PRESENT_MODE_FIFO_KHR;  // always available, and paces the loop to the display
  info.clipped = VK_TRUE;
  info.oldSwapchain = swapchain;

  // Nothing may still use the old images, views or semaphores once they are replaced.
  vkDeviceWaitIdle(device());
  VkSwapchainKHR created = VK_NULL_HANDLE;
  VK_CHECK(vkCreateSwapchainKHR(device(), &info, nullptr, &created));
  destroy_swapchain_views();
  if (swapchain) vkDestroySwapchainKHR(device(), swapchain, nullptr);
  swapchain = created;
  extent = size;
  min_image_count = std::max(caps.minImageCount, 2u);

  uint32_t count = 0;
  VK_CHECK(vkGetSwapchainImagesKHR(device(), swapchain, &count, nullptr));
  images.resize(count);
  VK_CHECK(vkGetSwapchainImagesKHR(device(), swapchain, &count, images.data()));
  for (uint32_t i = 0; i < count; ++i) {
    VkImageViewCreateInfo view_info{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    view_info.image = images[i];
    view_info.viewType = VK_IMAGE_VIEW_TYPE_2D;
    view_info.format = surface_format.format;
    view_info.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    VkImageView view = VK_NULL_HANDLE;
    VK_CHECK(vkCreateImageView(device(), &view_info, nullptr, &view));
    views.push_back(view);
    VkFramebufferCreateInfo fb_info{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fb_info.renderPass = ui_pass;
    fb_info.attachmentCount = 1;
    fb_info.pAttachments = &view;
    fb_info.width = size.width;
    fb_info.height = size.height;
    fb_info.layers = 1;
    VkFramebuffer fb = VK_NULL_HANDLE;
    VK_CHECK(vkCreateFramebuffer(device(), &fb_info, nullptr, &fb));
    framebuffers.push_back(fb);
    VkSemaphoreCreateInfo sem_info{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    VkSemaphore sem = VK_NULL_HANDLE;
    VK_CHECK(vkCreateSemaphore(device(), &sem_info, nullptr, &sem));
    render_finished.push_back(sem);
    ctx->set_name(images[i], VK_OBJECT_TYPE_IMAGE, "swapchain image " + std::to_string(i));
  }

  capture = gpu::Buffer(*ctx, VkDeviceSize(size.width) * size.height * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true,
                        "presented frame copy");
  capture_extent = size;
  capture_valid = false;
  capture_slot.reset();  // a copy still pending went into the buffer just replaced
  swapchain_dirty = false;
  if (imgui_vulkan) ImGui_ImplVulkan_SetMinImageCount(ui_min_image_count());
  return true;
}

void Window::Impl::destroy_swapchain_views() {
  for (VkFramebuffer fb : framebuffers) vkDestroyFramebuffer(device(), fb, nullptr);
  for (VkImageView view : views) vkDestroyImageView(device(), view, nullptr);
  for (VkSemaphore sem : render_finished) vkDestroySemaphore(device(), sem, nullptr);
  framebuffers.clear();
  views.clear();
  render_finished.clear();
  images.clear();
}

void Window::Impl::create_ui_pass() {
  // The scene has already been blitted in, so the overlay loads it; the pass leaves the image ready
  // for the copy into `capture`.
  VkAttachmentDescription color{};
  color.format = surface_format.format;
  color.samples = VK_SAMPLE_COUNT_1_BIT;
  color.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
  color.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  color.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  color.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  color.initialLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
  color.finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  VkAttachmentReference ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  VkSubpassDescription subpass{};
  subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  subpass.colorAttachmentCount = 1;
  subpass.pColorAttachments = &ref;
  VkSubpassDependency deps[2]{};
  deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
  deps[0].dstSubpass = 0;
  deps[0].srcStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
  deps[0].srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  deps[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  deps[1].srcSubpass = 0;
  deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
  deps[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
  deps[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  deps[1].dstStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
  deps[1].dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  VkRenderPassCreateInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  info.attachmentCount = 1;
  info.pAttachments = &color;
  info.subpassCount = 1;
  info.pSubpasses = &subpass;
  info.dependencyCount = 2;
  info.pDependencies = deps;
  VK_CHECK(vkCreateRenderPass(device(), &info, nullptr, &ui_pass));
  ctx->set_name(ui_pass, VK_OBJECT_TYPE_RENDER_PASS, "imgui overlay pass");
}

void Window::Impl::init_imgui() {
  VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 16}};
  VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pool_info.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
  pool_info.maxSets = 16;
  pool_info.poolSizeCount = 1;
  pool_info.pPoolSizes = sizes;
  VK_CHECK(vkCreateDescriptorPool(device(), &pool_info, nullptr, &ui_descriptors));

  IMGUI_CHECKVERSION();
  imgui = ImGui::CreateContext();
  ImGui::SetCurrentContext(imgui);
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // no imgui.ini dropped into whatever directory the program runs in
  ImGui::StyleColorsDark();
  if (!ImGui_ImplGlfw_InitForVulkan(window, true)) throw std::runtime_error("ImGui GLFW backend failed to start");
  imgui_glfw = true;

  ImGui_ImplVulkan_InitInfo init{};
  init.Instance = ctx->instance();
  init.PhysicalDevice = ctx->physical_device();
  init.Device = device();
  init.QueueFamily = ctx->queue_family();
  init.Queue = ctx->queue();
  init.PipelineCache = VK_NULL_HANDLE;
  init.DescriptorPool = ui_descriptors;
  init.Subpass = 0;
  init.MinImageCount = ui_min_image_count();
  init.ImageCount = std::max<uint32_t>(uint32_t(images.size()), ui_min_image_count());
  init.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
  init.Allocator = nullptr;
  init.CheckVkResultFn = check_imgui_vk;
  if (!ImGui_ImplVulkan_Init(&init, ui_pass)) throw std::runtime_error("ImGui Vulkan backend failed to start");
  imgui_vulkan = true;

  ctx->immediate_submit([](VkCommandBuffer cmd) { ImGui_ImplVulkan_CreateFontsTexture(cmd); });
  ImGui_ImplVulkan_DestroyFontUploadObjects();
}

void Window::Impl::shutdown() {
  if (ctx) vkDeviceWaitIdle(device());
  if (imgui) {
    ImGui::SetCurrentContext(imgui);
    if (imgui_vulkan) ImGui_ImplVulkan_Shutdown();
    if (imgui_glfw) ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext(imgui);
    imgui = nullptr;
    imgui_vulkan = imgui_glfw = false;
  }
  if (ctx) {
    capture.reset();
    destroy_swapchain_views();
    if (swapchain) vkDestroySwapchainKHR(device(), swapchain, nullptr);
    if (ui_descriptors) vkDestroyDescriptorPool(device(), ui_descriptors, nullptr);
    if (ui_pass) vkDestroyRenderPass(device(), ui_pass, nullptr);
    destroy_slots();
    if (command_pool) vkDestroyCommandPool(device(), command_pool, nullptr);
    if (surface) vkDestroySurfaceKHR(ctx->instance(), surface, nullptr);
    swapchain = VK_NULL_HANDLE;
    ui_descriptors = VK_NULL_HANDLE;
    ui_pass = VK_NULL_HANDLE;
    command_pool = VK_NULL_HANDLE;
    surface = VK_NULL_HANDLE;
    ctx = nullptr;
  }
  if (window) {
    glfwDestroyWindow(window);
    window = nullptr;
  }
  if (glfw_acquired) {
    release_glfw();
    glfw_acquired = false;
  }
}

void Window::Impl::record_present_part(VkCommandBuffer cmd, Renderer& renderer, uint32_t image_index,
                                       bool copy_to_capture) {
  VkImage target = images[image_index];
  // The first sync scope matches the acquire semaphore's wait stage, so the layout change waits for it.
  image_barrier(cmd, target, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, 0, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                VK_ACCESS_2_TRANSFER_WRITE_BIT);

  // The renderer finishes with a full barrier, so its output is readable here. The blit also swaps
  // RGBA to BGRA when the swapchain wants that order.
  const VkExtent2D src = renderer.extent();
  VkImageBlit blit{};
  blit.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  blit.srcOffsets[1] = {int32_t(src.width), int32_t(src.height), 1};
  blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  blit.dstOffsets[1] = {int32_t(extent.width), int32_t(extent.height), 1};
  const bool same_size = src.width == extent.width && src.height == extent.height;
  {
    // The window's own passes are timed with the renderer's, so the panel shows what a frame costs at
    // the window's size (on a CPU device this part does not shrink with the render scale).
    gpu::ScopedGpuRegion region(*ctx, renderer.profiler(), cmd, "window_blit");
    vkCmdBlitImage(cmd, renderer.output().handle(), VK_IMAGE_LAYOUT_GENERAL, target,
                   VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit, same_size ? VK_FILTER_NEAREST : VK_FILTER_LINEAR);
  }
  // The next frame's lighting pass overwrites the output (and the G-buffer pass of a frame in flight
  // behind this one runs after this point on the queue).
  gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, 0, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0);

  {
    gpu::ScopedGpuRegion region(*ctx, renderer.profiler(), cmd, "window_ui");
    VkRenderPassBeginInfo begin{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    begin.renderPass = ui_pass;
    begin.framebuffer = framebuffers[image_index];
    begin.renderArea = {{0, 0}, extent};
    vkCmdBeginRenderPass(cmd, &begin, VK_SUBPASS_CONTENTS_INLINE);
    ImGui_ImplVulkan_RenderDrawData(ImGui::GetDrawData(), cmd);
    vkCmdEndRenderPass(cmd);
  }

  if (copy_to_capture) {
    VkBufferImageCopy copy{};
    copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.imageExtent = {extent.width, extent.height, 1};
    vkCmdCopyImageToBuffer(cmd, target, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, capture.handle(), 1, &copy);
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
  }
  // Presentation is ordered by the render-finished semaphore, which waits for all commands.
  image_barrier(cmd, target, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
                VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, 0, VK_PIPELINE_STAGE_2_NONE, 0);
}

Window::Window(const WindowOptions& options) : impl_(std::make_unique<Impl>()) {
  acquire_glfw();
  impl_->glfw_acquired = true;
  if (glfwVulkanSupported() != GLFW_TRUE) {
    impl_->shutdown();
    throw std::runtime_error("cannot open a window: GLFW found no Vulkan loader");
  }
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
  impl_->window = glfwCreateWindow(int(std::max(options.width, 1u)), int(std::max(options.height, 1u)),
                                   options.title.c_str(), nullptr, nullptr);
  if (!impl_->window) {
    const std::string reason = glfw_error_text();
    impl_->shutdown();
    throw std::runtime_error("cannot open a window: " + reason);
  }
  glfwSetWindowUserPointer(impl_->window, impl_.get());
  glfwSetFramebufferSizeCallback(impl_->window, [](GLFWwindow* w, int, int) {
    static_cast<Impl*>(glfwGetWindowUserPointer(w))->swapchain_dirty = true;
  });
}

Window::~Window() {
  if (impl_) impl_->shutdown();
}

std::vector<const char*> Window::required_instance_extensions() {
  // GLFW owns the strings only until it terminates; keep copies that live as long as the program.
  static std::vector<std::string> names;
  if (names.empty()) {
    acquire_glfw();
    uint32_t count = 0;
    const char** list = glfwVulkanSupported() == GLFW_TRUE ? glfwGetRequiredInstanceExtensions(&count) : nullptr;
    if (!list) {
      const std::string reason = glfw_error_text();
      release_glfw();
      throw std::runtime_error("window system offers no Vulkan surface extensions: " + reason);
    }
    for (uint32_t i = 0; i < count; ++i) names.emplace_back(list[i]);
    release_glfw();
  }
  std::vector<const char*> out;
  for (const auto& n : names) out.push_back(n.c_str());
  return out;
}

void Window::attach(gpu::Context& ctx) {
  Impl& s = *impl_;
  if (s.ctx) throw std::logic_error("window is already attached to a context");
  s.ctx = &ctx;
  VK_CHECK(glfwCreateWindowSurface(ctx.instance(), s.window, nullptr, &s.surface));
  VkBool32 present_ok = VK_FALSE;
  VK_CHECK(vkGetPhysicalDeviceSurfaceSupportKHR(ctx.physical_device(), ctx.queue_family(), s.surface, &present_ok));
  if (!present_ok) throw std::runtime_error("the engine's queue cannot present to this window");

  VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pool_info.queueFamilyIndex = ctx.queue_family();
  VK_CHECK(vkCreateCommandPool(ctx.device(), &pool_info, nullptr, &s.command_pool));
  s.create_slots(1);  // draw_frame follows the renderer's frames in flight

  s.choose_surface_format();
  s.create_ui_pass();
  // A window that starts minimised gets its swapchain on the first visible frame.
  s.create_swapchain();
  s.init_imgui();
}

bool Window::should_close() const { return glfwWindowShouldClose(impl_->window) == GLFW_TRUE; }

void Window::poll_events() { glfwPollEvents(); }

VkExtent2D Window::framebuffer_extent() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(impl_->window, &w, &h);
  return {uint32_t(std::max(w, 0)), uint32_t(std::max(h, 0))};
}

void Window::set_size(uint32_t width, uint32_t height) {
  glfwSetWindowSize(impl_->window, int(std::max(width, 1u)), int(std::max(height, 1u)));
  impl_->swapchain_dirty = true;
}

void Window::set_render_scale(float scale) { impl_->render_scale = std::clamp(scale, 0.1f, 1.0f); }

float Window::render_scale() const { return impl_->render_scale; }

VkExtent2D Window::render_extent(VkExtent2D fb) const {
  const float k = impl_->render_scale;
  return {std::max(1u, uint32_t(float(fb.width) * k + 0.5f)), std::max(1u, uint32_t(float(fb.height) * k + 0.5f))};
}

GLFWwindow* Window::native_handle() const { return impl_->window; }

bool Window::draw_frame(Renderer& renderer, const std::function<void()>& build_ui, float dt) {
  Impl& s = *impl_;
  if (!s.ctx) throw std::logic_error("draw_frame before attach");
  const VkExtent2D fb = framebuffer_extent();
  if (fb.width == 0 || fb.height == 0 || glfwGetWindowAttrib(s.window, GLFW_ICONIFIED)) {
    // Minimised: sleep until something happens instead of spinning.
    glfwWaitEventsTimeout(0.1);
    return false;
  }
  const uint32_t in_flight = renderer.frames_in_flight();
  if (s.slots.size() != in_flight) {
    // Slots are replaced only with nothing in flight.
    renderer.finish_frames();
    s.create_slots(in_flight);
  }
  if (s.swapchain_dirty || !s.swapchain || fb.width != s.extent.width || fb.height != s.extent.height) {
    const bool created = s.create_swapchain();  // waits for the device
    renderer.finish_frames();                    // so the frames in flight have completed: say so
    if (!created) {
      glfwWaitEventsTimeout(0.1);
      return false;
    }
  }

  // Frame N reuses the slot of frame N - F: its command buffer, acquire semaphore and, in the
  // renderer, the per-frame data update() writes. Once its fence signals, that frame is done.
  const size_t slot_index = size_t(s.frames_submitted % in_flight);
  Impl::Slot& slot = s.slots[slot_index];
  s.wait_slot(slot_index);
  while (renderer.frames_pending() >= in_flight) renderer.after_frame();

  uint32_t image_index = 0;
  const VkResult acquired =
      vkAcquireNextImageKHR(s.device(), s.swapchain, UINT64_MAX, slot.image_available, VK_NULL_HANDLE, &image_index);
  if (acquired == VK_ERROR_OUT_OF_DATE_KHR) {
    // The semaphore was not signalled; nothing to undo.
    s.swapchain_dirty = true;
    return false;
  }
  if (acquired != VK_SUBOPTIMAL_KHR) VK_CHECK(acquired);
  // Suboptimal still signalled the semaphore, so this frame goes ahead and the swapchain is rebuilt after.
  if (acquired == VK_SUBOPTIMAL_KHR) s.swapchain_dirty = true;

  renderer.resize(render_extent(s.extent));  // waits for the device itself when the size changes
  renderer.update(dt);

  ImGui::SetCurrentContext(s.imgui);
  ImGui_ImplVulkan_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  if (build_ui) build_ui();
  ImGui::Render();

  VK_CHECK(vkResetCommandBuffer(slot.cmd, 0));
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VK_CHECK(vkBeginCommandBuffer(slot.cmd, &begin));
  renderer.record(slot.cmd);
  const bool capturing = s.capture_requested;
  s.record_present_part(slot.cmd, renderer, image_index, capturing);
  VK_CHECK(vkEndCommandBuffer(slot.cmd));

  VkSemaphoreSubmitInfo wait{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  wait.semaphore = slot.image_available;
  wait.stageMask = VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT;  // the first touch of the image is the blit
  VkSemaphoreSubmitInfo signal{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  signal.semaphore = s.render_finished[image_index];
  signal.stageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
  VkCommandBufferSubmitInfo cmd_info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO};
  cmd_info.commandBuffer = slot.cmd;
  VkSubmitInfo2 submit{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
  submit.waitSemaphoreInfoCount = 1;
  submit.pWaitSemaphoreInfos = &wait;
  submit.commandBufferInfoCount = 1;
  submit.pCommandBufferInfos = &cmd_info;
  submit.signalSemaphoreInfoCount = 1;
  submit.pSignalSemaphoreInfos = &signal;
  VK_CHECK(vkResetFences(s.device(), 1, &slot.fence));
  VK_CHECK(vkQueueSubmit2(s.ctx->queue(), 1, &submit, slot.fence));
  ++s.frames_submitted;
  if (capturing) {
    // Readable once this slot's fence has been waited for (read_last_frame waits if need be).
    s.capture_slot = slot_index;
    s.capture_requested = false;
  }

  VkPresentInfoKHR present{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
  present.waitSemaphoreCount = 1;
  present.pWaitSemaphores = &s.render_finished[image_index];
  present.swapchainCount = 1;
  present.pSwapchains = &s.swapchain;
  present.pImageIndices = &image_index;
  const VkResult presented = vkQueuePresentKHR(s.ctx->queue(), &present);
  if (presented == VK_ERROR_OUT_OF_DATE_KHR || presented == VK_SUBOPTIMAL_KHR)
    s.swapchain_dirty = true;
  else
    VK_CHECK(presented);
  // No wait here: the next frame waits for its own slot, F frames back.
  return true;
}

void Window::capture_next_frame() { impl_->capture_requested = true; }

std::vector<uint8_t> Window::read_last_frame(uint32_t& width, uint32_t& height) {
  Impl& s = *impl_;
  // The latest capturing frame may still be in flight.
  if (s.capture_slot) s.wait_slot(*s.capture_slot);
  if (!s.capture_valid) {
    width = height = 0;
    return {};
  }
  width = s.capture_extent.width;
  height = s.capture_extent.height;
  const size_t texels = size_t(width) * height;
  std::vector<uint8_t> out(texels * 4);
  std::memcpy(out.data(), s.capture.mapped(), out.size());
  const bool bgra = s.surface_format.format == VK_FORMAT_B8G8R8A8_UNORM;
  for (size_t i = 0; i < texels; ++i) {
    uint8_t* p = &out[i * 4];
    if (bgra) std::swap(p[0], p[2]);
    // The window is presented opaque; the overlay's blending leaves arbitrary alpha behind.
    p[3] = 255;
  }
  return out;
}

}  // namespace engine::platform
