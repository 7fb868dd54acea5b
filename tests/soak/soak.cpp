// Soak: many headless frames on `contact` with the sun turning, the casters moving and the technique
// changing every 100 frames through every mode. Resident memory and the number of live Vulkan
// memory allocations must stay flat once every mode has run once (warm-up): it fails when either grows.
//
//   shadow_soak [--frames 10000] [--size 64x48] [--rss-slack-mib 16] [--modes off,sm,...] [--trace auto|raster|compute]
//               [--verbose] [--still]
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "engine/assets/scene.hpp"
#include "gpu/context.hpp"
#include "engine/render/renderer.hpp"
#include "shadows_engine/shadows_engine.hpp"

namespace {

double resident_mib() {
  std::ifstream statm("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  statm >> pages_total >> pages_resident;
  return double(pages_resident) * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 10000;
  uint32_t width = 64, height = 48;
  double rss_slack_mib = 16.0;
  bool verbose = false;
  bool still = false;  // casters stay put (to tell their re-upload from other growth)
  shadows::PassBackend trace = shadows::PassBackend::Auto;
  std::vector<std::string> modes = {"off", "sm", "cascades", "izb", "izb+csm", "hybrid"};
  for (int i = 1; i < argc; i += 2) {
    const std::string key = argv[i], value = i + 1 < argc ? argv[i + 1] : "";
    if (key == "--verbose" || key == "--still") {
      (key == "--verbose" ? verbose : still) = true;
      --i;
    } else if (key == "--modes") {
      modes.clear();
      for (size_t start = 0; start <= value.size();) {
        const size_t comma = std::min(value.find(',', start), value.size());
        modes.push_back(value.substr(start, comma - start));
        start = comma + 1;
      }
    } else if (key == "--trace" && shadows::parse_backend(value)) {
      trace = *shadows::parse_backend(value);
    } else if (key == "--frames") {
      frames = std::atoi(value.c_str());
    } else if (key == "--size" && std::sscanf(value.c_str(), "%ux%u", &width, &height) == 2) {
    } else if (key == "--rss-slack-mib") {
      rss_slack_mib = std::atof(value.c_str());
    } else {
      std::fprintf(stderr, "shadow_soak: unknown option %s\n", key.c_str());
      return 2;
    }
  }
  try {
    engine::gpu::Context ctx(engine::gpu::ContextOptions{});
    auto scene = engine::load_scene("contact");
    scene->apply_view(0);
    engine::Renderer renderer(ctx, VkExtent2D{width, height});
    renderer.set_scene(*scene);
    // Small maps and grid: the run is about memory over time, and lavapipe pays per texel.
    shadows::Settings settings;
    settings.izb.resolution = 256;
    settings.cascades.map_size = 256;
    settings.shadow_map.size = 256;
    settings.izb.trace = trace;
    auto module = shadows::install(renderer, settings);
    module->set_collect_stats(false);

    for (const auto& mode : modes)
      if (!shadows::parse_mode(mode, settings)) throw std::runtime_error("--modes: unknown mode '" + mode + "'");
    const int frames_per_mode = 100;
    const int cycle = frames_per_mode * int(modes.size());
    // The casters' starting places: each then circles its own.
    std::map<uint32_t, glm::vec3> home;
    scene->registry.each<engine::ShadowCaster>([&](engine::Entity e, engine::ShadowCaster&) {
      const auto* name = scene->registry.try_get<engine::Name>(e);
      if (name && name->value == "ground") return;
      if (auto* t = scene->registry.try_get<engine::Transform>(e)) home[e.index] = t->translation;
    });
    auto& light = scene->registry.get<engine::DirectionalLight>(scene->light);
    std::printf("shadow_soak: %d frames at %ux%u on %s, %zu moving casters, modes every %d frames\n", frames, width,
                height, ctx.device_name().c_str(), home.size(), frames_per_mode);

    struct Sample {
      int frame;
      double rss;
      uint32_t allocations;
    };
    std::vector<Sample> cycle_ends;  // after every full cycle through the modes
    Sample start{};
    for (int f = 0; f < frames; ++f) {
      if (f % frames_per_mode == 0) {
        auto next = shadows::parse_mode(modes[size_t(f / frames_per_mode) % modes.size()], settings);
        module->settings() = *next;
      }
      const float t = float(f) * 0.02f;
      light.direction = glm::normalize(glm::vec3(std::cos(t * 0.3f), -1.2f, std::sin(t * 0.3f)));
      scene->registry.each<engine::Transform>([&](engine::Entity e, engine::Transform& tr) {
        auto it = home.find(e.index);
        if (it == home.end() || still) return;
        const float phase = float(e.index);
        tr.translation = it->second + 0.25f * glm::vec3(std::sin(t + phase), 0.0f, std::cos(t + phase));
      });
      renderer.render_frame(1.0f / 60.0f);
      if (verbose && (f + 1) % 10 == 0)
        std::printf("  frame %6d (%s): rss %.1f MiB, live allocations %u\n", f + 1,
                    shadows::mode_name(module->settings()).c_str(), resident_mib(), ctx.live_allocation_count());
      if (f == 0) start = {1, resident_mib(), ctx.live_allocation_count()};
      if ((f + 1) % cycle == 0) {
        cycle_ends.push_back({f + 1, resident_mib(), ctx.live_allocation_count()});
        std::printf("frame %6d: rss %.1f MiB, live allocations %u\n", f + 1, cycle_ends.back().rss,
                    cycle_ends.back().allocations);
        std::fflush(stdout);
      }
    }
    const Sample end{frames, resident_mib(), ctx.live_allocation_count()};
    std::printf("start (frame 1): rss %.1f MiB, %u allocations; end (frame %d): rss %.1f MiB, %u allocations\n",
                start.rss, start.allocations, end.frame, end.rss, end.allocations);
    if (cycle_ends.size() < 3) {
      std::printf("shadow_soak: too few frames to judge (needs 3 cycles of %d)\n", cycle);
      return 1;
    }
    // Warm-up: the first cycle creates every mode's passes; the second settles the pools' sizes.
    const Sample& warm = cycle_ends[1];
    bool flat = true;
    for (size_t i = 2; i < cycle_ends.size(); ++i) {
      if (cycle_ends[i].allocations != warm.allocations) flat = false;
      if (cycle_ends[i].rss > warm.rss + rss_slack_mib) flat = false;
    }
    std::printf("after warm-up (frame %d): rss %.1f MiB, %u allocations -> end %+.1f MiB, %+d allocations: %s\n",
                warm.frame, warm.rss, warm.allocations, end.rss - warm.rss,
                int(end.allocations) - int(warm.allocations), flat ? "flat" : "GROWING");
    return flat ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "shadow_soak: %s\n", e.what());
    return 1;
  }
}
