#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "cascades.h"
#include "shadows.h"
#include "shadow_common.h"
layout(local_size_x = 8, local_size_y = 8) in;

// One shader, three pipelines (kStage):
// - CASCADE_STAGE_CLASSIFY, over the frame: per pixel the cascade, the mask test and the one-tap
//   result; writes every pixel that needs nothing more, and lists the others.
// - CASCADE_STAGE_KERNEL, over the kernel list: the 12-tap kernel (or PCSS, kPcss) in one cascade.
// - CASCADE_STAGE_BAND, over the band list: pixels in a blend band, two cascades, each with its own
//   mask test, one tap or the kernel.
// Every stage writes exactly what one pass evaluating each pixel in full would. The split is for CPU
// implementations (llvmpipe runs both sides of every branch for all lanes of a SIMD row, so work
// behind an `if` is paid by every pixel); on a GPU the lists are compact and the classify stage is
// cheaper than a full pass with divergent kernels.
layout(constant_id = 0) const uint kStage = CASCADE_STAGE_CLASSIFY;
layout(constant_id = 1) const uint kMasking = CASCADE_MASKING_EDGE;  // CascadeParams::mode.x
layout(constant_id = 2) const uint kDebug = CASCADE_DEBUG_NONE;      // CascadeParams::mode.z
// The sun has a size (CascadeParams::pcss.x > 0): the kernel is PCSS's (pcss.glsl) wherever its
// penumbra is wider than the fixed kernel, which stays the narrowest filter.
layout(constant_id = 3) const bool kPcss = false;

layout(set = 0, binding = CASCADE_FILTER_BINDING_PARAMS) uniform Params { CascadeParams params; };
layout(set = 0, binding = CASCADE_FILTER_BINDING_WORLD_POSITION, rgba32f) readonly uniform image2D world_position;
layout(set = 0, binding = CASCADE_FILTER_BINDING_GEOMETRIC_NORMAL, rgba16f) readonly uniform image2D geometric_normal;
layout(set = 0, binding = CASCADE_FILTER_BINDING_DEPTH) uniform sampler2DArray depth_map;
// Per mask texel, four entries for the texels lo..hi with hi - lo = (k & 1, k >> 1): x whether any
// is an edge, y the union of their packed depth extents (see cascade_edges.comp).
layout(set = 0, binding = CASCADE_FILTER_BINDING_NEIGHBOURHOODS) readonly buffer Neighbourhoods { uvec2 neighbourhoods[]; };
// CASCADE_MASKING_PLANES: the same buffer a kSmBlock² block's plane an entry (cascade_edges.comp), over
// each cascade's mask_rect at the blocks' level, rows of its width from mask_offset.
layout(set = 0, binding = CASCADE_FILTER_BINDING_NEIGHBOURHOODS) readonly buffer Planes { vec4 planes[]; };
layout(set = 0, binding = CASCADE_FILTER_BINDING_ROTATION) uniform sampler2D rotation;
layout(set = 0, binding = CASCADE_FILTER_BINDING_SHADOW_TERM, r32f) writeonly uniform image2D shadow_term;
layout(set = 0, binding = CASCADE_FILTER_BINDING_RECEIVERS, rgba8) readonly uniform image2D receivers;
layout(set = 0, binding = CASCADE_FILTER_BINDING_OVERLAY, rgba8) writeonly uniform image2D overlay;
layout(set = 0, binding = CASCADE_FILTER_BINDING_COUNTERS) buffer Counters { uint counters[]; };
layout(set = 0, binding = CASCADE_FILTER_BINDING_BLUR_LIST) writeonly buffer BlurList { uint blur_list[]; };
// Kernel entries from the front, band entries from the back: a pixel is in at most one.
layout(set = 0, binding = CASCADE_FILTER_BINDING_WORK_LIST) buffer WorkList { uint work_list[]; };
// CASCADE_STAGE_CLASSIFY_LIST: the only pixels to filter (e.g. those the hybrid's IZB leaves to us).
layout(set = 0, binding = CASCADE_FILTER_BINDING_INPUT_LIST) readonly buffer InputList { uvec4 input_list[]; };
layout(set = 0, binding = CASCADE_FILTER_BINDING_INPUT_COUNTERS) readonly buffer InputCounters { uint input_counters[]; };

