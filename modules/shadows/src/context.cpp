#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <optional>

#include <glm/gtc/type_ptr.hpp>
#include <shared/host.h>

#include "barriers.hpp"
#include "context_impl.hpp"
#include "embedded_shaders.hpp"
#include "input_checks.hpp"
#include "light_space.hpp"
#include "shared/izb.h"

namespace shadows {

using engine::gpu::Buffer;
using engine::gpu::DescriptorWriter;
using engine::gpu::Image;
using engine::gpu::memory_barrier;

namespace detail {

namespace {

bool is_depth(VkFormat f) {
  return f == VK_FORMAT_D32_SFLOAT || f == VK_FORMAT_D24_UNORM_S8_UINT || f == VK_FORMAT_D32_SFLOAT_S8_UINT ||
         f == VK_FORMAT_D16_UNORM || f == VK_FORMAT_X8_D24_UNORM_PACK32 || f == VK_FORMAT_D16_UNORM_S8_UINT ||
         f == VK_FORMAT_S8_UINT;
}

bool is_integer_format(VkFormat f) {
  switch (f) {
    case VK_FORMAT_R8_UINT: case VK_FORMAT_R8_SINT: case VK_FORMAT_R8G8_UINT: case VK_FORMAT_R8G8_SINT:
    case VK_FORMAT_R8G8B8A8_UINT: case VK_FORMAT_R8G8B8A8_SINT: case VK_FORMAT_R16_UINT: case VK_FORMAT_R16_SINT:
    case VK_FORMAT_R16G16_UINT: case VK_FORMAT_R16G16_SINT: case VK_FORMAT_R16G16B16A16_UINT:
    case VK_FORMAT_R16G16B16A16_SINT: case VK_FORMAT_R32_UINT: case VK_FORMAT_R32_SINT: case VK_FORMAT_R32G32_UINT:
    case VK_FORMAT_R32G32_SINT: case VK_FORMAT_R32G32B32A32_UINT: case VK_FORMAT_R32G32B32A32_SINT:
    case VK_FORMAT_A2B10G10R10_UINT_PACK32: return true;
    default: return false;
  }
}

engine::gpu::Binding storage_image_binding(uint32_t binding) { return {binding, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE}; }

constexpr VkAccessFlags2 kStorageReadWrite = VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT |
                                             VK_ACCESS_2_SHADER_SAMPLED_READ_BIT;

}  // namespace

std::string format_name(VkFormat format) {
  switch (format) {
    case VK_FORMAT_D32_SFLOAT: return "VK_FORMAT_D32_SFLOAT";
    case VK_FORMAT_D24_UNORM_S8_UINT: return "VK_FORMAT_D24_UNORM_S8_UINT";
    case VK_FORMAT_D32_SFLOAT_S8_UINT: return "VK_FORMAT_D32_SFLOAT_S8_UINT";
    case VK_FORMAT_D16_UNORM: return "VK_FORMAT_D16_UNORM";
    case VK_FORMAT_R8_UNORM: return "VK_FORMAT_R8_UNORM";
    case VK_FORMAT_R16_SFLOAT: return "VK_FORMAT_R16_SFLOAT";
    case VK_FORMAT_R32_SFLOAT: return "VK_FORMAT_R32_SFLOAT";
    case VK_FORMAT_R8G8B8A8_UNORM: return "VK_FORMAT_R8G8B8A8_UNORM";
    case VK_FORMAT_UNDEFINED: return "VK_FORMAT_UNDEFINED";
    default: return "VkFormat " + std::to_string(int(format));
  }
}

std::string layout_name(VkImageLayout layout) {
  switch (layout) {
    case VK_IMAGE_LAYOUT_UNDEFINED: return "VK_IMAGE_LAYOUT_UNDEFINED";
    case VK_IMAGE_LAYOUT_GENERAL: return "VK_IMAGE_LAYOUT_GENERAL";
    case VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL: return "VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL";
    case VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL: return "VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL";
    case VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL: return "VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL";
    case VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL: return "VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL";
    case VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL: return "VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL";
    case VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL: return "VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL";
    case VK_IMAGE_LAYOUT_PREINITIALIZED: return "VK_IMAGE_LAYOUT_PREINITIALIZED";
    case VK_IMAGE_LAYOUT_DEPTH_READ_ONLY_OPTIMAL: return "VK_IMAGE_LAYOUT_DEPTH_READ_ONLY_OPTIMAL";
    case VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL: return "VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL";
    case VK_IMAGE_LAYOUT_READ_ONLY_OPTIMAL: return "VK_IMAGE_LAYOUT_READ_ONLY_OPTIMAL";
    case VK_IMAGE_LAYOUT_ATTACHMENT_OPTIMAL: return "VK_IMAGE_LAYOUT_ATTACHMENT_OPTIMAL";
    case VK_IMAGE_LAYOUT_PRESENT_SRC_KHR: return "VK_IMAGE_LAYOUT_PRESENT_SRC_KHR";
    default: return "VkImageLayout " + std::to_string(int(layout));
  }
}

void check_buffer(const BufferInput& b, const std::string& name, VkDeviceSize minimum, bool half_aligned) {
  if (b.buffer == VK_NULL_HANDLE) throw Error("shadows: " + name + ".buffer is VK_NULL_HANDLE");
  if (!(b.usage & VK_BUFFER_USAGE_STORAGE_BUFFER_BIT))
    throw Error("shadows: " + name + ".usage lacks VK_BUFFER_USAGE_STORAGE_BUFFER_BIT (the module reads it in compute)");
  if (b.offset % (half_aligned ? 2 : 4))
    throw Error("shadows: " + name + ".offset " + std::to_string(b.offset) + " is not a multiple of " +
                (half_aligned ? "2" : "4"));
  if (b.size < minimum)
    throw Error("shadows: " + name + ".size is " + std::to_string(b.size) + " bytes, the mesh needs " +
                std::to_string(minimum));
}

void check_deformed(const DeformedPositions& d, const std::string& name, uint32_t mesh_vertex_count) {
  if (d.format != VK_FORMAT_R32G32B32_SFLOAT && d.format != VK_FORMAT_R32G32B32A32_SFLOAT)
    throw Error("shadows: " + name + ".format is " + format_name(d.format) +
                " (VK_FORMAT_R32G32B32_SFLOAT or R32G32B32A32_SFLOAT)");
  const uint32_t position_bytes = d.format == VK_FORMAT_R32G32B32_SFLOAT ? 12 : 16;
  if (d.stride % 4) throw Error("shadows: " + name + ".stride " + std::to_string(d.stride) + " is not a multiple of 4");
  if (d.stride < position_bytes)
    throw Error("shadows: " + name + ".stride " + std::to_string(d.stride) + " is smaller than the format's " +
                std::to_string(position_bytes) + " bytes");
  if (d.vertex_count != mesh_vertex_count)
    throw Error("shadows: " + name + ".vertex_count " + std::to_string(d.vertex_count) + " differs from the mesh's " +
                std::to_string(mesh_vertex_count) + " (MeshDesc::vertex_count)");
  check_buffer(d.positions, name + ".positions", VkDeviceSize(d.vertex_count - 1) * d.stride + position_bytes);
  for (int c = 0; c < 3; ++c)
    if (!std::isfinite(d.bounds.min[c]) || !std::isfinite(d.bounds.max[c]))
      throw Error("shadows: " + name + ".bounds has a value that is not finite");
  if (!(d.bounds.min[0] <= d.bounds.max[0] && d.bounds.min[1] <= d.bounds.max[1] && d.bounds.min[2] <= d.bounds.max[2]))
    throw Error("shadows: " + name + ".bounds is not a box (min <= max on every axis)");
}

void check_image(const ImageInput& image, const std::string& name, std::initializer_list<VkFormat> formats,
                 VkImageUsageFlags usage, std::initializer_list<VkImageLayout> layouts,
                 std::optional<VkExtent2D> extent) {
  if (image.image == VK_NULL_HANDLE) throw Error("shadows: " + name + ".image is VK_NULL_HANDLE");
  if (image.view == VK_NULL_HANDLE) throw Error("shadows: " + name + ".view is VK_NULL_HANDLE");
  if (formats.size() > 0) {
    if (std::find(formats.begin(), formats.end(), image.format) == formats.end()) {
      std::string list;
      for (VkFormat f : formats) list += (list.empty() ? "" : ", ") + format_name(f);
      throw Error("shadows: " + name + ".format " + format_name(image.format) + " is not supported (one of " + list + ")");
    }
  } else if (image.format == VK_FORMAT_UNDEFINED || is_depth(image.format) || is_integer_format(image.format)) {
    throw Error("shadows: " + name + ".format " + format_name(image.format) +
                " is not supported (a float, UNORM or SNORM colour format)");
  }
  if ((image.usage & usage) != usage)
    throw Error("shadows: " + name + ".usage lacks " +
                (usage & VK_IMAGE_USAGE_STORAGE_BIT ? "VK_IMAGE_USAGE_STORAGE_BIT" : "VK_IMAGE_USAGE_SAMPLED_BIT"));
  if (std::find(layouts.begin(), layouts.end(), image.layout) == layouts.end())
    throw Error("shadows: " + name + ".layout " + layout_name(image.layout) + " is not supported (" +
                (layouts.size() == 1 ? "VK_IMAGE_LAYOUT_GENERAL" : "a read-only layout or GENERAL") + ")");
  if (image.extent.width == 0 || image.extent.height == 0) throw Error("shadows: " + name + ".extent is empty");
  if (extent && (image.extent.width != extent->width || image.extent.height != extent->height))
    throw Error("shadows: " + name + ".extent " + std::to_string(image.extent.width) + "x" +
                std::to_string(image.extent.height) + " differs from depth's " + std::to_string(extent->width) + "x" +
                std::to_string(extent->height));
}

// ---------------------------------------------------------------------------------------------------

namespace {

// The host's device as the helper layer's context, after checking every ContextDesc field it reads;
// its refusals name ContextDesc's fields.
std::unique_ptr<engine::gpu::Context> adopt_host_device(const ContextDesc& desc) {
  if (desc.instance == VK_NULL_HANDLE) throw Error("shadows: ContextDesc.instance is VK_NULL_HANDLE");
  if (desc.physical_device == VK_NULL_HANDLE) throw Error("shadows: ContextDesc.physical_device is VK_NULL_HANDLE");
  if (desc.device == VK_NULL_HANDLE) throw Error("shadows: ContextDesc.device is VK_NULL_HANDLE");
  if (desc.queue == VK_NULL_HANDLE) throw Error("shadows: ContextDesc.queue is VK_NULL_HANDLE");
  if (!desc.get_instance_proc_addr) throw Error("shadows: ContextDesc.get_instance_proc_addr is null");
  if (!desc.get_device_proc_addr) throw Error("shadows: ContextDesc.get_device_proc_addr is null");
  if (desc.frames_in_flight < 1 || desc.frames_in_flight > 8)
    throw Error("shadows: ContextDesc.frames_in_flight is " + std::to_string(desc.frames_in_flight) + " (1..8)");
  // Vulkan-style name arrays (as VkDeviceCreateInfo takes them): copied, so the host's arrays need not
  // outlive create().
  const auto names = [](const char* const* array, uint32_t count, const char* field) {
    if (count > 0 && !array)
      throw Error(std::string("shadows: ContextDesc.") + field + "_names is null with " + field + "_count " +
                  std::to_string(count));
    std::vector<std::string> out;
    for (uint32_t i = 0; i < count; ++i) {
      if (!array[i]) throw Error(std::string("shadows: ContextDesc.") + field + "_names[" + std::to_string(i) + "] is null");
      out.emplace_back(array[i]);
    }
    return out;
  };
  std::vector<std::string> instance_extensions =
      names(desc.enabled_instance_extension_names, desc.enabled_instance_extension_count, "enabled_instance_extension");
  std::vector<std::string> device_extensions =
      names(desc.enabled_device_extension_names, desc.enabled_device_extension_count, "enabled_device_extension");
  if (!desc.enabled_features)
    throw Error("shadows: ContextDesc.enabled_features is null (give the VkPhysicalDeviceFeatures2 chain passed to "
                "vkCreateDevice)");
  engine::gpu::AdoptedDevice adopted;
  adopted.instance = desc.instance;
  adopted.physical_device = desc.physical_device;
  adopted.device = desc.device;
  adopted.queue_family = desc.queue_family;
  adopted.queue = desc.queue;
  adopted.get_instance_proc_addr = desc.get_instance_proc_addr;
  adopted.get_device_proc_addr = desc.get_device_proc_addr;
  adopted.enabled_instance_extensions = std::move(instance_extensions);
  adopted.enabled_device_extensions = std::move(device_extensions);
  adopted.enabled_features = desc.enabled_features;
  adopted.api_version = desc.api_version;
  adopted.allocator = desc.allocator;
  adopted.pipeline_cache = desc.pipeline_cache;
  adopted.count_validation_messages = desc.count_validation_messages;
  adopted.masked_features = desc.masked_features;
  try {
    return std::make_unique<engine::gpu::Context>(adopted);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    // The adoption names its own fields, which are the host's ContextDesc fields of the same names.
    std::string what = e.what();
    for (size_t at; (at = what.find("AdoptedDevice.")) != std::string::npos;) what.replace(at, 14, "ContextDesc.");
    // Its extension lists are ContextDesc's name arrays.
    for (const char* list : {"enabled_instance_extensions", "enabled_device_extensions"}) {
      const std::string from = std::string(list), to = from.substr(0, from.size() - 1) + "_names";
      for (size_t at = 0; (at = what.find(from, at)) != std::string::npos; at += to.size()) what.replace(at, from.size(), to);
    }
    throw Error(what);
  }
}

}  // namespace

ContextImpl::ContextImpl(const ContextDesc& desc) : settings_(desc.settings) {
  // Every pipeline of the module is created after this, from the SPIR-V inside the library.
  engine::gpu::register_embedded_shaders(embedded_shaders());
  gpu_ = adopt_host_device(desc);
  cpu_paths_ = takes_cpu_paths(*gpu_);
  frames_in_flight_ = desc.frames_in_flight;
  // Resources the passes replace (pools growing, a resize) may still be read by frames in flight.
  gpu_->defer_releases(true);
  slots_.resize(frames_in_flight_);
  for (auto& slot : slots_) slot.profiler = std::make_unique<engine::gpu::GpuProfiler>(*gpu_);

  engine::gpu::Context& ctx = *gpu_;
  geometry_.init(ctx, ctx.features().ray_tracing_pipeline);
  nearest_ = engine::gpu::Sampler(ctx, VK_FILTER_NEAREST, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, "shadows inputs sampler");
  input_params_ = Buffer(ctx, sizeof(gpu_shared::HostInputs),
                         VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, false, "shadows input params");
  using engine::gpu::Binding;
  auto sampled = [](uint32_t b) { return Binding{b, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER}; };
  const auto storage = storage_image_binding;
  namespace gs = gpu_shared;
  inputs_pipeline_ = engine::gpu::PipelineFactory(ctx).compute(
      {.shader = subgroup_shader(ctx, "host_inputs"),
       .bindings = {{gs::HOST_INPUTS_BINDING_PARAMS, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER},
                    sampled(gs::HOST_INPUTS_BINDING_DEPTH), sampled(gs::HOST_INPUTS_BINDING_NORMAL),
                    sampled(gs::HOST_INPUTS_BINDING_GEOMETRIC), sampled(gs::HOST_INPUTS_BINDING_OFFSET),
                    sampled(gs::HOST_INPUTS_BINDING_RECEIVER), storage(gs::HOST_INPUTS_BINDING_WORLD_POSITION),
                    storage(gs::HOST_INPUTS_BINDING_GEOMETRIC_OUT), storage(gs::HOST_INPUTS_BINDING_ALBEDO_OUT),
                    storage(gs::HOST_INPUTS_BINDING_TERM_OUT), storage(gs::HOST_INPUTS_BINDING_OVERLAY_OUT)},
       .specialization = {{0, cpu_paths_ ? 1u : 0u}}});
  // The output pass into an R8 output with no overlay, made here rather than in the first frame; the
  // other formats and overlay choices are made on first use.
  (void)output_pipeline(0, 0u);
  // The passes' one-off set-up (uploads that wait for the queue) happens here, at creation, not in a
  // frame. A pass the device cannot run is left out; using its technique then fails in one line.
  try {
    izb();
  } catch (const std::exception&) {
  }
  try {
    cascades();
  } catch (const std::exception&) {
  }
  // Bound in place of an optional input the host did not give (never read then).
  dummy_input_ = Image(ctx, {1, 1}, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_STORAGE_BIT,
                       "shadows placeholder input");
  ctx.immediate_submit([&](VkCommandBuffer cmd) {
    dummy_input_.transition(cmd, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0,
                            VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  });
}

// The host destroys the context only after its frames completed (as for any resource of its own); the
// adopted engine::gpu::Context then releases what it deferred.
ContextImpl::~ContextImpl() = default;

// Fixed by the device and what the host enabled: made once, on first use (record() checks against it).
Capabilities ContextImpl::capabilities() const {
  if (!capabilities_) capabilities_ = find_capabilities();
  return *capabilities_;
}

Capabilities ContextImpl::find_capabilities() const {
  Capabilities c;
  auto& self = const_cast<ContextImpl&>(*this);
  const engine::gpu::DeviceFeatures& features = gpu_->features();
  const auto unavailable = [](const std::string& reason) { return Capability{false, reason}; };
  for (int type = 0; type < 3; ++type) {
    LightCapabilities& l = c.light[type];
    const bool local = LightType(type) != LightType::Directional;
    const std::string kind = LightType(type) == LightType::Spot ? "spot" : "point";
    for (int t = 0; t < 6; ++t) {
      l.technique[t].available = true;
      if (Technique(t) == Technique::RayTraced && !features.ray_tracing_pipeline)
        l.technique[t] = unavailable("shadows: Settings.technique rt: " + features.ray_tracing_missing);
    }
    if (!features.subgroup_arithmetic_compute_fragment) {
      mark_needing_subgroup_operations(l);
      continue;
    }
    l.compute_trace.available = true;
    l.compute_csm.available = true;
    // A local light's perspective grid (its near plane, the casters behind it ray-tested apart) is
    // set up, traced and culled by the compute passes alone.
    if (local) {
      l.raster_trace = unavailable("a " + kind + " light takes the IZB's compute trace: its perspective grid has no raster trace");
      l.raster_csm = unavailable("a " + kind + " light takes the IZB's compute CSM (hertel or bary): its perspective grid has "
                                 "no raster CSM");
    } else if (!features.geometry_shader) {
      // Both conservative rasterizers (software, and hardware reading gl_PrimitiveID) need them.
      l.raster_trace = unavailable("the raster trace needs geometry shaders, which " + gpu_->device_name() + " lacks");
      l.raster_csm = unavailable("the raster CSM (hertel or bary) needs geometry shaders, which " + gpu_->device_name() +
                                 " lacks");
    } else {
      l.raster_trace.available = l.raster_csm.available = true;
    }
    for (int t = 0; t < 4; ++t) {
      std::string why;
      const bool raster_only = CsmTest(t) == CsmTest::BarycentricHw || CsmTest(t) == CsmTest::InnerHw;
      if (local && raster_only) {
        l.csm_test[t] = unavailable("a " + kind + " light takes the IZB's compute CSM (hertel or bary): " +
                                    csm_test_name(CsmTest(t)) + " is raster work");
      } else if (self.izb().csm_test_supported(CsmTest(t), &why)) {
        l.csm_test[t].available = true;
      } else {
        l.csm_test[t] = unavailable("CSM test " + csm_test_name(CsmTest(t)) + " " + why);
      }
    }
  }
  const LightCapabilities& sun = c.light[int(LightType::Directional)];
  std::copy(std::begin(sun.technique), std::end(sun.technique), std::begin(c.technique));
  std::copy(std::begin(sun.csm_test), std::end(sun.csm_test), std::begin(c.csm_test));
  c.hardware_conservative_raster =
      features.subgroup_arithmetic_compute_fragment && self.izb().hardware_raster_available();
  return c;
}

// A device without subgroup arithmetic and ballot operations runs off, the plain shadow map and rt alone:
// the cascades' and the IZB's passes reduce and reserve by subgroups and have no variant without them.
void ContextImpl::mark_needing_subgroup_operations(LightCapabilities& l) const {
  const std::string lacks = " need subgroup arithmetic and ballot operations, which " + gpu_->device_name() + " lacks";
  const std::string technique = "shadows: Settings.technique ";
  l.technique[int(Technique::Cascades)] = Capability{false, technique + "cascades: the cascades" + lacks};
  l.technique[int(Technique::Izb)] = Capability{false, technique + "izb: the IZB's passes" + lacks};
  l.technique[int(Technique::Hybrid)] = Capability{false, technique + "hybrid: the IZB and the cascades" + lacks};
  const Capability izb{false, "the IZB's passes" + lacks};
  l.raster_trace = l.compute_trace = l.raster_csm = l.compute_csm = izb;
  for (Capability& test : l.csm_test) test = izb;
}

MeshId ContextImpl::register_mesh(const MeshDesc& mesh) { return geometry_.add(mesh); }
void ContextImpl::unregister_mesh(MeshId mesh) { geometry_.remove(mesh); }
MeshBounds ContextImpl::mesh_bounds(MeshId mesh) const {
  const MeshInfo* info = geometry_.find(mesh);
  if (!info) throw Error("shadows: mesh_bounds: mesh id " + std::to_string(mesh) + " is not registered");
  MeshBounds b;
  for (int c = 0; c < 3; ++c) b.min[c] = info->bounds.min[c], b.max[c] = info->bounds.max[c];
  return b;
}

void ContextImpl::validate_light(const Light& light, const std::string& name) const {
  if (light.type != LightType::Directional && light.type != LightType::Spot && light.type != LightType::Point)
    throw Error("shadows: " + name + ".type " + std::to_string(uint32_t(light.type)) + " is not a LightType");
  const glm::vec3 dir = glm::make_vec3(light.direction);
  if (light.type != LightType::Point && !(glm::length(dir) > 0.5f && glm::length(dir) < 1.5f))
    throw Error("shadows: " + name + ".direction must be a unit vector");
  if (!std::isfinite(light.angular_diameter_degrees) || light.angular_diameter_degrees < 0.0f ||
      light.angular_diameter_degrees > 10.0f)
    throw Error("shadows: " + name + ".angular_diameter_degrees " + std::to_string(light.angular_diameter_degrees) +
                " is not in 0..10 (degrees; the sun is 0.53)");
  if (!std::isfinite(light.radius) || light.radius < 0.0f)
    throw Error("shadows: " + name + ".radius " + std::to_string(light.radius) +
                " is not a finite radius >= 0 (world units)");
  if (light.type != LightType::Directional) {
    if (!std::isfinite(light.position[0]) || !std::isfinite(light.position[1]) || !std::isfinite(light.position[2]))
      throw Error("shadows: " + name + ".position must be finite");
    if (!(light.range > 0.0f) || !std::isfinite(light.range))
      throw Error("shadows: " + name + ".range must be finite and > 0");
    if (light.type == LightType::Spot &&
        !(light.inner_cone >= 0.0f && light.inner_cone < light.outer_cone && light.outer_cone <= 1.5707964f))
      throw Error("shadows: " + name + " cones must satisfy 0 <= inner_cone < outer_cone <= pi/2");
  }
  check_paths(light, name);
}

// The IZB's paths the settings ask for, against capabilities() for this light's type: whatever is
// unavailable there is refused here, with the same reason.
void ContextImpl::check_paths(const Light& light, const std::string& name) const {
  const IzbSettings& izb = settings_.izb;
  if (settings_.technique != Technique::Izb && settings_.technique != Technique::Hybrid) return;
  const bool raster_csm = izb.csm_backend == PassBackend::Raster && izb.csm_test != CsmTest::BarycentricHw &&
                          izb.csm_test != CsmTest::InnerHw;
  if (izb.trace != PassBackend::Raster && !izb.csm) return;  // nothing that may be missing
  if (!capabilities_) capabilities_ = find_capabilities();
  const LightCapabilities& l = capabilities_->of(light.type);
  const char* kind = light.type == LightType::Spot ? "spot" : light.type == LightType::Point ? "point" : "directional";
  const auto refuse = [&](const std::string& setting, const Capability& cap) {
    if (!cap.available)
      throw Error("shadows: " + name + " (a " + kind + " light) with " + setting + ": " + cap.reason);
  };
  if (izb.trace == PassBackend::Raster) refuse("Settings.izb.trace raster", l.raster_trace);
  if (!izb.csm) return;
  refuse("Settings.izb.csm_test " + csm_test_name(izb.csm_test), l.of(izb.csm_test));
  if (raster_csm) refuse("Settings.izb.csm_backend raster", l.raster_csm);
}

void ContextImpl::validate_settings() const {
  if (!(settings_.units_per_metre > 0.0f) || !std::isfinite(settings_.units_per_metre))
    throw Error("shadows: Settings.units_per_metre must be finite and > 0");
  // Distances in metres (Settings::units_per_metre): 0 means unlimited where a field says so.
  const std::pair<float, const char*> distances[] = {{settings_.hybrid_izb_distance, "hybrid_izb_distance"},
                                                     {settings_.izb.max_distance, "izb.max_distance"},
                                                     {settings_.cascades.max_distance, "cascades.max_distance"},
                                                     {settings_.cascades.kernel_radius, "cascades.kernel_radius"}};
  for (const auto& [value, field] : distances)
    if (!(value >= 0.0f) || !std::isfinite(value))
      throw Error("shadows: Settings." + std::string(field) + " " + std::to_string(value) + " must be finite and >= 0");
  if (settings_.rt_light_samples > 64)
    throw Error("shadows: Settings.rt_light_samples " + std::to_string(settings_.rt_light_samples) + " is not in 0..64");
}

void ContextImpl::validate(const FrameDesc& f) const {
  check_image(f.depth, "FrameDesc.depth",
              {VK_FORMAT_D32_SFLOAT, VK_FORMAT_D24_UNORM_S8_UINT, VK_FORMAT_D32_SFLOAT_S8_UINT, VK_FORMAT_D16_UNORM},
              VK_IMAGE_USAGE_SAMPLED_BIT, kReadLayouts, std::nullopt);
  const VkExtent2D extent = f.depth.extent;
  check_image(f.normals.image, "FrameDesc.normals.image", {}, VK_IMAGE_USAGE_SAMPLED_BIT, kReadLayouts, extent);
  if (f.geometric_normals.image.present())
    check_image(f.geometric_normals.image, "FrameDesc.geometric_normals.image", {}, VK_IMAGE_USAGE_SAMPLED_BIT,
                kReadLayouts, extent);
  else if (f.facing_in_alpha)
    throw Error("shadows: FrameDesc.facing_in_alpha is set but FrameDesc.geometric_normals has no image");
  if (f.terminator_offset.present())
    check_image(f.terminator_offset, "FrameDesc.terminator_offset", {}, VK_IMAGE_USAGE_SAMPLED_BIT, kReadLayouts, extent);
  if (f.receiver_mask.present()) {
    check_image(f.receiver_mask, "FrameDesc.receiver_mask", {}, VK_IMAGE_USAGE_SAMPLED_BIT, kReadLayouts, extent);
    if (f.receiver_channel > 3) throw Error("shadows: FrameDesc.receiver_channel is " + std::to_string(f.receiver_channel) + " (0..3)");
  }
  if (f.native.present()) {
    check_image(f.native.world_position, "FrameDesc.native.world_position", {VK_FORMAT_R32G32B32A32_SFLOAT},
                VK_IMAGE_USAGE_STORAGE_BIT, {VK_IMAGE_LAYOUT_GENERAL}, extent);
    check_image(f.native.geometric_normal, "FrameDesc.native.geometric_normal", {VK_FORMAT_R16G16B16A16_SFLOAT},
                VK_IMAGE_USAGE_STORAGE_BIT, {VK_IMAGE_LAYOUT_GENERAL}, extent);
    check_image(f.native.receives, "FrameDesc.native.receives", {VK_FORMAT_R8G8B8A8_UNORM}, VK_IMAGE_USAGE_STORAGE_BIT,
                {VK_IMAGE_LAYOUT_GENERAL}, extent);
  }
  check_image(f.output, "FrameDesc.output", {VK_FORMAT_R8_UNORM, VK_FORMAT_R16_SFLOAT, VK_FORMAT_R32_SFLOAT},
              VK_IMAGE_USAGE_STORAGE_BIT, {VK_IMAGE_LAYOUT_GENERAL}, extent);
  if (f.output_term != OutputTerm::Occlusion && f.output_term != OutputTerm::Combined)
    throw Error("shadows: FrameDesc.output_term " + std::to_string(uint32_t(f.output_term)) + " is not an OutputTerm");
  if (f.overlay.present())
    check_image(f.overlay, "FrameDesc.overlay", {VK_FORMAT_R8G8B8A8_UNORM}, VK_IMAGE_USAGE_STORAGE_BIT,
                {VK_IMAGE_LAYOUT_GENERAL}, extent);
  if (f.light_count < 1 || f.light_count > kMaxLightsPerRecord || !f.lights)
    throw Error("shadows: FrameDesc.light_count is " + std::to_string(f.light_count) + " (1.." +
                std::to_string(kMaxLightsPerRecord) + ", with FrameDesc.lights pointing at that many)");
  if (f.light_count > 1 && !f.light_outputs)
    throw Error("shadows: FrameDesc.light_count is " + std::to_string(f.light_count) +
                " but FrameDesc.light_outputs is null (one image per light after the first)");
  for (uint32_t i = 1; i < f.light_count; ++i)
    check_image(f.light_outputs[i - 1], ("FrameDesc.light_outputs[" + std::to_string(i - 1) + "]").c_str(),
                {VK_FORMAT_R8_UNORM, VK_FORMAT_R16_SFLOAT, VK_FORMAT_R32_SFLOAT}, VK_IMAGE_USAGE_STORAGE_BIT,
                {VK_IMAGE_LAYOUT_GENERAL}, extent);
  if (f.overlay_light >= f.light_count)
    throw Error("shadows: FrameDesc.overlay_light is " + std::to_string(f.overlay_light) + " with light_count " +
                std::to_string(f.light_count));
  for (uint32_t i = 0; i < f.light_count; ++i) validate_light(f.lights[i], "FrameDesc.lights[" + std::to_string(i) + "]");
  if (f.instance_count > 0 && !f.instances) throw Error("shadows: FrameDesc.instances is null with instance_count > 0");
  const auto finite = [](const auto* values, int count) {
    for (int k = 0; k < count; ++k)
      if (!std::isfinite(values[k])) return false;
    return true;
  };
  for (uint32_t i = 0; i < f.instance_count; ++i) {
    if (!finite(f.instances[i].world, 16))
      throw Error("shadows: FrameDesc.instances[" + std::to_string(i) + "].world has a value that is not finite");
    if (!geometry_.find(f.instances[i].mesh))
      throw Error("shadows: FrameDesc.instances[" + std::to_string(i) + "].mesh " + std::to_string(f.instances[i].mesh) +
                  " is not a registered mesh");
    if (f.instances[i].deformed.present())
      check_deformed(f.instances[i].deformed, "FrameDesc.instances[" + std::to_string(i) + "].deformed",
                     geometry_.find(f.instances[i].mesh)->vertex_count);
  }
  if (!(f.camera.near_plane > 0.0f) || !(f.camera.far_plane > f.camera.near_plane))
    throw Error("shadows: FrameDesc.camera near_plane/far_plane must satisfy 0 < near < far");
  if (!finite(f.camera.view, 16)) throw Error("shadows: FrameDesc.camera.view has a value that is not finite");
  if (!finite(f.camera.projection, 16)) throw Error("shadows: FrameDesc.camera.projection has a value that is not finite");
  if (!finite(f.origin, 3)) throw Error("shadows: FrameDesc.origin has a value that is not finite");
  validate_settings();
  // A technique the device cannot run is refused here, before anything is recorded.
  if (settings_.technique == Technique::RayTraced && !gpu_->features().ray_tracing_pipeline)
    throw Error(capabilities().of(Technique::RayTraced).reason);  // the line capabilities() gives
}

void ContextImpl::ensure_targets(VkExtent2D extent) {
  if (extent.width == extent_.width && extent.height == extent_.height && shadow_term_.valid()) return;
  engine::gpu::Context& ctx = *gpu_;
  const VkImageUsageFlags usage = VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
                                  VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  inputs_.world_position = Image(ctx, extent, VK_FORMAT_R32G32B32A32_SFLOAT, usage, "shadows world position");
  inputs_.geometric_normal = Image(ctx, extent, VK_FORMAT_R16G16B16A16_SFLOAT, usage, "shadows geometric normal");
  inputs_.albedo = Image(ctx, extent, VK_FORMAT_R8G8B8A8_UNORM, usage, "shadows receiver flags");
  shadow_term_ = Image(ctx, extent, VK_FORMAT_R32_SFLOAT, usage, "shadows term");
  overlay_ = Image(ctx, extent, VK_FORMAT_R8G8B8A8_UNORM, usage, "shadows overlay");
  extent_ = extent;
  targets_fresh_ = true;
  // The passes size their own per-pixel resources from the extent they see in the frame.
}

// The previous frame's reads of the module's per-pixel images finish before this frame rewrites them;
// fresh images move from UNDEFINED to GENERAL.
void ContextImpl::prepare_targets(VkCommandBuffer cmd, bool clear, const TermImage& term) {
  // The lit start's compute pass binds every target (and reads none of them when it writes a host's
  // term), a clear writes them, the passes write and read them.
  constexpr VkAccessFlags2 kTargetFirstUses =
      VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT;
  for (Image* img : {&inputs_.world_position, &inputs_.geometric_normal, &inputs_.albedo, &shadow_term_, &overlay_}) {
    if (targets_fresh_)
      img->transition(cmd, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0,
                      VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_CLEAR_BIT, kTargetFirstUses);
  }
  if (!targets_fresh_)
    memory_barrier(cmd, pass_shader_stages(*gpu_) | VK_PIPELINE_STAGE_2_COPY_BIT, kStorageReadWrite | VK_ACCESS_2_TRANSFER_READ_BIT,
                   VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_CLEAR_BIT, kTargetFirstUses);
  targets_fresh_ = false;
  // Without the input pass (native inputs), the term starts lit and the overlay, when a debug view
  // draws, empty.
  if (clear) clear_term_and_overlay(cmd, term);
}

// The term to lit and, when a debug view draws, the overlay to empty; visible to every pass.
void ContextImpl::clear_term_and_overlay(VkCommandBuffer cmd, const TermImage& term) {
  const bool overlay = settings_.debug != DebugView::None;
  // A host's output is written by compute shaders only (context.hpp's synchronization contract).
  const bool own = term.handle() == shadow_term_.handle();
  if (!cpu_paths_ || !own) {
    // A GPU may clear a storage image through its graphics units (on an H200, 0.6 ms for a 4K R32F
    // term, against 0.01 for compute stores): the output shader writes the term all lit instead, and
    // with a debug view the overlay empty.
    namespace gs = gpu_shared;
    const uint32_t what = gs::HOST_OUTPUT_ALL_LIT | (overlay ? gs::HOST_OUTPUT_ZERO_OVERLAY : 0u);
    record_output_pass(cmd, output_pipeline(2, what), term.view(), overlay_.view(),
                       {inputs_.world_position.view(), inputs_.geometric_normal.view(), inputs_.albedo.view()}, view_);
  } else {
    // A CPU device clears with a memset.
    const VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    const VkClearColorValue one{{1.0f, 1.0f, 1.0f, 1.0f}}, zero{{0.0f, 0.0f, 0.0f, 0.0f}};
    vkCmdClearColorImage(cmd, shadow_term_.handle(), VK_IMAGE_LAYOUT_GENERAL, &one, 1, &range);
    if (overlay) vkCmdClearColorImage(cmd, overlay_.handle(), VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &range);
  }
  // The clear's or the compute stores', before every pass's accesses.
  memory_barrier(cmd, VK_PIPELINE_STAGE_2_CLEAR_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                 VK_ACCESS_2_TRANSFER_WRITE_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, pass_shader_stages(*gpu_),
                 kStorageReadWrite);
}

void ContextImpl::record_inputs(VkCommandBuffer cmd, const FrameDesc& f, const View& view) {
  namespace gs = gpu_shared;
  gs::HostInputs p{};
  p.inverse_view_projection = view.inverse_view_projection;
  p.view_to_world = glm::inverse(view.view);
  // w: the host depth's step (UNORM formats; 0 for float ones, whose rounding the ray offset covers):
  // how far a rebuilt point may lie behind its surface, which host_inputs.glsl pushes it off by.
  const float depth_step = f.depth.format == VK_FORMAT_D16_UNORM           ? 1.0f / 65535.0f
                           : f.depth.format == VK_FORMAT_D24_UNORM_S8_UINT ? 1.0f / 16777215.0f
                                                                           : 0.0f;
  p.camera_position = glm::vec4(view.camera_position, depth_step);
  p.light_direction = glm::vec4(view.light_direction, 0.0f);
  p.normal_scale_bias = glm::vec4(f.normals.scale, f.normals.bias, f.geometric_normals.scale, f.geometric_normals.bias);
  auto normal_bits = [](const NormalInput& n, bool as_given) {
    uint32_t bits = 0;
    if (n.encoding == NormalEncoding::Octahedral) bits |= gs::HOST_NORMAL_OCTAHEDRAL;
    if (n.space == NormalSpace::View) bits |= gs::HOST_NORMAL_VIEW_SPACE;
    if (as_given) bits |= gs::HOST_NORMAL_AS_GIVEN;
    return bits;
  };
  // World-space xyz normals with no scale or bias that the host says face the camera are used bit for
  // bit (the engine's own G-buffer): the shading points then equal the engine's exactly.
  auto as_given = [](const NormalInput& n) {
    return n.facing_camera && n.encoding == NormalEncoding::Xyz && n.space == NormalSpace::World && n.scale == 1.0f &&
           n.bias == 0.0f;
  };
  uint32_t flags = 0;
  if (f.camera.reversed_z) flags |= gs::HOST_REVERSED_Z;
  if (settings_.debug != DebugView::None) flags |= gs::HOST_CLEAR_OVERLAY;
  if (f.geometric_normals.image.present()) flags |= gs::HOST_HAS_GEOMETRIC;
  if (f.facing_in_alpha) flags |= gs::HOST_FACING_IN_ALPHA;
  if (f.terminator_offset.present()) flags |= gs::HOST_HAS_OFFSET;
  if (f.receiver_mask.present()) flags |= gs::HOST_HAS_RECEIVER_MASK;
  flags |= normal_bits(f.normals, as_given(f.normals)) << gs::HOST_NORMAL_SHIFT;
  flags |= normal_bits(f.geometric_normals, as_given(f.geometric_normals)) << gs::HOST_GEOMETRIC_SHIFT;
  p.extent = glm::uvec4(extent_.width, extent_.height, flags, f.receiver_channel);

  // The previous frame's reads of the parameters finish before this frame rewrites them.
  memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, 0, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, 0);
  vkCmdUpdateBuffer(cmd, input_params_.handle(), 0, sizeof(p), &p);
  memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_UNIFORM_READ_BIT);

