#pragma once
// The shadow module on a host's own Vulkan device: the API a studio's renderer uses.
//
//   // before vkCreateDevice: what to enable (DeviceSetup fills the chain and the extension list)
//   shadows::DeviceSetup setup(physical_device);
//   // once
//   auto shadows = shadows::Context::create({.instance = ..., .device = ..., .frames_in_flight = 2, ...});
//   shadows::MeshId rock = shadows->register_mesh({.positions = {...}, .indices = {...}, ...});
//   // per frame, into the host's command buffer, after its G-buffer pass
//   shadows->record(cmd, {.frame_index = n, .depth = {...}, .normals = {...}, .camera = {...},
//                         .lights = &sun, .light_count = 1, .instances = ..., .output = {...}});
//
// Only Vulkan and the standard library appear here. Matrices are column-major float[16] (the layout of
// GLSL and GLM), world space is right-handed, clip space is Vulkan's (y down, depth in [0, 1]).
//
// Synchronization contract (every call of record()):
//   - Inputs (depth, normals, geometric normals, terminator offset, receiver mask, alpha textures) are
//     read only by compute shaders, through sampled-image descriptors. They must be in the layout named
//     in their ImageInput (SHADER_READ_ONLY_OPTIMAL, DEPTH_READ_ONLY_OPTIMAL,
//     DEPTH_STENCIL_READ_ONLY_OPTIMAL or GENERAL) when the command buffer executes, and the host's
//     writes to them must be made visible to VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT /
//     VK_ACCESS_2_SHADER_SAMPLED_READ_BIT by a barrier the host records before record(). The module
//     never changes their layout. Native inputs (FrameDesc::native) are read as storage images
//     instead: see NativeInputs.
//   - The outputs (FrameDesc::output, light_outputs, and the optional overlay) must be in
//     VK_IMAGE_LAYOUT_GENERAL, with every earlier
//     access by the host finished before VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT (a barrier whose
//     second scope is COMPUTE_SHADER / SHADER_STORAGE_WRITE). The module writes them with compute
//     shaders only and leaves them in GENERAL: the host's next barrier on them needs
//     srcStageMask = COMPUTE_SHADER, srcAccessMask = SHADER_STORAGE_WRITE.
//   - Host mesh buffers are read by compute shaders (storage-buffer reads) in the first record() after
//     register_mesh(), so they must hold their data, visible to COMPUTE_SHADER / SHADER_STORAGE_READ,
//     until that frame's commands have executed. A mesh registered without bounds has its positions
//     read once more inside register_mesh(), by a submission of the module's own to ContextDesc::queue
//     that it waits for (MeshDesc::bounds).
//   - Deformed positions (Instance::deformed) are read by compute shaders (storage-buffer reads) at
//     the start of the record() they are given to, copied into the module's own buffers: the host's
//     writes must be visible to COMPUTE_SHADER / SHADER_STORAGE_READ before that record()'s commands
//     run, and the region must keep them until those commands have executed (the next frame's
//     positions go to another region, or to this one once this frame has completed).
//   - Inside record() the module orders its own resources with barriers that name their stages and
//     accesses; it records no barrier on a host resource and no ALL_COMMANDS barrier.
//   - The command buffer must support compute and graphics (a queue of the family given at creation),
//     be outside a render pass, and have no pipeline or descriptor state the host relies on afterwards:
//     the module binds its own pipelines and push descriptors (the host rebinds after record()).
//
// Frames in flight: record() for frame N writes only the per-frame data of slot N % frames_in_flight,
// and reads back (statistics, pass timings, pool demand) the slot it last wrote frames_in_flight frames
// ago. The host promises what every renderer with F frames in flight already waits for: when it
// records frame N, the commands recorded for frame N - F have completed. Nothing in record() waits on
// the CPU; statistics describe the frame F - 1 frames before the current one.
//
// Errors: a bad argument throws shadows::Error, one line naming the argument, before anything is
// recorded. The context stays usable.
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include "shadows/version.hpp"

