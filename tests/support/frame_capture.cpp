#include "frame_capture.hpp"

namespace support {

reference::ShadingPoints capture_shading_points(engine::Renderer& renderer) {
  reference::ShadingPoints points;
  points.width = renderer.extent().width;
  points.height = renderer.extent().height;
  points.position = renderer.read_world_positions();
  points.normal = renderer.read_geometric_normals();
  points.facing_from_w = true;
  points.inv_view_proj = renderer.frame_view().inverse_view_projection;
  return points;
}

std::vector<float> reference_visibility(engine::Renderer& renderer, const reference::EmbreeTracer& tracer,
                                        uint32_t samples_per_pixel) {
  const auto points = capture_shading_points(renderer);
  const glm::vec3 light = renderer.frame_view().light_direction;
  return samples_per_pixel == 32 ? tracer.visibility_32spp(points, light) : tracer.visibility_1spp(points, light);
}

}  // namespace support