float pcss_map_depth(int layer, ivec2 texel) { return texelFetch(depth_map, ivec3(texel, layer), 0).r; }
#include "pcss.glsl"

PcssMap pcss_map(int c) {
  PcssMap m;
  m.layer = c;
  m.size = int(params.extent.z);
  m.texel = vec2(params.texel_world[c]);
  m.light_size = params.pcss.x;
  m.perspective = false;
  m.depth_range = params.depth_range[c];
  m.near_far = vec2(0.0);
  return m;
}

// A block outside the cascade's rectangle was not built: an infinite distance settles nothing.
vec4 depth_block(int c, ivec2 block) {
  ivec4 rect = params.mask_rect[c];
  if (any(lessThan(block, rect.xy)) || any(greaterThan(block, rect.zw))) return vec4(0.0, 0.0, 0.0, 3.0e38);
  return planes[cascade_mask_entry(rect, params.mask_offset[c], block)];
}
#define DEPTH_BLOCKS_SETTLE
#include "depth_blocks.glsl"

// A receiver's position in cascade c's map.
struct Probe {
  vec2 t;          // map texel coordinates
  float z;         // light depth
  vec2 gradient;   // the receiver's tangent plane, light depth per texel
  float r;         // kernel radius in texels
  float reach;     // radius in texels that any tap may lie at: r, or with PCSS its search radius if wider
  float bias;
  bool expensive;  // the mask test wants the 12-tap kernel
};

// Whether the kernel footprint [t - r, t + r] could see a depth step (edge mask) and, with the depth
// extent, whether the receiver's depth over the kernel could fall inside the footprint's map depths.
// Every texel of `level` that any tap's texel lies in is visited (the level is chosen so these are at
// most 2x2; a wider footprint, possible only where the level is capped, takes the kernel), so a
// skipped pixel provably has no edge texel under any of its taps.
bool needs_kernel(int c, vec2 t, float r, float z_lo, float z_hi) {
  if (kMasking == CASCADE_MASKING_OFF) return true;
  int level = params.mask_level[c];
  int size = int(params.extent.z);
  int level_size = max(size >> level, 1);
  ivec2 lo = clamp(ivec2(floor(t - r)), ivec2(0), ivec2(size - 1)) >> level;
  ivec2 hi = clamp(ivec2(floor(t + r)), ivec2(0), ivec2(size - 1)) >> level;
  lo = min(lo, ivec2(level_size - 1));
  hi = min(hi, ivec2(level_size - 1));
  // Masks exist only inside this frame's rectangle: elsewhere nothing is known, so take the kernel.
  ivec4 rect = params.mask_rect[c];
  bool unknown = any(lessThan(lo, rect.xy)) || any(greaterThan(hi, rect.zw)) || any(greaterThan(hi - lo, ivec2(1)));
  // The (at most) 2x2 texels lo..hi: one entry of lo's neighbourhood. (Clamped into the rectangle so
  // that the read stays inside the buffer where the result is not used.)
  ivec2 at = max(min(lo, rect.zw), rect.xy);
  uint texel = cascade_mask_entry(rect, params.mask_offset[c], at);
  uint k = uint(hi.x > lo.x) + 2u * uint(hi.y > lo.y);
  uvec2 m = neighbourhoods[texel * 4u + k];
  bool edge = m.x != 0u;
  if (kMasking == CASCADE_MASKING_EDGE) return unknown || edge;
  uint d_lo = m.y >> 16u, d_hi = m.y & 0xffffu;
  // Every tap compares a receiver depth in [z_lo, z_hi] with a map depth in [d_lo, d_hi]: entirely
  // in front (all lit) or entirely behind (all shadowed) means one tap gives the same answer.
  float bias = params.depth_bias[c];
  bool all_lit = z_hi <= float(d_lo) / 65535.0 + bias;
  bool all_shadowed = z_lo > float(d_hi) / 65535.0 + bias;
  return unknown || (edge && !(all_lit || all_shadowed));
}

