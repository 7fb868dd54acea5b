// The shadow map's resolve (sm, and the cascades' local-light maps), included by
// shadow_map_resolve.comp and, with SHADOWS_WITHOUT_SUBGROUP_OPS defined, by
// shadow_map_resolve_portable.comp for a device without subgroup arithmetic and ballot operations
// (DeviceFeatures::subgroup_arithmetic_compute_fragment): the plain shadow map needs neither, so that
// variant reserves its list slots and counts with an atomic an invocation instead.
#ifndef SHADOWS_WITHOUT_SUBGROUP_OPS
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#endif
#include "shadows.h"
#include "shadow_common.h"
#include "local_light.h"
// 64 invocations: 8x8 on a GPU; 64x1 on a CPU device (specialization constants 9 and 10,
// barriers.hpp's pixel_group_width), where lavapipe ran a row of 64 pixels about a fifth faster
// than 8 rows of 8 (16x16, 32x2 and 256x1 were no faster).
layout(local_size_x = 8, local_size_y = 8, local_size_x_id = 9, local_size_y_id = 10) in;

// A light with a size (ShadowMapResolveParams::pcss): the PCSS pipeline. A specialization constant
// rather than a branch, since llvmpipe pays for both sides of one.
layout(constant_id = 0) const bool kPcss = false;
// A fixed filter (ShadowMapResolveParams::bias.y > 0: the cascades' spot-light maps), likewise: a CPU
// device would run its 16 taps for every pixel, filter or not.
layout(constant_id = 1) const bool kPcf = false;
// PCSS's masking (ShadowMapSettings::masking): taps the depth map's blocks settle are not read.
layout(constant_id = 2) const bool kMasking = false;
// Stats: the resolve counts its facing receivers and those whose PCSS taps ran (SM_COUNTER_*).
layout(constant_id = 3) const bool kCount = false;
// With masking on a CPU device, which runs both sides of an `if` for every lane of a row (so a pixel
// the blocks settle would still pay for its neighbours' taps), the resolve runs in three passes
// (SM_STAGE_*): every pixel but the PCSS taps, listing the pixels the blocks do not settle; the
// list's dispatch; the listed pixels' taps. A GPU resolves each pixel in one pass (SM_STAGE_WHOLE).
layout(constant_id = 4) const uint kStage = SM_STAGE_WHOLE;
// A spot light or one of a point light's faces (a perspective map) rather than the sun: a CPU device
// would run the local light's reach and cone tests for every pixel under the sun too.
layout(constant_id = 5) const bool kLocalLight = false;
// A point light's face (on a CPU device, a spot light too): a workgroup a tile of the face's list
// (shadow_map_tiles.comp), not the whole frame.
layout(constant_id = 6) const bool kTiles = false;
// A CPU device (uniform_branch.glsl).
layout(constant_id = 7) const bool kCpuDevice = false;
// The blocks read through SM_RESOLVE_BINDING_BLOCK_TEXELS: a CPU device, whose driver gathers a
// texel fetch's lanes at once where it loads a storage buffer's lane by lane, where the view reaches
// every block (maxTexelBufferElements).
layout(constant_id = 8) const bool kBlockFetch = false;
#define UNIFORM_BRANCH_CPU kCpuDevice
#include "shadows/uniform_branch.glsl"

