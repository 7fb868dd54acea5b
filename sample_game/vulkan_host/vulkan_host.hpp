#pragma once
// A renderer of its own (raw Vulkan) that shadows its frames with the shadow module: a procedural
// scene drawn into the host's G-buffer (D24S8 standard depth, octahedral R16G16_SNORM world normals),
// the module recorded after it, a lighting pass, several frames in flight. run() is the whole program;
// main.cpp parses a command line into Options.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vulkan_host {

struct Options {
  uint32_t width = 640, height = 360;
  uint32_t frames = 3;            // the last one is captured
  uint32_t frames_in_flight = 3;
  std::string mode = "hybrid";    // shadows::parse_mode
  uint32_t spp = 1;               // 1 or 32
  uint32_t view = 0;              // camera 0 or 1
  std::string device;             // "gpu", "lavapipe" or empty (a GPU if there is one)
  bool validation = false;        // also ENGINE_VALIDATION=1 / ENGINE_SYNC_VALIDATION=1
  bool sync_validation = false;   // the layer's synchronization checks too
};

// The captured (last) frame, pixel (x, y) at index y * width + x.
struct Result {
  uint32_t width = 0, height = 0;
  std::string device_name;
  std::vector<float> depth;       // the host's depth in [0, 1], standard Z (1 = background)
  std::vector<float> normals;     // 3 per pixel: decoded world normal as stored (not turned to the camera)
  std::vector<float> visibility;  // the module's output, 1 lit .. 0 shadowed
  std::vector<uint8_t> rgba;      // the lit frame
  std::array<float, 16> inverse_view_projection{};  // Vulkan NDC (standard depth) -> world, column-major
  std::array<float, 3> light_direction{};           // the direction light travels, unit
  std::vector<float> caster_triangles;              // 9 per triangle: world-space corners at that frame
  uint32_t validation_messages = 0;
};

Result run(const Options& options);  // throws std::exception (one line) on any failure

}  // namespace vulkan_host
