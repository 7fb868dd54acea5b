#include "frame_capture.hpp"

#include <cmath>
#include <stdexcept>

namespace support {

reference::ShadingPoints capture_shading_points(engine::Renderer& renderer) {
  reference::ShadingPoints points;
  points.width = renderer.extent().width;
  points.height = renderer.extent().height;
  points.position = renderer.read_world_positions();
  points.normal = renderer.read_geometric_normals();
  points.facing_from_w = true;
  points.inv_view_proj = renderer.frame_view().inverse_view_projection;
  points.eye = renderer.frame_view().camera_position;
  return points;
}

glm::dvec3 frame_shift(engine::Renderer& renderer) {
  const glm::dvec3 scene_origin = renderer.scene() ? renderer.scene()->origin : glm::dvec3(0.0);
  return scene_origin - renderer.world_origin();
}

namespace {
// The reference must trace the triangles the frame drew, relative to the frame's origin.
void check_tracer(engine::Renderer& renderer, const reference::EmbreeTracer& tracer) {
  if (tracer.shift() != frame_shift(renderer))
    throw std::runtime_error("the reference tracer was built for another frame origin: build it with support::frame_shift(renderer)");
}
}  // namespace

std::vector<float> reference_visibility(engine::Renderer& renderer, const reference::EmbreeTracer& tracer,
                                        uint32_t samples_per_pixel) {
  check_tracer(renderer, tracer);
  const auto points = capture_shading_points(renderer);
  const glm::vec3 light = renderer.frame_view().light_direction;
  return samples_per_pixel == 32 ? tracer.visibility_32spp(points, light) : tracer.visibility_1spp(points, light);
}

std::vector<float> reference_visibility(engine::Renderer& renderer, const reference::EmbreeTracer& tracer,
                                        uint32_t samples_per_pixel, const reference::LocalLight& scene_light) {
  check_tracer(renderer, tracer);
  const auto points = capture_shading_points(renderer);
  reference::LocalLight light = scene_light;  // scene space -> the frame's coordinates
  light.position = glm::vec3(glm::dvec3(light.position) + frame_shift(renderer));
  return samples_per_pixel == 32 ? tracer.visibility_32spp(points, light) : tracer.visibility_1spp(points, light);
}

std::vector<float> area_reference_visibility(engine::Renderer& renderer, const reference::EmbreeTracer& tracer,
                                             uint32_t rays) {
  check_tracer(renderer, tracer);
  const engine::FrameView& view = renderer.frame_view();
  return tracer.area_visibility(capture_shading_points(renderer), view.light_direction,
                                view.light_angular_diameter_degrees, rays);
}

std::vector<float> area_reference_visibility(engine::Renderer& renderer, const reference::EmbreeTracer& tracer,
                                             uint32_t rays, const reference::LocalLight& scene_light, float radius) {
  check_tracer(renderer, tracer);
  reference::LocalLight light = scene_light;  // scene space -> the frame's coordinates
  light.position = glm::vec3(glm::dvec3(light.position) + frame_shift(renderer));
  return tracer.area_visibility(capture_shading_points(renderer), light, radius, rays);
}

std::vector<float> area_reference_visibility(engine::Renderer& renderer, const reference::EmbreeTracer& tracer,
                                             uint32_t rays, const FrameLightCheck& light) {
  check_tracer(renderer, tracer);
  const auto points = capture_shading_points(renderer);
  if (light.kind == "sun")
    return tracer.area_visibility(points, renderer.frame_view().light_direction, light.size, rays);
  return tracer.area_visibility(points, light.local, light.size, rays);
}

std::vector<FrameLightCheck> check_every_light(engine::Renderer& renderer, const reference::EmbreeTracer& tracer,
                                               uint32_t samples_per_pixel) {
  check_tracer(renderer, tracer);
  const auto points = capture_shading_points(renderer);
  const engine::FrameView& view = renderer.frame_view();
  const auto masked = [&](std::vector<float> term) {
    for (size_t i = 0; i < term.size(); ++i)
      if (!points.covered(i)) term[i] = -1.0f;
    return term;
  };
  std::vector<FrameLightCheck> out;
  if (glm::length(view.light_radiance) > 0.0f || view.local_lights.empty()) {
    FrameLightCheck c{"sun", masked(renderer.read_shadow_term()), {}, view.light_angular_diameter_degrees, {}};
    c.reference = samples_per_pixel == 32 ? tracer.visibility_32spp(points, view.light_direction)
                                          : tracer.visibility_1spp(points, view.light_direction);
    out.push_back(std::move(c));
  }
  for (uint32_t i = 0; i < view.local_lights.size(); ++i) {
    const engine::FrameLight& l = view.local_lights[i];
    reference::LocalLight light;  // already in the frame's coordinates
    light.position = l.position;
    light.range = l.range;
    light.spot = l.kind == engine::LocalLightKind::Spot;
    light.spot_direction = l.direction;
    light.cos_outer = light.spot ? std::cos(l.outer_cone) : -1.0f;
    FrameLightCheck c{light.spot ? "spot" : "point", masked(renderer.read_local_shadow_term(i)), {}, l.radius, light};
    c.reference = samples_per_pixel == 32 ? tracer.visibility_32spp(points, light) : tracer.visibility_1spp(points, light);
    out.push_back(std::move(c));
  }
  return out;
}

SceneLight local_light_at(const glm::mat4& world, shadows::LightType type, float range) {
  SceneLight out;
  out.module.type = type;
  const glm::vec3 position(world[3]), direction = glm::normalize(-glm::vec3(world[2]));
  for (int k = 0; k < 3; ++k) {
    out.module.position[k] = position[k];
    out.module.direction[k] = direction[k];
  }
  out.module.range = range;
  out.reference.position = position;
  out.reference.range = range;
  out.reference.spot_direction = direction;
  return out;
}

SceneLight scene_local_light(engine::Registry& registry, shadows::LightType type) {
  SceneLight out;
  out.module.type = type;
  bool found = false;
  auto place = [&](const engine::Transform& t, float range) {
    out = local_light_at(t.world, type, range);
    found = true;
  };
  if (type == shadows::LightType::Spot) {
    registry.each<engine::SpotLight, engine::Transform>([&](engine::Entity, engine::SpotLight& s, engine::Transform& t) {
      if (found) return;
      place(t, s.range);
      out.module.radius = s.radius;
      out.module.inner_cone = s.inner_cone;
      out.module.outer_cone = s.outer_cone;
      out.module.radius = s.radius;
      out.reference.spot = true;
      out.reference.cos_outer = std::cos(s.outer_cone);
    });
  } else if (type == shadows::LightType::Point) {
    registry.each<engine::PointLight, engine::Transform>([&](engine::Entity, engine::PointLight& p, engine::Transform& t) {
      if (found) return;
      place(t, p.range);
      out.module.radius = p.radius;
    });
  }
  if (!found) throw std::runtime_error(std::string("the scene has no ") +
                                       (type == shadows::LightType::Spot ? "spot" : "point") + " light");
  return out;
}

}  // namespace support
