#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "cascades.h"
#include "shadow_common.h"
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = CASCADE_FILTER_BINDING_PARAMS) uniform Params { CascadeParams params; };
layout(set = 0, binding = CASCADE_FILTER_BINDING_WORLD_POSITION, rgba32f) readonly uniform image2D world_position;
layout(set = 0, binding = CASCADE_FILTER_BINDING_GEOMETRIC_NORMAL, rgba16f) readonly uniform image2D geometric_normal;
layout(set = 0, binding = CASCADE_FILTER_BINDING_DEPTH) uniform sampler2DArray depth_map;
layout(set = 0, binding = CASCADE_FILTER_BINDING_EDGE) uniform usampler2DArray edge_mask;
layout(set = 0, binding = CASCADE_FILTER_BINDING_EXTENT) uniform usampler2DArray depth_extent;
layout(set = 0, binding = CASCADE_FILTER_BINDING_ROTATION) uniform sampler2D rotation;
layout(set = 0, binding = CASCADE_FILTER_BINDING_SHADOW_TERM, r32f) writeonly uniform image2D shadow_term;
layout(set = 0, binding = CASCADE_FILTER_BINDING_UNBLURRED, r32f) writeonly uniform image2D unblurred;
layout(set = 0, binding = CASCADE_FILTER_BINDING_OVERLAY, rgba8) writeonly uniform image2D overlay;
layout(set = 0, binding = CASCADE_FILTER_BINDING_COUNTERS) buffer Counters { uint counters[]; };
layout(set = 0, binding = CASCADE_FILTER_BINDING_BLUR_LIST) writeonly buffer BlurList { uint blur_list[]; };

struct Result {
  float visibility;
  bool expensive;
  bool mixed;  // some taps lit, some shadowed
};

// Whether the kernel footprint [t - r, t + r] could see a depth step (edge mask) and, with the depth
// extent, whether the receiver's depth over the kernel could fall inside the footprint's map depths.
// Every texel of `level` that any tap's texel lies in is visited, so a skipped pixel provably has no
// edge texel under any of its taps.
bool needs_kernel(int c, vec2 t, float r, float z_lo, float z_hi) {
  uint masking = params.mode.x;
  if (masking == CASCADE_MASKING_OFF) return true;
  int level = params.mask_level[c];
  int size = int(params.extent.z);
  int level_size = max(size >> level, 1);
  ivec2 lo = clamp(ivec2(floor(t - r)), ivec2(0), ivec2(size - 1)) >> level;
  ivec2 hi = clamp(ivec2(floor(t + r)), ivec2(0), ivec2(size - 1)) >> level;
  lo = min(lo, ivec2(level_size - 1));
  hi = min(hi, ivec2(level_size - 1));
  // Masks exist only inside this frame's rectangle: elsewhere nothing is known, so take the kernel.
  ivec4 rect = params.mask_rect[c];
  if (any(lessThan(lo, rect.xy)) || any(greaterThan(hi, rect.zw))) return true;
  bool edge = false;
  uint d_lo = 0xffffu, d_hi = 0u;
  for (int y = lo.y; y <= hi.y; ++y) {
    for (int x = lo.x; x <= hi.x; ++x) {
      edge = edge || texelFetch(edge_mask, ivec3(x, y, c), level).r != 0u;
      if (masking == CASCADE_MASKING_DEPTH_EXTENT) {
        uint v = texelFetch(depth_extent, ivec3(x, y, c), level).r;
        d_lo = min(d_lo, v >> 16u);
        d_hi = max(d_hi, v & 0xffffu);
      }
    }
  }
  if (!edge || masking == CASCADE_MASKING_EDGE) return edge;
  // Every tap compares a receiver depth in [z_lo, z_hi] with a map depth in [d_lo, d_hi]: entirely
  // in front (all lit) or entirely behind (all shadowed) means one tap gives the same answer.
  float bias = params.depth_bias[c];
  bool all_lit = z_hi <= float(d_lo) / 65535.0 + bias;
  bool all_shadowed = z_lo > float(d_hi) / 65535.0 + bias;
  return !(all_lit || all_shadowed);
}