  auto input_view = [&](const ImageInput& in) { return in.present() ? in.view : dummy_input_.view(); };
  auto input_layout = [&](const ImageInput& in) { return in.present() ? in.layout : VK_IMAGE_LAYOUT_GENERAL; };
  inputs_pipeline_.bind(cmd);
  DescriptorWriter()
      .uniform_buffer(gs::HOST_INPUTS_BINDING_PARAMS, input_params_.handle())
      .sampled_image(gs::HOST_INPUTS_BINDING_DEPTH, f.depth.view, nearest_.handle(), f.depth.layout)
      .sampled_image(gs::HOST_INPUTS_BINDING_NORMAL, f.normals.image.view, nearest_.handle(), f.normals.image.layout)
      .sampled_image(gs::HOST_INPUTS_BINDING_GEOMETRIC, input_view(f.geometric_normals.image), nearest_.handle(),
                     input_layout(f.geometric_normals.image))
      .sampled_image(gs::HOST_INPUTS_BINDING_OFFSET, input_view(f.terminator_offset), nearest_.handle(),
                     input_layout(f.terminator_offset))
      .sampled_image(gs::HOST_INPUTS_BINDING_RECEIVER, input_view(f.receiver_mask), nearest_.handle(),
                     input_layout(f.receiver_mask))
      .storage_image(gs::HOST_INPUTS_BINDING_WORLD_POSITION, inputs_.world_position.view())
      .storage_image(gs::HOST_INPUTS_BINDING_GEOMETRIC_OUT, inputs_.geometric_normal.view())
      .storage_image(gs::HOST_INPUTS_BINDING_ALBEDO_OUT, inputs_.albedo.view())
      .storage_image(gs::HOST_INPUTS_BINDING_TERM_OUT, shadow_term_.view())
      .storage_image(gs::HOST_INPUTS_BINDING_OVERLAY_OUT, overlay_.view())
      .push(*gpu_, cmd, inputs_pipeline_);
  vkCmdDispatch(cmd, groups(extent_.width, 8), groups(extent_.height, 8), 1);
  // The module's inputs, term and overlay: written above, read and written by every pass that follows.
  memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                 pass_shader_stages(*gpu_), kStorageReadWrite);
}

