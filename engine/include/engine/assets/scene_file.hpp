#pragma once
// Scene files: a small JSON format that places procedural shapes and glTF files with transforms,
// per-object shadow flags and animations, and sets the sun, the player's start and the tour views.
// The format is documented in content/levels/README.md.
#include <filesystem>
#include <memory>

#include "engine/assets/scene.hpp"

namespace engine {

// Loads a .json scene file. Throws SceneError with one line naming the file and the field at fault,
// e.g. "content/levels/x.json: objects[3].box.min: expected an array of 3 numbers".
std::unique_ptr<Scene> load_scene_file(const std::filesystem::path& path, Detail detail = Detail::Full);

}  // namespace engine