Result evaluate(int c, vec3 p, vec3 n, ivec2 pixel) {
  Result result = Result(1.0, false, false);
  vec3 q = shadow_ray_origin(p, n) + n * params.normal_offset[c];
  vec4 light = params.light_view_projection[c] * vec4(q, 1.0);
  float size = float(params.extent.z);
  vec2 t = (light.xy * 0.5 + 0.5) * size;  // map texel coordinates
  float z = light.z;
  // The receiver's tangent plane in map space: each tap compares the plane's depth at its texel's
  // centre, so a planar receiver agrees with its own stored depth at every tap.
  vec3 nc = mat3(params.light_normal_matrix[c]) * n;
  float max_slope = 8.0 * params.edge_threshold[c];
  vec2 slope = abs(nc.z) > 1.0e-8 ? -nc.xy / nc.z * (2.0 / size) : vec2(1.0e8);
  vec2 gradient = clamp(slope, vec2(-max_slope), vec2(max_slope));
  // Near-grazing receivers get a clamped plane that no longer tracks the map, so their taps can
  // disagree on a smooth map: they always take the kernel, which keeps masking exact.
  bool grazing = any(greaterThan(abs(slope), vec2(max_slope)));
  float r = params.kernel_texels[c];
  float bias = params.depth_bias[c];
  float spread = (abs(gradient.x) + abs(gradient.y)) * (r + 1.0);
  result.expensive = grazing || needs_kernel(c, t, r, z - spread, z + spread);
  int last = int(size) - 1;
  if (!result.expensive) {
    ivec2 texel = ivec2(floor(t));
    float zt = z + dot(gradient, vec2(texel) + 0.5 - t);
    float d = texelFetch(depth_map, ivec3(clamp(texel, ivec2(0), ivec2(last)), c), 0).r;
    result.visibility = zt <= d + bias ? 1.0 : 0.0;
    return result;
  }
  // Only the kernel needs the pixel's rotation.
  vec2 rot = texelFetch(rotation, pixel % int(kRotationTileSize), 0).xy;
  uint lit = 0u;
  for (uint i = 0u; i < kPoissonTaps; ++i) {
    vec2 o = kPoissonDisk[i];
    o = vec2(o.x * rot.x - o.y * rot.y, o.x * rot.y + o.y * rot.x) * r;
    ivec2 texel = ivec2(floor(t + o));
    float zt = z + dot(gradient, vec2(texel) + 0.5 - t);
    float d = texelFetch(depth_map, ivec3(clamp(texel, ivec2(0), ivec2(last)), c), 0).r;
    lit += zt <= d + bias ? 1u : 0u;
  }
  result.visibility = float(lit) / float(kPoissonTaps);
  result.mixed = lit != 0u && lit != kPoissonTaps;
  return result;
}

// Counters and the blur list are updated once per subgroup, not per pixel, and without shared
// memory, so the workgroup needs no barrier (which costs a lot on CPU implementations).
void main() {
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  bool inside = all(lessThan(uvec2(pixel), params.extent.xy));
  vec4 p = inside ? imageLoad(world_position, pixel) : vec4(0.0);
  bool facing = false, expensive = false, mixed = false;
  if (inside && p.w == 0.0) imageStore(unblurred, pixel, vec4(-1.0));
  if (inside && p.w != 0.0) {
    vec3 n = imageLoad(geometric_normal, pixel).xyz;
    float visibility = 0.0;
    int cascade = -1;
    // Surfaces facing away from the light are shadowed by themselves: no lookups.
    facing = dot(n, -params.light_direction.xyz) > 0.0;
    if (facing) {
      float depth = dot(p.xyz - params.camera_position.xyz, params.camera_forward.xyz);
      uint count = params.extent.w;
      visibility = 1.0;
      if (depth < params.split_far[count - 1u]) {
        cascade = 0;
        while (cascade < int(count) - 1 && depth >= params.split_far[cascade]) ++cascade;
        float start = params.blend_start[cascade];
        bool band = depth > start;
        // Inside the band the next cascade takes over gradually; the last one fades to lit. One loop
        // over one or two cascades keeps a single copy of the kernel in the shader.
        int last = band && cascade + 1 < int(count) ? cascade + 1 : cascade;
        float first = 1.0, next = 1.0;
        for (int c = cascade; c <= last; ++c) {
          Result r = evaluate(c, p.xyz, n, pixel);
          if (c == cascade) first = r.visibility;
          else next = r.visibility;
          expensive = expensive || r.expensive;
          mixed = mixed || r.mixed;
        }
        visibility = first;
        if (band) {
          float w = (depth - start) / max(params.split_far[cascade] - start, 1.0e-6);
          visibility = mix(first, next, clamp(w, 0.0, 1.0));
        }
      }
    }
    imageStore(shadow_term, pixel, vec4(visibility));
    imageStore(unblurred, pixel, vec4(visibility));
    if (params.mode.z == CASCADE_DEBUG_CASCADES && cascade >= 0) {
      const vec3 tint[4] = vec3[4](vec3(1.0, 0.2, 0.2), vec3(0.2, 1.0, 0.2), vec3(0.25, 0.45, 1.0), vec3(1.0, 0.9, 0.2));
      imageStore(overlay, pixel, vec4(tint[cascade], 0.35));
    } else if (params.mode.z == CASCADE_DEBUG_EXPENSIVE && expensive) {
      imageStore(overlay, pixel, vec4(1.0, 0.0, 1.0, 0.6));
    }
  }
  bool blur = mixed && params.mode.y != 0u;
  uint n_expensive = subgroupAdd(expensive ? 1u : 0u);
  uint n_facing = subgroupAdd(facing ? 1u : 0u);
  uint n_blur = subgroupAdd(blur ? 1u : 0u);
  uint slot = subgroupExclusiveAdd(blur ? 1u : 0u);
  uint base = 0u;
  if (subgroupElect()) {
    if (n_expensive != 0u) atomicAdd(counters[CASCADE_COUNTER_EXPENSIVE], n_expensive);
    if (n_facing != 0u) atomicAdd(counters[CASCADE_COUNTER_FACING], n_facing);
    if (n_blur != 0u) base = atomicAdd(counters[CASCADE_COUNTER_BLUR], n_blur);
  }
  base = subgroupBroadcastFirst(base);
  if (blur) blur_list[base + slot] = uint(pixel.x) | (uint(pixel.y) << 16u);
}