const engine::gpu::Pipeline& ContextImpl::output_pipeline(int format, uint32_t what) {
  engine::gpu::Pipeline& pipeline = output_pipelines_[format][what];
  if (pipeline.valid()) return pipeline;
  namespace gs = gpu_shared;
  const auto storage = storage_image_binding;
  const char* shaders[3] = {"host_output_r8.comp", "host_output_r16f.comp", "host_output_r32f.comp"};
  pipeline = engine::gpu::PipelineFactory(*gpu_).compute(
      {.shader = shaders[format],
       .bindings = {storage(gs::HOST_OUTPUT_BINDING_TERM), storage(gs::HOST_OUTPUT_BINDING_OVERLAY),
                    storage(gs::HOST_OUTPUT_BINDING_OUT), storage(gs::HOST_OUTPUT_BINDING_OVERLAY_OUT),
                    storage(gs::HOST_OUTPUT_BINDING_WORLD_POSITION), storage(gs::HOST_OUTPUT_BINDING_GEOMETRIC_NORMAL)},
       .push_constant_size = sizeof(gs::HostOutputPush),
       .specialization = {{0, what}}});
  return pipeline;
}

uint32_t ContextImpl::output_bits(const FrameDesc& f, bool with_overlay) const {
  namespace gs = gpu_shared;
  uint32_t what = settings_.technique == Technique::Off ? gs::HOST_OUTPUT_ALL_LIT : 0u;
  if (f.output_term == OutputTerm::Occlusion) what |= gs::HOST_OUTPUT_OCCLUSION;
  // The overlay is FrameDesc::overlay_light's (the other lights leave the host's overlay alone).
  if (f.overlay.present() && with_overlay)
    what |= settings_.debug != DebugView::None ? gs::HOST_OUTPUT_COPY_OVERLAY : gs::HOST_OUTPUT_ZERO_OVERLAY;
  return what;
}