#include "shadows/settings.hpp"

namespace shadows {

// One line naming the argument and what is wrong with it.
class SHADOWS_API Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What the host should enable before vkCreateDevice. Required items are needed by every technique;
// optional ones unlock a path, each with what it unlocks. Only what `physical_device` supports is
// listed among the optional items.
struct DeviceRequirement {
  std::string name;     // extension name ("VK_KHR_push_descriptor") or feature ("geometryShader")
  std::string unlocks;  // for optional items: which technique or path needs it
};
struct DeviceRequirements {
  uint32_t api_version = VK_API_VERSION_1_3;
  std::vector<DeviceRequirement> required_extensions;
  std::vector<DeviceRequirement> required_features;
  std::vector<DeviceRequirement> optional_extensions;
  std::vector<DeviceRequirement> optional_features;
  std::string missing;  // empty when the device can run the module; else the one-line reason
};
SHADOWS_API DeviceRequirements device_requirements(VkPhysicalDevice physical_device);

struct ContextDesc;

// What vkCreateDevice needs for the module, in a few lines:
//
//   shadows::DeviceSetup setup(physical_device);          // required items + the optional ones it has
//   if (!setup.missing().empty()) fail(setup.missing());
//   setup.add_extension(VK_KHR_SWAPCHAIN_EXTENSION_NAME);  // the host's own wishes, if any
//   setup.add_features(my_features2);                      // (a chain rooted at VkPhysicalDeviceFeatures2)
//   VkDeviceCreateInfo info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
//   info.pNext = setup.features();
//   info.enabledExtensionCount = setup.extension_count();
//   info.ppEnabledExtensionNames = setup.extension_names();
//   ... vkCreateDevice ...;  setup.describe(context_desc);  // the arrays and chain ContextDesc wants
//
// It owns every structure, string and array it hands out (valid while it lives, until its next add_*): a
// VkPhysicalDeviceFeatures2 chained to VkPhysicalDeviceVulkan11/12/13Features and, where their
// extensions are in the list, the fragment shader barycentric, acceleration structure, ray tracing
// pipeline and ray query structures. Optional items are taken where the device has them (each with
// what it unlocks in optional_items()); `leave_out` names extensions or feature bits not to take
// (a required one left out gives a device the module refuses, which tests use).
class SHADOWS_API DeviceSetup {
 public:
  explicit DeviceSetup(VkPhysicalDevice physical_device, const std::vector<std::string>& leave_out = {});
  ~DeviceSetup();
  DeviceSetup(DeviceSetup&&) noexcept;
  DeviceSetup& operator=(DeviceSetup&&) noexcept;
  DeviceSetup(const DeviceSetup&) = delete;
  DeviceSetup& operator=(const DeviceSetup&) = delete;

  // Empty when the device can run the module; else one line saying what it lacks.
  const std::string& missing() const;
  // The optional extensions and feature bits taken, each with what it unlocks.
  const std::vector<DeviceRequirement>& optional_items() const;

  // Adds a device extension of the host's (no effect when already listed).
  DeviceSetup& add_extension(const char* name);
  // ORs in the bits the host sets in its own chain: VkPhysicalDeviceFeatures2 (its `features`), the
  // Vulkan 1.1/1.2/1.3 structures, the structures promoted into them that the module knows
  // (synchronization2, dynamic rendering, maintenance4, buffer device address, scalar block layout,
  // host query reset, timeline semaphore, 8-bit storage, float16/int8) and the
  // four extension structures above. Throws shadows::Error, one line naming it, for any other
  // structure (a host chains those itself after features()) or for bits of an extension structure
  // whose extension is not listed (add_extension first).
  DeviceSetup& add_features(const VkPhysicalDeviceFeatures2& host_chain);

