#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#define IZB_RAY_BLOCK 16u  // the workgroup's pixels at each k of fit_pixel
#include "shadows/izb_pixel.glsl"
// 256 invocations over a block of kIzbFitBlockWidth x kIzbFitBlockHeight pixels: 16x16 (make_block_rays'
// IZB_RAY_BLOCK), or 32x8 on a CPU device where no block rays are made (IzbPipelineCache::fit_group).
layout(local_size_x = 16, local_size_y = 16, local_size_x_id = 20, local_size_y_id = 21) in;

layout(push_constant) uniform Push { IzbComputePush push; };
// Coherent: the last workgroup reads every other workgroup's.
layout(set = 0, binding = IZB_BINDING_BOUNDS_PARTIALS, std430) coherent buffer BoundsPartials { vec4 bounds_partials[]; };
#include "shadows/izb_setup.glsl"

shared bool last_workgroup;

// The invocation's k-th pixel: neighbouring invocations read neighbouring pixels at each k.
const uint kFitPixels = kIzbFitBlockWidth * kIzbFitBlockHeight / 256u;
const uint kBoundedFitBatch = 2u;
ivec2 fit_pixel(uint k) {
  uvec2 block = gl_WorkGroupID.xy * uvec2(kIzbFitBlockWidth, kIzbFitBlockHeight);
  uint columns = kIzbFitBlockWidth / gl_WorkGroupSize.x;
  return ivec2(block + gl_LocalInvocationID.xy + gl_WorkGroupSize.xy * uvec2(k % columns, k / columns));
}

// IZB_FLAG_FIT_CLEARS_GRID: this workgroup's slice of the grid emptied (every list's head, or its
// count with sorted lists, and every texel's and tile's farthest depth), neighbouring invocations on
// neighbouring words. Nothing reads the grid before the build, after the light frustum's barrier.
void clear_grid_slice() {
  uint groups = gl_NumWorkGroups.x * gl_NumWorkGroups.y;
  uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
  uint texels = izb_resolution() * izb_resolution();
  uint words = texels + tiles_per_side() * tiles_per_side();  // farthest's (tile_farthest_index)
  uint per_group = (words + groups - 1u) / groups;
  uint last = min((group + 1u) * per_group, words);
  for (uint i = group * per_group + gl_LocalInvocationIndex; i < last; i += gl_WorkGroupSize.x * gl_WorkGroupSize.y) {
    farthest[i] = 0u;
    if (i >= texels) continue;
    if (sorted_lists()) list_counts[i] = 0u;
    else heads[i] = kIzbEndOfList;
  }
}

