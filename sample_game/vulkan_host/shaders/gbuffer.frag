#version 450
layout(location = 0) in vec3 world_normal;
layout(push_constant) uniform Push {
  mat4 view_projection;
  vec4 world_rows[3];
  vec4 albedo;
};
layout(location = 0) out vec4 out_albedo;
layout(location = 1) out vec2 out_normal;  // R16G16_SNORM: octahedral world normal

vec2 octahedral_encode(vec3 n) {
  n /= abs(n.x) + abs(n.y) + abs(n.z);
  vec2 e = n.xy;
  if (n.z < 0.0) e = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
  return e;
}

void main() {
  out_albedo = albedo;  // alpha 1: covered (the clear leaves 0 for the sky)
  out_normal = octahedral_encode(normalize(world_normal));
}
