#version 450
layout(location = 0) in vec3 world_normal;
layout(push_constant) uniform Push {
  mat4 view_projection;
  vec4 world_rows[3];
  vec4 albedo;
};
layout(set = 0, binding = 0) uniform Frame {
  vec4 view_rows[3];  // world -> view rotation, row by row; [0].w: 1 = the module's normals in view space;
                      // [1].w: the terminator offset along the normal
  vec4 to_sun;        // xyz: toward the sun; w: the module's normal encoding (0 octahedral, 1 xyz * 0.5 + 0.5)
};
layout(location = 0) out vec4 out_albedo;
layout(location = 1) out vec2 out_normal;           // R16G16_SNORM: octahedral world normal (the lighting's)
layout(location = 2) out vec4 out_module_normal;    // the module's normals, in the encoding and space asked for
layout(location = 3) out vec4 out_geometric_normal; // R16G16B16A16_SFLOAT: world face normal; a: faces the sun
layout(location = 4) out vec4 out_terminator;       // R16G16B16A16_SFLOAT: the terminator offset

vec2 octahedral_encode(vec3 n) {
  n /= abs(n.x) + abs(n.y) + abs(n.z);
  vec2 e = n.xy;
  if (n.z < 0.0) e = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
  return e;
}

void main() {
  out_albedo = albedo;  // alpha 1: covered (the clear leaves 0 for the sky)
  vec3 n = normalize(world_normal);
  out_normal = octahedral_encode(n);
  vec3 m = view_rows[0].w > 0.5 ? vec3(dot(view_rows[0].xyz, n), dot(view_rows[1].xyz, n), dot(view_rows[2].xyz, n)) : n;
  out_module_normal = to_sun.w > 0.5 ? vec4(m * 0.5 + 0.5, 0.0) : vec4(octahedral_encode(m), 0.0, 0.0);
  // Closed boxes and a ground seen from above: every visible face's outward normal faces the camera.
  out_geometric_normal = vec4(n, dot(n, to_sun.xyz) > 0.0 ? 1.0 : 0.0);
  out_terminator = vec4(n * view_rows[1].w, 0.0);
}
