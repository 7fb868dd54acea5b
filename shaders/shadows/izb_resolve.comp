#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_pixel.glsl"
layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform Push { IzbComputePush push; };
layout(set = 0, binding = IZB_BINDING_OVERLAY, rgba8) uniform image2D overlay;
layout(set = 0, binding = IZB_BINDING_HYBRID_LIST) writeonly buffer HybridList { uvec4 hybrid_list[]; };

const uint kDebugVisibility = 1u;
const uint kDebugListLength = 2u;
const uint kDebugCsm = 4u;

vec3 heat(float t) {
  t = clamp(t, 0.0, 1.0);
  return clamp(vec3(1.5 - abs(4.0 * t - 3.0), 1.5 - abs(4.0 * t - 2.0), 1.5 - abs(4.0 * t - 1.0)), 0.0, 1.0);
}

// A ray (t in [0, t_max] along the unit `dir`) against a world triangle, either face (Moller-Trumbore);
// `uv` the hit's barycentrics of vertices 1 and 2.
bool ray_hits_triangle(vec3 o, vec3 dir, float t_max, vec3 v0, vec3 v1, vec3 v2, out vec2 uv) {
  vec3 e1 = v1 - v0, e2 = v2 - v0;
  vec3 pv = cross(dir, e2);
  float det = dot(e1, pv);
  uv = vec2(0.0);
  if (abs(det) < 1.0e-30) return false;
  float inv = 1.0 / det;
  vec3 tv = o - v0;
  float u = dot(tv, pv) * inv;
  if (u < 0.0 || u > 1.0) return false;
  vec3 qv = cross(tv, e1);
  float v = dot(dir, qv) * inv;
  if (v < 0.0 || u + v > 1.0) return false;
  float t = dot(e2, qv) * inv;
  uv = vec2(u, v);
  return t >= 0.0 && t <= t_max;
}

// A spot light's caster triangles that reach behind its near plane (izb_triangles.comp lists them):
// the samples of candidate `p` they shadow, by rays toward the light in world space, as rt and the
// reference trace them.
uint straddler_samples(ivec2 pixel, PixelPoint p) {
  uint count = counters[IZB_COUNTER_STRADDLERS];
  if (count == 0u) return 0u;
  vec3 c[4];
  if (izb_samples() == 32u) micro_quad_corners(pixel, p, c);
  uint bits = 0u;
  for (uint s = 0u; s < izb_samples(); ++s) {
    vec3 o = izb_samples() == 32u ? micro_quad_blend(c[0], c[1], c[2], c[3], kSamplePattern[s])
                                  : shadow_ray_origin(p.position, p.normal);
    float t_max = local_shadow_ray_length(o, params.light_position.xyz);
    if (t_max <= 0.0) continue;
    vec3 dir = normalize(params.light_position.xyz - o);
    for (uint k = 0u; k < count; ++k) {
      uint t = floatBitsToUint(grid_triangles[3u * push.triangle_count + k].x);
      vec2 uv;
      if (!ray_hits_triangle(o, dir, t_max, casters[t].p0.xyz, casters[t].p1.xyz, casters[t].p2.xyz, uv)) continue;
      CasterAlpha ca = load_caster_alpha(t);
      if (izb_flag(IZB_FLAG_ALPHA) && ca.threshold != 0u &&
          !material_alpha_kept(ca.texture, ca.threshold, (1.0 - uv.x - uv.y) * ca.uv0 + uv.x * ca.uv1 + uv.y * ca.uv2))
        continue;
      bits |= 1u << s;
      break;
    }
  }
  return bits;
}

// Specialized per debug view and hybrid (a CPU driver would otherwise run every branch).
layout(constant_id = 12) const uint kDebug = 0u;
layout(constant_id = 13) const uint kHybrid = 0u;

