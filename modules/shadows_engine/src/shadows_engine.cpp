#include "shadows_engine/shadows_engine.hpp"

#include <cstdlib>
#include <cstring>
#include <deque>
#include <map>
#include <optional>
#include <stdexcept>
#include <tuple>

#include <glm/gtc/type_ptr.hpp>
#include <shared/material.h>

#include "context_impl.hpp"
#include "geometry_store.hpp"

namespace shadows {

namespace {

// SceneGeometry's buffers are storage buffers (and more); the module only needs that.
constexpr VkBufferUsageFlags kGeometryUsage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;

ImageInput image_input(engine::gpu::Image& image) {
  ImageInput in;
  in.image = image.handle();
  in.view = image.view();
  in.format = image.format();
  in.extent = image.extent();
  in.usage = image.usage();
  in.layout = VK_IMAGE_LAYOUT_GENERAL;  // the renderer keeps every target in GENERAL
  return in;
}

struct TextureImage {
  engine::gpu::Image image;
  ImageInput input;
  AlphaWrap wrap_u = AlphaWrap::Repeat, wrap_v = AlphaWrap::Repeat;
};

// An engine texture (entry `index` of the packed texture words) as a sampled image, as a host has them.
TextureImage upload_texture(engine::gpu::Context& ctx, const std::vector<uint32_t>& words, uint32_t index) {
  const uint32_t* header = &words[1 + gpu_shared::kTextureHeaderWords * index];
  const VkExtent2D extent{header[1], header[2]};
  TextureImage t;
  t.image = engine::gpu::Image(ctx, extent, VK_FORMAT_R8G8B8A8_UNORM,
                               VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, "shadows adapter texture");
  const VkDeviceSize bytes = VkDeviceSize(extent.width) * extent.height * 4;
  engine::gpu::Buffer staging(ctx, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true, "shadows adapter texture staging");
  staging.write(&words[header[0]], bytes);
  // Set-up work before the frame is recorded, as any host uploads its textures.
  ctx.immediate_submit([&](VkCommandBuffer cmd) {
    t.image.transition(cmd, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0,
                       VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
    VkBufferImageCopy copy{};
    copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.imageExtent = {extent.width, extent.height, 1};
    vkCmdCopyBufferToImage(cmd, staging.handle(), t.image.handle(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &copy);
    t.image.transition(cmd, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_PIPELINE_STAGE_2_COPY_BIT,
                       VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                       VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
  });
  t.input = image_input(t.image);
  t.input.layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  t.wrap_u = AlphaWrap(header[3] & 0xffu);
  t.wrap_v = AlphaWrap((header[3] >> 8) & 0xffu);
  return t;
}

// The renderer's G-buffer and camera as the module's frame inputs (lights, instances and outputs not
// yet set). Its own shading points, normals and receiver flags are in the module's formats: read in
// place, no input pass, unless `host_inputs` asks for the input pass (the depth and normals are then
// converted; otherwise only checked).
FrameDesc frame_inputs(engine::FrameContext& frame, bool smooth_terminator, bool host_inputs) {
  engine::GBuffer& g = frame.gbuffer;
  FrameDesc f;
  // The renderer's frame index: the module's slot (frame_index % F) is then the renderer's, and the
  // shared profiler's last collected frame is the one that last used the slot (backend probes).
  f.frame_index = frame.view.frame_index;
  // The combined term, as before the choice existed: the renderer's lighting relies on it for points
  // whose geometric normal turns away while the shading normal still faces the light, and the GPU
  // tests compare it with the reference's combined term.
  f.output_term = OutputTerm::Combined;
  f.depth = image_input(g.depth);
  f.normals.image = image_input(g.normal);
  f.normals.facing_camera = true;
  f.geometric_normals.image = image_input(g.geometric_normal);
  f.geometric_normals.facing_camera = true;
  f.facing_in_alpha = true;  // gbuffer.frag's light-facing decision
  if (smooth_terminator) f.terminator_offset = image_input(g.terminator_offset);
  f.receiver_mask = image_input(g.albedo);
  f.receiver_channel = 3;
  if (!host_inputs) {
    f.native.world_position = image_input(g.world_position);
    f.native.geometric_normal = image_input(g.geometric_normal);
    f.native.receives = image_input(g.albedo);
  }
  std::memcpy(f.camera.view, glm::value_ptr(frame.view.view), sizeof(f.camera.view));
  std::memcpy(f.camera.projection, glm::value_ptr(frame.view.projection), sizeof(f.camera.projection));
  f.camera.reversed_z = true;
  for (int k = 0; k < 3; ++k) f.origin[k] = frame.view.origin[k];
  f.camera.near_plane = frame.view.near_plane;
  f.camera.far_plane = frame.view.far_plane;
  return f;
}

// The module on the renderer's device, queue and enabled extensions and features.
std::unique_ptr<detail::ContextImpl> make_context(engine::Renderer& renderer, const Settings& settings) {
  engine::gpu::Context& ctx = renderer.context();
  ContextDesc desc;
  desc.instance = ctx.instance();
  desc.physical_device = ctx.physical_device();
  desc.device = ctx.device();
  desc.queue_family = ctx.queue_family();
  desc.queue = ctx.queue();
  desc.get_instance_proc_addr = vkGetInstanceProcAddr;
  desc.get_device_proc_addr = vkGetDeviceProcAddr;
  // Name arrays as vkCreateInstance/vkCreateDevice took them; the module copies them.
  std::vector<const char*> instance_extensions, device_extensions;
  for (const std::string& e : ctx.enabled_instance_extensions()) instance_extensions.push_back(e.c_str());
  for (const std::string& e : ctx.enabled_device_extensions()) device_extensions.push_back(e.c_str());
  desc.enabled_instance_extension_names = instance_extensions.data();
  desc.enabled_instance_extension_count = uint32_t(instance_extensions.size());
  desc.enabled_device_extension_names = device_extensions.data();
  desc.enabled_device_extension_count = uint32_t(device_extensions.size());
  desc.enabled_features = ctx.enabled_features();
  desc.masked_features = ctx.masked_features();
  // As many as the renderer: it waits for frame N - F before recording frame N and reports each
  // completed frame through after_frame().
  desc.frames_in_flight = renderer.frames_in_flight();
  desc.settings = settings;
  return std::make_unique<detail::ContextImpl>(desc);
}

class EngineShadowModule final : public ShadowModule {
 public:
  EngineShadowModule(engine::Renderer& renderer, const Settings& settings)
      : renderer_(renderer), context_(make_context(renderer, settings)) {
    context_->use_profiler(&renderer.profiler());
    // ENGINE_HOST_INPUTS=1 starts every module on the host path, so a whole test suite (or a
    // program) runs through the module's input pass without changing its code.
    const char* host = std::getenv("ENGINE_HOST_INPUTS");
    host_inputs_ = host && *host && std::strcmp(host, "0") != 0;
  }

  std::string name() const override { return "shadows"; }
  Settings& settings() override { return context_->settings(); }
  const Stats& stats() const override { return context_->stats(); }
  void set_collect_stats(bool enabled) override { context_->set_collect_stats(enabled); }
  std::vector<std::string> pass_names() const override { return context_->pass_names(); }
  Context& context() override { return *context_; }
  void set_light(std::optional<Light> light) override { light_ = light; }
  void set_host_inputs(bool enabled) override { host_inputs_ = enabled; }

  bool supported(CsmTest test, std::string* why) const override {
    const Capability c = context_->capabilities().of(test);
    if (why) *why = c.reason;
    return c.available;
  }
  bool supported(Technique technique, std::string* why) const override {
    const Capability c = context_->capabilities().of(technique);
    if (why) *why = c.reason;
    return c.available;
  }

  void on_scene(engine::gpu::Context&, engine::Scene& scene, engine::SceneGeometry& geometry) override {
    // The scene's units (engine::Scene::units_per_metre) scale the settings' distances in metres.
    context_->settings().units_per_metre = float(scene.units_per_metre);
    // A new scene: its meshes and textures are registered as they are first drawn.
    for (const auto& [key, id] : meshes_) context_->unregister_mesh(id);
    meshes_.clear();
    textures_.clear();
    geometry_ = &geometry;
  }

  void record(engine::FrameContext& frame) override {
    // Shadows off with no debug view: nothing to record. The renderer keeps the terms it was not told
    // were written at rest, lit (FrameContext::written), so the frame pays nothing for the module.
    const Settings& settings = context_->settings();
    if (settings.technique == Technique::Off && settings.debug == DebugView::None) return;
    if (geometry_ != &frame.geometry) on_scene(frame.ctx, *renderer_.scene(), frame.geometry);
    gather_instances(frame);
    FrameDesc f = frame_inputs(frame, renderer_.smooth_terminator(), host_inputs_);
    const bool sun_lit = gather_lights(frame);
    // The debug overlay shows the nearest local light's passes when one is shadowed (the lamps a
    // player stands by at night), else the sun's.
    f.overlay_light = (!light_ && sun_lit && lights_.size() > 1) ? 1u : 0u;
    f.lights = lights_.data();
    f.light_count = uint32_t(lights_.size());
    f.output = outputs_.front();
    f.light_outputs = outputs_.data() + 1;
    f.instances = instances_.data();
    f.instance_count = uint32_t(instances_.size());
    // The overlay only while a debug view draws into it (else the renderer's keeps its zeros).
    if (settings.debug != DebugView::None) f.overlay = image_input(frame.overlay);
    context_->record(frame.cmd, f);
    frame.written |= written_ | (f.overlay.present() ? engine::FrameContext::kWroteOverlay : 0u);
    recorded_.push_back(f.frame_index);
  }

  void after_frame(engine::gpu::Context&) override {
    // Frames complete in the order they were recorded; a frame the module did not record (the
    // renderer showed an external shadow term) has nothing to report.
    std::optional<uint64_t> done;
    while (!recorded_.empty() && recorded_.front() <= renderer_.completed_frame()) {
      done = recorded_.front();
      recorded_.pop_front();
    }
    if (done) context_->frame_completed(*done);
  }

  std::vector<float> read_visibility() override {
    auto term = renderer_.read_shadow_term();
    const auto positions = renderer_.read_world_positions();
    for (size_t i = 0; i < term.size(); ++i)
      if (positions[i].w == 0.0f) term[i] = -1.0f;
    return term;
  }

  CsmSnapshot read_csm() override {
    detail::CsmSnapshot s = context_->read_csm();
    return {s.resolution, std::move(s.depth), s.light_view_projection};
  }

  CsmSnapshot read_lit_map() override {
    detail::LitMapSnapshot s = context_->read_lit_map();
    return {s.resolution,        std::move(s.depth),      s.light_view_projection,
            std::move(s.corner_depth), s.tile,              s.tiles_per_side,
            std::move(s.tile_depth),   std::move(s.tile_corner_depth), std::move(s.tile_least_depth)};
  }

 private:
  // The frame's draws as the module's instances (instances_).
  void gather_instances(engine::FrameContext& frame) {
    instances_.clear();
    for (const auto& d : frame.draws) {
      const engine::Mesh* mesh = frame.registry.try_get<engine::Mesh>(d.entity);
      Instance in;
      in.mesh = mesh_for(frame, d, mesh);
      std::memcpy(in.world, glm::value_ptr(d.world), sizeof(in.world));
      in.casts_shadow = d.shadow.casts_shadow;
      in.csm = d.shadow.csm == engine::CsmChoice::On ? CsmMode::On
               : d.shadow.csm == engine::CsmChoice::Off ? CsmMode::Off
                                                        : CsmMode::Auto;
      in.id = instance_id_of(d.entity);
      const auto* name = frame.registry.try_get<engine::Name>(d.entity);
      in.name = name ? name->value.c_str() : "";
      if (const engine::GpuMeshRange& range = frame.geometry.mesh(d.mesh); range.deformed != UINT32_MAX)
        in.deformed = deformed_positions(frame, range, d.deformed_bounds);
      instances_.push_back(in);
    }
  }

  // The frame's lights and their shadow terms (lights_, outputs_); whether the sun is among them.
  bool gather_lights(engine::FrameContext& frame) {
    // The sun into the renderer's shadow term, then each local light into its own; a night without
    // sunlight shadows the local lights alone. set_light() replaces them all with one light.
    lights_.clear();
    outputs_.clear();
    const bool sun_lit = glm::length(frame.view.light_radiance) > 0.0f || frame.view.local_lights.empty();
    written_ = light_ || sun_lit ? engine::FrameContext::kWroteSunTerm : 0u;
    if (light_) {
      // set_light() takes scene-space positions (as Transform places lights): rebased to the frame's
      // origin like the rest, Scene::origin included.
      Light light = *light_;
      const glm::dvec3 shift = renderer_.scene()->origin - frame.view.origin;
      for (int k = 0; k < 3; ++k) light.position[k] = float(double(light.position[k]) + shift[k]);
      lights_.push_back(light);
      outputs_.push_back(image_input(frame.shadow_term));
    } else {
      if (sun_lit) {
        Light sun;
        std::memcpy(sun.direction, glm::value_ptr(frame.view.light_direction), sizeof(sun.direction));
        sun.angular_diameter_degrees = frame.view.light_angular_diameter_degrees;
        lights_.push_back(sun);
        outputs_.push_back(image_input(frame.shadow_term));
      }
      for (size_t i = 0; i < frame.view.local_lights.size(); ++i) {
        lights_.push_back(light_of(frame.view.local_lights[i]));
        outputs_.push_back(image_input(frame.local_shadow_terms[i]));
        written_ |= engine::FrameContext::kWroteLocalTerm << i;
      }
    }
    return sun_lit;
  }

  // A deformed entity's vertices for this frame (skinning.comp's output in the renderer's vertex
  // buffer, written before the G-buffer pass and made visible to compute reads by its barrier).
  static DeformedPositions deformed_positions(engine::FrameContext& frame, const engine::GpuMeshRange& range,
                                              const engine::Aabb& bounds) {
    DeformedPositions p;
    p.positions = {frame.geometry.vertices().handle(), VkDeviceSize(range.vertex_offset) * sizeof(engine::Vertex),
                   VkDeviceSize(range.vertex_count) * sizeof(engine::Vertex), kGeometryUsage};
    p.format = VK_FORMAT_R32G32B32_SFLOAT;
    p.stride = sizeof(engine::Vertex);
    p.vertex_count = range.vertex_count;
    std::memcpy(p.bounds.min, &bounds.min, sizeof(p.bounds.min));
    std::memcpy(p.bounds.max, &bounds.max, sizeof(p.bounds.max));
    return p;
  }

  // One host mesh per (mesh, texture, alpha threshold): the module keeps alpha tests per mesh, the
  // engine per draw. A deformed entity's instance uses its mesh's rest vertices (same triangles and uvs).
  MeshId mesh_for(engine::FrameContext& frame, const engine::DrawItem& d, const engine::Mesh* mesh) {
    const uint32_t slot = frame.geometry.mesh(d.mesh).rest_mesh;
    const auto key = std::make_tuple(slot, d.base_color_texture, d.alpha_threshold);
    if (auto it = meshes_.find(key); it != meshes_.end()) return it->second;
    const engine::GpuMeshRange& range = frame.geometry.mesh(slot);
    MeshDesc m;
    m.name = mesh && mesh->data ? mesh->data->name : "mesh " + std::to_string(slot);
    const VkDeviceSize first_vertex = VkDeviceSize(range.vertex_offset) * sizeof(engine::Vertex);
    m.positions = {frame.geometry.vertices().handle(), first_vertex, VkDeviceSize(range.vertex_count) * sizeof(engine::Vertex),
                   kGeometryUsage};
    m.position_format = VK_FORMAT_R32G32B32_SFLOAT;
    m.position_stride = sizeof(engine::Vertex);
    m.vertex_count = range.vertex_count;
    m.indices = {frame.geometry.indices().handle(), VkDeviceSize(range.first_index) * 4,
                 VkDeviceSize(range.index_count) * 4, kGeometryUsage};
    m.index_type = VK_INDEX_TYPE_UINT32;
    m.index_count = range.index_count;
    engine::Aabb bounds;
    if (mesh && mesh->data)
      for (const auto& v : mesh->data->vertices) bounds.extend(v.position);
    if (!bounds.valid()) bounds.extend(glm::vec3(0.0f));
    // Given from the CPU copy the engine keeps anyway: no readback at registration.
    m.bounds.emplace();
    std::memcpy(m.bounds->min, &bounds.min, sizeof(m.bounds->min));
    std::memcpy(m.bounds->max, &bounds.max, sizeof(m.bounds->max));
    if (d.alpha_tested() && d.base_color_texture != gpu_shared::kNoTexture) {
      m.uvs = {frame.geometry.vertices().handle(), first_vertex + offsetof(engine::Vertex, uv),
               VkDeviceSize(range.vertex_count) * sizeof(engine::Vertex) - offsetof(engine::Vertex, uv), kGeometryUsage};
      m.uv_stride = sizeof(engine::Vertex);
      const TextureImage& tex = texture(frame, d.base_color_texture);
      m.alpha_texture = tex.input;
      m.wrap_u = tex.wrap_u;
      m.wrap_v = tex.wrap_v;
      m.alpha_cutoff = d.alpha_mode == engine::AlphaMode::Blend ? 0.5f : d.alpha_cutoff;
      m.alpha_scale = d.base_color.a;
      if (engine::alpha_threshold(m.alpha_cutoff, m.alpha_scale) != d.alpha_threshold)
        throw std::logic_error("shadows: the module's alpha threshold differs from the engine's for '" + m.name + "'");
    }
    const MeshId id = context_->register_mesh(m);
    meshes_.emplace(key, id);
    return id;
  }

  const TextureImage& texture(engine::FrameContext& frame, uint32_t index) {
    if (auto it = textures_.find(index); it != textures_.end()) return it->second;
    return textures_.emplace(index, upload_texture(renderer_.context(), frame.geometry.texture_table().words(), index))
        .first->second;
  }

  engine::Renderer& renderer_;
  std::unique_ptr<detail::ContextImpl> context_;
  std::optional<Light> light_;  // set_light(): shadowed instead of the renderer's sun
  const engine::SceneGeometry* geometry_ = nullptr;
  std::map<std::tuple<uint32_t, uint32_t, uint32_t>, MeshId> meshes_;
  std::map<uint32_t, TextureImage> textures_;
  std::vector<Instance> instances_;
  bool host_inputs_ = false;          // set_host_inputs()
  std::vector<Light> lights_;         // this frame's, in FrameDesc order
  std::vector<ImageInput> outputs_;   // their shadow terms
  uint32_t written_ = 0;               // engine::FrameContext::written bits of outputs_
  std::deque<uint64_t> recorded_;  // frames recorded and not yet reported complete, oldest first
};

}  // namespace

Light light_of(const engine::FrameLight& l) {
  Light out;
  out.type = l.kind == engine::LocalLightKind::Spot ? LightType::Spot : LightType::Point;
  std::memcpy(out.position, glm::value_ptr(l.position), sizeof(out.position));
  std::memcpy(out.direction, glm::value_ptr(l.direction), sizeof(out.direction));
  out.range = l.range;
  out.inner_cone = l.inner_cone;
  out.outer_cone = l.outer_cone;
  out.radius = l.radius;
  return out;
}

std::shared_ptr<ShadowModule> install(engine::Renderer& renderer, const Settings& settings) {
  auto module = std::make_shared<EngineShadowModule>(renderer, settings);
  renderer.add_feature(module);
  return module;
}

}  // namespace shadows
