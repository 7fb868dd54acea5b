// The raw-Vulkan host (sample_game/vulkan_host) against the Embree reference from its own shading
// points, with frames in flight, and the module's refusals of bad host input.
#include <cstdlib>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <cstring>
#include <glm/gtc/type_ptr.hpp>

#include "device.hpp"
#include "reference/comparator.hpp"
#include "reference/embree_tracer.hpp"
#include "reference/synthetic.hpp"
#include "vulkan_host.hpp"

namespace {

// The device the host tests run on: ENGINE_DEVICE (the lent GPU: gpu), else lavapipe as in CTest.
std::string test_device() {
  const char* device = std::getenv("ENGINE_DEVICE");
  return device && *device ? device : "lavapipe";
}

using vulkan_host::Result;

// The host's shading points of a captured frame, rebuilt on the CPU the way the module's inputs pass
// builds them (shaders/shadows/host_inputs.comp): position from the standard depth, the decoded
// shading normal turned toward the camera (no geometric normals given: it also pushes the ray
// origins), facing `light` (a sun; local lights are faced by the reference itself) decided from it.
reference::ShadingPoints shading_points(const vulkan_host::FrameCapture& f, uint32_t width, uint32_t height,
                                        const vulkan_host::HostLight& light) {
  reference::ShadingPoints sp;
  sp.resize(width, height);
  glm::mat4 flip(1.0f);  // z' = w - z: the module's reversed depth
  flip[2][2] = -1.0f;
  flip[3][2] = 1.0f;
  sp.inv_view_proj = glm::make_mat4(f.inverse_view_projection.data()) * flip;
  sp.facing_from_w = light.kind == "sun";
  const glm::vec4 eye_h = glm::make_mat4(f.inverse_view_projection.data()) * glm::vec4(0, 0, 1, 0);  // w = 0 in clip
  const glm::vec3 eye = glm::vec3(eye_h) / eye_h.w;
  sp.eye = eye;  // the shadow-ray offset grows with the distance from the camera
  const glm::vec3 to_light = -glm::make_vec3(light.direction.data());
  for (uint32_t y = 0; y < height; ++y)
    for (uint32_t x = 0; x < width; ++x) {
      const size_t i = sp.index(x, y);
      if (f.depth[i] >= 1.0f) continue;  // background
      const glm::vec2 ndc = (glm::vec2(x, y) + 0.5f) / glm::vec2(width, height) * 2.0f - 1.0f;
      const glm::vec4 w = sp.inv_view_proj * glm::vec4(ndc, 1.0f - f.depth[i], 1.0f);
      const glm::vec3 p = glm::vec3(w) / w.w;
      glm::vec3 n = glm::normalize(glm::make_vec3(&f.normals[3 * i]));
      if (glm::dot(n, eye - p) < 0.0f) n = -n;
      sp.position[i] = glm::vec4(p, 1.0f);
      sp.normal[i] = glm::vec4(n, glm::dot(n, to_light) > 0.0f ? 1.0f : 0.0f);
    }
  return sp;
}

// Light `l` of a captured frame against Embree tracing the host's casters of that frame.
reference::Comparison compare_with_embree(const vulkan_host::FrameCapture& f, uint32_t width, uint32_t height,
                                          size_t l, uint32_t spp) {
  auto mesh = std::make_shared<engine::MeshData>();
  mesh->name = "host casters";
  for (size_t i = 0; i < f.caster_triangles.size(); i += 3) {
    mesh->vertices.push_back({glm::make_vec3(&f.caster_triangles[i]), glm::vec3(0.0f), glm::vec2(0.0f)});
    mesh->indices.push_back(uint32_t(i / 3));
  }
  mesh->compute_bounds();
  engine::Registry registry;
  reference::add_mesh_entity(registry, mesh, glm::mat4(1.0f));
  const reference::EmbreeTracer tracer(registry);
  const vulkan_host::HostLight& light = f.lights.at(l);
  const reference::ShadingPoints sp = shading_points(f, width, height, light);
  std::vector<float> expected;
  if (light.kind == "sun") {
    const glm::vec3 direction = glm::make_vec3(light.direction.data());
    expected = spp == 1 ? tracer.visibility_1spp(sp, direction) : tracer.visibility_32spp(sp, direction);
  } else {
    reference::LocalLight local;
    local.position = glm::make_vec3(light.position.data());
    local.range = light.range;
    local.spot = light.kind == "spot";
    local.spot_direction = glm::make_vec3(light.direction.data());
    local.cos_outer = local.spot ? std::cos(light.outer_cone) : -1.0f;
    expected = spp == 1 ? tracer.visibility_1spp(sp, local) : tracer.visibility_32spp(sp, local);
  }
  std::vector<float> actual = f.visibility.at(l);
  for (size_t i = 0; i < actual.size(); ++i)
    if (!sp.covered(i)) actual[i] = -1.0f;
  return reference::compare_visibility(actual, expected);
}
reference::Comparison compare_with_embree(const Result& r, uint32_t spp) {
  return compare_with_embree(r.frames.back(), r.width, r.height, 0, spp);
}

vulkan_host::Options options(const std::string& mode, uint32_t view, uint32_t spp) {
  vulkan_host::Options o;
  o.width = o.height = 256;
  o.mode = mode;
  o.view = view;
  o.spp = spp;
  o.device = test_device();
  o.validation = true;
  return o;
}

struct MatchCase {
  std::string mode;
  uint32_t view, spp;
};
void PrintTo(const MatchCase& c, std::ostream* os) { *os << c.mode << " view " << c.view << " " << c.spp << " spp"; }

class HostMatchesEmbree : public ::testing::TestWithParam<MatchCase> {};

TEST_P(HostMatchesEmbree, FromItsOwnShadingPoints) {
  const MatchCase c = GetParam();
  const Result r = vulkan_host::run(options(c.mode, c.view, c.spp));
  EXPECT_EQ(r.validation_messages, 0u);
  const reference::Comparison cmp = compare_with_embree(r, c.spp);
  std::printf("[ measure ] %s view %u %u spp: %llu pixels, mismatch %.6f (%llu), coverage MAE %.6f\n", c.mode.c_str(),
              c.view, c.spp, (unsigned long long)cmp.pixels, cmp.mismatch_rate, (unsigned long long)cmp.mismatched,
              cmp.coverage_mae);
  EXPECT_GT(cmp.pixels, 256u * 256u / 4);
  EXPECT_EQ(cmp.coverage_disagreements, 0u);
  if (c.spp == 1) EXPECT_LE(cmp.mismatch_rate, 0.0002);
  else EXPECT_LE(cmp.coverage_mae, 1.0e-3);  // the sun suite's bound (measured: under 1e-4)
}

std::vector<MatchCase> match_cases() {
  std::vector<MatchCase> cases;
  for (const char* mode : {"izb", "izb+csm", "hybrid"})
    for (uint32_t view : {0u, 1u})
      for (uint32_t spp : {1u, 32u}) cases.push_back({mode, view, spp});
  return cases;
}
INSTANTIATE_TEST_SUITE_P(Modes, HostMatchesEmbree, ::testing::ValuesIn(match_cases()), [](const auto& info) {
  std::string mode = info.param.mode;
  for (char& ch : mode)
    if (ch == '+') ch = '_';
  return mode + "_view" + std::to_string(info.param.view) + "_" + std::to_string(info.param.spp) + "spp";
});

// Every light of every captured frame against Embree, within the sun suite's bounds: 1 spp mismatch
// within 0.02 %, 32 spp coverage MAE within 1e-3, and no pixel covered in one and not the other.
void expect_every_frame_matches(const Result& r, uint32_t spp, size_t frames) {
  ASSERT_EQ(r.frames.size(), frames);
  for (const vulkan_host::FrameCapture& f : r.frames)
    for (size_t l = 0; l < f.lights.size(); ++l) {
      SCOPED_TRACE(testing::Message() << "frame " << f.frame << ", light " << l << " (" << f.lights[l].kind << ")");
      const reference::Comparison cmp = compare_with_embree(f, r.width, r.height, l, spp);
      std::printf("[ measure ] frame %u %-5s %u spp: %llu pixels, %llu lit, mismatch %.6f (%llu), coverage MAE %.6f\n", f.frame,
                  f.lights[l].kind.c_str(), spp, (unsigned long long)cmp.pixels,
                  (unsigned long long)std::count(f.visibility[l].begin(), f.visibility[l].end(), 1.0f), cmp.mismatch_rate,
                  (unsigned long long)cmp.mismatched, cmp.coverage_mae);
      EXPECT_GT(cmp.pixels, uint64_t(r.width) * r.height / 4);
      EXPECT_EQ(cmp.coverage_disagreements, 0u);
      if (spp == 1) EXPECT_LE(cmp.mismatch_rate, 0.0002);
      else EXPECT_LE(cmp.coverage_mae, 1.0e-3);
    }
}

// 1, 2, 3 and 8 frames in flight, the caster moving every frame, every frame captured and compared, and
// frame_completed() called for each frame the host has waited for: izb+csm's automatic CSM choice
// measures on the GPU, comes back, and the prepass runs and culls. No validation message. CTest's
// `syncval.host_frames_in_flight` runs these under synchronization validation.
class HostFramesInFlight : public ::testing::TestWithParam<uint32_t> {};

TEST_P(HostFramesInFlight, EveryFrameOfAMovingCasterMatchesTheReference) {
  vulkan_host::Options o = options("izb+csm", 0, 1);
  o.frames_in_flight = GetParam();
  o.frames = o.frames_in_flight + 4;
  o.capture_every_frame = true;
  const Result r = vulkan_host::run(o);
  EXPECT_EQ(r.validation_messages, 0u);
  expect_every_frame_matches(r, 1, o.frames);
  // The caster moves: consecutive frames' shadows differ.
  for (size_t k = 1; k < r.frames.size(); ++k) EXPECT_NE(r.frames[k].visibility[0], r.frames[k - 1].visibility[0]);
  std::printf("[ measure ] %u in flight: csm %s, %llu points culled\n", o.frames_in_flight, r.csm_status.c_str(),
              (unsigned long long)r.csm_culled);
  EXPECT_EQ(r.csm_status, "ran");
  EXPECT_GT(r.csm_culled, 0u);
}
INSTANTIATE_TEST_SUITE_P(Slots, HostFramesInFlight, ::testing::Values(1u, 2u, 3u, 8u),
                         [](const auto& info) { return std::to_string(info.param) + "_in_flight"; });

// A sun that turns every frame and a spot and a point light, all in one record(): every light of every
// frame, frame 0 included, matches the reference. The sun's techniques read a "faces the light" bit the
// host inputs pass writes; decided from another light's direction (the previous record's last light,
// or the default on the first frame), side faces would come out shadowed and a moving sun a frame late.
struct LightsCase {
  std::string mode;
  uint32_t spp;
};
void PrintTo(const LightsCase& c, std::ostream* os) { *os << c.mode << " " << c.spp << " spp"; }
class HostLights : public ::testing::TestWithParam<LightsCase> {};

TEST_P(HostLights, EveryLightOfEveryFrameMatchesTheReference) {
  vulkan_host::Options o = options(GetParam().mode, 0, GetParam().spp);
  o.lights = {"sun", "spot", "point"};
  o.moving_sun = true;
  o.frames = 4;
  o.frames_in_flight = 2;
  o.capture_every_frame = true;
  const Result r = vulkan_host::run(o);
  EXPECT_EQ(r.validation_messages, 0u);
  expect_every_frame_matches(r, o.spp, o.frames);
}
INSTANTIATE_TEST_SUITE_P(Modes, HostLights,
                         ::testing::Values(LightsCase{"izb", 1}, LightsCase{"izb+csm", 1}, LightsCase{"izb", 32}),
                         [](const auto& info) {
                           return (info.param.mode == "izb" ? std::string("izb") : std::string("izb_csm")) + "_" +
                                  std::to_string(info.param.spp) + "spp";
                         });

// ----- Bad host input: one-line shadows::Error naming the argument, nothing recorded, no message.

class HostBadInput : public ::testing::Test {
 protected:
  static constexpr VkExtent2D kExtent{64, 64};
  void SetUp() override {
    device_ = std::make_unique<vulkan_host::Device>(vulkan_host::DeviceOptions{.device = test_device(), .validation = true});
    shadows::Settings settings;
    settings.technique = shadows::Technique::Izb;
    module_ = shadows::Context::create(device_->context_desc(2, settings));
    const VkImageUsageFlags sampled = VK_IMAGE_USAGE_SAMPLED_BIT;
    depth_ = make(kExtent, VK_FORMAT_D24_UNORM_S8_UINT, sampled | VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT);
    normals_ = make(kExtent, VK_FORMAT_R16G16_SNORM, sampled | VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT);
    output_ = make(kExtent, VK_FORMAT_R8_UNORM,
                   VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT);
    readback_ = vulkan_host::make_buffer(*device_, kExtent.width * kExtent.height, VK_BUFFER_USAGE_TRANSFER_DST_BIT);
    VkCommandPoolCreateInfo pool{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool.queueFamilyIndex = device_->family;
    vulkan_host::check(vkCreateCommandPool(device_->device, &pool, nullptr, &pool_), "vkCreateCommandPool");
    // The output holds 0.25 (64/255) before any frame: a recorded module pass would change it.
    submit([&](VkCommandBuffer cmd) {
      vulkan_host::image_barrier(cmd, output_, VK_PIPELINE_STAGE_2_NONE, 0, VK_PIPELINE_STAGE_2_CLEAR_BIT,
                                 VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL);
      const VkClearColorValue quarter{{0.25f, 0.0f, 0.0f, 0.0f}};
      const VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
      vkCmdClearColorImage(cmd, output_.image, VK_IMAGE_LAYOUT_GENERAL, &quarter, 1, &range);
      vulkan_host::image_barrier(cmd, output_, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                                 VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_COPY_BIT,
                                 VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_READ_BIT,
                                 VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL);
    });
    frame_.depth = depth_.input(VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL);
    frame_.normals.image = normals_.input(VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    frame_.normals.encoding = shadows::NormalEncoding::Octahedral;
    frame_.camera.reversed_z = false;
    frame_.lights = &sun_;
    frame_.light_count = 1;
    frame_.output = output_.input(VK_IMAGE_LAYOUT_GENERAL);
  }
  void TearDown() override {
    module_.reset();
    for (auto* image : {&depth_, &normals_, &output_, &extra_})
      if (image->image) vulkan_host::destroy(*device_, *image);
    vulkan_host::destroy(*device_, readback_);
    vkDestroyCommandPool(device_->device, pool_, nullptr);
    EXPECT_EQ(device_->validation_messages(), 0u);
  }

  vulkan_host::Image make(VkExtent2D extent, VkFormat format, VkImageUsageFlags usage) {
    return vulkan_host::make_image(*device_, extent, format, usage);
  }
  template <typename F>
  void submit(F&& record) {
    VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO, nullptr, pool_,
                                      VK_COMMAND_BUFFER_LEVEL_PRIMARY, 1};
    VkCommandBuffer cmd;
    vulkan_host::check(vkAllocateCommandBuffers(device_->device, &alloc, &cmd), "vkAllocateCommandBuffers");
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    vkBeginCommandBuffer(cmd, &begin);
    record(cmd);
    vkEndCommandBuffer(cmd);
    VkSubmitInfo info{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    info.commandBufferCount = 1;
    info.pCommandBuffers = &cmd;
    vulkan_host::check(vkQueueSubmit(device_->queue, 1, &info, VK_NULL_HANDLE), "vkQueueSubmit");
    vkQueueWaitIdle(device_->queue);
    vkFreeCommandBuffers(device_->device, pool_, 1, &cmd);
  }

  // record() refuses `frame` with one line naming `argument`; the command buffer stays empty (submitted,
  // it leaves the output as it was).
  void expect_two_lights_refused(const shadows::Light& second, const shadows::ImageInput& second_output,
                                 const std::string& argument);
  void expect_refused(const shadows::FrameDesc& frame, const std::string& argument) {
    std::string what;
    submit([&](VkCommandBuffer cmd) {
      try {
        module_->record(cmd, frame);
      } catch (const shadows::Error& e) {
        what = e.what();
      }
    });
    EXPECT_NE(what.find(argument), std::string::npos) << "message: '" << what << "'";
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    submit([&](VkCommandBuffer cmd) {
      VkBufferImageCopy region{};
      region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
      region.imageExtent = {kExtent.width, kExtent.height, 1};
      vkCmdCopyImageToBuffer(cmd, output_.image, VK_IMAGE_LAYOUT_GENERAL, readback_.buffer, 1, &region);
      const VkMemoryBarrier2 to_host{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2, nullptr, VK_PIPELINE_STAGE_2_COPY_BIT,
                                     VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT};
      VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
      dep.memoryBarrierCount = 1;
      dep.pMemoryBarriers = &to_host;
      vkCmdPipelineBarrier2(cmd, &dep);
    });
    const auto* texels = static_cast<const uint8_t*>(readback_.mapped);
    size_t changed = 0;
    for (uint32_t i = 0; i < kExtent.width * kExtent.height; ++i) changed += texels[i] != 64;
    EXPECT_EQ(changed, 0u) << "the output changed: something was recorded";
  }

  std::unique_ptr<vulkan_host::Device> device_;
  std::unique_ptr<shadows::Context> module_;
  vulkan_host::Image depth_, normals_, output_, extra_;
  vulkan_host::Buffer readback_;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  shadows::Light sun_{.direction = {0.0f, -1.0f, 0.0f}};
  shadows::FrameDesc frame_;
};

TEST_F(HostBadInput, NullDepthView) {
  shadows::FrameDesc f = frame_;
  f.depth.view = VK_NULL_HANDLE;
  expect_refused(f, "FrameDesc.depth.view");
}

// Non-finite matrices and origins are refused, each naming its field.
TEST_F(HostBadInput, NonFiniteCameraInstanceAndOrigin) {
  const float nan = std::nanf("");
  shadows::FrameDesc f = frame_;
  f.camera.view[13] = nan;
  expect_refused(f, "FrameDesc.camera.view");
  f = frame_;
  f.origin[2] = std::numeric_limits<double>::infinity();
  expect_refused(f, "FrameDesc.origin");
  shadows::Instance instance;
  instance.world[12] = nan;
  f = frame_;
  f.instances = &instance;
  f.instance_count = 1;
  expect_refused(f, "FrameDesc.instances[0].world");
}

TEST_F(HostBadInput, UnsupportedOutputFormat) {
  extra_ = make(kExtent, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_STORAGE_BIT);
  shadows::FrameDesc f = frame_;
  f.output = extra_.input(VK_IMAGE_LAYOUT_GENERAL);
  expect_refused(f, "FrameDesc.output.format");
}

TEST_F(HostBadInput, OutputWithoutStorageUsage) {
  extra_ = make(kExtent, VK_FORMAT_R8_UNORM, VK_IMAGE_USAGE_SAMPLED_BIT);
  shadows::FrameDesc f = frame_;
  f.output = extra_.input(VK_IMAGE_LAYOUT_GENERAL);
  expect_refused(f, "FrameDesc.output.usage lacks VK_IMAGE_USAGE_STORAGE_BIT");
}

TEST_F(HostBadInput, NormalsExtentDiffersFromDepth) {
  extra_ = make({32, 64}, VK_FORMAT_R16G16_SNORM, VK_IMAGE_USAGE_SAMPLED_BIT);
  shadows::FrameDesc f = frame_;
  f.normals.image = extra_.input(VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  expect_refused(f, "FrameDesc.normals.image.extent");
}

// Native inputs come as a set: one alone (here the world positions, in the right format) is refused
// naming the first one missing.
TEST_F(HostBadInput, NativeInputsComeTogether) {
  extra_ = make(kExtent, VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT);
  shadows::FrameDesc f = frame_;
  f.native.world_position = extra_.input(VK_IMAGE_LAYOUT_GENERAL);
  expect_refused(f, "FrameDesc.native.geometric_normal");
}

TEST_F(HostBadInput, NativeWorldPositionInAnotherFormat) {
  extra_ = make(kExtent, VK_FORMAT_R16G16B16A16_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT);
  shadows::FrameDesc f = frame_;
  f.native.world_position = extra_.input(VK_IMAGE_LAYOUT_GENERAL);
  expect_refused(f, "FrameDesc.native.world_position.format");
}

// A spot light 3 above the host's scene, shining down.
constexpr shadows::Light kSpotLight{.type = shadows::LightType::Spot, .direction = {0.0f, -1.0f, 0.0f},
                                    .position = {0.0f, 3.0f, 0.0f}, .range = 10.0f, .inner_cone = 0.2f, .outer_cone = 0.5f};

// The hybrid shadows a local light with the IZB alone, which takes the compute trace.
TEST_F(HostBadInput, SpotLightWithTheHybridsRasterTrace) {
  module_->settings().technique = shadows::Technique::Hybrid;
  module_->settings().izb.trace = shadows::PassBackend::Raster;
  shadows::FrameDesc f = frame_;
  f.lights = &kSpotLight;
  expect_refused(f, "a spot light takes the IZB's compute trace");
}

TEST_F(HostBadInput, SecondLightWithoutItsOutput) {
  const shadows::Light lights[2] = {sun_, kSpotLight};
  shadows::FrameDesc f = frame_;
  f.lights = lights;
  f.light_count = 2;
  expect_refused(f, "FrameDesc.light_outputs is null");
}

TEST_F(HostBadInput, TooManyLights) {
  std::vector<shadows::Light> lights(shadows::kMaxLightsPerRecord + 1, sun_);
  std::vector<shadows::ImageInput> outputs(lights.size() - 1, frame_.output);
  shadows::FrameDesc f = frame_;
  f.lights = lights.data();
  f.light_count = uint32_t(lights.size());
  f.light_outputs = outputs.data();
  expect_refused(f, "FrameDesc.light_count is 9 (1..8");
}

// Two lights, the second `second` and its output `second_output`, must be refused naming `argument`.
void HostBadInput::expect_two_lights_refused(const shadows::Light& second, const shadows::ImageInput& second_output,
                                             const std::string& argument) {
  const shadows::Light lights[2] = {sun_, second};
  const shadows::ImageInput outputs[1] = {second_output};
  shadows::FrameDesc f = frame_;
  f.lights = lights;
  f.light_count = 2;
  f.light_outputs = outputs;
  expect_refused(f, argument);
}

TEST_F(HostBadInput, SecondLightMalformed) {
  shadows::Light bad = kSpotLight;
  bad.outer_cone = 2.0f;
  expect_two_lights_refused(bad, frame_.output, "FrameDesc.lights[1] cones");
}

TEST_F(HostBadInput, SecondLightsOutputInAnotherFormat) {
  extra_ = make(kExtent, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_STORAGE_BIT);
  expect_two_lights_refused(kSpotLight, extra_.input(VK_IMAGE_LAYOUT_GENERAL), "FrameDesc.light_outputs[0]");
}

TEST_F(HostBadInput, OverlayOfALightNotRecorded) {
  shadows::FrameDesc f = frame_;
  f.overlay_light = 1;
  expect_refused(f, "FrameDesc.overlay_light is 1 with light_count 1");
}

TEST_F(HostBadInput, SpotLightWithTheRasterTrace) {
  module_->settings().technique = shadows::Technique::Izb;
  module_->settings().izb.trace = shadows::PassBackend::Raster;
  shadows::FrameDesc f = frame_;
  f.lights = &kSpotLight;
  expect_refused(f, "a spot light takes the IZB's compute trace");
}

TEST_F(HostBadInput, PointLightWithoutRange) {
  module_->settings().technique = shadows::Technique::RayTraced;
  shadows::FrameDesc f = frame_;
  const shadows::Light point{.type = shadows::LightType::Point, .position = {0.0f, 3.0f, 0.0f}, .range = 0.0f};
  f.lights = &point;
  expect_refused(f, "FrameDesc.lights[0].range");
}

TEST_F(HostBadInput, RayTracingMissingOnLavapipe) {
  const shadows::Capability rt = module_->capabilities().of(shadows::Technique::RayTraced);
  if (rt.available) GTEST_SKIP() << "the device traces rays";
  EXPECT_FALSE(rt.available);
  EXPECT_NE(rt.reason.find("VK_KHR_"), std::string::npos) << rt.reason;
  module_->settings().technique = shadows::Technique::RayTraced;
  expect_refused(frame_, "technique rt");
}

TEST_F(HostBadInput, MeshWithZeroTriangles) {
  vulkan_host::Buffer buffer = vulkan_host::make_buffer(*device_, 64, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  shadows::MeshDesc mesh;
  mesh.name = "empty";
  mesh.positions = buffer.input();
  mesh.vertex_count = 3;
  mesh.indices = buffer.input();
  mesh.index_type = VK_INDEX_TYPE_UINT16;
  mesh.index_count = 0;
  std::string what;
  try {
    module_->register_mesh(mesh);
  } catch (const shadows::Error& e) {
    what = e.what();
  }
  EXPECT_NE(what.find("MeshDesc 'empty'.index_count"), std::string::npos) << "message: '" << what << "'";
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  // Nothing was queued: the next frame has no import to record.
  expect_refused([&] {
    shadows::FrameDesc f = frame_;
    f.output.view = VK_NULL_HANDLE;
    return f;
  }(), "FrameDesc.output.view");
  vulkan_host::destroy(*device_, buffer);
}

// A device created without an extension the module requires: Context::create names it.
TEST(HostDevice, WithoutPushDescriptorCreateThrowsNamingIt) {
  vulkan_host::Device device({.device = test_device(), .validation = true, .leave_out = {"VK_KHR_push_descriptor"}});
  std::string what;
  try {
    shadows::Context::create(device.context_desc(2, shadows::Settings{}));
  } catch (const shadows::Error& e) {
    what = e.what();
  }
  EXPECT_NE(what.find("VK_KHR_push_descriptor"), std::string::npos) << "message: '" << what << "'";
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  EXPECT_EQ(device.validation_messages(), 0u);
}

}  // namespace