  // For VkDeviceCreateInfo::pNext (pEnabledFeatures stays null).
  const VkPhysicalDeviceFeatures2* features() const;
  const char* const* extension_names() const;
  uint32_t extension_count() const;
  // Sets desc.enabled_device_extension_names / enabled_device_extension_count (pointing at this
  // object's own array, extension_names()) and desc.enabled_features (features()). They stay valid
  // while this object lives and until its next add_*: it must outlive Context::create, which copies
  // the names and reads the chain; the context keeps no pointer into it afterwards.
  void describe(ContextDesc& desc) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct ContextDesc {
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical_device = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  uint32_t queue_family = 0;  // a family with graphics and compute; record()'s command buffers come from it
  // Used only for one-off work the module waits for: uploads at creation, and register_mesh() of a
  // mesh without bounds (MeshDesc::bounds).
  VkQueue queue = VK_NULL_HANDLE;
  PFN_vkGetInstanceProcAddr get_instance_proc_addr = nullptr;  // required
  PFN_vkGetDeviceProcAddr get_device_proc_addr = nullptr;      // required
  // What the host enabled, as it gave them to vkCreateInstance and vkCreateDevice
  // (VkInstanceCreateInfo::ppEnabledExtensionNames / VkDeviceCreateInfo::ppEnabledExtensionNames and
  // their counts): the module uses exactly these (a feature the device has but the host did not enable
  // counts as absent, and the techniques that need it say so in capabilities()). Each array holds
  // `count` null-terminated names; it may be null only with a count of 0 (a null array with a nonzero
  // count is refused naming the field). create() copies the names: the arrays need not outlive it.
  const char* const* enabled_instance_extension_names = nullptr;
  uint32_t enabled_instance_extension_count = 0;
  const char* const* enabled_device_extension_names = nullptr;
  uint32_t enabled_device_extension_count = 0;
  // The VkPhysicalDeviceFeatures2 chain given to vkCreateDevice (its pNext); required. Read by
  // create() only.
  const VkPhysicalDeviceFeatures2* enabled_features = nullptr;
  uint32_t api_version = VK_API_VERSION_1_3;                    // the instance's apiVersion (>= 1.3)
  const VkAllocationCallbacks* allocator = nullptr;             // for every object the module creates
  VkPipelineCache pipeline_cache = VK_NULL_HANDLE;              // for every pipeline it creates
  uint32_t frames_in_flight = 2;                                // 1..8
  Settings settings;                                            // initial settings (settings() changes them)
  // Counts validation messages on the host's instance (needs VK_EXT_debug_utils enabled there); tests.
  bool count_validation_messages = false;
  // Optional features to treat as absent (tests of the other paths): "conservative_rasterization",
  // "geometry_shader", "fragment_shader_barycentric", "subgroup_arithmetic" (subgroup arithmetic and
  // ballot operations); see capabilities(). Another name is refused in one line.
  std::vector<std::string> masked_features;
};

// A host buffer region: the buffer must have been created with VK_BUFFER_USAGE_STORAGE_BUFFER_BIT
// (stated in `usage`, which the module checks), and `offset` must be a multiple of 4.
struct BufferInput {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceSize offset = 0;     // bytes
  VkDeviceSize size = 0;       // bytes from offset the module may read
  VkBufferUsageFlags usage = 0;  // the flags the buffer was created with
};

// A host image: 2D, one mip level and one layer in `view`; usage is the flags it was created with.
struct ImageInput {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;  // for depth/stencil formats: a view of the depth aspect only
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkExtent2D extent{};
  VkImageUsageFlags usage = 0;
  VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;  // the layout when the commands execute
  bool present() const { return view != VK_NULL_HANDLE; }
};

using MeshId = uint32_t;
inline constexpr MeshId kNoMesh = 0xffffffffu;

enum class AlphaWrap : uint32_t { Repeat = 0, ClampToEdge = 1, MirroredRepeat = 2 };

// An axis-aligned box in a mesh's object space.
struct MeshBounds {
  float min[3] = {0.0f, 0.0f, 0.0f};
  float max[3] = {0.0f, 0.0f, 0.0f};
};

// A caster mesh, registered once. The module copies (and converts) it into its own buffers during the
// next record(); the host's buffers must stay valid until that frame has executed. Without `bounds`,
// register_mesh() also reads the positions at once, on the device (see `bounds`).
struct MeshDesc {
  std::string name;                     // for statistics and messages
  // Positions: VK_FORMAT_R32G32B32_SFLOAT or R32G32B32A32_SFLOAT (w ignored), `stride` bytes apart
  // (a multiple of 4, at least the format's size), object space.
  BufferInput positions;
  VkFormat position_format = VK_FORMAT_R32G32B32_SFLOAT;
  uint32_t position_stride = 12;
  uint32_t vertex_count = 0;
  // Triangle list; VK_INDEX_TYPE_UINT16 or UINT32. index_count a positive multiple of 3. 16-bit indices
  // are read as 4-byte words: offset + size must reach offset + 2 * index_count rounded up to a
  // multiple of 4 (an odd index_count at the very end of a buffer needs 2 bytes of padding there).
  BufferInput indices;
  VkIndexType index_type = VK_INDEX_TYPE_UINT32;
  uint32_t index_count = 0;
  // Optional alpha test (cut-out casters): per-vertex texture coordinates (VK_FORMAT_R32G32_SFLOAT,
  // `uv_stride` bytes apart) and a texture whose alpha channel is tested against `alpha_cutoff`
  // (kept where alpha >= cutoff, nearest texel of level 0). The texture must be R8G8B8A8_UNORM,
  // R8G8B8A8_SRGB, B8G8R8A8_UNORM or R8_UNORM (alpha = r), with SAMPLED usage.
  BufferInput uvs;
  uint32_t uv_stride = 8;
  ImageInput alpha_texture;
  float alpha_cutoff = 0.5f;
  float alpha_scale = 1.0f;  // the texture's alpha is multiplied by this first (glTF's base colour factor)
  AlphaWrap wrap_u = AlphaWrap::Repeat, wrap_v = AlphaWrap::Repeat;
  // Object-space bounds of the positions, which the light-space fits and culling use (on the CPU).
  // Given: finite with min <= max on every axis (refused otherwise, naming MeshDesc.bounds), and
  // holding every position (not checked: a box too small lets casters be culled where they reach). Absent (std::nullopt, the default): register_mesh() computes them on the device
  // before it returns: one compute dispatch (min and max over all vertex_count positions, exact)
  // submitted to ContextDesc::queue, which it waits for, and the 24 bytes read back. The positions
  // must then hold their data when register_mesh() is called (written by the host, or by device work
  // that has completed), and the queue must not be in use by another thread during the call (as for
  // vkQueueSubmit). A non-finite position is then refused, naming MeshDesc.positions. Either way the
  // bounds the module uses are what Context::mesh_bounds() returns.
  std::optional<MeshBounds> bounds;
};

// Whether an instance enters the conservative shadow map prepass.
enum class CsmMode : uint32_t { Auto, On, Off };

// An instance's own object-space positions for this frame, replacing its mesh's (a skinned or morphed
// caster: the host's skinning or morph output). Topology, uvs and the alpha test stay the registered
// mesh's. The buffer region is read by compute shaders (storage-buffer reads) in the record() it is
// given to, on the device: the host's writes to it must be visible to COMPUTE_SHADER /
// SHADER_STORAGE_READ before that record()'s commands run, and it must hold them until they have
// executed (the synchronization contract above). The module copies the positions into its own
// buffers at the start of the frame's commands, so the host may overwrite the region once the frame
// has executed. With Technique::RayTraced the instance's acceleration structure is refitted to them
// every frame. CsmMode::Auto treats such an instance as dynamic (it never enters the CSM); On still
// puts it there.
// Memory: the k-th deformed instance of a mesh in a frame draws from the mesh's k-th copy in the
// module's vertex buffer, made the first frame a mesh has k deformed instances and kept for the
// context's life (as a registered mesh's space: a new context compacts).
// Refused (shadows::Error naming FrameDesc.instances[i].deformed.<field>): a format or stride other
// than these, vertex_count other than the mesh's, a region too small or misaligned (as BufferInput),
// bounds not finite or not a box.
struct DeformedPositions {
  // Format and stride as MeshDesc::positions: R32G32B32_SFLOAT or R32G32B32A32_SFLOAT, `stride` a
  // multiple of 4 at least the format's size; the region must hold vertex_count vertices.
  BufferInput positions;
  VkFormat format = VK_FORMAT_R32G32B32_SFLOAT;
  uint32_t stride = 12;
  uint32_t vertex_count = 0;  // must equal the mesh's MeshDesc::vertex_count
  // A box in object space holding every position of this frame (finite, min <= max): the light-space
  // fits and culling use it as they use MeshDesc::bounds. Not checked against the positions.
  MeshBounds bounds;
  bool present() const { return positions.buffer != VK_NULL_HANDLE; }
};

struct Instance {
  MeshId mesh = kNoMesh;
  float world[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};  // object -> world
  bool casts_shadow = true;
  CsmMode csm = CsmMode::Auto;
  uint64_t id = 0;              // the host's identifier, echoed in Stats::csm_decisions
  const char* name = nullptr;   // for statistics and messages (null: the mesh's name)
  // Optional (deformed.positions.buffer null: the mesh's registered positions, moved by `world`).
  DeformedPositions deformed;
};

enum class LightType : uint32_t { Directional, Spot, Point };

// Every technique shadows every light type. A directional light as the technique says; a spot light
// with one perspective light space from its position: Technique::Izb and Hybrid trace it with the IZB
// (CSM prepass included; compute trace and CSM, no lit culling: the hybrid needs no filtered term
// within a light's range), ShadowMap with one perspective map, Cascades with the same map PCF-filtered,
// RayTraced with rays toward its position. A point light is six such cones around the axes (its
// Stats::lights entry sums them). A local light shadows the points it reaches: within
// `range` of `position` and, for a spot light, inside its outer cone. What the output holds at every
// other point, and at every point whose geometric normal turns away from the light, is chosen by
// FrameDesc::output_term (1 by default; 0 with OutputTerm::Combined). Shadow rays run from the
// point (pushed off its surface as for the sun) toward `position`, and occluders closer to the light
// than its bulb, 1/1000 of its range (its bulb and housing), do not count (shaders/shared/local_light.h).
struct Light {
  LightType type = LightType::Directional;
  float direction[3] = {0.0f, -1.0f, 0.0f};  // directional and spot: the direction light travels, unit
  float position[3] = {0.0f, 0.0f, 0.0f};    // spot and point (world)
  float range = 0.0f;                        // spot and point: > 0, world units
  float inner_cone = 0.0f, outer_cone = 0.0f;  // spot: half angles in radians, 0 <= inner < outer <= pi/2
  // The light's size, which sets how fast penumbrae widen with the distance from occluder to receiver.
  // Directional: the sun's angular diameter in degrees, finite, 0 (a point: hard shadows) to 10; the
  // real sun is 0.53. Spot and point: the radius of the emitting sphere in world units, finite, >= 0.
  // `sm` and `cascades` filter by it (PCSS), and `hybrid` by the sun's (keeping the exact IZB term
  // wherever the penumbra is narrower than a pixel; a spot or point light takes the IZB's hard term
  // whatever its radius); `rt` samples it with Settings::rt_light_samples rays; `izb` and `izb+csm`
  // draw the exact hard shadow of the light's centre whatever its size.
  float angular_diameter_degrees = 0.53f;
  float radius = 0.0f;
};

enum class NormalSpace : uint32_t { World, View };
enum class NormalEncoding : uint32_t {
  Xyz,         // rgb = normal * scale + bias per channel (e.g. UNORM storing n * 0.5 + 0.5: scale 2, bias -1)
  Octahedral,  // rg = octahedral encoding * scale + bias, in [-1, 1] after scale and bias
};
struct NormalInput {
  ImageInput image;
  NormalSpace space = NormalSpace::World;
  NormalEncoding encoding = NormalEncoding::Xyz;
  float scale = 1.0f, bias = 0.0f;  // decoded = texel * scale + bias, then decoded as `encoding`
  // Set when the normals already face the camera (a G-buffer that flips back faces). World-space Xyz
  // normals with scale 1 and bias 0 are then used as stored (they must be unit length); otherwise the
  // module normalizes them and turns them toward the camera itself.
  bool facing_camera = false;
};

// The module's own per-pixel inputs, given directly. Each: STORAGE usage, GENERAL layout, extent equal
// to depth's; read (never written) as storage images by the module's passes, which run in
// COMPUTE_SHADER, FRAGMENT_SHADER and (with rt) RAY_TRACING_SHADER stages: the host's writes must be
// visible to those stages / SHADER_STORAGE_READ before the command buffer reaches record()'s commands.
struct NativeInputs {
  // R32G32B32A32_SFLOAT: the shading point in world space (any terminator offset already added);
  // w = 1 covered, 0 background.
  ImageInput world_position;
  // R16G16B16A16_SFLOAT: the unit geometric (triangle) normal facing the camera; w > 0.5 where the point
  // faces the light (the host's decision, as FrameDesc::facing_in_alpha).
  ImageInput geometric_normal;
  // R8G8B8A8_UNORM: a > 0.5 receives shadows (rgb not read).
  ImageInput receives;
  bool present() const { return world_position.present() || geometric_normal.present() || receives.present(); }
};

struct Camera {
  float view[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};        // world -> view
  float projection[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};  // view -> Vulkan clip
  bool reversed_z = true;    // depth 1 near, 0 far (else 0 near, 1 far)
  float near_plane = 0.05f;  // view-space distances of the projection's planes (the cascades split
  float far_plane = 200.0f;  // the range between them; an infinite projection: the farthest shadowed)
};

constexpr uint32_t kMaxLightsPerRecord = 8;

// What FrameDesc::output (and light_outputs) hold per pixel, for every technique and light type.
enum class OutputTerm : uint32_t {
  // Occlusion only (the default): 1 wherever nothing blocks the light, including points a local light
  // does not reach (outside its range or a spot light's outer cone), points whose geometric normal
  // turns away from the light, background and points that receive no shadow; only real occlusion
  // lowers it. The host's lighting applies its own range, cone and facing terms (N.L, attenuation).
  Occlusion,
  // Occlusion times reach and facing: 0 also where the light does not reach (outside its range or
  // cone) and where the point faces away from it, as this engine's renderer multiplies each light by
  // it. Receiver-masked points that face the light stay 1.
  Combined,
};

struct FrameDesc {
  uint64_t frame_index = 0;  // increases by one per record(); slot = frame_index % frames_in_flight
  // Depth: D32_SFLOAT, D24_UNORM_S8_UINT, D32_SFLOAT_S8_UINT or D16_UNORM, SAMPLED usage. A pixel at
  // the clear depth (0 reversed, 1 standard) is background: lit, not a shading point. A point rebuilt
  // from a UNORM depth is pushed off its surface (along the geometric normal, else the shading one)
  // by the distance half a step of the format spans there, so a coarse depth (D16 standard Z: about
  // 5 mm 8 units from a 0.1 near plane) does not shadow its own surface.
  ImageInput depth;
  // Shading normals (required), facing the camera or not (the module turns them toward it). Any
  // float/UNORM/SNORM colour format with SAMPLED usage; `extent` equal to depth's.
  NormalInput normals;
  // Optional geometric (triangle) normals: shadow-ray origins are pushed off the surface along them.
  // Without them the shading normal is used. When `facing_in_alpha` is set, the image's alpha holds
  // the host's per-pixel decision whether the point faces the light (> 0.5 facing); otherwise the
  // module decides from the shading normal.
  NormalInput geometric_normals;
  bool facing_in_alpha = false;
  // Optional smooth-terminator offset (world-space xyz added to the shading point; the GLSL function in
  // shadows/terminator_offset.glsl, installed beside this header, computes it in a G-buffer shader).
  // Float format.
  ImageInput terminator_offset;
  // Optional receiver mask: channel `receiver_channel` > 0.5 receives shadows; others stay lit (1), except
  // that with OutputTerm::Combined a point facing away from the light is 0 whether it receives or not.
  ImageInput receiver_mask;
  uint32_t receiver_channel = 3;
  // Optional, for a host whose G-buffer already holds the shading points in the module's own formats
  // (all three, or none): the module then reads them in place and skips its input pass, and depth,
  // normals, geometric normals, terminator offset and receiver mask are checked but not read.
  NativeInputs native;
  // Large worlds: the world position, in double, that every world-space value of this FrameDesc is
  // relative to: camera.view, instances' world matrices, lights' positions and native world positions
  // (world = value + origin). A host whose world reaches far from its origin passes a point near the
  // camera here (Unreal's rebasing, a floating origin) and makes its matrices relative to it, so float
  // keeps its precision; the shadows are the same wherever the origin is. Finite.
  double origin[3] = {0.0, 0.0, 0.0};
  Camera camera;
  // The lights to shadow, 1..kMaxLightsPerRecord, each into its own image: lights[0] into `output`,
  // lights[i] into light_outputs[i - 1]. They run one after another through the same passes, with a
  // profiler region "light i" each when there are several; Stats::lights has an entry per light. A
  // spot or point light whose cone (a point light's ball) within its range meets none of the camera's
  // frustum runs no technique pass: one pass writes its term, 0 where a point is covered and 1 on the
  // background, as the passes would have (Stats::LightStats::reaches_view false).
  const Light* lights = nullptr;
  uint32_t light_count = 0;
  const Instance* instances = nullptr;  // every caster this frame
  uint32_t instance_count = 0;
  // Visibility (1 lit .. 0 shadowed), per pixel of depth: R8_UNORM, R16_SFLOAT or R32_SFLOAT with
  // STORAGE usage, GENERAL layout, extent equal to depth's. Every pixel is written, as `output_term` says.
  // With `native` inputs, an R32_SFLOAT output, OutputTerm::Combined, no overlay handed over for this
  // light and a technique other than RayTraced, the module's passes write the term into it in place
  // (no copy pass; the same values), reading back what they wrote: its earlier contents are not read.
  ImageInput output;
  OutputTerm output_term = OutputTerm::Occlusion;  // for output and every light_outputs image
  // With light_count > 1: light_count - 1 more images, as `output`, for lights[1..].
  const ImageInput* light_outputs = nullptr;
  // Optional debug overlay (Settings::debug) of lights[overlay_light]: R8G8B8A8_UNORM, STORAGE usage,
  // GENERAL; rgb colour, a blend weight. Pixels the overlay does not mark are written 0, and without a
  // debug view every pixel is: a host that keeps its overlay cleared itself hands it over only while
  // Settings::debug draws one, which spares a store a pixel (the engine's client does).
  ImageInput overlay;
  uint32_t overlay_light = 0;  // < light_count
};

// Whether something can run on this device, with the one-line reason where not.
struct Capability {
  bool available = false;
  std::string reason;  // empty when available
};
// What the module can do for one light type (LightType) on this device. record() refuses exactly what
// is unavailable here, for a light of this type, with the settings that ask for it, in a line that
// names the light (FrameDesc.lights[i]) and carries `reason`; everything available records. A device
// without subgroup arithmetic and ballot operations in compute and fragment shaders (or with
// "subgroup_arithmetic" in ContextDesc::masked_features) runs Off, ShadowMap and RayTraced only: the
// cascades' and the IZB's passes need them.
struct LightCapabilities {
  Capability technique[6];  // indexed by Technique
  // The IZB's paths (Technique::Izb and Hybrid; a local light's grid is traced by compute passes only):
  Capability raster_trace;   // IzbSettings::trace Raster
  Capability compute_trace;  // IzbSettings::trace Compute
  Capability raster_csm;     // the CSM prepass as raster work: IzbSettings::csm_backend Raster
  Capability compute_csm;    // the CSM prepass as compute work (csm_test hertel or bary)
  Capability csm_test[4];    // indexed by CsmTest, with IzbSettings::csm
  const Capability& of(Technique t) const { return technique[static_cast<int>(t)]; }
  const Capability& of(CsmTest t) const { return csm_test[static_cast<int>(t)]; }
};
struct Capabilities {
  // The directional light's (light[LightType::Directional] holds the same), kept for hosts with a sun only.
  Capability technique[6];  // indexed by Technique
  Capability csm_test[4];   // indexed by CsmTest
  bool hardware_conservative_raster = false;
  LightCapabilities light[3];  // indexed by LightType
  const Capability& of(Technique t) const { return technique[static_cast<int>(t)]; }
  const Capability& of(CsmTest t) const { return csm_test[static_cast<int>(t)]; }
  const LightCapabilities& of(LightType t) const { return light[static_cast<int>(t)]; }
};

class SHADOWS_API Context {
 public:
  // Throws shadows::Error (one line naming the field) on a bad description or a device that lacks a
  // required feature; see device_requirements().
  static std::unique_ptr<Context> create(const ContextDesc& desc);
  virtual ~Context() = default;

