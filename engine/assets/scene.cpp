#include "engine/assets/scene.hpp"

#include <glm/gtx/component_wise.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <unordered_map>

#include "engine/assets/scene_file.hpp"
#include "engine/core/animation.hpp"
#include "engine/core/skinning.hpp"
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

void replicate_scene(Scene& scene, uint32_t copies) {
  if (copies == 0) throw SceneError(scene.name + ": the instance count must be at least 1");
  if (copies == 1) return;
  const Aabb bounds = scene.world_bounds();
  if (!bounds.valid()) return;
  const glm::vec3 extent = bounds.extent();
  const float gap = 0.1f * std::max(extent.x, extent.z);
  const glm::vec2 spacing(extent.x + gap, extent.z + gap);
  const uint32_t side = uint32_t(std::ceil(std::sqrt(double(copies))));
  // Every entity of a mesh hierarchy: the meshes, their skeletons' joints and their ancestors.
  std::vector<Entity> sources;
  std::unordered_map<uint32_t, bool> wanted;
  const auto want = [&](Entity e) {
    for (Entity a = e; a != kNullEntity && !wanted.count(a.index); a = scene.registry.get<Transform>(a).parent) {
      wanted[a.index] = true;
      sources.push_back(a);
      if (!scene.registry.has<Transform>(a)) break;
    }
  };
  for (Entity e : scene.registry.view<Transform, Mesh>()) {
    want(e);
    if (const auto* skeleton = scene.registry.try_get<Skeleton>(e))
      for (Entity j : skeleton->joints)
        if (scene.registry.has<Transform>(j)) want(j);
  }
  const std::vector<Entity> players = scene.registry.view<AnimationPlayer>();
  for (uint32_t k = 1; k < copies; ++k) {
    const glm::vec3 offset(float(k % side) * spacing.x, 0.0f, float(k / side) * spacing.y);
    std::unordered_map<uint32_t, Entity> clone;
    for (Entity e : sources) clone[e.index] = scene.registry.create();
    for (Entity e : sources) {
      Registry& r = scene.registry;
      const Entity c = clone[e.index];
      Transform t = r.get<Transform>(e);
      if (t.parent == kNullEntity) t.translation += offset;
      else t.parent = clone.at(t.parent.index);
      r.emplace<Transform>(c, t);
      if (auto* x = r.try_get<Mesh>(e)) r.emplace<Mesh>(c, *x);
      if (auto* x = r.try_get<Material>(e)) r.emplace<Material>(c, *x);
      if (auto* x = r.try_get<ShadowCaster>(e)) r.emplace<ShadowCaster>(c, *x);
      if (auto* x = r.try_get<Collider>(e)) r.emplace<Collider>(c, *x);
      if (auto* x = r.try_get<Animated>(e)) {
        Animated a = *x;
        if (t.parent == kNullEntity) {  // a walking root walks its own copy of the path
          a.rest_translation += offset;
          for (auto& p : a.path) p += offset;
        }
        r.emplace<Animated>(c, std::move(a));
      }
      if (auto* x = r.try_get<Name>(e)) r.emplace<Name>(c, Name{x->value + " #" + std::to_string(k)});
      if (auto* x = r.try_get<MorphWeights>(e)) r.emplace<MorphWeights>(c, *x);
      if (auto* x = r.try_get<Skeleton>(e)) {
        Skeleton skeleton = *x;
        for (Entity& j : skeleton.joints)
          if (auto it = clone.find(j.index); it != clone.end()) j = it->second;
        r.emplace<Skeleton>(c, std::move(skeleton));
      }
    }
    // Each copy plays its own copy of the clips that drive what it copied.
    for (Entity p : players) {
      const AnimationPlayer& player = scene.registry.get<AnimationPlayer>(p);
      if (!player.clip) continue;
      auto clip = std::make_shared<AnimationClip>(*player.clip);
      bool drives_copy = false;
      for (auto& ch : clip->channels)
        if (auto it = clone.find(ch.target.index); it != clone.end()) ch.target = it->second, drives_copy = true;
      if (!drives_copy) continue;
      AnimationPlayer copy = player;
      copy.clip = std::move(clip);
      const Entity c = clone.count(p.index) ? clone.at(p.index) : scene.registry.create();
      scene.registry.emplace<AnimationPlayer>(c, std::move(copy));
    }
  }
  scene.name += " x" + std::to_string(copies);
  update_world_transforms(scene.registry);
}

