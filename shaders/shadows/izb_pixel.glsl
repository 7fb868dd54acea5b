// Per-pixel classification shared by the fit, build and resolve passes.
layout(set = 0, binding = IZB_BINDING_WORLD_POSITION, rgba32f) readonly uniform image2D world_position_image;
layout(set = 0, binding = IZB_BINDING_GEOMETRIC_NORMAL, rgba16f) readonly uniform image2D geometric_normal_image;
layout(set = 0, binding = IZB_BINDING_ALBEDO, rgba8) readonly uniform image2D albedo_image;

struct PixelPoint {
  bool covered;
  bool candidate;  // covered, receiving, facing the light, inside the IZB range
  vec3 position;
  vec3 normal;
  bool facing;     // faces_light (shadow_common.h)
};

// The surface only (`candidate` false): for passes that read the candidates from the build's state.
PixelPoint load_surface(ivec2 pixel) {
  PixelPoint p;
  vec4 pos = imageLoad(world_position_image, pixel);
  p.covered = pos.w > 0.5;
  p.position = pos.xyz;
  vec4 normal = imageLoad(geometric_normal_image, pixel);
  p.normal = normal.xyz;
  // A spot light: lit only where it reaches and the geometric normal faces it (local_light.h).
  p.facing = spot_light() ? p.covered &&
                                local_light_reaches(params.light_position.xyz, params.light_position.w,
                                                    params.light_direction.xyz, params.light_cone.x, true, p.position) &&
                                faces_local_light(p.normal, p.position, params.light_position.xyz)
                          : faces_light(normal);
  p.candidate = false;
  return p;
}

// The IZB's range from the camera (params.camera_position.w; 0: unlimited, read as a huge reach). A
// select, not a branch on the uniform alone (max_distance <= 0.0 || ...): Mesa 22.3's lavapipe can
// latch onto such a branch and compile a new copy of the shader at every dispatch, never freed
// (tests/soak).
float izb_reach() {
  float max_distance = params.camera_position.w;
  return max_distance > 0.0 ? max_distance : 3.0e38;
}

PixelPoint load_pixel(ivec2 pixel) {
  // Loaded with the surface's, not after the coverage test: one round trip to memory instead of two.
  float receiver = imageLoad(albedo_image, pixel).a;
  PixelPoint p = load_surface(pixel);
  if (!p.covered) return p;
  bool receives = receiver > 0.5;
  bool in_range = distance(p.position, params.camera_position.xyz) <= izb_reach();
  p.candidate = receives && p.facing && in_range;
  return p;
}

// The μQuad corners of `pixel` with the shadow-ray offset applied (world space).
void micro_quad_corners(ivec2 pixel, PixelPoint p, out vec3 c[4]) {
  vec2 viewport = vec2(params.extent.xy);
  vec2 base = vec2(pixel);
  c[0] = shadow_ray_origin(micro_quad_corner(base, viewport, params.inverse_view_projection, p.position, p.normal), p.normal);
  c[1] = shadow_ray_origin(micro_quad_corner(base + vec2(1, 0), viewport, params.inverse_view_projection, p.position, p.normal), p.normal);
  c[2] = shadow_ray_origin(micro_quad_corner(base + vec2(0, 1), viewport, params.inverse_view_projection, p.position, p.normal), p.normal);
  c[3] = shadow_ray_origin(micro_quad_corner(base + vec2(1, 1), viewport, params.inverse_view_projection, p.position, p.normal), p.normal);
}