  virtual Capabilities capabilities() const = 0;
  virtual Settings& settings() = 0;

  // Caster meshes. The id stays valid until unregister_mesh(). Unregistering stops the mesh from being
  // drawn; its space in the module's buffers is not reused (a new context compacts after a level change).
  virtual MeshId register_mesh(const MeshDesc& mesh) = 0;
  virtual void unregister_mesh(MeshId mesh) = 0;
  // The object-space bounds a registered mesh is fitted and culled with: MeshDesc::bounds as given, or
  // those computed on the device at registration. Throws shadows::Error for an id not registered.
  virtual MeshBounds mesh_bounds(MeshId mesh) const = 0;

  // Records the frame's shadow passes into `cmd` (see the synchronization contract above). Throws
  // shadows::Error before recording anything when an argument is invalid.
  virtual void record(VkCommandBuffer cmd, const FrameDesc& frame) = 0;

  // Optional: the host knows frame `frame_index` has completed (it waited for its fence). Its
  // statistics and pass timings are read now instead of frames_in_flight frames later.
  virtual void frame_completed(uint64_t frame_index) = 0;

  // Statistics of the latest frame whose results have come back (see frames in flight); collected only
  // while enabled (a small readback). The automatic choices (trace_choice, csm_choice, lit_choice,
  // csm_run_choice, tile_work_choice) and csm_status follow every frame either way.
  virtual void set_collect_stats(bool enabled) = 0;
  virtual const Stats& stats() const = 0;
  // The module's GPU passes of the latest completed frame: name and milliseconds, in recording order.
  struct PassTime {
    std::string name;
    double ms = 0.0;
  };
  virtual std::vector<PassTime> pass_times() const = 0;
  // Names of the passes the current settings can record, in order (one a frame did not run has no time).
  virtual std::vector<std::string> pass_names() const = 0;

  // Validation messages counted on the host's instance (ContextDesc::count_validation_messages).
  virtual uint32_t validation_message_count() const = 0;
};

}  // namespace shadows
