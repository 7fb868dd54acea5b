#pragma once
// A scene is an ECS registry plus the things a frame needs to find in it: the camera, the sun, and
// named views (camera pose + light direction) that tests and the benchmark select by index.
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/core/components.hpp"

namespace engine {

// Thrown by every loader: what() is one line naming the file (or scene) and the problem.
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// How finely generated content (the plants of scene files) is built. Full is the content as authored,
// which tests, the reference and the benchmark use; Low is for devices that cannot afford it (the
// walkthrough on a CPU device): the same plants with a quarter of their leaf cards, each twice the
// size (the same leaf area), and thinner stem tessellation; characters with a quarter of their slices.
enum class Detail { Full, Low };

struct SceneView {
  std::string name;
  glm::vec3 eye{0.0f};
  glm::vec3 target{0.0f, 0.0f, -1.0f};
  glm::vec3 light_direction{-0.4f, -1.0f, -0.3f};  // direction light travels, normalised on use
  float vertical_fov = glm::radians(60.0f);
};

struct Scene {
  std::string name;
  Registry registry;
  // Large worlds: the world position (double) that every Transform, view and light of the scene is
  // relative to. A host far from the world's origin keeps its entities' floats small and puts the
  // distance here; the renderer and the shadow module then work relative to a point near the camera.
  glm::dvec3 origin{0.0};
  // How many world units make a metre (1: metres; 100: centimetres). The shadow module's distances
  // in metres (the hybrid's split, the cascades' range) scale with it.
  double units_per_metre = 1.0;
  Entity camera = kNullEntity;
  Entity light = kNullEntity;
  // The hemisphere ambient's sky colour (lighting.comp) and how bright the sky background is (1: day;
  // a night scene lowers both).
  glm::vec3 sky_color{0.26f, 0.31f, 0.40f};
  float sky_brightness = 1.0f;
  std::vector<SceneView> views;  // at least one (the tour)
  std::optional<SceneView> start;  // where a player starts, when the scene says (else views[0])

  // Bounds of all meshes in world space (after update_world_transforms).
  Aabb world_bounds();
  // Moves the camera and turns the light to views[index]; throws SceneError when out of range.
  void apply_view(size_t index);
  size_t triangle_count();
};

// Places `copies` copies of the scene's meshes (the original included) on a square grid in the
// ground plane, spaced by the scene's footprint, for scaling measurements. The copies share the
// originals' MeshData (one GPU mesh, one acceleration structure) and keep their hierarchy, materials,
// shadow flags and animations; camera, light and views stay with the original. Throws SceneError for
// copies == 0.
void replicate_scene(Scene& scene, uint32_t copies);

// Scales the whole scene about the world origin by `scale`, then moves it by `offset` (world units):
// root transforms, views, the camera's near and far planes, light ranges (and their intensities, by
// scale², as lighting falls off with the distance squared) and animation paths, so
// that the scene looks the same in another unit (100: centimetres for metres) or far from the origin.
// Throws SceneError naming `what` (the option that asked for it) when the result could not be held in
// float: a scale that is not finite and positive, an offset that is not finite, or a scene that would
// reach past 1e7 units from the origin (where float spacing reaches a unit).
void transform_scene(Scene& scene, double scale, const glm::dvec3& offset, const std::string& what = "transform");

// The procedural scenes built in code: "contact", "atrium", "foliage", "canopy", "lamps", "hall",
// "characters" (100 skinned walking figures).
std::vector<std::string> procedural_scene_names();
std::unique_ptr<Scene> build_procedural_scene(const std::string& name);

// Loads a .gltf or .glb file into a new scene. Cameras in the file become views; a file without
// cameras gets two default views derived from its bounds (0: overview from above, 1: inside at eye
// height). A directional light in the file is the sun; a file with none gets a default sun, which stays
// dark (intensity 0: neither lit nor shadowed) when the file brings spot or point lights of its own.
std::unique_ptr<Scene> load_gltf_scene(const std::filesystem::path& path);
// The same for a file's bytes already in memory: `name` stands for the file in errors (and names the
// scene), external buffers resolve in `base_dir`.
std::unique_ptr<Scene> load_gltf_scene_from_memory(std::string bytes, const std::string& name,
                                                   const std::filesystem::path& base_dir);

// Lights a scene's dark sun (a glTF file lit by its own lights) with the default sun's intensity, for
// runs that ask for the sun (--sun). Returns whether it changed anything.
bool enable_default_sun(Scene& scene);

// A procedural scene name, a path to a glTF file, or a .json scene file (engine/assets/scene_file.hpp).
// `detail` applies to scene files' generated content.
std::unique_ptr<Scene> load_scene(const std::string& name_or_path, Detail detail = Detail::Full);

}  // namespace engine
