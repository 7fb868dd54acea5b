#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows.h"
#include "shadow_common.h"
#include "local_light.h"
layout(local_size_x = 8, local_size_y = 8) in;

// A light with a size (ShadowMapResolveParams::pcss): the PCSS pipeline. A specialization constant
// rather than a branch, since llvmpipe pays for both sides of one.
layout(constant_id = 0) const bool kPcss = false;
// A fixed filter (ShadowMapResolveParams::bias.y > 0: the cascades' spot-light maps), likewise: a CPU
// device would run its 16 taps for every pixel, filter or not.
layout(constant_id = 1) const bool kPcf = false;

layout(set = 0, binding = SM_RESOLVE_BINDING_PARAMS) uniform Params { ShadowMapResolveParams params; };
layout(set = 0, binding = SM_RESOLVE_BINDING_WORLD_POSITION, rgba32f) readonly uniform image2D world_position;
layout(set = 0, binding = SM_RESOLVE_BINDING_GEOMETRIC_NORMAL, rgba16f) readonly uniform image2D geometric_normal;
layout(set = 0, binding = SM_RESOLVE_BINDING_SHADOW_MAP) uniform sampler2D shadow_map;
layout(set = 0, binding = SM_RESOLVE_BINDING_SHADOW_TERM, r32f) writeonly uniform image2D shadow_term;
layout(set = 0, binding = SM_RESOLVE_BINDING_RECEIVERS, rgba8) readonly uniform image2D receivers;

float pcss_map_depth(int layer, ivec2 texel) { return texelFetch(shadow_map, texel, 0).r; }
#include "pcss.glsl"

// Where the light has a size: the PCSS term from the shading point p (normal n) at map position uv,
// or `hard` (the one tap, or the fixed filter) where no tap blocks or the penumbra is narrower than
// half a texel (or than the fixed filter): so a small light leaves the hard result bit for bit.
float soft_visibility(ivec2 pixel, vec3 p, vec3 n, vec2 uv, float z, float hard) {
  PcssMap m;
  m.layer = 0;
  m.size = int(params.extent.z);
  m.texel = params.pcss_texel.xy;
  m.light_size = params.pcss.x;
  m.perspective = params.pcss_texel.w > 0.0;
  m.depth_range = params.pcss.y;
  m.near_far = params.pcss.zw;
  PcssReceiver r;
  r.t = uv * vec2(params.extent.zw);
  r.z = z;
  r.gradient = pcss_plane_gradient(params.light_plane_matrix, p, n, m.size, pcss_max_slope(m, z));
  r.bias = params.bias.x;
  float soft = pcss_visibility(m, r, pcss_rotation(pixel), params.pcss_texel.z, max(params.bias.y, 0.5));
  return soft >= 0.0 ? soft : hard;
}

// One tap, no filtering: the baseline whose aliasing the other techniques remove (a light with a size
// widens it to the PCSS penumbra where that is at least half a texel, soft_visibility). A spot light's map
// is a perspective one from the light (a point light's, one per cube-face cone); points it does not
// reach or that turn away from it are 0; a point that does not receive shadows (its receiver flag) and
// faces the light is 1, as in every technique.
void main() {
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(uvec2(pixel), params.extent.xy))) return;
  vec4 p = imageLoad(world_position, pixel);
  if (p.w == 0.0) return;
  // One of a point light's cube-face cones: the points outside it belong to another face's map.
  if (params.light_cone.z > 0.0 && dot(p.xyz - params.light_position.xyz, params.light_direction.xyz) <
                                       params.light_cone.x * length(p.xyz - params.light_position.xyz))
    return;
  vec4 normal = imageLoad(geometric_normal, pixel);
  vec3 n = normal.xyz;
  float visibility = 0.0;
  bool spot = params.light_position.w > 0.0;
  bool facing = spot ? local_light_reaches(params.light_position.xyz, params.light_position.w, params.light_direction.xyz,
                                           params.light_cone.x, true, p.xyz) &&
                           faces_local_light(n, p.xyz, params.light_position.xyz)
                     : faces_light(normal);
  if (facing && imageLoad(receivers, pixel).a <= 0.5) {
    visibility = 1.0;
  } else if (facing) {
    vec3 origin = shadow_ray_origin(p.xyz, n, shadow_ray_offset(p.xyz, params.camera_position.xyz));
    vec4 light = params.light_view_projection * vec4(origin, 1.0);
    light.xyz /= light.w;  // 1 for the sun's orthographic map
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
  imageStore(shadow_term, pixel, vec4(visibility));
}
