#version 450
// The host's G-buffer: world-space normals and a flat albedo per object.
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(push_constant) uniform Push {
  mat4 view_projection;
  vec4 world_rows[3];  // affine object -> world, row by row
  vec4 albedo;
};
layout(location = 0) out vec3 world_normal;

void main() {
  vec4 p = vec4(position, 1.0);
  vec3 world = vec3(dot(world_rows[0], p), dot(world_rows[1], p), dot(world_rows[2], p));
  // Boxes scaled along their own axes: the linear part keeps face normals' directions.
  world_normal = vec3(dot(world_rows[0].xyz, normal), dot(world_rows[1].xyz, normal), dot(world_rows[2].xyz, normal));
  gl_Position = view_projection * vec4(world, 1.0);
}
