#pragma once
// Glue between a rendered frame and the reference: reads the shading points the shadow passes used,
// and runs the Embree reference on them.
#include <string>
#include <vector>

#include "engine/render/renderer.hpp"
#include "reference/comparator.hpp"
#include "reference/embree_tracer.hpp"
#include "reference/shading_points.hpp"
#include "shadows/context.hpp"

namespace support {

// World positions and geometric normals exactly as the GPU passes read them this frame.
reference::ShadingPoints capture_shading_points(engine::Renderer& renderer);

// What the frame's rebasing adds to scene-space positions (Scene::origin - FrameView::origin): build
// the reference tracer with it (reference::EmbreeTracer(registry, frame_shift(renderer))).
glm::dvec3 frame_shift(engine::Renderer& renderer);

// Reference visibility (1 lit, 0 shadowed, fraction at 32 spp, -1 background) for the last frame.
std::vector<float> reference_visibility(engine::Renderer& renderer, const reference::EmbreeTracer& tracer,
                                        uint32_t samples_per_pixel);
// The same toward a spot or point light (its position in scene space, as scene_local_light gives it).
// Both throw std::runtime_error when the tracer was built for another frame origin.
std::vector<float> reference_visibility(engine::Renderer& renderer, const reference::EmbreeTracer& tracer,
                                        uint32_t samples_per_pixel, const reference::LocalLight& light);

// The area-light reference (reference::EmbreeTracer::area_visibility: the lit fraction of `rays` rays a
// pixel, stratified over the light; -1 background) for the last frame, toward the sun with the frame's
// FrameView::light_angular_diameter_degrees (0: exactly the 1 spp reference).
std::vector<float> area_reference_visibility(engine::Renderer& renderer, const reference::EmbreeTracer& tracer,
                                             uint32_t rays);
// The same toward a spot or point light of `radius` (world units) at its scene-space position (as
// scene_local_light gives it). Both throw std::runtime_error when the tracer was built for another
// frame origin, std::invalid_argument on a bad size or rays == 0.
std::vector<float> area_reference_visibility(engine::Renderer& renderer, const reference::EmbreeTracer& tracer,
                                             uint32_t rays, const reference::LocalLight& light, float radius);

// Every light the frame shadows, as the engine adapter records them without set_light(): the sun (while
// it shines, or when there is no local light) into Renderer::shadow_term, then each of
// FrameView::local_lights into its own term. `visibility` is the light's term (-1 background), and
// `reference` Embree's answer for it, toward the light as the frame placed it.
// `size` is the light's: the sun's angular diameter in degrees, a local light's radius in world units;
// `local` a local light as the reference takes it, in the frame's coordinates.
struct FrameLightCheck {
  std::string kind;  // "sun", "spot" or "point"
  std::vector<float> visibility;
  std::vector<float> reference;
  float size = 0.0f;
  reference::LocalLight local{};
};
std::vector<FrameLightCheck> check_every_light(engine::Renderer& renderer, const reference::EmbreeTracer& tracer,
                                               uint32_t samples_per_pixel);
// The area-light reference of one of check_every_light's lights (its `size`, `rays` rays a pixel) for
// the same frame.
std::vector<float> area_reference_visibility(engine::Renderer& renderer, const reference::EmbreeTracer& tracer,
                                             uint32_t rays, const FrameLightCheck& light);

// A scene's spot or point light (its first engine::SpotLight or PointLight, placed and aimed by its
// Transform's world matrix, with its radius in module.radius) as the module and the reference take
// it; throws std::runtime_error when the scene has none.
struct SceneLight {
  shadows::Light module;
  reference::LocalLight reference;
};
// A spot or point light placed and aimed by `world` (a spot shines down its -Z), with its range; a
// spot's cones are the caller's to set.
SceneLight local_light_at(const glm::mat4& world, shadows::LightType type, float range);
SceneLight scene_local_light(engine::Registry& registry, shadows::LightType type);

}  // namespace support