layout(set = 0, binding = SM_RESOLVE_BINDING_PARAMS) uniform Params { ShadowMapResolveParams params; };
layout(set = 0, binding = SM_RESOLVE_BINDING_WORLD_POSITION, rgba32f) readonly uniform image2D world_position;
layout(set = 0, binding = SM_RESOLVE_BINDING_GEOMETRIC_NORMAL, rgba16f) readonly uniform image2D geometric_normal;
layout(set = 0, binding = SM_RESOLVE_BINDING_SHADOW_MAP) uniform sampler2D shadow_map;
layout(set = 0, binding = SM_RESOLVE_BINDING_SHADOW_TERM, r32f) writeonly uniform image2D shadow_term;
layout(set = 0, binding = SM_RESOLVE_BINDING_RECEIVERS, rgba8) readonly uniform image2D receivers;
layout(set = 0, binding = SM_RESOLVE_BINDING_BLOCKS, std430) readonly buffer Blocks { vec4 blocks[]; };
layout(set = 0, binding = SM_RESOLVE_BINDING_BLOCK_TEXELS) uniform samplerBuffer block_texels;
layout(set = 0, binding = SM_RESOLVE_BINDING_COUNTERS, std430) buffer Counters { uint counters[]; };
// SM_STAGE_*: its count, the listed pass's dispatch (x, y, z), then a pixel an entry (x | y << 16).
layout(set = 0, binding = SM_RESOLVE_BINDING_LIST, std430) buffer TapList { uint tap_list[]; };
layout(set = 0, binding = SM_RESOLVE_BINDING_TILES, std430) readonly buffer TileLists { uint tile_lists[]; };
#define LIGHT_TILES_LIST tile_lists
#include "shadows/light_tiles.glsl"

float pcss_map_depth(int layer, ivec2 texel) { return texelFetch(shadow_map, texel, 0).r; }
#include "pcss.glsl"

int map_blocks_x;  // the depth blocks a row, read from the parameters once a pixel (soft_visibility)
vec4 depth_block(int layer, ivec2 block) {
  int index = block.y * map_blocks_x + block.x;
  return kBlockFetch ? texelFetch(block_texels, index) : blocks[index];
}
#define DEPTH_BLOCKS_SETTLE
#include "depth_blocks.glsl"

// Whether the depth map's blocks (shadow_map_blocks.comp) settle every tap PCSS could make for `r`
// (those within `search` map units, which hold the blocker search's and the filter's: neither
// radius exceeds it): 1 every tap lit, 0 every tap shadowed, -1 not settled.
int pcss_settled(PcssMap m, PcssReceiver r, float search) {
  return depth_blocks_settled(0, r.t, r.z, r.gradient, r.bias, search / m.texel, m.size);
}

bool sized = false, taps_ran = false;  // for the counts

// Where the light has a size: the PCSS term from the shading point p (normal n) at map position uv,
// or `hard` (the one tap, or the fixed filter) where no tap blocks or the penumbra is narrower than
// half a texel (or than the fixed filter): so a small light leaves the hard result bit for bit.
float soft_visibility(ivec2 pixel, vec3 p, vec3 n, vec2 uv, float z, float hard) {
  PcssMap m;
  m.layer = 0;
  m.size = int(params.extent.z);
  m.texel = params.pcss_texel.xy;
  m.light_size = params.pcss.x;
  m.perspective = kLocalLight;
  m.depth_range = params.pcss.y;
  m.near_far = params.pcss.zw;
  PcssReceiver r;
  r.t = uv * vec2(params.extent.zw);
  r.z = z;
  r.gradient = pcss_plane_gradient(params.light_plane_matrix, m.perspective, p, n, m.size, pcss_max_slope(m, z));
  map_blocks_x = (m.size + int(kSmBlock) - 1) / int(kSmBlock);
  r.bias = params.bias.x;
  // Settled lit, PCSS would find no blocker and leave `hard`; settled shadowed, it would give 0 or
  // leave `hard`, which is then 0 too. (The listed pass takes only pixels the first did not settle.)
  sized = true;
  if (kMasking && kStage != SM_STAGE_LISTED) {
    int settled = pcss_settled(m, r, pcss_search_radius(m, r.z, params.pcss_texel.z));
    if (settled == 1 || (settled == 0 && hard == 0.0)) return hard;
  }
  taps_ran = true;
  if (kStage == SM_STAGE_LIST) return hard;  // its taps are the listed pass's
  float soft = pcss_visibility(m, r, pcss_rotation(pixel), params.pcss_texel.z, max(params.bias.y, 0.5));
  return soft >= 0.0 ? soft : hard;
}