// In place where the output pass would only copy: native inputs (the input pass, which starts the
// module's term lit, does not run), an R32F output, nothing to convert or draw in the overlay, and a
// technique that writes the term with compute shaders only (rt writes it from its ray generation
// shader; the host's barrier after record() names COMPUTE_SHADER). The frame is spared a pass over
// every pixel.
TermImage ContextImpl::term_target(const FrameDesc& f, uint32_t i) const {
  const ImageInput& output = i == 0 ? f.output : f.light_outputs[i - 1];
  const bool in_place = f.native.present() && output.format == VK_FORMAT_R32_SFLOAT &&
                        settings_.technique != Technique::RayTraced && output_bits(f, i == f.overlay_light) == 0u;
  return in_place ? TermImage{output.image, output.view} : TermImage{shadow_term_.handle(), shadow_term_.view()};
}

void ContextImpl::record_output(VkCommandBuffer cmd, const FrameDesc& f, const ImageInput& output, bool with_overlay,
                                const ShadingInputs& inputs, const View& view) {
  // Every pass's writes of the term and overlay, visible to the copy into the host's images.
  memory_barrier(cmd, pass_shader_stages(*gpu_), VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
  const uint32_t what = output_bits(f, with_overlay);
  const int which = output.format == VK_FORMAT_R8_UNORM ? 0 : output.format == VK_FORMAT_R16_SFLOAT ? 1 : 2;
  record_output_pass(cmd, output_pipeline(which, what), output.view, f.overlay.present() ? f.overlay.view : overlay_.view(),
                     inputs, view);
}

// host_output's pass over the frame: the term (and overlay) into `out` (and `overlay_out`), as
// `p`'s HOST_OUTPUT_* bits say.
void ContextImpl::record_output_pass(VkCommandBuffer cmd, const engine::gpu::Pipeline& p, VkImageView out,
                                     VkImageView overlay_out, const ShadingInputs& inputs, const View& view) {
  namespace gs = gpu_shared;
  p.bind(cmd);
  DescriptorWriter()
      .storage_image(gs::HOST_OUTPUT_BINDING_TERM, shadow_term_.view())
      .storage_image(gs::HOST_OUTPUT_BINDING_OVERLAY, overlay_.view())
      .storage_image(gs::HOST_OUTPUT_BINDING_OUT, out)
      .storage_image(gs::HOST_OUTPUT_BINDING_OVERLAY_OUT, overlay_out)
      .storage_image(gs::HOST_OUTPUT_BINDING_WORLD_POSITION, inputs.world_position)
      .storage_image(gs::HOST_OUTPUT_BINDING_GEOMETRIC_NORMAL, inputs.geometric_normal)
      .push(*gpu_, cmd, p);
  // The light as set_light() handed it to the passes (a point light's whole sphere, not a face).
  gs::HostOutputPush push{};
  const uint32_t kind = !view.local_light                ? gs::HOST_OUTPUT_LIGHT_DIRECTIONAL
                        : view.light_cos_outer <= -1.0f ? gs::HOST_OUTPUT_LIGHT_POINT
                                                         : gs::HOST_OUTPUT_LIGHT_SPOT;
  push.extent = glm::uvec4(extent_.width, extent_.height, kind, 0u);
  push.light_position = glm::vec4(view.light_position, view.light_range);
  push.light_direction = glm::vec4(view.light_direction, view.light_cos_outer);
  p.push_constants(cmd, push);
  vkCmdDispatch(cmd, groups(extent_.width, gs::HOST_OUTPUT_BLOCK), groups(extent_.height, gs::HOST_OUTPUT_BLOCK), 1);
}

void ContextImpl::set_light(View& view, const Light& light) {
  view.local_light = light.type != LightType::Directional;
  if (light.type != LightType::Point) view.light_direction = glm::normalize(glm::make_vec3(light.direction));
  view.light_position = glm::make_vec3(light.position);
  view.light_range = light.range;
  view.light_cos_outer = light.type == LightType::Spot ? std::cos(light.outer_cone) : -1.0f;
  view.light_face = false;
  view.light_tan_half_angle =
      light.type == LightType::Directional ? std::tan(0.5f * light.angular_diameter_degrees * 0.017453292f) : 0.0f;
  view.light_radius = light.type == LightType::Directional ? 0.0f : light.radius;
}

// Whether a spot or point light can reach a point of the view: its cone (a point light's ball) within
// its range meets the camera's frustum (cone_may_reach_view, which errs towards yes). A light that
// cannot lights no pixel of the frame and shadows none: every technique would write 0 on every
// covered point, which record_unreached_term does in one pass instead of the technique's.
bool ContextImpl::reaches_view(const Light& light) const {
  if (light.type == LightType::Directional) return true;
  View lit = view_;
  set_light(lit, light);
  // (A point light's cosine of -1 makes its cone the whole ball, whatever the axis.)
  const glm::vec3 axis = light.type == LightType::Spot ? lit.light_direction : glm::vec3(0.0f, 1.0f, 0.0f);
  return cone_may_reach_view(lit.view_projection, lit.light_position, axis, lit.light_cos_outer, lit.light_range);
}

// The light's passes into the frame's term: the technique's, or for a light that reaches no point of
// the view the one pass that writes its term (record_unreached_term).
void ContextImpl::record_light(Frame& frame, const Light& light, Slot::LightRecords& records) {
  records.reaches_view = settings_.technique == Technique::Off || reaches_view(light);
  if (records.reaches_view) record_technique(frame);
  else record_unreached_term(frame.cmd, frame.shadow_term, frame.gbuffer);
  records.faces = records.reaches_view ? point_light_faces_recorded_ : 0u;
}

// The term of a light that reaches no point of the view (reaches_view): 0 on every covered point,
// 1 on the background, what the technique's passes would have left.
void ContextImpl::record_unreached_term(VkCommandBuffer cmd, const TermImage& term, const ShadingInputs& inputs) {
  // The previous light's or the input pass's accesses of the term are ordered by restart_term's and
  // the input pass's barriers; the output pass's stores, before the host's output pass reads them.
  record_output_pass(cmd, output_pipeline(2, gpu_shared::HOST_OUTPUT_UNREACHED), term.view(), overlay_.view(), inputs,
                     view_);
  memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                 pass_shader_stages(*gpu_), kStorageReadWrite);
}

