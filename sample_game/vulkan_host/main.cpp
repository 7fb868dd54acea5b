// vulkan_host: a renderer on its own Vulkan device that shadows its frames with the shadow module.
//   vulkan_host [--out FILE.png] [--frames N] [--size WxH] [--mode izb|izb+csm|hybrid|...] [--spp 1|32]
//               [--view 0|1] [--device gpu|lavapipe] [--validation] [--frames-in-flight 1..8]
//               [--lights sun,spot,point] [--moving-sun] [--depth d32|d24s8|d32s8|d16] [--reversed-z]
//               [--normals oct|xyz] [--view-normals] [--geometric-normals] [--facing-in-alpha]
//               [--output r8|r16f|r32f] [--output-term occlusion|combined] [--no-mesh-bounds]
//               [--sun-size DEGREES] [--light-radius R] [--world-scale S] [--world-offset X,Y,Z]
//               [--origin-step X,Y,Z] [--shaders DIR]   (its own SPIR-V; default vulkan_host_shaders/ beside the executable)
// Exits non-zero on any error, and on any validation message when the layer is on (--validation,
// ENGINE_VALIDATION=1 or ENGINE_SYNC_VALIDATION=1).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image_write.h>

#include "vulkan_host.hpp"

int main(int argc, char** argv) {
  vulkan_host::Options o;
  std::string out = "vulkan_host.png";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const char* value = i + 1 < argc ? argv[i + 1] : nullptr;
    bool ok = true;
    if (arg == "--validation") { o.validation = true; continue; }
    if (arg == "--moving-sun") { o.moving_sun = true; continue; }
    if (arg == "--reversed-z") { o.reversed_z = true; continue; }
    if (arg == "--view-normals") { o.view_space_normals = true; continue; }
    if (arg == "--geometric-normals") { o.geometric_normals = true; continue; }
    if (arg == "--facing-in-alpha") { o.facing_in_alpha = o.geometric_normals = true; continue; }
    if (arg == "--no-mesh-bounds") { o.mesh_bounds = false; continue; }
    if (!value) ok = false;
    else if (arg == "--out") out = value;
    else if (arg == "--frames") ok = (o.frames = unsigned(std::atoi(value))) > 0;
    else if (arg == "--size") ok = std::sscanf(value, "%ux%u", &o.width, &o.height) == 2 && o.width && o.height;
    else if (arg == "--mode") o.mode = value;
    else if (arg == "--spp") ok = (o.spp = unsigned(std::atoi(value))) > 0;
    else if (arg == "--view") o.view = unsigned(std::atoi(value));
    else if (arg == "--device") o.device = value;
    else if (arg == "--frames-in-flight") o.frames_in_flight = unsigned(std::atoi(value));
    else if (arg == "--depth") o.depth_format = value;
    else if (arg == "--normals") o.normals = value;
    else if (arg == "--output") o.output_format = value;
    else if (arg == "--output-term") o.output_term = value;
    else if (arg == "--shaders") o.shader_directory = value;
    else if (arg == "--sun-size") o.sun_size_degrees = float(std::atof(value));
    else if (arg == "--light-radius") o.local_radius = float(std::atof(value));
    else if (arg == "--world-scale") ok = (o.world_scale = float(std::atof(value))) > 0.0f;
    else if (arg == "--world-offset")
      ok = std::sscanf(value, "%lf,%lf,%lf", &o.world_offset[0], &o.world_offset[1], &o.world_offset[2]) == 3;
    else if (arg == "--origin-step")
      ok = std::sscanf(value, "%lf,%lf,%lf", &o.origin_step[0], &o.origin_step[1], &o.origin_step[2]) == 3;
    else if (arg == "--lights") {
      o.lights.clear();
      for (std::string list = value; !list.empty();) {
        const size_t comma = list.find(',');
        o.lights.push_back(list.substr(0, comma));
        list = comma == std::string::npos ? "" : list.substr(comma + 1);
      }
    }
    else ok = false;
    if (!ok) {
      std::fprintf(stderr, "vulkan_host: bad argument '%s'%s%s\n", arg.c_str(), value ? " " : "", value ? value : "");
      return 2;
    }
    ++i;
  }
  try {
    const vulkan_host::Result r = vulkan_host::run(o);
    if (!stbi_write_png(out.c_str(), int(r.width), int(r.height), 4, r.rgba.data(), int(r.width * 4))) {
      std::fprintf(stderr, "vulkan_host: cannot write %s\n", out.c_str());
      return 1;
    }
    if (r.validation_messages) {
      std::fprintf(stderr, "vulkan_host: %u validation messages\n", r.validation_messages);
      return 1;
    }
    std::printf("vulkan_host: %s, %ux%u, %s, %u frames: wrote %s\n", r.device_name.c_str(), r.width, r.height,
                o.mode.c_str(), o.frames, out.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vulkan_host: %s\n", e.what());
    return 1;
  }
}