Probe probe(int c, vec3 p, vec3 n) {
  Probe pr;
  // `precise` from the point to every tap's comparison: a GPU's compiler fuses multiply-adds as the
  // code around them lets it, and the variants of this shader (with and without PCSS, say) must round
  // a tap at a shadow's edge alike (on the H200 it was the band's blend, below, that differed).
  precise vec3 q = shadow_ray_origin(p, n, shadow_ray_offset(p, params.camera_position.xyz)) + n * params.normal_offset[c];
  precise vec4 light = params.light_view_projection[c] * vec4(q, 1.0);
  float size = float(params.extent.z);
  precise vec2 t = (light.xy * 0.5 + 0.5) * size;
  pr.t = t;
  pr.z = light.z;
  // The receiver's tangent plane in map space: each tap compares the plane's depth at its texel's
  // centre, so a planar receiver agrees with its own stored depth at every tap.
  precise vec3 nc = mat3(params.light_normal_matrix[c]) * n;
  float max_slope = 8.0 * params.edge_threshold[c];
  precise vec2 slope = abs(nc.z) > 1.0e-8 ? -nc.xy / nc.z * (2.0 / size) : vec2(1.0e8);
  pr.gradient = clamp(slope, vec2(-max_slope), vec2(max_slope));
  // Near-grazing receivers get a clamped plane that no longer tracks the map, so their taps can
  // disagree on a smooth map: they always take the kernel, which keeps masking exact.
  bool grazing = any(greaterThan(abs(slope), vec2(max_slope)));
  pr.r = params.kernel_texels[c];
  pr.bias = params.depth_bias[c];
  // PCSS's taps lie within its search radius (its filter's radius, the reach of the average blocker,
  // is never wider): the mask test over that footprint keeps skipping exact.
  pr.reach = kPcss ? max(pr.r, pcss_search_radius(pcss_map(c), pr.z, params.pcss.y) / params.texel_world[c]) : pr.r;
  if (kMasking == CASCADE_MASKING_PLANES) {
    // Every tap (the kernel's, or PCSS's searches and filter) within the reach settled alike: the one
    // tap at the receiver's texel, which is among them, is the filtered term, bit for bit.
    pr.expensive = depth_blocks_settled(c, pr.t, pr.z, pr.gradient, pr.bias, vec2(pr.reach), int(size)) < 0 || grazing;
    return pr;
  }
  float spread = (abs(pr.gradient.x) + abs(pr.gradient.y)) * (pr.reach + 1.0);
  pr.expensive = needs_kernel(c, pr.t, pr.reach, pr.z - spread, pr.z + spread) || grazing;
  return pr;
}

// 1 where the tap at map texel coordinates t + o is lit.
uint tap(int c, Probe pr, vec2 o) {
  int last = int(params.extent.z) - 1;
  precise vec2 at = pr.t + o;
  ivec2 texel = ivec2(floor(at));
  precise float zt = pr.z + dot(pr.gradient, vec2(texel) + 0.5 - pr.t);
  float d = texelFetch(depth_map, ivec3(clamp(texel, ivec2(0), ivec2(last)), c), 0).r;
  precise float limit = d + pr.bias;
  return zt <= limit ? 1u : 0u;
}

// Lit taps of the rotated 12-tap Poisson disk.
uint kernel(int c, Probe pr, ivec2 pixel) {
  vec2 rot = texelFetch(rotation, pixel % int(kRotationTileSize), 0).xy;
  uint lit = 0u;
  for (uint i = 0u; i < kPoissonTaps; ++i) {
    vec2 disk = kPoissonDisk[i];
    precise vec2 o = vec2(disk.x * rot.x - disk.y * rot.y, disk.x * rot.y + disk.y * rot.x) * pr.r;
    lit += tap(c, pr, o);
  }
  return lit;
}

