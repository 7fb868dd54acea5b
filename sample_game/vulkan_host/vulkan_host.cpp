#include "vulkan_host.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <optional>
#include <fstream>
#include <functional>
#include <stdexcept>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/packing.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "device.hpp"

namespace vulkan_host {
namespace {

// ----- The scene: two meshes (a ground quad with 16-bit indices, a cube with 32-bit ones), five instances.
struct Vertex {
  glm::vec3 position, normal;
};
struct MeshData {
  std::vector<Vertex> vertices;
  std::vector<uint32_t> indices;
  glm::vec3 min, max;
};
MeshData ground_quad() {
  const glm::vec3 up(0, 1, 0);
  return {{{{-1, 0, -1}, up}, {{1, 0, -1}, up}, {{1, 0, 1}, up}, {{-1, 0, 1}, up}}, {0, 2, 1, 0, 3, 2}, {-1, 0, -1}, {1, 0, 1}};
}
MeshData unit_cube() {
  MeshData m{{}, {}, glm::vec3(-0.5f), glm::vec3(0.5f)};
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f}) {
      glm::vec3 n(0.0f), u(0.0f), v(0.0f);
      n[axis] = sign;
      u[(axis + 1) % 3] = 1.0f;
      v[(axis + 2) % 3] = 1.0f;
      const uint32_t base = uint32_t(m.vertices.size());
      for (glm::vec2 c : {glm::vec2(-1, -1), glm::vec2(1, -1), glm::vec2(1, 1), glm::vec2(-1, 1)})
        m.vertices.push_back({0.5f * (n + c.x * u + c.y * v), n});
      for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) m.indices.push_back(base + i);
    }
  return m;
}

// The cube in shape `shape` (Options::cube_shapes): 0 as is, 1 sheared along x with height, 2 tapered
// toward its top (normals kept: the G-buffer shades it as the cube).
MeshData shaped_cube(uint32_t shape) {
  MeshData m = unit_cube();
  if (shape > 2) throw std::runtime_error("unknown cube shape " + std::to_string(shape) + " (0, 1 or 2)");
  m.min = glm::vec3(1.0e30f);
  m.max = glm::vec3(-1.0e30f);
  for (Vertex& v : m.vertices) {
    const float height = v.position.y + 0.5f;  // 0 at the bottom, 1 at the top
    if (shape == 1) v.position.x += 0.6f * height;
    if (shape == 2) v.position.x *= 1.0f - 0.7f * height, v.position.z *= 1.0f - 0.7f * height;
    m.min = glm::min(m.min, v.position);
    m.max = glm::max(m.max, v.position);
  }
  return m;
}

struct Object {
  int mesh;  // 0 ground, 1 cube
  glm::mat4 world;
  glm::vec4 albedo;
};
std::vector<Object> scene_at(uint32_t frame) {
  auto box = [](glm::vec3 at, glm::vec3 size, float yaw_degrees) {
    return glm::scale(glm::rotate(glm::translate(glm::mat4(1.0f), at), glm::radians(yaw_degrees), {0, 1, 0}), size);
  };
  // The moving caster slides along x, a new place every frame.
  const float slide = std::sin(0.7f * float(frame));
  return {{0, glm::scale(glm::mat4(1.0f), glm::vec3(5.0f, 1.0f, 5.0f)), {0.75f, 0.72f, 0.65f, 1}},
          {1, box({-2.0f, 2.0f, -1.5f}, {0.6f, 4.0f, 0.6f}, 0.0f), {0.8f, 0.3f, 0.25f, 1}},      // pillar
          // A low tile in the pillar's shadow; its albedo alpha (0.25) marks it as no receiver where the
          // albedo is the receiver mask (Options::receiver_mask), which then keeps it lit.
          {1, box({-1.1f, 0.02f, -0.9f}, {0.8f, 0.04f, 0.8f}, 0.0f), {0.6f, 0.6f, 0.6f, 0.25f}},
          {1, box({1.8f, 0.6f, 0.8f}, {1.2f, 1.2f, 1.2f}, 30.0f), {0.3f, 0.5f, 0.8f, 1}},        // box
          {1, box({0.0f, 2.2f, 2.2f}, {2.5f, 0.15f, 0.8f}, -15.0f), {0.4f, 0.7f, 0.35f, 1}},     // floating slab
          {1, box({-0.5f + 1.5f * slide, 1.0f, -0.2f}, glm::vec3(0.7f), 45.0f), {0.9f, 0.8f, 0.3f, 1}}};
}

// Frame k's placement of the scene (Options::world_scale, world_offset, origin_step): a scene point p
// (metres, at the origin) stands at world_offset + scale * p, which is shift + scale * p relative to
// the frame's origin.
struct Placement {
  float scale = 1.0f;
  glm::vec3 shift{0.0f};  // world_offset - the frame's origin: small, so float keeps its precision
  std::array<double, 3> origin{};
  glm::vec3 point(glm::vec3 p) const { return shift + scale * p; }
  glm::mat4 matrix(const glm::mat4& scene) const {
    return glm::translate(glm::mat4(1.0f), shift) * glm::scale(glm::mat4(1.0f), glm::vec3(scale)) * scene;
  }
};
Placement placement_at(const Options& o, uint32_t frame) {
  Placement p;
  p.scale = o.world_scale;
  for (int i = 0; i < 3; ++i) {
    p.origin[i] = o.world_offset[i] + double(frame) * o.origin_step[i];
    p.shift[i] = float(o.world_offset[i] - p.origin[i]);
  }
  return p;
}