const uint kListGroup = 64u;  // the listed pass's pixels a workgroup
const uint kListHeader = 4u;  // tap_list's words before its entries
const uint kListRow = 65535u;  // workgroups a row: the portable limit of a dispatch's dimension

// SM_STAGE_LIST_DISPATCH: the listed pass's workgroups, in rows of kListRow.
void size_list_dispatch() {
  if (gl_LocalInvocationIndex != 0u) return;
  uint groups = (tap_list[0] + kListGroup - 1u) / kListGroup;
  tap_list[1] = min(groups, kListRow);
  tap_list[2] = (groups + kListRow - 1u) / kListRow;
  tap_list[3] = 1u;
}

// One of a point light's six faces (else a spot light, or the sun); izb_pixel.glsl's function of the
// same name reads the IZB's parameters.
bool point_light_face_pass() { return uniform_branch(params.light_cone.z) > 0.0; }

// This invocation's pixel: its own, its face's tile's (kTiles), or in the listed pass its entry's (false
// past the list's end).
bool stage_pixel(out ivec2 pixel) {
  if (kTiles) return light_tile_pixel(point_light_face_pass() ? uint(params.light_cone.w) : 0u, params.extent.xy, pixel);
  if (kStage != SM_STAGE_LISTED) {
    pixel = ivec2(gl_GlobalInvocationID.xy);
    return true;
  }
  uint entry = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * kListGroup + gl_LocalInvocationIndex;
  if (entry >= tap_list[0]) return false;
  uint packed = tap_list[kListHeader + entry];
  pixel = ivec2(packed & 0xffffu, packed >> 16u);
  return true;
}

// The listing pass: a listed pixel's entry, a slot a subgroup reserved (on a CPU device or without
// subgroup operations, its own: lavapipe runs the subgroup's sums, election and broadcast for every
// lane, and its atomic only for the few listed ones, 1.2 ms less at 1280x720).
void list_pixel(bool listed, ivec2 pixel) {
#ifndef SHADOWS_WITHOUT_SUBGROUP_OPS
  if (!kCpuDevice) {
    uint count = subgroupAdd(listed ? 1u : 0u), base = 0u;
    if (subgroupElect() && count != 0u) base = atomicAdd(tap_list[0], count);
    uint slot = subgroupBroadcastFirst(base) + subgroupExclusiveAdd(listed ? 1u : 0u);
    if (listed) tap_list[kListHeader + slot] = uint(pixel.x) | (uint(pixel.y) << 16u);
    return;
  }
#endif
  if (listed) tap_list[kListHeader + atomicAdd(tap_list[0], 1u)] = uint(pixel.x) | (uint(pixel.y) << 16u);
}

// The statistics (SM_COUNTER_*): the facing receivers and those whose PCSS taps ran, added a subgroup
// at a time (or, without subgroup operations, a pixel at a time).
void count_pixel() {
#ifdef SHADOWS_WITHOUT_SUBGROUP_OPS
  if (sized) atomicAdd(counters[SM_COUNTER_FACING], 1u);
  if (taps_ran) atomicAdd(counters[SM_COUNTER_TAPPED], 1u);
#else
  uint facing_count = subgroupAdd(sized ? 1u : 0u), tapped = subgroupAdd(taps_ran ? 1u : 0u);
  if (subgroupElect() && facing_count != 0u) {
    atomicAdd(counters[SM_COUNTER_FACING], facing_count);
    atomicAdd(counters[SM_COUNTER_TAPPED], tapped);
  }
#endif
}