// Between two lights of one record: every access of the previous light's passes (their statistics
// copies, the output pass's reads of the term) finishes before the next light's rewrite the same
// resources; the term starts lit again and each light's debug view marks a clean overlay
// (FrameDesc::overlay_light's is the one handed over).
void ContextImpl::restart_term(VkCommandBuffer cmd, bool lit_start, const TermImage& term) {
  pass_barrier(*gpu_, cmd);
  if (lit_start) clear_term_and_overlay(cmd, term);
}

// Whether the technique's passes write every pixel of the term for `light`, which then need not start
// lit (with a debug view the overlay starts empty by the same pass, so it always runs).
bool ContextImpl::writes_every_pixel(const Light& light) {
  if (settings_.debug != DebugView::None) return false;
  if (settings_.technique != Technique::Off && !reaches_view(light)) return true;  // record_unreached_term
  // Both take a local light with the IZB alone (record_local_light).
  const bool local = light.type != LightType::Directional;
  if (settings_.technique == Technique::Izb || (settings_.technique == Technique::Hybrid && local))
    return izb().writes_every_pixel(settings_.izb, settings_.izb.max_distance, settings_.debug, false, !local);
  if (settings_.technique == Technique::Hybrid)
    return izb().writes_every_pixel(settings_.izb, settings_.hybrid_izb_distance, settings_.debug, true, true);
  // The sun's map and cascades resolve every pixel of the frame (shadow_map_resolve.glsl,
  // cascade_filter.comp), and so does a spot light's map on a GPU; a point light's cone maps (and on a
  // CPU device a spot light's map) resolve only the tiles their cones reach.
  if (settings_.technique == Technique::ShadowMap || settings_.technique == Technique::Cascades)
    return !local || (light.type == LightType::Spot && !cpu_paths_);
  return false;
}

