#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows.h"
#include "shadow_common.h"
#include "local_light.h"
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = SM_RESOLVE_BINDING_PARAMS) uniform Params { ShadowMapResolveParams params; };
layout(set = 0, binding = SM_RESOLVE_BINDING_WORLD_POSITION, rgba32f) readonly uniform image2D world_position;
layout(set = 0, binding = SM_RESOLVE_BINDING_GEOMETRIC_NORMAL, rgba16f) readonly uniform image2D geometric_normal;
layout(set = 0, binding = SM_RESOLVE_BINDING_SHADOW_MAP) uniform sampler2D shadow_map;
layout(set = 0, binding = SM_RESOLVE_BINDING_SHADOW_TERM, r32f) writeonly uniform image2D shadow_term;
layout(set = 0, binding = SM_RESOLVE_BINDING_RECEIVERS, rgba8) readonly uniform image2D receivers;

// One tap, no filtering: the baseline whose aliasing the other techniques remove. A spot light's map
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
    vec4 light = params.light_view_projection * vec4(shadow_ray_origin(p.xyz, n, shadow_ray_offset(p.xyz, params.camera_position.xyz)), 1.0);
    light.xyz /= light.w;  // 1 for the sun's orthographic map
    vec2 uv = light.xy * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) {
      visibility = 1.0;
    } else {
      ivec2 texel = clamp(ivec2(uv * vec2(params.extent.zw)), ivec2(0), ivec2(params.extent.zw) - 1);
      float stored = texelFetch(shadow_map, texel, 0).r;
      visibility = light.z <= stored + params.bias.x ? 1.0 : 0.0;
      if (params.bias.y > 0.0) {
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
    }
  }
  imageStore(shadow_term, pixel, vec4(visibility));
}