// The filtered term in cascade c, and whether its taps disagreed (the blur takes those): PCSS where
// it finds blockers and a penumbra wider than the kernel, else the rotated 12-tap kernel.
float filtered(int c, Probe pr, ivec2 pixel, out bool mixed) {
  if (kPcss) {
    PcssReceiver r;
    r.t = pr.t;
    r.z = pr.z;
    r.gradient = pr.gradient;
    r.bias = pr.bias;
    float soft = pcss_visibility(pcss_map(c), r, pcss_rotation(pixel), params.pcss.y, max(pr.r, 0.5));
    if (soft >= 0.0) {
      mixed = soft > 0.0 && soft < 1.0;
      return soft;
    }
  }
  uint lit = kernel(c, pr, pixel);
  mixed = lit != 0u && lit != kPoissonTaps;
  return float(lit) / float(kPoissonTaps);
}

// The pixel's cascade and blend weight toward the next one (or toward lit after the last).
struct Choice {
  int cascade;
  bool in_range;  // nearer than the last split
  bool band;
  bool two;       // the band blends into another cascade
  float w;
};

// The blend (mix) of a pixel in a band, like its depth and weight, is `precise`: one fused multiply-add
// more or less in one variant of this shader (with PCSS, or reading the host's inputs) moves the blend
// by a rounding step.
float blend(float a, float b, float w) {
  precise float v = a + (b - a) * w;
  return v;
}

// The pixel's view depth, as choose() takes it.
float view_depth(vec3 p) {
  precise float depth = dot(p - params.camera_position.xyz, params.camera_forward.xyz);
  return depth;
}

Choice choose(float depth) {
  Choice ch;
  int count = int(params.extent.w);
  ch.in_range = depth < params.split_far[count - 1];
  // The first cascade whose far split lies beyond the depth (the last one otherwise).
  bvec3 past = greaterThanEqual(vec3(depth), params.split_far.xyz);
  ch.cascade = min(int(past.x) + int(past.x && past.y) + int(past.x && past.y && past.z), count - 1);
  float start = params.blend_start[ch.cascade];
  ch.band = depth > start;
  ch.two = ch.band && ch.cascade + 1 < count;
  precise float w = (depth - start) / max(params.split_far[ch.cascade] - start, 1.0e-6);
  ch.w = clamp(w, 0.0, 1.0);
  return ch;
}

void write_overlay(ivec2 pixel, int cascade, bool expensive) {
  if (kDebug == CASCADE_DEBUG_CASCADES && cascade >= 0) {
    const vec3 tint[4] = vec3[4](vec3(1.0, 0.2, 0.2), vec3(0.2, 1.0, 0.2), vec3(0.25, 0.45, 1.0), vec3(1.0, 0.9, 0.2));
    imageStore(overlay, pixel, vec4(tint[cascade], 0.35));
  } else if (kDebug == CASCADE_DEBUG_EXPENSIVE && expensive) {
    imageStore(overlay, pixel, vec4(1.0, 0.0, 1.0, 0.6));
  }
}

uint pack_pixel(ivec2 pixel) { return uint(pixel.x) | (uint(pixel.y) << 16u); }

// Counters and lists are updated once per subgroup, not per pixel, and without shared memory, so the
// workgroup needs no barrier (which costs a lot on CPU implementations).
uint append(uint counter, bool flag, out uint slot) {
  uint total = subgroupAdd(flag ? 1u : 0u);
  slot = subgroupExclusiveAdd(flag ? 1u : 0u);
  uint base = 0u;
  if (subgroupElect() && total != 0u) base = atomicAdd(counters[counter], total);
  return subgroupBroadcastFirst(base);
}

void count(uint counter, bool flag) {
  uint total = subgroupAdd(flag ? 1u : 0u);
  if (subgroupElect() && total != 0u) atomicAdd(counters[counter], total);
}

// Masking off: every evaluated pixel takes the kernel, so the classify stage filters it in its one
// cascade itself rather than list it for the kernel stage, which would load and probe it again (a CPU
// device pays every stage's loads for every listed pixel). Band pixels still go to the band stage.
const bool kKernelInClassify = kMasking == CASCADE_MASKING_OFF;

