#version 450
// albedo * (ambient + sun * max(n.l, 0) * visibility); the sky where nothing was drawn.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0) uniform sampler2D albedo_image;
layout(set = 0, binding = 1) uniform sampler2D normal_image;
layout(set = 0, binding = 2) uniform sampler2D visibility_image;
layout(set = 0, binding = 3, rgba8) writeonly uniform image2D lit_image;
layout(push_constant) uniform Push { vec4 to_light; };

vec3 octahedral_decode(vec2 e) {
  vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
  if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
  return normalize(n);
}

void main() {
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(pixel, imageSize(lit_image)))) return;
  vec4 albedo = texelFetch(albedo_image, pixel, 0);
  vec3 color = vec3(0.55, 0.7, 0.9);
  if (albedo.a > 0.0) {  // alpha: 1 a receiver, 0.25 the tile that is none under a receiver mask, 0 the sky
    vec3 n = octahedral_decode(texelFetch(normal_image, pixel, 0).xy);
    float sun = max(dot(n, to_light.xyz), 0.0) * texelFetch(visibility_image, pixel, 0).r;
    color = albedo.rgb * (0.25 + 0.85 * sun);
  }
  imageStore(lit_image, pixel, vec4(pow(color, vec3(1.0 / 2.2)), 1.0));
}