struct CameraSetup {
  glm::mat4 view, projection;
};
constexpr float kNear = 0.1f, kFar = 100.0f;  // metres, times the placement's scale
CameraSetup camera_for(uint32_t index, float aspect, bool reversed_z, const Placement& at) {
  const glm::vec3 eye = at.point(index == 0 ? glm::vec3(5.0f, 5.0f, 6.0f) : glm::vec3(-6.0f, 3.5f, 3.0f));
  const glm::vec3 target = at.point(index == 0 ? glm::vec3(0.0f, 0.5f, 0.0f) : glm::vec3(0.5f, 0.8f, -0.5f));
  // Right-handed perspective into Vulkan clip space: y down, standard depth (0 near, 1 far).
  const float n = kNear * at.scale, f = kFar * at.scale, t = 1.0f / std::tan(glm::radians(55.0f) * 0.5f);
  glm::mat4 p(0.0f);
  p[0][0] = t / aspect;
  p[1][1] = -t;
  p[2][2] = reversed_z ? n / (f - n) : f / (n - f);  // reversed: depth 1 at the near plane, 0 at the far one
  p[2][3] = -1.0f;
  p[3][2] = reversed_z ? n * f / (f - n) : n * f / (n - f);
  return {glm::lookAt(eye, target, glm::vec3(0, 1, 0)), p};
}

// The sun of frame `frame`: (0.45, -1, 0.3) normalized, turning about the vertical when it moves.
glm::vec3 sun_direction(uint32_t frame, bool moving) {
  const float radius = std::hypot(0.45f, 0.3f), azimuth = std::atan2(0.3f, 0.45f) + (moving ? 0.5f * float(frame) : 0.0f);
  return glm::normalize(glm::vec3(radius * std::cos(azimuth), -1.0f, radius * std::sin(azimuth)));
}

// The lights of a frame, as the module takes them and as the result reports them. The spot light looks
// down at the scene from a corner; the point light hangs above the middle, over the moving caster.
struct FrameLights {
  std::vector<shadows::Light> module;
  std::vector<HostLight> host;
};
FrameLights lights_at(const std::vector<std::string>& kinds, uint32_t frame, bool moving_sun, float range_scale,
                      float sun_size_degrees, float local_radius, const Placement& at) {
  FrameLights out;
  for (const std::string& kind : kinds) {
    shadows::Light l;
    HostLight h{kind};
    if (kind == "sun") {
      const glm::vec3 d = sun_direction(frame, moving_sun);
      l.type = shadows::LightType::Directional;
      std::memcpy(l.direction, &d, 12);
      l.angular_diameter_degrees = sun_size_degrees;
      h.angular_diameter_degrees = sun_size_degrees;
    } else if (kind == "spot") {
      const glm::vec3 position(3.0f, 4.5f, 3.5f), d = glm::normalize(glm::vec3(0.0f, 0.3f, 0.0f) - position);
      l.type = shadows::LightType::Spot;
      std::memcpy(l.direction, &d, 12);
      std::memcpy(l.position, &position, 12);
      l.range = 12.0f * range_scale;
      l.inner_cone = 0.45f;
      l.outer_cone = 0.6f;
    } else if (kind == "point") {
      const glm::vec3 position(0.5f, 3.4f, -0.6f);
      l.type = shadows::LightType::Point;
      std::memcpy(l.position, &position, 12);
      l.range = 9.0f * range_scale;
    } else {
      throw std::runtime_error("unknown light '" + kind + "' (sun, spot or point)");
    }
    if (kind != "sun") {
      const glm::vec3 placed = at.point(glm::make_vec3(l.position));
      std::memcpy(l.position, &placed, 12);
      l.range *= at.scale;
      l.radius = local_radius * at.scale;
    }
    h.radius = l.radius;
    std::memcpy(h.direction.data(), l.direction, 12);
    std::memcpy(h.position.data(), l.position, 12);
    h.range = l.range;
    h.outer_cone = l.outer_cone;
    out.module.push_back(l);
    out.host.push_back(h);
  }
  return out;
}