// One pixel of the classify stage; returns its counts, packed as in classify(): x the facing count
// (low 16 bits) and the band list's (high), y the kernel list's or, with kKernelInClassify, the blur
// list's (low), and the pixels filtered here with the kernel (high).
uvec2 classify_pixel(ivec2 pixel) {
  bool inside = all(lessThan(uvec2(pixel), params.extent.xy));
  vec4 p = inside ? imageLoad(world_position, pixel) : vec4(0.0);
  vec4 normal = inside ? imageLoad(geometric_normal, pixel) : vec4(0.0);
  vec3 n = normal.xyz;
  bool covered = inside && p.w != 0.0;
  // Surfaces facing away from the light are shadowed by themselves: no lookups.
  bool facing = covered && faces_light(normal);
  Choice ch = choose(view_depth(p.xyz));
  // A point that does not receive shadows (its receiver flag) and faces the light is lit, unfiltered.
  bool receives = covered && imageLoad(receivers, pixel).a > 0.5;
  bool evaluated = facing && receives && ch.in_range;
  Probe pr = probe(ch.cascade, p.xyz, n);
  // (The kernel stage's arithmetic, so the same term.)
  bool mixed = false;
  float visibility = kKernelInClassify ? filtered(ch.cascade, pr, pixel, mixed) : float(tap(ch.cascade, pr, vec2(0.0)));
  // The last cascade fades to lit over its band.
  if (ch.band) visibility = blend(visibility, 1.0, ch.w);
  visibility = evaluated ? visibility : (facing ? 1.0 : 0.0);
  bool band = evaluated && ch.two;
  bool filtered_here = kKernelInClassify && evaluated && !band;
  bool deferred = evaluated && (band || (pr.expensive && !kKernelInClassify));
  // Over the whole frame an uncovered pixel is stored lit too, so that the term needs no fill before
  // (ContextImpl::writes_every_pixel).
  bool stored = (covered || (inside && kStage == CASCADE_STAGE_CLASSIFY)) && !deferred;
  if (stored) imageStore(shadow_term, pixel, vec4(covered ? visibility : 1.0));
  if (kDebug != CASCADE_DEBUG_NONE && covered && !deferred) write_overlay(pixel, evaluated ? ch.cascade : -1, filtered_here);
  bool kernel_only = deferred && !band;
  bool blur = filtered_here && mixed && params.mode.y != 0u;
  return uvec2((facing ? 1u : 0u) | (band ? 1u << 16u : 0u),
               (kernel_only || blur ? 1u : 0u) | (filtered_here ? 1u << 16u : 0u));
}