namespace {

// The host's camera of this record into the module's view (reversed Z whatever the host's convention).
void set_camera(View& view, const FrameDesc& f) {
  view.view = glm::make_mat4(f.camera.view);
  glm::mat4 projection = glm::make_mat4(f.camera.projection);
  if (!f.camera.reversed_z) {
    // z' = w - z: standard depth becomes reversed (1 near, 0 far), the module's convention.
    glm::mat4 flip(1.0f);
    flip[2][2] = -1.0f;
    flip[3][2] = 1.0f;
    projection = flip * projection;
  }
  view.projection = projection;
  view.view_projection = projection * view.view;
  view.inverse_view_projection = glm::inverse(view.view_projection);
  view.camera_position = glm::vec3(glm::inverse(view.view)[3]);
  // A perspective projection scales x and y by the cotangent of the half field of view.
  view.tan_half_fov = glm::vec2(1.0f / std::max(std::abs(projection[0][0]), 1e-6f),
                                1.0f / std::max(std::abs(projection[1][1]), 1e-6f));
  view.near_plane = f.camera.near_plane;
  view.far_plane = f.camera.far_plane;
  view.extent = f.depth.extent;
  view.frame_index = f.frame_index;
}

// The record's instances as the module's caster draws, with world bounds; `entries`: each one's mesh
// table entry (GeometryStore::record_deformed), a deformed instance's slot bounded by its own box.
void collect_draws(const FrameDesc& f, const GeometryStore& geometry, const std::vector<uint32_t>& entries,
                   std::vector<DrawItem>& draws) {
  draws.clear();
  draws.reserve(f.instance_count);
  for (uint32_t i = 0; i < f.instance_count; ++i) {
    const Instance& in = f.instances[i];
    const MeshInfo& mesh = *geometry.find(in.mesh);
    DrawItem d;
    d.id = in.id;
    d.name = in.name ? in.name : mesh.name;
    d.world = glm::make_mat4(in.world);
    d.mesh = entries[i];
    d.alpha_threshold = mesh.alpha_threshold;
    d.base_color_texture = mesh.texture;
    d.shadow.casts_shadow = in.casts_shadow;
    d.shadow.csm = in.csm == CsmMode::On ? CsmChoice::On : in.csm == CsmMode::Off ? CsmChoice::Off : CsmChoice::Auto;
    d.shadow.deformed = in.deformed.present();
    if (d.shadow.deformed) {
      Aabb box;
      box.extend(glm::make_vec3(in.deformed.bounds.min));
      box.extend(glm::make_vec3(in.deformed.bounds.max));
      d.bounds = box.transformed(d.world);
    } else {
      d.bounds = mesh.bounds.transformed(d.world);
    }
    draws.push_back(std::move(d));
  }
}

}  // namespace

// The geometry of the frame: the queued mesh imports, the deformed instances' positions into their
// slots (a profiler region of their own), and the frame's draws.
void ContextImpl::record_geometry(VkCommandBuffer cmd, const FrameDesc& f, engine::gpu::GpuProfiler& profiler) {
  geometry_.record_imports(cmd);
  std::optional<engine::gpu::ScopedGpuRegion> deformed_region;
  for (uint32_t i = 0; i < f.instance_count && !deformed_region; ++i)
    if (f.instances[i].deformed.present()) deformed_region.emplace(*gpu_, profiler, cmd, "deformed_import");
  const std::vector<uint32_t>& entries = geometry_.record_deformed(cmd, f.instances, f.instance_count);
  deformed_region.reset();
  collect_draws(f, geometry_, entries, draws_);
}

// The shading points the passes read: the host's native inputs in place, else the input pass's.
ShadingInputs ContextImpl::shading_inputs(const FrameDesc& f) const {
  if (f.native.present())
    return ShadingInputs{f.native.world_position.view, f.native.geometric_normal.view, f.native.receives.view};
  return ShadingInputs{inputs_.world_position.view(), inputs_.geometric_normal.view(), inputs_.albedo.view()};
}

void ContextImpl::record(VkCommandBuffer cmd, const FrameDesc& f) {
  if (cmd == VK_NULL_HANDLE) throw Error("shadows: record: cmd is VK_NULL_HANDLE");
  validate(f);
  Slot& slot = slots_[f.frame_index % frames_in_flight_];
  // The host's promise: the frame recorded in this slot frames_in_flight frames ago has completed.
  if (slot.frame) complete_slot(slot);
  if (f.frame_index >= frames_in_flight_) gpu_->release_through(f.frame_index - frames_in_flight_);
  gpu_->set_recording_frame(f.frame_index);

  engine::gpu::GpuProfiler& profiler = external_profiler_ ? *external_profiler_ : *slot.profiler;
  if (!external_profiler_) profiler.begin_frame(cmd);
  engine::gpu::ScopedGpuRegion region(*gpu_, profiler, cmd, "shadows");

  record_geometry(cmd, f, profiler);
  View& view = view_;
  set_camera(view, f);

  ensure_targets(f.depth.extent);
  // With shadows off nothing reads the inputs: the output pass writes the host's image lit. Native
  // inputs are read in place.
  const bool off = settings_.technique == Technique::Off;
  {
    engine::gpu::ScopedGpuRegion targets_region(*gpu_, profiler, cmd, "prepare_targets");
    prepare_targets(cmd, !off && f.native.present() && (f.light_count == 0 || !writes_every_pixel(f.lights[0])),
                    term_target(f, 0));
  }
  // The input pass stores whether each point faces the sun (host_inputs.glsl): for the sun of this
  // record, not the light the previous record left in view_ (a spot's axis, or none on the first
  // frame). A later sun of another direction in the same record runs the pass again (below).
  const bool host_inputs = !off && !f.native.present();
  const auto sun_direction = [&](uint32_t i) { return glm::normalize(glm::make_vec3(f.lights[i].direction)); };
  std::optional<glm::vec3> inputs_sun;
  for (uint32_t i = 0; i < f.light_count && !inputs_sun; ++i)
    if (f.lights[i].type == LightType::Directional) inputs_sun = sun_direction(i);
  if (host_inputs) {
    engine::gpu::ScopedGpuRegion inputs_region(*gpu_, profiler, cmd, "host_inputs");
    if (inputs_sun) view.light_direction = *inputs_sun;
    record_inputs(cmd, f, view);
  }
  const ShadingInputs inputs = shading_inputs(f);
  const uint32_t slot_index = uint32_t(f.frame_index % frames_in_flight_);
  slot.lights.clear();
  for (uint32_t i = 0; i < f.light_count; ++i) {
    Slot::LightRecords records;
    records.kind = f.lights[i].type == LightType::Spot ? "spot" : f.lights[i].type == LightType::Point ? "point" : "directional";
    records.izb_first = izb_ ? izb_->records_so_far(slot_index, f.frame_index) : 0u;
    records.rt_first = ray_traced_ ? ray_traced_->records_so_far(slot_index, f.frame_index) : 0u;
    // Each light in turn through the same passes, into its own term; a region per light when there are several.
    std::optional<engine::gpu::ScopedGpuRegion> light_region;
    if (f.light_count > 1) light_region.emplace(*gpu_, profiler, cmd, "light " + std::to_string(i));
    const TermImage term = term_target(f, i);
    if (i > 0) {
      engine::gpu::ScopedGpuRegion restart_region(*gpu_, profiler, cmd, "restart_term");
      restart_term(cmd, !writes_every_pixel(f.lights[i]), term);
    }
    set_light(view, f.lights[i]);
    if (host_inputs && f.lights[i].type == LightType::Directional && sun_direction(i) != *inputs_sun) {
      // restart_term's barrier has ordered the previous light's reads of the inputs before this rewrite.
      engine::gpu::ScopedGpuRegion inputs_region(*gpu_, profiler, cmd, "host_inputs");
      record_inputs(cmd, f, view);
      inputs_sun = sun_direction(i);
    }
    Frame frame{*gpu_, cmd, profiler, view, inputs, term, overlay_, geometry_.geometry(), draws_,
                slot_index, frames_in_flight_};
    record_light(frame, f.lights[i], records);
    // Written in place (the term's writes were compute shaders', which the host's barrier after
    // record() orders), the output needs no pass.
    if (term.handle() == shadow_term_.handle()) {
      engine::gpu::ScopedGpuRegion output_region(*gpu_, profiler, cmd, "host_output");
      record_output(cmd, f, i == 0 ? f.output : f.light_outputs[i - 1], i == f.overlay_light, inputs, view);
    }
    records.izb_count = (izb_ ? izb_->records_so_far(slot_index, f.frame_index) : 0u) - records.izb_first;
    records.rt_count = (ray_traced_ ? ray_traced_->records_so_far(slot_index, f.frame_index) : 0u) - records.rt_first;
    slot.lights.push_back(std::move(records));
  }
  slot.frame = f.frame_index;
  slot.technique = settings_.technique;
  slot.csm = settings_.izb.csm;
}

