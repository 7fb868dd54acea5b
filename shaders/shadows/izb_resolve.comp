#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_pixel.glsl"
layout(local_size_x = 8, local_size_y = 8) in;

layout(push_constant) uniform Push { IzbComputePush push; };
layout(set = 0, binding = IZB_BINDING_SHADOW_TERM, r32f) uniform image2D shadow_term;
layout(set = 0, binding = IZB_BINDING_OVERLAY, rgba8) uniform image2D overlay;

const uint kDebugVisibility = 1u;
const uint kDebugListLength = 2u;
const uint kDebugCsm = 4u;

vec3 heat(float t) {
  t = clamp(t, 0.0, 1.0);
  return clamp(vec3(1.5 - abs(4.0 * t - 3.0), 1.5 - abs(4.0 * t - 2.0), 1.5 - abs(4.0 * t - 1.0)), 0.0, 1.0);
}

// Specialized per debug view and hybrid (a CPU driver would otherwise run every branch).
layout(constant_id = 12) const uint kDebug = 0u;
layout(constant_id = 13) const uint kHybrid = 0u;

// Visibility mask -> shadow term. kHybrid: blends toward the term already there (the
// cascades') by occluder distance, and over the last tenth of the IZB's range.
void main() {
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(uvec2(pixel), params.extent.xy))) return;
  uint index = uint(pixel.y) * params.extent.x + uint(pixel.x);
  PixelPoint p = load_pixel(pixel);
  if (!p.covered) return;
  uint state = pixel_state[index];
  uint mask = (state & IZB_PIXEL_CANDIDATE) != 0u ? visibility_mask[index] : 0u;
  float visibility;
  bool facing = p.facing;
  float max_distance = params.camera_position.w;
  float dist = distance(p.position, params.camera_position.xyz);
  if ((state & IZB_PIXEL_CANDIDATE) != 0u) {
    visibility = 1.0 - float(bitCount(mask)) / float(izb_samples());
  } else if (!facing) {
    visibility = 0.0;
  } else if (max_distance > 0.0 && dist > max_distance) {
    return;  // beyond the IZB: the cascades' term stays
  } else {
    visibility = 1.0;  // does not receive shadows
  }
  if (kHybrid != 0u) {
    // Hybrid: hard at contact, soft away from it. The farther the nearest occluder sits above the
    // point (in world units along the light), the more the cascades' filtered term takes over; and
    // near the IZB's range limit the cascades take over completely.
    float soft = imageLoad(shadow_term, pixel).r;
    float gap_world = uintBitsToFloat(occluder_distance[index]) * (params.depth_range.y - params.depth_range.x);
    if ((state & IZB_PIXEL_CANDIDATE) != 0u && mask != 0u && gap_world < 1.0e20 && push.soft_distance > 0.0)
      visibility = mix(visibility, soft, clamp(gap_world / push.soft_distance, 0.0, 1.0));
    if (max_distance > 0.0) {
      float fade = clamp((dist - 0.9 * max_distance) / (0.1 * max_distance), 0.0, 1.0);
      visibility = mix(visibility, soft, fade);
    }
  }
  imageStore(shadow_term, pixel, vec4(visibility));

  if (kDebug == kDebugVisibility && (state & IZB_PIXEL_CANDIDATE) != 0u) {
    imageStore(overlay, pixel, vec4(mix(vec3(1.0, 0.2, 0.1), vec3(0.1, 1.0, 0.2), visibility), 0.6));
  } else if (kDebug == kDebugListLength && (state & IZB_PIXEL_CANDIDATE) != 0u) {
    ivec2 t = grid_texel(quad_point(index, 0u));
    uint length = list_length(texel_index(t), 64u);
    imageStore(overlay, pixel, vec4(heat(log2(float(length) + 1.0) / 6.0), 0.7));
  } else if (kDebug == kDebugCsm && (state & IZB_PIXEL_CSM_CULLED) != 0u) {
    imageStore(overlay, pixel, vec4(0.1, 0.4, 1.0, 0.6));
  }
}
