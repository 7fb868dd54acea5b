#include "engine/assets/scene.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "engine/assets/scene_file.hpp"
#include "engine/core/transform_system.hpp"

namespace engine {

Aabb Scene::world_bounds() {
  update_world_transforms(registry);
  Aabb bounds;
  registry.each<Transform, Mesh>([&](Entity, Transform& t, Mesh& m) {
    if (m.data) bounds.extend(m.data->bounds.transformed(t.world));
  });
  return bounds;
}

void Scene::apply_view(size_t index) {
  if (index >= views.size()) {
    throw SceneError(name + ": view index " + std::to_string(index) + " out of range (" +
                     std::to_string(views.size()) + " views)");
  }
  const SceneView& v = views[index];
  if (registry.has<Transform>(camera)) {
    place_camera(registry, camera, v.eye, v.target);
    if (Camera* c = registry.try_get<Camera>(camera)) c->vertical_fov = v.vertical_fov;
  }
  if (DirectionalLight* light_component = registry.try_get<DirectionalLight>(light)) {
    const float len = glm::length(v.light_direction);
    // A zero or broken direction would poison every shadow matrix; straight down is a safe stand-in.
    light_component->direction =
        (len > 0.0f && std::isfinite(len)) ? v.light_direction / len : glm::vec3(0.0f, -1.0f, 0.0f);
  }
}

size_t Scene::triangle_count() {
  size_t total = 0;
  registry.each<Mesh>([&](Entity, Mesh& m) {
    if (m.data) total += m.data->triangle_count();
  });
  return total;
}

std::unique_ptr<Scene> load_scene(const std::string& name_or_path) {
  const std::vector<std::string> names = procedural_scene_names();
  if (std::find(names.begin(), names.end(), name_or_path) != names.end()) {
    return build_procedural_scene(name_or_path);
  }
  const std::filesystem::path path(name_or_path);
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  std::error_code ec;
  const bool is_file = std::filesystem::is_regular_file(path, ec);
  // A glTF extension goes to the loader even when the file is missing so the error names the file.
  if (ext == ".json") return load_scene_file(path);
  if (is_file || ext == ".gltf" || ext == ".glb") return load_gltf_scene(path);
  throw SceneError("unknown scene '" + name_or_path +
                   "': expected one of contact, atrium, foliage, canopy, a .gltf/.glb file or a .json scene file");
}

}  // namespace engine