// Light frustum fit, step 1: light-view x/y bounds of every lit candidate's ray origin (and, at 32
// spp, its μQuad corners), reduced over the workgroup's block of pixels and written once per
// workgroup, not by atomics on the bounds' four addresses. One count per workgroup finds the last to
// finish, which reduces the partials, fits the grid and culls the casters (izb_setup.glsl).
void main() {
  if (izb_flag(IZB_FLAG_FIT_CLEARS_GRID)) clear_grid_slice();
  vec2 lo = vec2(1.0e30), hi = vec2(-1.0e30);
  float reach = izb_reach();
  if (spot_light()) {
    // A spot light's grid is its cone's (izb_setup.glsl): no bounds, one workgroup.
  } else if (izb_samples() == 1u) {
    // Every covered point in range bounds the candidates among them (a superset: the window only
    // needs to hold every node), and a ray origin lies within the normal offset of its point. So
    // one image load instead of the candidate test's three; all issued before any is used.
    vec4 position[kFitPixels];
    for (uint k = 0u; k < kFitPixels; ++k) {
      ivec2 pixel = fit_pixel(k);
      position[k] = all(lessThan(uvec2(pixel), params.extent.xy)) ? imageLoad(world_position_image, pixel) : vec4(0.0);
    }
    for (uint k = 0u; k < kFitPixels; ++k) {
      if (position[k].w <= 0.5 || distance(position[k].xyz, params.camera_position.xyz) > reach) continue;
      vec2 v = (params.light_view * vec4(position[k].xyz, 1.0)).xy;
      float offset = izb_ray_offset(position[k].xyz);
      lo = min(lo, v - offset);
      hi = max(hi, v + offset);
    }
  } else if (izb_flag(IZB_FLAG_BOUNDED_FIT)) {
    // 32 spp: every covered point in range that faces the light bounds its μQuad (bound_micro_quad; as
    // at 1 spp, a superset of the candidates: the receiver test is left out). No workgroup barrier; each
    // batch's loads are issued before any is used, two pixels at a time (on an H200 the fit took
    // 0.101 ms at 4K so, 0.124 four at a time and 0.146 all eight: the registers they hold).
    for (uint first = 0u; first < kFitPixels; first += kBoundedFitBatch) {
      vec4 position[kBoundedFitBatch];
      vec4 normal[kBoundedFitBatch];
      for (uint k = 0u; k < kBoundedFitBatch; ++k) {
        ivec2 pixel = fit_pixel(first + k);
        bool inside = all(lessThan(uvec2(pixel), params.extent.xy));
        position[k] = inside ? imageLoad(world_position_image, pixel) : vec4(0.0);
        normal[k] = inside ? imageLoad(geometric_normal_image, pixel) : vec4(0.0);
      }
      for (uint k = 0u; k < kBoundedFitBatch; ++k) {
        if (position[k].w <= 0.5 || !faces_light(normal[k]) || distance(position[k].xyz, params.camera_position.xyz) > reach)
          continue;
        bound_micro_quad(fit_pixel(first + k), position[k].xyz, normal[k].xyz, params.light_view, lo, hi);
      }
    }
  } else {
    // Every candidate's μQuad corners (32 spp) or ray origin.
    for (uint k = 0u; k < kFitPixels; ++k) {
      ivec2 pixel = fit_pixel(k);
      ivec2 block = pixel - ivec2(gl_LocalInvocationID.xy);
      if (izb_samples() == 32u) make_block_rays(block);  // (uniform: every invocation, every k)
      if (any(greaterThanEqual(uvec2(pixel), params.extent.xy))) continue;
      PixelPoint p = load_pixel(pixel);
      if (!p.candidate) continue;
      if (izb_samples() == 32u) {
        vec3 c[4];
        block_micro_quad_corners(pixel, block, p, c);
        for (int i = 0; i < 4; ++i) {
          vec2 v = (params.light_view * vec4(c[i], 1.0)).xy;
          lo = min(lo, v);
          hi = max(hi, v);
        }
      } else {
        vec2 v = (params.light_view * vec4(shadow_ray_origin(p.position, p.normal, izb_ray_offset(p.position)), 1.0)).xy;
        lo = min(lo, v);
        hi = max(hi, v);
      }
    }
  }
  lo = subgroupMin(lo);
  hi = subgroupMax(hi);
  if (subgroupElect()) subgroup_bounds[gl_SubgroupID] = vec4(lo, hi);
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    vec4 b = subgroup_bounds[0];
    for (uint i = 1u; i < gl_NumSubgroups; ++i) b = vec4(min(b.xy, subgroup_bounds[i].xy), max(b.zw, subgroup_bounds[i].zw));
    bounds_partials[kIzbPartialsAt + gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x] = b;
    if (!izb_flag(IZB_FLAG_CPU_DEVICE)) {
      memoryBarrierBuffer();  // the partial is visible before the count says so
      uint done = atomicAdd(counters[IZB_COUNTER_FIT_GROUPS_DONE], 1u);
      last_workgroup = done + 1u == gl_NumWorkGroups.x * gl_NumWorkGroups.y;
    }
  }
  if (izb_flag(IZB_FLAG_CPU_DEVICE)) return;  // a CPU device: izb_setup.comp runs the second step
  barrier();
  if (!last_workgroup) return;
  memoryBarrierBuffer();  // every partial, counted before this workgroup's, is read after the count
  set_up_frustum();
}