// Each invocation takes a 2x2 quad (or four consecutive input-list entries), so the subgroup scan and
// the atomics (costly on CPU implementations) are shared by four times as many pixels.
void classify() {
  ivec2 pixels[4];
  for (int k = 0; k < 4; ++k) {
    if (kStage == CASCADE_STAGE_CLASSIFY_LIST) {
      // Consecutive invocations read consecutive entries (coalesced on a GPU, a SIMD row on a CPU).
      uint entry = (gl_WorkGroupID.x * 4u + uint(k)) * CASCADE_LIST_GROUP + gl_LocalInvocationIndex;
      uint packed_pixel = entry < input_counters[params.mode.w] ? input_list[entry].x : 0xffffffffu;  // none: outside
      pixels[k] = ivec2(packed_pixel & 0xffffu, packed_pixel >> 16u);
    } else {
      pixels[k] = ivec2(gl_GlobalInvocationID.xy) * 2 + ivec2(k & 1, k >> 1);
    }
  }
  // Counts in 16-bit fields (classify_pixel): at most 4 x 128 per subgroup.
  uvec2 flags = uvec2(0u);
  uint listed_bits = 0u, band_bits = 0u;
  for (int k = 0; k < 4; ++k) {
    uvec2 f = classify_pixel(pixels[k]);
    flags += f;
    listed_bits |= (f.y & 1u) << k;
    band_bits |= (f.x >> 16u) << k;
  }
  uvec2 total = subgroupAdd(flags);
  uvec2 prefix = subgroupExclusiveAdd(flags);
  // The second list: the kernel stage's, or with kKernelInClassify the blur's.
  uint listed_counter = kKernelInClassify ? CASCADE_COUNTER_BLUR : CASCADE_COUNTER_KERNEL;
  uvec2 base = uvec2(0u);
  if (subgroupElect()) {
    if ((total.x & 0xffffu) != 0u) atomicAdd(counters[CASCADE_COUNTER_FACING], total.x & 0xffffu);
    if ((total.y & 0xffffu) != 0u) base.x = atomicAdd(counters[listed_counter], total.y & 0xffffu);
    if ((total.x >> 16u) != 0u) base.y = atomicAdd(counters[CASCADE_COUNTER_BAND], total.x >> 16u);
    if ((total.y >> 16u) != 0u) atomicAdd(counters[CASCADE_COUNTER_EXPENSIVE], total.y >> 16u);
  }
  base = subgroupBroadcastFirst(base);
  uint listed_slot = base.x + (prefix.y & 0xffffu);
  uint band_slot = params.extent.x * params.extent.y - 1u - (base.y + (prefix.x >> 16u));
  for (int k = 0; k < 4; ++k) {
    uint packed_pixel = pack_pixel(pixels[k]);
    if ((listed_bits & (1u << k)) != 0u) {
      if (kKernelInClassify) blur_list[listed_slot++] = packed_pixel;
      else work_list[listed_slot++] = packed_pixel;
    }
    if ((band_bits & (1u << k)) != 0u) work_list[band_slot--] = packed_pixel;
  }
}

// A listed pixel: the kernel in its cascade, or both cascades of its band.
void finish() {
  uint index = gl_WorkGroupID.x * CASCADE_LIST_GROUP + gl_LocalInvocationIndex;
  bool band_stage = kStage == CASCADE_STAGE_BAND;
  bool valid = index < counters[band_stage ? CASCADE_COUNTER_BAND : CASCADE_COUNTER_KERNEL];
  uint packed_pixel = valid ? work_list[band_stage ? params.extent.x * params.extent.y - 1u - index : index] : 0u;
  ivec2 pixel = ivec2(packed_pixel & 0xffffu, packed_pixel >> 16u);
  vec3 p = imageLoad(world_position, pixel).xyz;
  vec3 n = imageLoad(geometric_normal, pixel).xyz;
  Choice ch = choose(view_depth(p));
  float visibility;
  bool expensive, mixed;
  if (!band_stage) {
    // Listed because the mask test wants the kernel.
    Probe pr = probe(ch.cascade, p, n);
    visibility = filtered(ch.cascade, pr, pixel, mixed);
    if (ch.band) visibility = blend(visibility, 1.0, ch.w);
    expensive = true;
  } else {
    float v[2];
    expensive = false;
    mixed = false;
    for (int k = 0; k < 2; ++k) {
      int c = ch.cascade + k;
      Probe pr = probe(c, p, n);
      bool disagree;
      float soft = filtered(c, pr, pixel, disagree);
      uint one = tap(c, pr, vec2(0.0));
      v[k] = pr.expensive ? soft : float(one);
      expensive = expensive || pr.expensive;
      mixed = mixed || (pr.expensive && disagree);
    }
    visibility = blend(v[0], v[1], ch.w);
    count(CASCADE_COUNTER_EXPENSIVE, valid && expensive);
  }
  if (valid) {
    imageStore(shadow_term, pixel, vec4(visibility));
    if (kDebug != CASCADE_DEBUG_NONE) write_overlay(pixel, ch.cascade, expensive);
  }
  bool blur = valid && mixed && params.mode.y != 0u;
  uint slot;
  uint base = append(CASCADE_COUNTER_BLUR, blur, slot);
  if (blur) blur_list[base + slot] = pack_pixel(pixel);
}

void main() {
  if (kStage == CASCADE_STAGE_CLASSIFY || kStage == CASCADE_STAGE_CLASSIFY_LIST) classify();
  else finish();
}