// The PCF radius of a spot light's filtered map (Technique::Cascades), in map texels.
constexpr float kSpotFilterTexels = 2.5f;

// A point light's six cones (kPointLightFaceAxes), each shadowed as a spot light; a face's passes
// write only its own points, those in its cube face's pyramid (point_light_face_of in
// light_tiles.glsl), which its cone holds. A cone in which no point of the view can lie within the
// light's range (cone_may_reach_view) is skipped: none of its points is seen. The first face recorded
// also lists every face's tiles and writes the term of the points beyond the range, so one runs even
// when no cone reaches the view.
std::vector<View> ContextImpl::point_light_face_views(const View& view) {
  View face_view = view;
  face_view.light_face = true;
  face_view.light_cos_outer = point_light_face_cos_outer();
  std::vector<uint32_t> faces;
  for (uint32_t face = 0; face < 6; ++face)
    if (cone_may_reach_view(view.view_projection, view.light_position, kPointLightFaceAxes[face],
                            face_view.light_cos_outer, view.light_range))
      faces.push_back(face);
  if (faces.empty()) faces.push_back(0);
  point_light_faces_recorded_ = uint32_t(faces.size());
  std::vector<View> views;
  for (size_t k = 0; k < faces.size(); ++k) {
    const uint32_t face = faces[k];
    face_view.light_direction = kPointLightFaceAxes[face];
    face_view.light_face_index = face;
    face_view.light_face_order = uint32_t(k);
    face_view.last_light_face = k + 1 == faces.size();
    views.push_back(face_view);
  }
  return views;
}

// The faces' Frames (the rest as `frame`'s), all given to `record_faces` at once.
template <typename RecordFaces>
void ContextImpl::record_point_light_faces(Frame& frame, RecordFaces&& record_faces) {
  const std::vector<View> views = point_light_face_views(frame.view);  // (the Frames refer to them)
  std::vector<Frame> faces;
  faces.reserve(views.size());
  for (const View& v : views)
    faces.push_back(Frame{frame.ctx, frame.cmd, frame.profiler, v, frame.gbuffer, frame.shadow_term, frame.overlay,
                          frame.geometry, frame.draws, frame.slot, frame.slots});
  record_faces(faces);
}

// The techniques whose passes differ for a spot or point light (off and rt take every light alike).
void ContextImpl::record_local_light(Frame& frame, const Settings& settings) {
  const bool point = frame.view.light_cos_outer <= -1.0f;
  switch (settings.technique) {
    case Technique::Off:
    case Technique::RayTraced:
      break;
    case Technique::ShadowMap:
    case Technique::Cascades: {
      // One perspective map per spot light (per cube-face cone of a point light), unfiltered for sm and
      // PCF-filtered for cascades.
      if (!shadow_map_) shadow_map_ = std::make_unique<ShadowMapPass>(*gpu_, cpu_paths_);
      const float filter = settings.technique == Technique::Cascades ? kSpotFilterTexels : 0.0f;
      // (The counts are sm's: the cascades report their own filter's.)
      const bool count = collect_stats_ && settings.technique == Technique::ShadowMap;
      if (point) {
        record_point_light_faces(frame, [&](std::vector<Frame>& faces) {
          for (Frame& f : faces) {
            shadow_map_->record(f, settings.shadow_map, filter, count);
            pass_barrier(*gpu_, f.cmd);
          }
        });
      } else {
        shadow_map_->record(frame, settings.shadow_map, filter, count);
      }
      break;
    }
    case Technique::Izb:
    case Technique::Hybrid: {
      // The hybrid shadows a local light with the IZB alone: its range bounds the work, and every point
      // it reaches gets the exact term.
      if (point) {
        // The faces' steps interleaved where they can be (IzbPass::record_faces).
        record_point_light_faces(frame, [&](std::vector<Frame>& faces) {
          izb().record_faces(faces, settings.izb, settings.debug, collect_stats_);
        });
      } else {
        izb().record(frame, settings.izb, settings.debug, false, collect_stats_);
      }
      break;
    }
  }
}

void ContextImpl::record_technique(Frame& frame) {
  point_light_faces_recorded_ = 0;
  const Settings settings = in_world_units(settings_);
  if (frame.view.local_light && settings.technique != Technique::Off && settings.technique != Technique::RayTraced) {
    record_local_light(frame, settings);
    return;
  }
  switch (settings.technique) {
    case Technique::Off:
      break;
    case Technique::ShadowMap:
      if (!shadow_map_) shadow_map_ = std::make_unique<ShadowMapPass>(*gpu_, cpu_paths_);
      shadow_map_->record(frame, settings.shadow_map, 0.0f, collect_stats_);
      break;
    case Technique::Cascades:
      cascades().record(frame, settings.cascades, frame.shadow_term.view(), settings.debug);
      break;
    case Technique::Izb:
      izb().record(frame, settings.izb, settings.debug, false, collect_stats_);
      break;
    case Technique::Hybrid: {
      // The IZB's exact term, then the penumbrae the light's size casts around its edges. With a
      // limited range its resolve also lists the pixels that take some of the cascades' term, and the
      // cascades filter only those.
      IzbSettings near = settings.izb;
      near.max_distance = settings.hybrid_izb_distance;
      izb().record(frame, near, settings.debug, true, collect_stats_);
      pass_barrier(*gpu_, frame.cmd);
      izb().record_hybrid_penumbra(frame, settings.izb.step_timings);
      if (near.max_distance <= 0.0f) break;
      pass_barrier(*gpu_, frame.cmd);
      PixelList listed = izb().hybrid_list();
      listed.nearest_view_depth = detail::nearest_view_depth_at(frame.view, gpu_shared::kIzbHybridFadeStart * near.max_distance);
      cascades().record(frame, settings.cascades, izb().soft_term().view(), settings.debug, &listed);
      pass_barrier(*gpu_, frame.cmd);
      izb().record_hybrid_blend(frame);
      break;
    }
    case Technique::RayTraced:
      if (!ray_traced_) ray_traced_ = std::make_unique<RayTracedPass>(*gpu_);
      ray_traced_->record(frame, settings.izb.samples_per_pixel, settings.rt_light_samples, collect_stats_);
      break;
  }
}

void ContextImpl::frame_completed(uint64_t frame_index) {
  // One queue: every earlier frame has completed too; they report in the order they ran.
  std::vector<Slot*> done;
  for (auto& slot : slots_)
    if (slot.frame && *slot.frame <= frame_index) done.push_back(&slot);
  std::sort(done.begin(), done.end(), [](const Slot* a, const Slot* b) { return *a->frame < *b->frame; });
  for (Slot* slot : done) complete_slot(*slot);
  gpu_->release_through(frame_index);
}