// One tap, no filtering: the baseline whose aliasing the other techniques remove (a light with a size
// widens it to the PCSS penumbra where that is at least half a texel, soft_visibility). A spot light's map
// is a perspective one from the light (a point light's, one per cube-face cone); points it does not
// reach or that turn away from it are 0; a point that does not receive shadows (its receiver flag) and
// faces the light is 1, as in every technique.
void main() {
  if (kStage == SM_STAGE_LIST_DISPATCH) {
    size_list_dispatch();
    return;
  }
  ivec2 pixel;
  if (!stage_pixel(pixel) || any(greaterThanEqual(uvec2(pixel), params.extent.xy))) return;
  vec4 p = imageLoad(world_position, pixel);
  // An uncovered pixel is lit, stored here so that the sun's map writes every pixel and the term needs
  // no fill before it (ContextImpl::writes_every_pixel; a listed pass reads covered pixels only).
  if (p.w == 0.0) {
    if (kStage != SM_STAGE_LISTED) imageStore(shadow_term, pixel, vec4(1.0));
    return;
  }
  // One of a point light's cube-face cones: the points of another face (point_light_face_of) are its map's.
  precise vec3 from_light = p.xyz - params.light_position.xyz;
  if (kLocalLight && point_light_face_pass() && point_light_face_of(from_light) != uint(params.light_cone.w)) return;
  vec4 normal = imageLoad(geometric_normal, pixel);
  vec3 n = normal.xyz;
  float visibility = 0.0;
  bool facing = kLocalLight ? local_light_reaches(params.light_position.xyz, params.light_position.w, params.light_direction.xyz,
                                           params.light_cone.x, true, p.xyz) &&
                           faces_local_light(n, p.xyz, params.light_position.xyz)
                     : faces_light(normal);
  if (facing && imageLoad(receivers, pixel).a <= 0.5) {
    visibility = 1.0;
  } else if (facing) {
    vec3 origin = shadow_ray_origin(p.xyz, n, shadow_ray_offset(p.xyz, params.camera_position.xyz));
    // The sun's map is orthographic (fit_orthographic times a rigid view): its last row is (0, 0, 0, 1), so w is
    // 1 and only three rows are read (lavapipe loads each uniform value again for every invocation).
    vec4 light = kLocalLight ? params.light_view_projection * vec4(origin, 1.0)
                             : vec4(mat4x3(params.light_view_projection) * vec4(origin, 1.0), 1.0);
    light.xyz /= light.w;
    vec2 uv = light.xy * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) {
      visibility = 1.0;
    } else {
      ivec2 texel = clamp(ivec2(uv * vec2(params.extent.zw)), ivec2(0), ivec2(params.extent.zw) - 1);
      float stored = texelFetch(shadow_map, texel, 0).r;
      visibility = light.z <= stored + params.bias.x ? 1.0 : 0.0;
      if (kPcf) {
        // Percentage-closer filtering: 16 taps on a disk of bias.y texels (a fixed golden-angle spiral).
        float lit = 0.0;
        for (int k = 0; k < 16; ++k) {
          float r = params.bias.y * sqrt((float(k) + 0.5) / 16.0);
          float a = float(k) * 2.39996323;
          ivec2 tap = clamp(ivec2(uv * vec2(params.extent.zw) + r * vec2(cos(a), sin(a))), ivec2(0),
                            ivec2(params.extent.zw) - 1);
          lit += light.z <= texelFetch(shadow_map, tap, 0).r + params.bias.x ? 1.0 : 0.0;
        }
        visibility = lit / 16.0;
      }
      if (kPcss) visibility = soft_visibility(pixel, origin, n, uv, light.z, visibility);
    }
  }
  // A listed pixel's term is the listed pass's to store.
  bool listed = kStage == SM_STAGE_LIST && taps_ran;
  if (!listed) imageStore(shadow_term, pixel, vec4(visibility));
  if (kStage == SM_STAGE_LIST) list_pixel(listed, pixel);
  if (kCount && kStage != SM_STAGE_LISTED) count_pixel();
}
