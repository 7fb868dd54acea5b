// libFuzzer target: arbitrary bytes through the glTF-to-scene loader. A well-formed scene or a
// SceneError are the two allowed outcomes; anything else (a crash, a sanitizer report, another
// exception, a hang past -timeout) is a defect, and the input that found it is kept under
// content/test_gltf/fuzz_regressions/, which the unit tests load on every run.
#include <cstddef>
#include <cstdint>
#include <string>

#include "engine/assets/scene.hpp"

#ifndef ENGINE_FUZZ_BASE_DIR
#error "ENGINE_FUZZ_BASE_DIR names the folder external buffers resolve in"
#endif

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    auto scene = engine::load_gltf_scene_from_memory(std::string(reinterpret_cast<const char*>(data), size),
                                                     "fuzz.gltf", ENGINE_FUZZ_BASE_DIR);
    scene->triangle_count();  // touches every mesh the loader produced
    for (size_t view = 0; view < scene->views.size(); ++view) scene->apply_view(view);
    scene->world_bounds();
  } catch (const engine::SceneError&) {
  }
  return 0;
}