void transform_scene(Scene& scene, double scale, const glm::dvec3& offset, const std::string& what) {
  if (!(std::isfinite(scale) && scale > 0.0)) {
    char line[160];
    std::snprintf(line, sizeof(line), ": %s scale %g must be finite and positive", what.c_str(), scale);
    throw SceneError(scene.name + line);
  }
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(offset[i])) throw SceneError(scene.name + ": " + what + " offset must be finite");
  const Aabb bounds = scene.world_bounds();
  if (bounds.valid()) {
    const glm::dvec3 lo = glm::dvec3(bounds.min) * scale + offset, hi = glm::dvec3(bounds.max) * scale + offset;
    const double reach = std::max(glm::compMax(glm::abs(lo)), glm::compMax(glm::abs(hi)));
    const double size = glm::compMax(hi - lo);
    // Past 1e7 float spacing is a unit; a scene smaller than float's spacing at its distance has no shape.
    if (!(reach <= 1.0e7) || !(size > 1.0e-30) || !(size >= reach * 1.0e-7)) {
      char line[256];
      std::snprintf(line, sizeof(line),
                    ": %s scale %g and offset put the scene out of float's reach (%g units across, %g from the origin; "
                    "at most 1e7 from it, and no smaller than float's spacing there)",
                    what.c_str(), scale, size, reach);
      throw SceneError(scene.name + line);
    }
  }
  const auto move = [&](const glm::vec3& p) { return glm::vec3(glm::dvec3(p) * scale + offset); };
  const float s = float(scale);
  Registry& r = scene.registry;
  // A clip's keys on a root entity set what the root's transform holds: moved and scaled with it.
  r.each<AnimationPlayer>([&](Entity, AnimationPlayer& player) {
    if (!player.clip) return;
    auto clip = std::make_shared<AnimationClip>(*player.clip);
    for (auto& c : clip->channels) {
      const auto* t = r.try_get<Transform>(c.target);
      if (!t || t->parent != kNullEntity) continue;
      const bool cubic = c.interpolation == AnimationClip::Interpolation::CubicSpline;
      for (size_t i = 0; i + 3 <= c.values.size(); i += 3) {
        glm::vec3 v(c.values[i], c.values[i + 1], c.values[i + 2]);
        // A cubic spline's tangents (the first and third of each key's triples) scale without the offset.
        const bool tangent = cubic && (i / 3) % 3 != 1;
        if (c.path == AnimationClip::Path::Translation) v = tangent ? v * s : move(v);
        else if (c.path == AnimationClip::Path::Scale) v *= s;
        else break;
        c.values[i] = v.x, c.values[i + 1] = v.y, c.values[i + 2] = v.z;
      }
    }
    player.clip = std::move(clip);
  });
  r.each<Transform>([&](Entity e, Transform& t) {
    if (t.parent != kNullEntity) return;
    t.translation = move(t.translation);
    t.scale *= s;
    if (auto* a = r.try_get<Animated>(e)) {
      a->rest_translation = move(a->rest_translation);
      for (auto& p : a->path) p = move(p);
      if (a->kind == Animated::Kind::Walk) a->speed *= s;
    }
  });
  // Lights and the camera are placed by translation and rotation alone: a root one keeps its unit
  // scale (which would otherwise scale its children) and scales its ranges instead.
  const auto keep_unit_scale = [&](Entity e) {
    if (auto* t = r.try_get<Transform>(e); t && t->parent == kNullEntity) t->scale /= s;
  };
  // Intensities in candela light a point by intensity / distance²: scaled by scale² they light the
  // scaled scene as before.
  const float intensity_scale = float(scale * scale);
  const auto scale_light = [&](Entity e, float& range, float& intensity, float& radius) {
    range *= s;
    radius *= s;
    intensity *= intensity_scale;
    keep_unit_scale(e);
  };
  r.each<SpotLight>([&](Entity e, SpotLight& l) { scale_light(e, l.range, l.intensity, l.radius); });
  r.each<PointLight>([&](Entity e, PointLight& l) { scale_light(e, l.range, l.intensity, l.radius); });
  r.each<Camera>([&](Entity e, Camera& c) {
    c.near_plane *= s;
    c.far_plane *= s;
    keep_unit_scale(e);
  });
  for (auto& v : scene.views) {
    v.eye = move(v.eye);
    v.target = move(v.target);
  }
  if (scene.start) {
    scene.start->eye = move(scene.start->eye);
    scene.start->target = move(scene.start->target);
  }
  scene.units_per_metre *= scale;
  update_world_transforms(r);
}

bool enable_default_sun(Scene& scene) {
  auto* sun = scene.registry.try_get<DirectionalLight>(scene.light);
  if (!sun || sun->intensity > 0.0f) return false;
  sun->intensity = DirectionalLight{}.intensity;
  return true;
}

size_t Scene::triangle_count() {
  size_t total = 0;
  registry.each<Mesh>([&](Entity, Mesh& m) {
    if (m.data) total += m.data->triangle_count();
  });
  return total;
}

std::unique_ptr<Scene> load_scene(const std::string& name_or_path, Detail detail) {
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
  if (ext == ".json") return load_scene_file(path, detail);
  if (is_file || ext == ".gltf" || ext == ".glb") return load_gltf_scene(path);
  throw SceneError("unknown scene '" + name_or_path +
                   "': expected one of contact, atrium, foliage, canopy, a .gltf/.glb file or a .json scene file");
}

}  // namespace engine