// Visibility mask -> shadow term. kHybrid: the term blends toward the cascades' by occluder distance
// and over the last tenth of the IZB's range, and beyond it is the cascades' alone. The resolve runs
// before the cascades then: it writes the hard term and lists the pixels that take any of the
// cascades' term, with their two weights, so that the cascades filter only those (a CPU device pays
// every pixel of a full-screen pass) and izb_hybrid_blend.comp mixes them.
void main() {
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  bool inside = all(lessThan(uvec2(pixel), params.extent.xy));
  uint index = uint(pixel.y) * params.extent.x + uint(pixel.x);
  // The build classified every pixel (IZB_PIXEL_*). The surface itself is read only where the blend's
  // distance or a local light's rays need it.
  uint state = inside ? pixel_state[index] : 0u;
  bool covered = (state & IZB_PIXEL_COVERED) != 0u;
  bool surface = covered && (kHybrid != 0u || spot_light());
  PixelPoint p = surface ? load_surface(pixel) : PixelPoint(false, false, vec3(0.0), vec3(0.0), false);
  uint mask = (state & IZB_PIXEL_CANDIDATE) != 0u ? visibility_mask[index] : 0u;
  float visibility = 1.0;
  bool facing = (state & IZB_PIXEL_FACING) != 0u;
  float reach = izb_reach();
  bool beyond = false;  // past the IZB's range: the cascades' term alone
  if ((state & IZB_PIXEL_CANDIDATE) != 0u) {
    if (spot_light() && mask != full_mask()) mask |= straddler_samples(pixel, p);
    visibility = 1.0 - float(bitCount(mask)) / float(izb_samples());
  } else if (!facing) {
    visibility = 0.0;
  } else if ((state & IZB_PIXEL_BEYOND) != 0u) {
    beyond = true;
    visibility = 0.0;
  } else {
    visibility = 1.0;  // does not receive shadows
  }
  if (kHybrid != 0u) {
    // The farther the nearest occluder sits above the point (in world units along the light), the
    // more the cascades' filtered term takes over; near the IZB's range limit they take over fully.
    // Surfaces facing away are 0 in both terms, so they need no blend.
    // IZB_FLAG_GAPS is set only with a positive soft distance.
    float gap_world = izb_flag(IZB_FLAG_GAPS) ? uintBitsToFloat(occluder_distance[index]) * (params.depth_range.y - params.depth_range.x)
                                              : 1.0e30;
    bool occluded = (state & IZB_PIXEL_CANDIDATE) != 0u && mask != 0u && gap_world < 1.0e20;
    float gap_weight = occluded ? clamp(gap_world / push.soft_distance, 0.0, 1.0) : 0.0;
    // (Unlimited range: reach is huge and the fade 0.)
    float dist = distance(p.position, params.camera_position.xyz);
    float fade = beyond ? 1.0 : clamp((dist - 0.9 * reach) / (0.1 * reach), 0.0, 1.0);
    bool listed = covered && facing && (gap_weight > 0.0 || fade > 0.0);
    // One atomic per subgroup; the dispatch over the list grows with it.
    uint total = subgroupAdd(listed ? 1u : 0u);
    uint slot = subgroupExclusiveAdd(listed ? 1u : 0u);
    uint base = 0u;
    if (subgroupElect() && total != 0u) {
      base = atomicAdd(counters[IZB_COUNTER_HYBRID], total);
      atomicMax(counters[IZB_COUNTER_HYBRID + 1u], (base + total + kIzbHybridEntriesPerGroup - 1u) / kIzbHybridEntriesPerGroup);
    }
    base = subgroupBroadcastFirst(base);
    if (listed)
      hybrid_list[base + slot] = uvec4(uint(pixel.x) | (uint(pixel.y) << 16u), floatBitsToUint(gap_weight),
                                       floatBitsToUint(fade), 0u);
  }
  if (!covered) return;
  if (beyond && kHybrid == 0u) return;  // beyond the IZB: the term already there stays
  // One face of a point light (six overlapping cones that cover every direction): only the points in
  // its cone are this pass's; the others keep what the other faces write.
  if (params.light_cone.z > 0.0 && dot(p.position - params.light_position.xyz, params.light_direction.xyz) <
                                       params.light_cone.x * length(p.position - params.light_position.xyz))
    return;
  imageStore(shadow_term, pixel, vec4(visibility));

  if (kDebug == kDebugVisibility && (state & IZB_PIXEL_CANDIDATE) != 0u) {
    imageStore(overlay, pixel, vec4(mix(vec3(1.0, 0.2, 0.1), vec3(0.1, 1.0, 0.2), visibility), 0.6));
  } else if (kDebug == kDebugListLength && (state & IZB_PIXEL_CANDIDATE) != 0u) {
    // A pixel culled whole (by the CSM or the lit map) has no node nor stored points: no list.
    bool has_nodes = (state & (IZB_PIXEL_CSM_CULLED | IZB_PIXEL_LIT_CULLED)) == 0u;
    uint length = has_nodes ? list_length(texel_index(grid_texel(quad_point(index, 0u))), 64u) : 0u;
    imageStore(overlay, pixel, vec4(heat(log2(float(length) + 1.0) / 6.0), 0.7));
  } else if (kDebug == kDebugCsm && (state & IZB_PIXEL_CSM_CULLED) != 0u) {
    imageStore(overlay, pixel, vec4(0.1, 0.4, 1.0, 0.6));
  }
}
