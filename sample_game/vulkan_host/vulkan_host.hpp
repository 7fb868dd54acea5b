#pragma once
// A renderer of its own (raw Vulkan) that shadows its frames with the shadow module: a procedural
// scene drawn into the host's G-buffer (D24S8 standard depth, octahedral R16G16_SNORM world normals),
// the module recorded after it, a lighting pass, several frames in flight. run() is the whole program;
// main.cpp parses a command line into Options.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "shadows/context.hpp"
#include "shadows/settings.hpp"

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
  // The lights of every record(), in order, each at most once: "sun", "spot", "point" (the first one's
  // visibility lights the frame; the others go to FrameDesc::light_outputs).
  std::vector<std::string> lights = {"sun"};
  bool moving_sun = false;        // the sun turns a little every frame (frame 0 as when still)
  float local_range_scale = 1.0f;  // scales the spot and point lights' ranges (below 1: ground they no longer reach)
  float sun_size_degrees = 0.53f;  // the sun's Light::angular_diameter_degrees (0: hard shadows)
  float local_radius = 0.0f;       // the spot and point lights' Light::radius, world units (0: hard shadows)
  // Where the scene stands: every length times world_scale (1: metres; 100: centimetres), its origin at
  // world_offset. Frame k's floating origin (FrameDesc::origin) is world_offset + k * origin_step, and
  // all the host draws and hands over is relative to it in float, as a large world's host does.
  float world_scale = 1.0f;
  std::array<double, 3> world_offset{};
  std::array<double, 3> origin_step{};
  bool capture_every_frame = false;  // Result::frames holds every frame, not only the last
  // Calls Context::frame_completed() for each frame whose fence it has waited for, as a host that
  // knows its frames' completion does (statistics and the automatic choices' measures come back then).
  bool report_completed = true;
  // The G-buffer as the module reads it (the host tests' input matrix). The lighting pass always reads
  // its own octahedral world normals; these are what FrameDesc hands the module.
  std::string depth_format = "d24s8";  // d32, d24s8, d32s8 or d16
  bool reversed_z = false;             // depth 1 near, 0 far (cleared to 0, GREATER); else 0 near, 1 far
  std::string normals = "oct";         // oct: R16G16_SNORM octahedral; xyz: R16G16B16A16_SFLOAT n * 0.5 + 0.5 (scale 2, bias -1)
  bool view_space_normals = false;     // normals in view space (NormalSpace::View); else world
  bool geometric_normals = false;      // an R16G16B16A16_SFLOAT face normal (world) beside them
  bool facing_in_alpha = false;        // its alpha: the host's decision whether the point faces the sun
  std::string output_format = "r8";    // the module's outputs: r8 (R8_UNORM), r16f or r32f
  bool terminator_offset = false;      // an R16G16B16A16_SFLOAT offset of kTerminatorOffset along the normal
  bool receiver_mask = false;          // the albedo's alpha as the receiver mask: a tile in the pillar's shadow receives none
  // FrameDesc::output_term: "occlusion" (the module's default; this host's lighting applies N.L itself)
  // or "combined" (0 also where a light does not reach or face a point: what the reference traces).
  std::string output_term = "occlusion";
  bool mesh_bounds = true;             // MeshDesc::bounds given; false: absent, computed by the module on the device
  // Deforming casters. The cubes' shape of each frame, cube_shapes[min(frame, size - 1)] (empty: 0): 0
  // the unit cube, 1 sheared along x with height, 2 tapered toward its top; the G-buffer draws it.
  // With deformed_cubes the cube is registered as the unit cube and every cube instance hands the
  // module its shape's positions (Instance::deformed: the host's vertex buffer, position and normal
  // interleaved, stride 24); otherwise the cube is registered in frame 0's shape and drawn rigidly.
  std::vector<uint32_t> cube_shapes;
  bool deformed_cubes = false;
  shadows::CsmMode cube_csm = shadows::CsmMode::Auto;  // the cube instances' Instance::csm
  bool still = false;                                   // every frame the scene of frame 0 (nothing slides)
  std::vector<std::string> masked_features;             // ContextDesc::masked_features (tests of other devices)
  // Where the program's own SPIR-V lies (gbuffer.vert.spv, gbuffer.frag.spv, light.comp.spv); empty:
  // vulkan_host_shaders/ next to the executable. A file missing there is an error naming it.
  std::string shader_directory;
};

// The terminator offset the host writes with Options::terminator_offset: this far along the outward normal.
inline constexpr float kTerminatorOffset = 0.01f;

// A light as the host recorded it (world space).
struct HostLight {
  std::string kind;                  // "sun", "spot" or "point"
  std::array<float, 3> direction{};  // sun and spot: the direction light travels, unit
  std::array<float, 3> position{};   // spot and point
  float range = 0.0f;                // spot and point
  float outer_cone = 0.0f;           // spot: half angle, radians
  float angular_diameter_degrees = 0.0f;  // sun: Light::angular_diameter_degrees (0: a point sun)
  float radius = 0.0f;                    // spot and point: Light::radius (0: a point light)
};

// One captured frame, pixel (x, y) at index y * width + x.
struct FrameCapture {
  uint32_t frame = 0;
  bool reversed_z = false;
  float depth_step = 0.0f;     // the depth format's step: 1 / (2^bits - 1) for D16 and D24, 0 for float ones
  std::vector<float> depth;    // the host's depth in [0, 1] as stored (background: 1 standard, 0 reversed)
  std::vector<float> normals;  // 3 per pixel: decoded world normal as stored (not turned to the camera)
  std::array<float, 16> inverse_view_projection{};  // Vulkan NDC (the depth convention used) -> world, column-major
  float terminator_offset = 0.0f;                  // along the outward normal, world units (0: none given)
  std::vector<uint8_t> receives;                   // with a receiver mask: 1 where the point receives shadows
  std::vector<HostLight> lights;                   // as recorded, in Options::lights order
  std::vector<std::vector<float>> visibility;      // the module's output per light, 1 lit .. 0 shadowed
  std::vector<float> caster_triangles;             // 9 per triangle: world-space corners at that frame
};

// The last frame (the fields below; its first light), and every captured frame in order (`frames`).
struct Result {
  uint32_t width = 0, height = 0;
  std::string device_name;
  std::vector<float> depth;       // as FrameCapture::depth
  std::vector<float> normals;     // 3 per pixel: decoded world normal as stored (not turned to the camera)
  std::vector<float> visibility;  // the module's output, 1 lit .. 0 shadowed
  std::vector<uint8_t> rgba;      // the lit frame
  std::array<float, 16> inverse_view_projection{};  // as FrameCapture::inverse_view_projection
  std::array<float, 3> light_direction{};           // the direction light travels, unit
  std::vector<float> caster_triangles;              // 9 per triangle: world-space corners at that frame
  uint32_t validation_messages = 0;
  std::vector<FrameCapture> frames;  // capture_every_frame: all, in order; else the last one
  std::string csm_status;            // Stats::csm_status after the last frame (izb+csm: whether the prepass ran)
  uint64_t csm_culled = 0;           // Stats::csm_culled_points, summed over the frames whose statistics came back
  std::vector<shadows::Stats::LightStats> light_stats;  // report_completed: Stats::lights after the last frame
  std::vector<shadows::CsmDecision> csm_decisions;      // Stats::csm_decisions after the last frame
};

Result run(const Options& options);  // throws std::exception (one line) on any failure

}  // namespace vulkan_host