void ContextImpl::complete_slot(Slot& slot) {
  if (!external_profiler_) {
    slot.profiler->collect();
    last_pass_times_.clear();
    for (const auto& [name, ms] : slot.profiler->last_frame()) last_pass_times_.push_back({name, ms});
  }
  // Always: the passes grow their pools and buffers to the demand they measured.
  Stats fresh;  // only the techniques that ran this frame report
  const Technique t = slot.technique;
  const uint32_t index = uint32_t(&slot - slots_.data());
  std::vector<Stats> izb_records, rt_records;
  if ((t == Technique::Izb || t == Technique::Hybrid) && izb_) izb_->after_frame(izb_records, index);
  if (t == Technique::RayTraced && ray_traced_) ray_traced_->after_frame(rt_records, index);
  if (!rt_records.empty()) fresh = rt_records.back();
  else if (!izb_records.empty()) fresh = izb_records.back();
  // A spot or point light's grid is traced (and CSM-culled) by the compute passes whatever the probes
  // chose for the sun: its records report that choice.
  const auto local_choice = [&](const std::string& kind) {
    return Stats::BackendChoice{"compute", "a " + kind + " light's perspective grid takes the compute passes"};
  };
  if (!izb_records.empty() && !slot.lights.empty() && slot.lights.back().kind != "directional") {
    fresh.trace_choice = local_choice(slot.lights.back().kind);
    if (slot.csm) fresh.csm_choice = local_choice(slot.lights.back().kind);
  }
  if ((t == Technique::Cascades || t == Technique::Hybrid) && cascades_) cascades_->after_frame(fresh, index);
  if (t == Technique::ShadowMap && shadow_map_) shadow_map_->after_frame(fresh, index);
  if (collect_stats_) {
    const std::vector<PassTime> times = pass_times();
    auto region_ms = [&](const std::string& name) {
      double ms = 0.0;
      for (const PassTime& p : times) ms += p.name == name ? p.ms : 0.0;
      return ms;
    };
    for (size_t i = 0; i < slot.lights.size(); ++i) {
      const Slot::LightRecords& r = slot.lights[i];
      Stats::LightStats& l = fresh.lights.emplace_back();
      l.kind = r.kind;
      l.faces_recorded = r.faces;
      l.reaches_view = r.reaches_view;
      for (uint32_t k = r.izb_first; k < r.izb_first + r.izb_count && k < izb_records.size(); ++k) {
        const Stats& s = izb_records[k];
        l.lit_candidates += s.lit_candidates;
        l.nodes_inserted += s.nodes_inserted;
        l.csm_culled += s.csm_culled;
        l.node_overflow += s.node_overflow;
        l.list_length_max = std::max(l.list_length_max, s.list_length_max);
        l.trace_choice = r.kind == "directional" ? s.trace_choice : local_choice(r.kind);
        if (slot.csm) l.csm_choice = r.kind == "directional" ? s.csm_choice : local_choice(r.kind);
      }
      for (uint32_t k = r.rt_first; k < r.rt_first + r.rt_count && k < rt_records.size(); ++k) {
        l.lit_candidates += rt_records[k].lit_candidates;
        l.rays_traced += rt_records[k].rays_traced;
        l.rays_occluded += rt_records[k].rays_occluded;
      }
      l.gpu_ms = slot.lights.size() > 1 ? region_ms("light " + std::to_string(i)) : region_ms("shadows");
    }
    add_memory(fresh, t, slot.csm);
    stats_ = std::move(fresh);
  } else if (!izb_records.empty()) {
    // Without the statistics the automatic choices still show (a caller waits for their probes).
    stats_.trace_choice = fresh.trace_choice;
    stats_.csm_choice = fresh.csm_choice;
    stats_.lit_choice = fresh.lit_choice;
    stats_.csm_run_choice = fresh.csm_run_choice;
    stats_.tile_work_choice = fresh.tile_work_choice;
    stats_.csm_status = fresh.csm_status;
  }
  slot.frame.reset();
}

std::vector<Context::PassTime> ContextImpl::pass_times() const {
  if (!external_profiler_) return last_pass_times_;
  std::vector<PassTime> out;
  for (const auto& [name, ms] : external_profiler_->last_frame()) out.push_back({name, ms});
  return out;
}

// The technique's own passes (statistics-only passes such as izb_stats and csm_coverage excluded).
std::vector<std::string> ContextImpl::pass_names() const {
  // (A point light's passes once before its faces: point_light_tiles, sm_light_tiles.)
  std::vector<std::string> izb = {"light_frustum", "point_light_tiles", "izb_build", "frustum_trace", "izb_fallback",
                                  "izb_resolve"};
  if (settings_.izb.csm) izb.insert(izb.begin() + 1, "csm");
  if (settings_.izb.lit_culling != LitCulling::Off) izb.insert(izb.begin() + 1, "lit_map");
  const std::vector<std::string> cascades = {"cascade_depth", "cascade_masks", "cascade_filter", "cascade_blur"};
  const std::vector<std::string> shadow_map = {"sm_depth", "sm_blocks", "sm_light_tiles", "sm_resolve"};
  switch (settings_.technique) {
    case Technique::Off: return {};
    case Technique::ShadowMap: return shadow_map;
    case Technique::Cascades: {
      // A local light's filtered maps are the shadow map's passes.
      std::vector<std::string> names = cascades;
      names.insert(names.end(), shadow_map.begin(), shadow_map.end());
      return names;
    }
    case Technique::Izb: return izb;
    case Technique::Hybrid: {
      izb.push_back("hybrid_penumbra");
      if (settings_.hybrid_izb_distance > 0.0f) {
        izb.insert(izb.begin(), cascades.begin(), cascades.end());
        izb.push_back("hybrid_blend");
      }
      return izb;
    }
    case Technique::RayTraced: return {"rt_build", "rt_trace"};
  }
  return {};
}

// The memory of the technique's resources, found by the prefixes of their debug names.
void ContextImpl::add_memory(Stats& s, Technique technique, bool csm) const {
  std::vector<std::string> prefixes;
  switch (technique) {
    case Technique::Off: break;
    case Technique::ShadowMap: prefixes = {"sm "}; break;
    case Technique::Cascades: prefixes = {"cascade ", "sm "}; break;  // "sm ": a local light's maps
    case Technique::Izb: prefixes = {"izb "}; break;
    case Technique::Hybrid: prefixes = {"izb ", "cascade "}; break;
    case Technique::RayTraced: prefixes = {"rt "}; break;
  }
  if ((technique == Technique::Izb || technique == Technique::Hybrid) && csm) prefixes.push_back("csm ");
  for (const auto& a : gpu_->allocations()) {
    // Staging and readback copies are transient or host-side; they are not the technique's memory.
    if (a.name.find("staging") != std::string::npos || a.name.find("readback") != std::string::npos) continue;
    for (const auto& prefix : prefixes) {
      if (a.name.compare(0, prefix.size(), prefix) != 0) continue;
      // Numbered resources (one bottom level per mesh) add up under one name.
      std::string key = a.name;
      while (!key.empty() && (std::isdigit(static_cast<unsigned char>(key.back())) || key.back() == ' ')) key.pop_back();
      s.memory_bytes[key] += a.bytes;
      s.memory_total_bytes += a.bytes;
      break;
    }
  }
}

IzbPass& ContextImpl::izb() {
  if (!izb_) izb_ = std::make_unique<IzbPass>(*gpu_, cpu_paths_);
  return *izb_;
}
CascadesPass& ContextImpl::cascades() {
  if (!cascades_) cascades_ = std::make_unique<CascadesPass>(*gpu_);
  return *cascades_;
}

}  // namespace detail

std::unique_ptr<Context> Context::create(const ContextDesc& desc) { return std::make_unique<detail::ContextImpl>(desc); }

namespace {

// What an optional extension or feature unlocks, for DeviceRequirement::unlocks.
std::string what_unlocks(const std::string& name) {
  if (name.find("conservative") != std::string::npos) return "hardware conservative raster trace and CSM inner coverage";
  if (name.find("barycentric") != std::string::npos) return "CSM coverage test bary-hw";
  if (name.find("ray_tracing") != std::string::npos || name.find("acceleration_structure") != std::string::npos ||
      name.find("deferred_host") != std::string::npos || name.find("ray_query") != std::string::npos ||
      name == "bufferDeviceAddress" || name == "rayTracingPipeline" || name == "accelerationStructure")
    return "technique rt (ray-traced shadows)";
  if (name == "geometryShader") return "software conservative raster paths (raster trace and CSM on devices without conservative rasterization)";
  if (name.find("debug_utils") != std::string::npos) return "object names and labels in captures";
  return "faster paths";
}

}  // namespace

DeviceRequirements device_requirements(VkPhysicalDevice physical_device) {
  DeviceRequirements out;
  if (physical_device == VK_NULL_HANDLE) {
    out.missing = "shadows: device_requirements: physical_device is VK_NULL_HANDLE";
    return out;
  }
  const engine::gpu::DeviceRequirements r = engine::gpu::device_requirements(physical_device);
  for (const auto& e : r.required_device_extensions) out.required_extensions.push_back({e, "every technique"});
  for (const auto& e : r.optional_device_extensions) out.optional_extensions.push_back({e, what_unlocks(e)});
  for (const auto& e : r.required_features) out.required_features.push_back({e, "every technique"});
  for (const auto& e : r.optional_features) out.optional_features.push_back({e, what_unlocks(e)});
  VkPhysicalDeviceProperties properties;
  vkGetPhysicalDeviceProperties(physical_device, &properties);
  if (properties.apiVersion < VK_API_VERSION_1_3) {
    out.missing = "shadows: the device supports Vulkan " + std::to_string(VK_API_VERSION_MAJOR(properties.apiVersion)) +
                  "." + std::to_string(VK_API_VERSION_MINOR(properties.apiVersion)) + " (1.3 needed)";
    return out;
  }
  uint32_t count = 0;
  vkEnumerateDeviceExtensionProperties(physical_device, nullptr, &count, nullptr);
  std::vector<VkExtensionProperties> extensions(count);
  vkEnumerateDeviceExtensionProperties(physical_device, nullptr, &count, extensions.data());
  for (const auto& e : r.required_device_extensions)
    if (std::none_of(extensions.begin(), extensions.end(),
                     [&](const VkExtensionProperties& p) { return e == p.extensionName; })) {
      out.missing = "shadows: the device lacks " + e;
      break;
    }
  return out;
}

}  // namespace shadows
