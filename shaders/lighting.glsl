// The lighting pass (lighting.comp: the sun alone; lighting_local_lights.comp, LOCAL_LIGHTS defined:
// the sun and up to kMaxLocalLights spot and point lights). Two pipelines, because a CPU device runs
// even the untaken local-light code for every pixel.
#include "frame.h"
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = LIGHTING_BINDING_FRAME) uniform Frame { FrameUniforms frame; };
layout(set = 0, binding = LIGHTING_BINDING_ALBEDO, rgba8) readonly uniform image2D albedo_image;
layout(set = 0, binding = LIGHTING_BINDING_NORMAL, rgba16f) readonly uniform image2D normal_image;
layout(set = 0, binding = LIGHTING_BINDING_WORLD_POSITION, rgba32f) readonly uniform image2D world_position_image;
layout(set = 0, binding = LIGHTING_BINDING_SHADOW, r32f) readonly uniform image2D shadow_image;
layout(set = 0, binding = LIGHTING_BINDING_OVERLAY, rgba8) readonly uniform image2D overlay_image;
layout(set = 0, binding = LIGHTING_BINDING_OUTPUT, rgba8) writeonly uniform image2D output_image;
#ifdef LOCAL_LIGHTS
layout(set = 0, binding = LIGHTING_BINDING_LOCAL_SHADOW + 0, r32f) readonly uniform image2D local_shadow0;
layout(set = 0, binding = LIGHTING_BINDING_LOCAL_SHADOW + 1, r32f) readonly uniform image2D local_shadow1;
layout(set = 0, binding = LIGHTING_BINDING_LOCAL_SHADOW + 2, r32f) readonly uniform image2D local_shadow2;

// A spot or point light at a surface point: inverse-square falloff windowed to zero at its range (the
// glTF KHR_lights_punctual recommendation) and, for a spot light, a smooth edge between its cones.
vec3 local_light(LocalLightUniforms light, vec3 p, vec3 n) {
  vec3 to_light = light.position_range.xyz - p;
  float d2 = max(dot(to_light, to_light), 1e-4);
  vec3 l = to_light * inversesqrt(d2);
  float ratio = d2 / (light.position_range.w * light.position_range.w);
  float window = clamp(1.0 - ratio * ratio, 0.0, 1.0);
  float attenuation = window * window / d2;
  if (light.direction_kind.w < 0.5)
    attenuation *= smoothstep(light.cone.x, light.cone.y, dot(-l, light.direction_kind.xyz));
  return light.radiance.rgb * attenuation * max(dot(n, l), 0.0);
}
#endif

vec3 linear_to_srgb(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

// Sky and bounce light, independent of the shadow term: a hemisphere between the sky colour
// (frame.ambient, above) and a ground colour lit by the sun (below), plus a weak bounce from the
// sunlit ground and walls arriving from the side away from the sun. Surfaces in shadow keep their
// shape (up-facing ones read blue-bright, walls facing away from the sun get the warm bounce)
// instead of one flat grey.
vec3 ambient_light(vec3 n, vec3 l) {
  float sun_height = clamp(l.y, 0.0, 1.0);
  vec3 sky = frame.ambient.rgb;
  vec3 ground = frame.ambient.rgb * vec3(0.55, 0.5, 0.42) + frame.light_radiance.rgb * (0.035 * sun_height);
  vec3 hemisphere = mix(ground, sky, 0.5 + 0.5 * n.y);
  vec3 away = vec3(-l.x, 0.0, -l.z);
  float away_len = length(away);
  float bounce = away_len > 1e-4 ? max(dot(n, away / away_len), 0.0) : 0.0;
  return hemisphere + frame.light_radiance.rgb * vec3(1.0, 0.92, 0.8) * (0.045 * bounce * sun_height);
}

void main() {
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(uvec2(pixel), frame.extent.xy))) return;
  vec4 position = imageLoad(world_position_image, pixel);
  vec3 color;
  if (position.w == 0.0) {
    // Sky: a vertical gradient.
    vec2 ndc = (vec2(pixel) + 0.5) / vec2(frame.extent.xy) * 2.0 - 1.0;
    vec4 far_point = frame.inverse_view_projection * vec4(ndc, 0.0001, 1.0);
    vec3 dir = normalize(far_point.xyz / far_point.w - frame.camera_position.xyz);
    color = mix(vec3(0.60, 0.68, 0.78), vec3(0.25, 0.42, 0.70), clamp(dir.y, 0.0, 1.0)) * frame.ambient.w;
  } else {
    vec4 albedo = imageLoad(albedo_image, pixel);
    vec3 n = normalize(imageLoad(normal_image, pixel).xyz);
    vec3 l = -frame.light_direction.xyz;
    float shadow = albedo.a > 0.5 ? imageLoad(shadow_image, pixel).r : 1.0;
    float n_dot_l = max(dot(n, l), 0.0);
    vec3 light = frame.light_radiance.rgb * n_dot_l * shadow + ambient_light(n, l);
#ifdef LOCAL_LIGHTS
    // Each local light with its own shadow term (receivers only; others are lit by it unshadowed).
    uint local_count = frame.local_light_count.x;
    bool receives = albedo.a > 0.5;
    if (local_count > 0u)
      light += local_light(frame.local_lights[0], position.xyz, n) * (receives ? imageLoad(local_shadow0, pixel).r : 1.0);
    if (local_count > 1u)
      light += local_light(frame.local_lights[1], position.xyz, n) * (receives ? imageLoad(local_shadow1, pixel).r : 1.0);
    if (local_count > 2u)
      light += local_light(frame.local_lights[2], position.xyz, n) * (receives ? imageLoad(local_shadow2, pixel).r : 1.0);
#endif
    color = albedo.rgb * light;
    color = color / (1.0 + color);  // Reinhard: bright sunlit surfaces keep their gradation
  }
  vec4 overlay = imageLoad(overlay_image, pixel);
  color = linear_to_srgb(color);
  color = mix(color, overlay.rgb, overlay.a);
  imageStore(output_image, pixel, vec4(color, 1.0));
}