VkShaderModule load_shader(VkDevice device, const std::string& directory, const char* name) {
  // The program's SPIR-V lies in vulkan_host_shaders/ next to the executable unless told otherwise.
  const std::filesystem::path folder = directory.empty()
                                           ? std::filesystem::read_symlink("/proc/self/exe").parent_path() / "vulkan_host_shaders"
                                           : std::filesystem::path(directory);
  const auto path = folder / name;
  std::ifstream file(path, std::ios::binary);
  const std::vector<char> code((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (code.empty() || code.size() % 4) throw std::runtime_error("cannot read shader " + path.string());
  VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  info.codeSize = code.size();
  info.pCode = reinterpret_cast<const uint32_t*>(code.data());
  VkShaderModule module;
  check(vkCreateShaderModule(device, &info, nullptr, &module), "vkCreateShaderModule");
  return module;
}

struct DrawPush {  // gbuffer.vert / gbuffer.frag: 128 bytes, the least every device offers
  glm::mat4 view_projection;
  glm::vec4 world_rows[3];  // the affine object -> world transform, row by row
  glm::vec4 albedo;
};
struct DrawFrame {  // gbuffer.frag's uniform buffer, one per frame slot
  glm::vec4 view_rows[3];  // world -> view rotation; view_rows[0].w: the module's normals in view space
  glm::vec4 to_sun;        // w: the module's normal encoding (0 octahedral, 1 xyz * 0.5 + 0.5)
};

VkFormat depth_format_of(const std::string& name) {
  if (name == "d32") return VK_FORMAT_D32_SFLOAT;
  if (name == "d24s8") return VK_FORMAT_D24_UNORM_S8_UINT;
  if (name == "d32s8") return VK_FORMAT_D32_SFLOAT_S8_UINT;
  if (name == "d16") return VK_FORMAT_D16_UNORM;
  throw std::runtime_error("unknown depth format '" + name + "' (d32, d24s8, d32s8 or d16)");
}
VkFormat output_format_of(const std::string& name) {
  if (name == "r8") return VK_FORMAT_R8_UNORM;
  if (name == "r16f") return VK_FORMAT_R16_SFLOAT;
  if (name == "r32f") return VK_FORMAT_R32_SFLOAT;
  throw std::runtime_error("unknown output format '" + name + "' (r8, r16f or r32f)");
}
// A depth texel as copied to a buffer (the depth aspect: D24 as X8_D24, D32 as float, D16 as unorm).
float depth_texel(const void* data, size_t i, VkFormat format) {
  if (format == VK_FORMAT_D16_UNORM) return static_cast<const uint16_t*>(data)[i] / 65535.0f;
  if (format == VK_FORMAT_D24_UNORM_S8_UINT) return float(static_cast<const uint32_t*>(data)[i] & 0xffffffu) / float(0xffffff);
  return static_cast<const float*>(data)[i];
}
float output_texel(const void* data, size_t i, VkFormat format) {
  if (format == VK_FORMAT_R8_UNORM) return static_cast<const uint8_t*>(data)[i] / 255.0f;
  if (format == VK_FORMAT_R16_SFLOAT) return glm::unpackHalf1x16(static_cast<const uint16_t*>(data)[i]);
  return static_cast<const float*>(data)[i];
}

// What run() made on the host's device, destroyed newest first when run() leaves: at its end, or when a
// step throws (a missing shader, a refused input), so that an error leaves no object alive when the
// device goes. Each step holds copies of its handles (the variables may be gone by then); the device
// is idle first, and the module goes before the host's objects it was handed.
class Teardown {
 public:
  Teardown(const Device& device, std::unique_ptr<shadows::Context>& module) : device_(device), module_(module) {}
  ~Teardown() { run(); }
  Teardown(const Teardown&) = delete;
  Teardown& operator=(const Teardown&) = delete;
  // Each returns what it was handed, now destroyed with the rest.
  Buffer kept(Buffer b) {
    steps_.push_back([this, b]() mutable { destroy(device_, b); });
    return b;
  }
  Image kept(Image i) {
    steps_.push_back([this, i]() mutable { destroy(device_, i); });
    return i;
  }
  template <class Handle>
  Handle kept(Handle handle, void (*destroy_handle)(VkDevice, Handle, const VkAllocationCallbacks*)) {
    steps_.push_back([this, handle, destroy_handle] { destroy_handle(device_.device, handle, nullptr); });
    return handle;
  }
  void run() {
    vkDeviceWaitIdle(device_.device);
    module_.reset();
    for (; !steps_.empty(); steps_.pop_back()) steps_.back()();
  }

 private:
  const Device& device_;
  std::unique_ptr<shadows::Context>& module_;
  std::vector<std::function<void()>> steps_;
};

}  // namespace

Result run(const Options& o) {
  std::optional<shadows::Settings> settings = shadows::parse_mode(o.mode, shadows::Settings{});
  if (!settings) throw std::runtime_error("unknown mode '" + o.mode + "'");
  if (o.spp != 1 && o.spp != 32) throw std::runtime_error("--spp must be 1 or 32");
  settings->izb.samples_per_pixel = o.spp;
  // The scene's metres are world_scale world units: the module's distances in metres (the cascades'
  // narrowest filter, the ranges) follow them.
  settings->units_per_metre = o.world_scale;
  const VkFormat depth_format = depth_format_of(o.depth_format), output_format = output_format_of(o.output_format);
  if (o.normals != "oct" && o.normals != "xyz") throw std::runtime_error("unknown normals '" + o.normals + "' (oct or xyz)");
  if (o.facing_in_alpha && !o.geometric_normals) throw std::runtime_error("facing in alpha needs the geometric normals");
  if (o.lights.empty() || o.lights.size() > shadows::kMaxLightsPerRecord)
    throw std::runtime_error("--lights takes 1 to " + std::to_string(shadows::kMaxLightsPerRecord) + " lights");
  const uint32_t F = o.frames_in_flight;
  Device d({.device = o.device, .validation = o.validation, .sync_validation = o.sync_validation});
  const VkDevice dev = d.device;
  shadows::ContextDesc desc = d.context_desc(F, *settings);
  desc.masked_features = o.masked_features;
  auto module = shadows::Context::create(desc);
  Teardown teardown(d, module);
  if (o.output_term != "occlusion" && o.output_term != "combined")
    throw std::runtime_error("unknown output term '" + o.output_term + "' (occlusion or combined)");
  const shadows::OutputTerm output_term =
      o.output_term == "combined" ? shadows::OutputTerm::Combined : shadows::OutputTerm::Occlusion;
  const shadows::Capability can = module->capabilities().of(settings->technique);
  if (!can.available) throw std::runtime_error(can.reason);
  module->set_collect_stats(o.report_completed);

  // ----- Meshes: one buffer per mesh (interleaved position + normal, then indices), also the module's input.
  const VkBufferUsageFlags mesh_usage =
      VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_INDEX_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  const auto shape_of = [&](uint32_t frame) {
    return o.cube_shapes.empty() ? 0u : o.cube_shapes[std::min<size_t>(frame, o.cube_shapes.size() - 1)];
  };
  const MeshData meshes[2] = {ground_quad(), shaped_cube(o.deformed_cubes ? 0 : shape_of(0))};
  // The cube in each shape, as the G-buffer draws it and deformed instances hand it to the module
  // (vertices, then the 32-bit indices at the cube's index offset).
  const MeshData shapes[3] = {shaped_cube(0), shaped_cube(1), shaped_cube(2)};
  Buffer shape_buffers[3];
  for (uint32_t k = 0; k < 3; ++k) {
    const VkDeviceSize vertex_bytes = shapes[k].vertices.size() * sizeof(Vertex);
    shape_buffers[k] = teardown.kept(make_buffer(d, vertex_bytes + shapes[k].indices.size() * 4, mesh_usage));
    auto* bytes = static_cast<uint8_t*>(shape_buffers[k].mapped);
    std::memcpy(bytes, shapes[k].vertices.data(), vertex_bytes);
    std::memcpy(bytes + vertex_bytes, shapes[k].indices.data(), shapes[k].indices.size() * 4);
  }
  const VkIndexType index_types[2] = {VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32};
  Buffer mesh_buffers[2];
  VkDeviceSize index_offsets[2];
  shadows::MeshId mesh_ids[2];
  for (int m = 0; m < 2; ++m) {
    const MeshData& mesh = meshes[m];
    const VkDeviceSize vertex_bytes = mesh.vertices.size() * sizeof(Vertex);
    const uint32_t index_size = index_types[m] == VK_INDEX_TYPE_UINT16 ? 2 : 4;
    index_offsets[m] = vertex_bytes;
    mesh_buffers[m] = teardown.kept(make_buffer(d, vertex_bytes + mesh.indices.size() * index_size, mesh_usage));
    auto* bytes = static_cast<uint8_t*>(mesh_buffers[m].mapped);
    std::memcpy(bytes, mesh.vertices.data(), vertex_bytes);
    for (size_t i = 0; i < mesh.indices.size(); ++i) {
      if (index_size == 2) reinterpret_cast<uint16_t*>(bytes + vertex_bytes)[i] = uint16_t(mesh.indices[i]);
      else reinterpret_cast<uint32_t*>(bytes + vertex_bytes)[i] = mesh.indices[i];
    }
    shadows::MeshDesc desc;
    desc.name = m == 0 ? "ground" : "cube";
    desc.positions = {mesh_buffers[m].buffer, 0, vertex_bytes, mesh_usage};
    desc.position_stride = sizeof(Vertex);  // positions interleaved with the normals the G-buffer reads
    desc.vertex_count = uint32_t(mesh.vertices.size());
    desc.indices = mesh_buffers[m].input(vertex_bytes);
    desc.index_type = index_types[m];
    desc.index_count = uint32_t(mesh.indices.size());
    if (o.mesh_bounds) {
      desc.bounds.emplace();
      std::memcpy(desc.bounds->min, &mesh.min, 12);
      std::memcpy(desc.bounds->max, &mesh.max, 12);
    }
    mesh_ids[m] = module->register_mesh(desc);
  }

  // ----- Targets: the host's G-buffer in its own formats, the module's output, the lit frame.
  const VkExtent2D extent{o.width, o.height};
  const VkImageUsageFlags read = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  Image depth = teardown.kept(make_image(d, extent, depth_format, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | read));
  Image albedo = teardown.kept(make_image(d, extent, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | read));
  Image normals = teardown.kept(make_image(d, extent, VK_FORMAT_R16G16_SNORM, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | read));
  // What the module reads as normals (octahedral world: the lighting's own image), and the geometric
  // normals; both always drawn, handed over as the options say.
  const bool own_normals = o.normals != "oct" || o.view_space_normals;
  Image module_normals = teardown.kept(make_image(d, extent, o.normals == "xyz" ? VK_FORMAT_R16G16B16A16_SFLOAT : VK_FORMAT_R16G16_SNORM,
                                    VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | read));
  Image geometric_normals = teardown.kept(make_image(d, extent, VK_FORMAT_R16G16B16A16_SFLOAT, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | read));
  Image terminator = teardown.kept(make_image(d, extent, VK_FORMAT_R16G16B16A16_SFLOAT, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | read));
  // The module's outputs, one per light (the first lights the frame; the others are light_outputs).
  const uint32_t light_count = uint32_t(o.lights.size());
  std::vector<Image> visibility;
  std::vector<shadows::ImageInput> light_outputs;
  for (uint32_t l = 0; l < light_count; ++l) {
    visibility.push_back(teardown.kept(make_image(d, extent, output_format, VK_IMAGE_USAGE_STORAGE_BIT | read)));
    if (l > 0) light_outputs.push_back(visibility.back().input(VK_IMAGE_LAYOUT_GENERAL));
  }
  Image lit = teardown.kept(make_image(d, extent, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_STORAGE_BIT | read));
  const size_t pixels = size_t(o.width) * o.height;
  // Read-backs per frame slot, read when the host waits for that slot's fence (so frames stay in
  // flight while every one of them is captured).
  struct SlotCapture {
    Buffer depth, normals, lit, albedo;  // the depth aspect, R16G16_SNORM, RGBA8, RGBA8
    std::vector<Buffer> visibility;  // the output format, per light
    bool pending = false;
    uint32_t frame = 0;
    glm::mat4 inverse_view_projection{1.0f};
    std::vector<HostLight> lights;
    std::vector<Object> objects;
  };
  std::vector<SlotCapture> captures(F);
  auto readbacks_of = [&](SlotCapture& c) -> SlotCapture& {
    if (!c.depth.buffer) {
      c.depth = teardown.kept(make_buffer(d, pixels * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT));
      c.normals = teardown.kept(make_buffer(d, pixels * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT));
      c.lit = teardown.kept(make_buffer(d, pixels * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT));
      c.albedo = teardown.kept(make_buffer(d, pixels * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT));
      for (uint32_t l = 0; l < light_count; ++l) c.visibility.push_back(teardown.kept(make_buffer(d, pixels * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT)));
    }
    return c;
  };

  // ----- Pipelines: G-buffer (dynamic rendering) and lighting (compute, push descriptors).
  VkSampler sampler;
  VkSamplerCreateInfo sampler_info{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  check(vkCreateSampler(dev, &sampler_info, nullptr, &sampler), "vkCreateSampler");
  teardown.kept(sampler, vkDestroySampler);
  VkPushConstantRange draw_push{VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(DrawPush)};
  // gbuffer.frag: the frame's uniform buffer (DrawFrame), a push descriptor.
  const VkDescriptorSetLayoutBinding frame_binding{0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, VK_SHADER_STAGE_FRAGMENT_BIT, nullptr};
  VkDescriptorSetLayoutCreateInfo frame_set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  frame_set_info.flags = VK_DESCRIPTOR_SET_LAYOUT_CREATE_PUSH_DESCRIPTOR_BIT_KHR;
  frame_set_info.bindingCount = 1;
  frame_set_info.pBindings = &frame_binding;
  VkDescriptorSetLayout draw_set;
  check(vkCreateDescriptorSetLayout(dev, &frame_set_info, nullptr, &draw_set), "vkCreateDescriptorSetLayout");
  teardown.kept(draw_set, vkDestroyDescriptorSetLayout);
  VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  layout_info.setLayoutCount = 1;
  layout_info.pSetLayouts = &draw_set;
  layout_info.pushConstantRangeCount = 1;
  layout_info.pPushConstantRanges = &draw_push;
  VkPipelineLayout draw_layout, light_layout;
  check(vkCreatePipelineLayout(dev, &layout_info, nullptr, &draw_layout), "vkCreatePipelineLayout");
  teardown.kept(draw_layout, vkDestroyPipelineLayout);
  // light.comp: albedo, normals, visibility (sampled), the lit frame (storage).
  VkDescriptorSetLayoutBinding bindings[4];
  for (uint32_t b = 0; b < 4; ++b)
    bindings[b] = {b, b < 3 ? VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER : VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1,
                   VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  set_info.flags = VK_DESCRIPTOR_SET_LAYOUT_CREATE_PUSH_DESCRIPTOR_BIT_KHR;
  set_info.bindingCount = 4;
  set_info.pBindings = bindings;
  VkDescriptorSetLayout light_set;
  check(vkCreateDescriptorSetLayout(dev, &set_info, nullptr, &light_set), "vkCreateDescriptorSetLayout");
  teardown.kept(light_set, vkDestroyDescriptorSetLayout);
  VkPushConstantRange light_push{VK_SHADER_STAGE_COMPUTE_BIT, 0, 16};
  layout_info.setLayoutCount = 1;
  layout_info.pSetLayouts = &light_set;
  layout_info.pPushConstantRanges = &light_push;
  check(vkCreatePipelineLayout(dev, &layout_info, nullptr, &light_layout), "vkCreatePipelineLayout");
  teardown.kept(light_layout, vkDestroyPipelineLayout);

  // (The modules live until the teardown: a later one's missing file must not leave the first.)
  const VkShaderModule vs = teardown.kept(load_shader(dev, o.shader_directory, "gbuffer.vert.spv"), vkDestroyShaderModule);
  const VkShaderModule fs = teardown.kept(load_shader(dev, o.shader_directory, "gbuffer.frag.spv"), vkDestroyShaderModule);
  const VkShaderModule cs = teardown.kept(load_shader(dev, o.shader_directory, "light.comp.spv"), vkDestroyShaderModule);
  VkPipelineShaderStageCreateInfo stages[2] = {
      {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_VERTEX_BIT, vs, "main"},
      {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_FRAGMENT_BIT, fs, "main"}};
  const VkVertexInputBindingDescription vertex_binding{0, sizeof(Vertex), VK_VERTEX_INPUT_RATE_VERTEX};
  const VkVertexInputAttributeDescription attributes[2] = {{0, 0, VK_FORMAT_R32G32B32_SFLOAT, 0},
                                                           {1, 0, VK_FORMAT_R32G32B32_SFLOAT, 12}};
  VkPipelineVertexInputStateCreateInfo vertex_input{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
  vertex_input.vertexBindingDescriptionCount = 1;
  vertex_input.pVertexBindingDescriptions = &vertex_binding;
  vertex_input.vertexAttributeDescriptionCount = 2;
  vertex_input.pVertexAttributeDescriptions = attributes;
  VkPipelineInputAssemblyStateCreateInfo assembly{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
  assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  const VkViewport viewport{0, 0, float(o.width), float(o.height), 0, 1};
  const VkRect2D scissor{{0, 0}, extent};
  VkPipelineViewportStateCreateInfo viewport_state{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
  viewport_state.viewportCount = viewport_state.scissorCount = 1;
  viewport_state.pViewports = &viewport;
  viewport_state.pScissors = &scissor;
  VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  raster.cullMode = VK_CULL_MODE_NONE;
  raster.lineWidth = 1.0f;
  VkPipelineMultisampleStateCreateInfo multisample{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
  multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
  VkPipelineDepthStencilStateCreateInfo depth_state{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
  depth_state.depthTestEnable = depth_state.depthWriteEnable = VK_TRUE;
  // Standard Z: cleared to 1, nearer is smaller; reversed: cleared to 0, nearer is larger.
  depth_state.depthCompareOp = o.reversed_z ? VK_COMPARE_OP_GREATER : VK_COMPARE_OP_LESS;
  VkPipelineColorBlendAttachmentState blend[5] = {};
  for (auto& b : blend) b.colorWriteMask = 0xf;
  VkPipelineColorBlendStateCreateInfo blend_state{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
  blend_state.attachmentCount = 5;
  blend_state.pAttachments = blend;
  const VkFormat color_formats[5] = {albedo.format, normals.format, module_normals.format, geometric_normals.format,
                                     terminator.format};
  VkPipelineRenderingCreateInfo rendering{VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO};
  rendering.colorAttachmentCount = 5;
  rendering.pColorAttachmentFormats = color_formats;
  rendering.depthAttachmentFormat = depth.format;
  const bool has_stencil = depth.format == VK_FORMAT_D24_UNORM_S8_UINT || depth.format == VK_FORMAT_D32_SFLOAT_S8_UINT;
  rendering.stencilAttachmentFormat = has_stencil ? depth.format : VK_FORMAT_UNDEFINED;
  VkGraphicsPipelineCreateInfo gp{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO, &rendering};
  gp.stageCount = 2;
  gp.pStages = stages;
  gp.pVertexInputState = &vertex_input;
  gp.pInputAssemblyState = &assembly;
  gp.pViewportState = &viewport_state;
  gp.pRasterizationState = &raster;
  gp.pMultisampleState = &multisample;
  gp.pDepthStencilState = &depth_state;
  gp.pColorBlendState = &blend_state;
  gp.layout = draw_layout;
  VkPipeline draw_pipeline, light_pipeline;
  check(vkCreateGraphicsPipelines(dev, VK_NULL_HANDLE, 1, &gp, nullptr, &draw_pipeline), "vkCreateGraphicsPipelines");
  teardown.kept(draw_pipeline, vkDestroyPipeline);
  VkComputePipelineCreateInfo cp{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  cp.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_COMPUTE_BIT, cs, "main"};
  cp.layout = light_layout;
  check(vkCreateComputePipelines(dev, VK_NULL_HANDLE, 1, &cp, nullptr, &light_pipeline), "vkCreateComputePipelines");
  teardown.kept(light_pipeline, vkDestroyPipeline);
  auto push_descriptors = reinterpret_cast<PFN_vkCmdPushDescriptorSetKHR>(vkGetDeviceProcAddr(dev, "vkCmdPushDescriptorSetKHR"));

  // ----- Frames in flight: a command buffer and a fence per slot.
  VkCommandPool pool;
  VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pool_info.queueFamilyIndex = d.family;
  check(vkCreateCommandPool(dev, &pool_info, nullptr, &pool), "vkCreateCommandPool");
  teardown.kept(pool, vkDestroyCommandPool);
  std::vector<VkCommandBuffer> cmds(F);
  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO, nullptr, pool,
                                    VK_COMMAND_BUFFER_LEVEL_PRIMARY, F};
  check(vkAllocateCommandBuffers(dev, &alloc, cmds.data()), "vkAllocateCommandBuffers");
  std::vector<VkFence> fences(F);
  std::vector<Buffer> draw_frames;
  for (uint32_t k = 0; k < F; ++k) draw_frames.push_back(teardown.kept(make_buffer(d, sizeof(DrawFrame), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT)));
  VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO, nullptr, VK_FENCE_CREATE_SIGNALED_BIT};
  for (VkFence& f : fences) {
    check(vkCreateFence(dev, &fence_info, nullptr, &f), "vkCreateFence");
    teardown.kept(f, vkDestroyFence);
  }

  const auto C = VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT;
  // What reads a target before the next frame writes it: the module's and the lighting's compute
  // passes, and a captured frame's copies.
  const auto READERS = C | VK_PIPELINE_STAGE_2_COPY_BIT;
  const auto FRAGMENT_TESTS = VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT;
  Result r;
  std::vector<uint8_t> last_rgba;
  // A slot's captured frame, once its fence has been waited for: decoded into r.frames.
  auto collect = [&](SlotCapture& c) {
    FrameCapture f;
    f.frame = c.frame;
    f.depth.resize(pixels);
    f.normals.resize(pixels * 3);
    const auto* depth_words = static_cast<const uint32_t*>(c.depth.mapped);
    const auto* normal_texels = static_cast<const int16_t*>(c.normals.mapped);
    f.reversed_z = o.reversed_z;
    f.terminator_offset = o.terminator_offset ? kTerminatorOffset : 0.0f;
    if (o.receiver_mask) {
      const auto* rgba = static_cast<const uint8_t*>(c.albedo.mapped);
      f.receives.resize(pixels);
      for (size_t i = 0; i < pixels; ++i) f.receives[i] = rgba[4 * i + 3] > 127 ? 1 : 0;
    }
    f.depth_step = depth_format == VK_FORMAT_D16_UNORM           ? 1.0f / 65535.0f
                   : depth_format == VK_FORMAT_D24_UNORM_S8_UINT ? 1.0f / 16777215.0f
                                                                 : 0.0f;
    for (size_t i = 0; i < pixels; ++i) {
      f.depth[i] = depth_texel(depth_words, i, depth_format);
      glm::vec2 e(std::max(normal_texels[2 * i] / 32767.0f, -1.0f), std::max(normal_texels[2 * i + 1] / 32767.0f, -1.0f));
      glm::vec3 n(e, 1.0f - std::abs(e.x) - std::abs(e.y));
      if (n.z < 0.0f) n = glm::vec3((1.0f - glm::abs(glm::vec2(n.y, n.x))) * glm::vec2(n.x >= 0 ? 1 : -1, n.y >= 0 ? 1 : -1), n.z);
      n = glm::normalize(n);
      std::memcpy(&f.normals[3 * i], &n, 12);
    }
    for (const Buffer& b : c.visibility) {
      std::vector<float>& v = f.visibility.emplace_back(pixels);
      for (size_t i = 0; i < pixels; ++i) v[i] = output_texel(b.mapped, i, output_format);
    }
    std::memcpy(f.inverse_view_projection.data(), glm::value_ptr(c.inverse_view_projection), 64);
    f.lights = c.lights;
    for (const Object& obj : c.objects)
      for (uint32_t index : meshes[obj.mesh].indices) {
        const MeshData& mesh = obj.mesh == 1 ? shapes[shape_of(c.frame)] : meshes[obj.mesh];
        const glm::vec3 p(obj.world * glm::vec4(mesh.vertices[index].position, 1.0f));
        f.caster_triangles.insert(f.caster_triangles.end(), {p.x, p.y, p.z});
      }
    if (c.frame + 1 == o.frames) {
      const auto* rgba = static_cast<const uint8_t*>(c.lit.mapped);
      last_rgba.assign(rgba, rgba + pixels * 4);
    }
    r.frames.push_back(std::move(f));
    c.pending = false;
  };
  // The host knows `frame` has completed: the module reads its statistics now.
  auto completed = [&](uint32_t frame) {
    if (!o.report_completed) return;
    module->frame_completed(frame);
    r.csm_culled += module->stats().csm_culled;
  };
  for (uint32_t frame = 0; frame < o.frames; ++frame) {
    // The slot's previous frame (frame - F) has completed: the module's frames-in-flight promise.
    const uint32_t slot = frame % F;
    check(vkWaitForFences(dev, 1, &fences[slot], VK_TRUE, UINT64_MAX), "vkWaitForFences");
    if (captures[slot].pending) collect(captures[slot]);
    if (frame >= F) completed(frame - F);
    check(vkResetFences(dev, 1, &fences[slot]), "vkResetFences");
    VkCommandBuffer cmd = cmds[slot];
    check(vkResetCommandBuffer(cmd, 0), "vkResetCommandBuffer");
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    check(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");
    const Placement placement = placement_at(o, frame);
    const CameraSetup camera = camera_for(o.view, float(o.width) / float(o.height), o.reversed_z, placement);
    const glm::mat4 view_projection = camera.projection * camera.view;
    const FrameLights lights =
        lights_at(o.lights, frame, o.moving_sun, o.local_range_scale, o.sun_size_degrees, o.local_radius, placement);
    const bool capture = o.capture_every_frame || frame + 1 == o.frames;

    // G-buffer. Earlier frames read it (module, lighting, capture copies); their contents are discarded.
    image_barrier(cmd, depth, READERS, 0, FRAGMENT_TESTS, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT |
                  VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                  VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL);
    for (const Image* target : {&albedo, &normals, &module_normals, &geometric_normals, &terminator})
      image_barrier(cmd, *target, READERS, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                    VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                    VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
    VkRenderingAttachmentInfo colors[5];
    const Image* targets[5] = {&albedo, &normals, &module_normals, &geometric_normals, &terminator};
    for (int i = 0; i < 5; ++i) {
      colors[i] = {VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
      colors[i].imageView = targets[i]->view;
      colors[i].imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
      colors[i].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
      colors[i].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    }
    VkRenderingAttachmentInfo depth_attachment{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    depth_attachment.imageView = depth.view;
    depth_attachment.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    depth_attachment.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    depth_attachment.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    depth_attachment.clearValue.depthStencil = {o.reversed_z ? 0.0f : 1.0f, 0};  // far
    VkRenderingInfo rendering_info{VK_STRUCTURE_TYPE_RENDERING_INFO};
    rendering_info.renderArea = scissor;
    rendering_info.layerCount = 1;
    rendering_info.colorAttachmentCount = 5;
    rendering_info.pColorAttachments = colors;
    rendering_info.pDepthAttachment = &depth_attachment;
    rendering_info.pStencilAttachment = has_stencil ? &depth_attachment : nullptr;
    vkCmdBeginRendering(cmd, &rendering_info);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, draw_pipeline);
    // The slot's uniforms: its previous frame has completed (its fence), so the host may write them.
    const glm::mat4 view_rows = glm::transpose(camera.view);
    const DrawFrame frame_uniforms{{glm::vec4(glm::vec3(view_rows[0]), o.view_space_normals ? 1.0f : 0.0f),
                                    glm::vec4(glm::vec3(view_rows[1]), o.terminator_offset ? kTerminatorOffset : 0.0f),
                                    view_rows[2]},
                                   glm::vec4(-sun_direction(frame, o.moving_sun), o.normals == "xyz" ? 1.0f : 0.0f)};
    std::memcpy(draw_frames[slot].mapped, &frame_uniforms, sizeof(frame_uniforms));
    const VkDescriptorBufferInfo frame_buffer{draw_frames[slot].buffer, 0, sizeof(DrawFrame)};
    const VkWriteDescriptorSet frame_write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, VK_NULL_HANDLE, 0, 0, 1,
                                           VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, nullptr, &frame_buffer, nullptr};
    push_descriptors(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, draw_layout, 0, 1, &frame_write);
    std::vector<Object> objects = scene_at(o.still ? 0 : frame);
    for (Object& obj : objects) obj.world = placement.matrix(obj.world);
    std::vector<shadows::Instance> instances(objects.size());
    const uint32_t shape = shape_of(frame);
    for (size_t i = 0; i < objects.size(); ++i) {
      const Object& obj = objects[i];
      const glm::mat4 rows = glm::transpose(obj.world);
      const DrawPush push{view_projection, {rows[0], rows[1], rows[2]}, obj.albedo};
      vkCmdPushConstants(cmd, draw_layout, draw_push.stageFlags, 0, sizeof(push), &push);
      const VkDeviceSize zero = 0;
      const VkBuffer drawn = obj.mesh == 1 ? shape_buffers[shape].buffer : mesh_buffers[obj.mesh].buffer;
      vkCmdBindVertexBuffers(cmd, 0, 1, &drawn, &zero);
      vkCmdBindIndexBuffer(cmd, drawn, index_offsets[obj.mesh], index_types[obj.mesh]);
      vkCmdDrawIndexed(cmd, uint32_t(meshes[obj.mesh].indices.size()), 1, 0, 0, 0);
      instances[i].mesh = mesh_ids[obj.mesh];
      std::memcpy(instances[i].world, glm::value_ptr(obj.world), 64);
      instances[i].id = i;
      if (obj.mesh != 1) continue;
      instances[i].csm = o.cube_csm;
      if (!o.deformed_cubes) continue;
      // The shape's positions straight from the host's vertex buffer (written once, before any frame).
      shadows::DeformedPositions& deformed = instances[i].deformed;
      deformed.positions = {drawn, 0, shapes[shape].vertices.size() * sizeof(Vertex), mesh_usage};
      deformed.stride = sizeof(Vertex);
      deformed.vertex_count = uint32_t(shapes[shape].vertices.size());
      std::memcpy(deformed.bounds.min, &shapes[shape].min, 12);
      std::memcpy(deformed.bounds.max, &shapes[shape].max, 12);
    }
    vkCmdEndRendering(cmd);

    // The module's inputs: G-buffer writes visible to its compute reads (the contract's barrier).
    image_barrier(cmd, depth, FRAGMENT_TESTS, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, C,
                  VK_ACCESS_2_SHADER_SAMPLED_READ_BIT, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                  VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL);
    for (const Image* target : {&albedo, &normals, &module_normals, &geometric_normals, &terminator})
      image_barrier(cmd, *target, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                    C, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                    VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    // Its outputs: the previous frames' lighting reads and copies finish before the module writes (GENERAL).
    for (const Image& v : visibility)
      image_barrier(cmd, v, READERS, 0, C, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                    frame == 0 ? VK_IMAGE_LAYOUT_UNDEFINED : VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL);

    shadows::FrameDesc fd;
    fd.frame_index = frame;
    fd.depth = depth.input(VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL);
    fd.normals.image = (own_normals ? module_normals : normals).input(VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    if (o.normals == "xyz") {
      fd.normals.encoding = shadows::NormalEncoding::Xyz;  // stored n * 0.5 + 0.5
      fd.normals.scale = 2.0f;
      fd.normals.bias = -1.0f;
    } else {
      fd.normals.encoding = shadows::NormalEncoding::Octahedral;  // SNORM: already in [-1, 1]
    }
    fd.normals.space = o.view_space_normals ? shadows::NormalSpace::View : shadows::NormalSpace::World;
    if (o.geometric_normals) {
      fd.geometric_normals.image = geometric_normals.input(VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
      fd.geometric_normals.encoding = shadows::NormalEncoding::Xyz;
      fd.facing_in_alpha = o.facing_in_alpha;
    }
    if (o.terminator_offset) fd.terminator_offset = terminator.input(VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    if (o.receiver_mask) {
      fd.receiver_mask = albedo.input(VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
      fd.receiver_channel = 3;
    }
    std::memcpy(fd.camera.view, glm::value_ptr(camera.view), 64);
    std::memcpy(fd.camera.projection, glm::value_ptr(camera.projection), 64);
    fd.camera.reversed_z = o.reversed_z;
    fd.camera.near_plane = kNear * placement.scale;
    fd.camera.far_plane = kFar * placement.scale;
    std::memcpy(fd.origin, placement.origin.data(), sizeof(fd.origin));
    fd.lights = lights.module.data();
    fd.light_count = light_count;
    fd.instances = instances.data();
    fd.instance_count = uint32_t(instances.size());
    fd.output = visibility[0].input(VK_IMAGE_LAYOUT_GENERAL);
    fd.light_outputs = light_outputs.empty() ? nullptr : light_outputs.data();
    fd.output_term = output_term;
    module->record(cmd, fd);

    // Lighting: albedo * (ambient + sun * the first light's visibility), into the lit frame (written
    // last frame and maybe copied: WAW and WAR).
    image_barrier(cmd, visibility[0], C, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, C, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT,
                  VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL);
    image_barrier(cmd, lit, READERS, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, C, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                  frame == 0 ? VK_IMAGE_LAYOUT_UNDEFINED : VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, light_pipeline);
    VkDescriptorImageInfo image_infos[4] = {{sampler, albedo.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL},
                                            {sampler, normals.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL},
                                            {sampler, visibility[0].view, VK_IMAGE_LAYOUT_GENERAL},
                                            {VK_NULL_HANDLE, lit.view, VK_IMAGE_LAYOUT_GENERAL}};
    VkWriteDescriptorSet writes[4];
    for (uint32_t b = 0; b < 4; ++b)
      writes[b] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, nullptr, VK_NULL_HANDLE, b, 0, 1, bindings[b].descriptorType,
                   &image_infos[b], nullptr, nullptr};
    push_descriptors(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, light_layout, 0, 4, writes);
    const glm::vec4 to_light(-sun_direction(frame, o.moving_sun), 0.0f);
    vkCmdPushConstants(cmd, light_layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, 16, &to_light);
    vkCmdDispatch(cmd, (o.width + 7) / 8, (o.height + 7) / 8, 1);

    if (capture) {
      // Capture: every image of the frame into the slot's read-back buffers, then to the host.
      SlotCapture& c = readbacks_of(captures[slot]);
      image_barrier(cmd, depth, C, 0, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT,
                    VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
      for (const Image* image : {&normals, &albedo})
        image_barrier(cmd, *image, C, 0, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT,
                      VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
      for (const Image& v : visibility)
        image_barrier(cmd, v, C, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
                      VK_ACCESS_2_TRANSFER_READ_BIT, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL);
      image_barrier(cmd, lit, C, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
                    VK_ACCESS_2_TRANSFER_READ_BIT, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_GENERAL);
      std::vector<std::pair<const Image*, const Buffer*>> copies = {
          {&depth, &c.depth}, {&normals, &c.normals}, {&albedo, &c.albedo}, {&lit, &c.lit}};
      for (uint32_t l = 0; l < light_count; ++l) copies.push_back({&visibility[l], &c.visibility[l]});
      for (const auto& [image, buffer] : copies) {
        VkBufferImageCopy region{};
        region.imageSubresource = {image->aspect, 0, 0, 1};
        region.imageExtent = {o.width, o.height, 1};
        const VkImageLayout layout = image == &depth || image == &normals || image == &albedo
                                         ? VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL
                                         : VK_IMAGE_LAYOUT_GENERAL;
        vkCmdCopyImageToBuffer(cmd, image->image, layout, buffer->buffer, 1, &region);
      }
      VkMemoryBarrier2 to_host{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2, nullptr, VK_PIPELINE_STAGE_2_COPY_BIT,
                               VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT};
      VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
      dep.memoryBarrierCount = 1;
      dep.pMemoryBarriers = &to_host;
      vkCmdPipelineBarrier2(cmd, &dep);
      c.pending = true;
      c.frame = frame;
      c.inverse_view_projection = glm::inverse(view_projection);
      c.lights = lights.host;
      c.objects = objects;
    }
    check(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    check(vkQueueSubmit(d.queue, 1, &submit, fences[slot]), "vkQueueSubmit");
  }
  check(vkWaitForFences(dev, F, fences.data(), VK_TRUE, UINT64_MAX), "vkWaitForFences");
  for (uint32_t frame = o.frames > F ? o.frames - F : 0; frame < o.frames; ++frame) {
    SlotCapture& c = captures[frame % F];
    if (c.pending && c.frame == frame) collect(c);
    completed(frame);
  }
  r.csm_status = module->stats().csm_status;
  r.light_stats = module->stats().lights;
  r.csm_decisions = module->stats().csm_decisions;

  // ----- The last frame, for the PNG and for tests that trace the same scene.
  const FrameCapture& last = r.frames.back();
  r.width = o.width;
  r.height = o.height;
  r.device_name = d.name;
  r.depth = last.depth;
  r.normals = last.normals;
  r.visibility = last.visibility[0];
  r.rgba = last_rgba;
  r.inverse_view_projection = last.inverse_view_projection;
  r.light_direction = last.lights[0].direction;
  r.caster_triangles = last.caster_triangles;

  // ----- Teardown (the module first: it holds objects of the host's device), before the messages are counted.
  teardown.run();
  r.validation_messages = d.validation_messages();
  return r;
}

}  // namespace vulkan_host
