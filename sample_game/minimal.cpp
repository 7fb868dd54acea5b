// The smallest program that uses the engine with the shadow module: the code a game would copy.
//   minimal [SCENE.gltf|contact|atrium|foliage] [OUT.png] [FRAMES] [WxH]
// Loads the scene (default: the procedural `contact` scene), installs the shadow module, renders
// FRAMES frames headless (default 3) and writes the last one as a PNG (default minimal.png).
#include <cstdio>
#include <algorithm>
#include <cstdlib>
#include <string>

#include "engine/assets/scene.hpp"
#include "gpu/context.hpp"
#include "engine/render/renderer.hpp"
#include "shadows_engine/shadows_engine.hpp"

int main(int argc, char** argv) {
  const std::string scene_name = argc > 1 ? argv[1] : "contact";
  const std::string out = argc > 2 ? argv[2] : "minimal.png";
  const int frames = argc > 3 ? std::atoi(argv[3]) : 3;
  unsigned width = 320, height = 180;
  if (argc > 4 && std::sscanf(argv[4], "%ux%u", &width, &height) != 2) {
    std::fprintf(stderr, "minimal: size '%s': expected WxH\n", argv[4]);
    return 1;
  }
  try {
    engine::gpu::Context ctx(engine::gpu::ContextOptions{});  // a GPU if there is one, else lavapipe
    auto scene = engine::load_scene(scene_name);      // glTF file or procedural scene
    engine::Renderer renderer(ctx, {width, height});  // G-buffer, lighting, PNG output
    renderer.set_scene(*scene);

    shadows::Settings settings;                       // hybrid: exact IZB near, filtered cascades far
    settings.izb.csm = true;                          // conservative shadow map z-prepass
    auto module = shadows::install(renderer, settings);
    module->set_collect_stats(true);

    for (int f = 0; f < std::max(frames, 1); ++f) renderer.render_frame(1.0f / 30.0f);
    renderer.write_png(out);

    const shadows::Stats& s = module->stats();
    std::printf("minimal: %s, %ux%u on %s: %llu shading points, %llu IZB nodes, CSM culled %.1f%%\n",
                scene->name.c_str(), width, height, ctx.device_name().c_str(),
                (unsigned long long)s.shading_points, (unsigned long long)s.nodes_inserted, s.culling_rate * 100.0);
    std::printf("minimal: wrote %s\n", out.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "minimal: %s\n", e.what());
    return 1;
  }
}
