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

// IZB_FLAG_LISTED_RESOLVE: the pixels with nodes (row-major indices), which the build lists; with
// IZB_FLAG_FACE_TILES, a point light's six lists of tiles (light_tiles.h).
layout(set = 0, binding = IZB_BINDING_RESOLVE_LIST) buffer ResolveList { uint resolve_list[]; };
#define LIGHT_TILES_LIST resolve_list
#include "shadows/light_tiles.glsl"
// Whether this pass is one face of a point light (six cones about the axes that cover every direction,
// params.light_cone.z), not a spot light or the sun.
bool point_light_face_pass() { return params.light_cone.z > 0.0; }
// A point light's face from its axis (params.light_direction): izb_face_tiles.comp's order, +x, -x,
// +y, -y, +z, -z.
uint point_light_face() { return point_light_face_of(params.light_direction.xyz); }
// A point light's face: whether `position` belongs to another face (point_light_face_of), whose pass
// writes its term.
bool outside_light_face(vec3 position) {
  precise vec3 from_light = position - params.light_position.xyz;
  return spot_light() && point_light_face_pass() && point_light_face_of(from_light) != point_light_face();
}

// Whether a spot light (or a point-light face) reaches `position`: in its range and cone, and a face's
// point besides (not outside_light_face: the rest of its cone is other faces' to shadow).
bool local_light_reaches_point(vec3 position) {
  return local_light_reaches(params.light_position.xyz, params.light_position.w, params.light_direction.xyz,
                             params.light_cone.x, true, position) &&
         !outside_light_face(position);
}

// The surface only (`candidate` false): for passes that read the candidates from the build's state.
PixelPoint load_surface(ivec2 pixel) {
  PixelPoint p;
  vec4 pos = imageLoad(world_position_image, pixel);
  p.covered = pos.w > 0.5;
  p.position = pos.xyz;
  vec4 normal = imageLoad(geometric_normal_image, pixel);
  p.normal = normal.xyz;
  // A spot light: lit only where it reaches and the geometric normal faces it (local_light.h).
  p.facing = spot_light() ? p.covered && local_light_reaches_point(p.position) &&
                                faces_local_light(p.normal, p.position, params.light_position.xyz)
                          : faces_light(normal);
  p.candidate = false;
  return p;
}

// The shadow-ray offset of a shading point at `position` (shadow_common.h).
float izb_ray_offset(vec3 position) { return shadow_ray_offset(position, params.camera_position.xyz); }

// The IZB's range from the camera (params.camera_position.w; 0: unlimited, read as a huge reach). A
// select, not a branch on the uniform alone (max_distance <= 0.0 || ...): Mesa 22.3's lavapipe can
// latch onto such a branch and compile a new copy of the shader at every dispatch, never freed
// (tests/soak).
float izb_reach() {
  float max_distance = params.camera_position.w;
  return max_distance > 0.0 ? max_distance : 3.0e38;
}

// A covered point with its facing decided is a candidate where it receives shadows (its receiver flag)
// and lies within the IZB's range.
bool is_candidate(PixelPoint p, float receiver) {
  return receiver > 0.5 && p.facing && distance(p.position, params.camera_position.xyz) <= izb_reach();
}

// A local light reaches a part of the view (its cone, its range): on a GPU the normal and the receiver
// flag are read only for the points it reaches (a point light's face: a sixth of them), the others
// being settled by their position alone, as load_surface settles them.
PixelPoint load_local_light_pixel(ivec2 pixel) {
  vec4 pos = imageLoad(world_position_image, pixel);
  PixelPoint p = PixelPoint(pos.w > 0.5, false, pos.xyz, vec3(0.0), false);
  if (!p.covered || !local_light_reaches_point(p.position)) return p;
  float receiver = imageLoad(albedo_image, pixel).a;
  p.normal = imageLoad(geometric_normal_image, pixel).xyz;
  p.facing = faces_local_light(p.normal, p.position, params.light_position.xyz);
  p.candidate = is_candidate(p, receiver);
  return p;
}

PixelPoint load_pixel(ivec2 pixel) {
  if (spot_light() && !izb_flag(IZB_FLAG_CPU_DEVICE)) return load_local_light_pixel(pixel);
  // Loaded with the surface's, not after the coverage test: one round trip to memory instead of two.
  float receiver = imageLoad(albedo_image, pixel).a;
  PixelPoint p = load_surface(pixel);
  if (!p.covered) return p;
  p.candidate = is_candidate(p, receiver);
  return p;
}

// pixel_corner_ray (shadow_common.h) for this frame's camera. Where the inverse view-projection's w
// ignores x and y (IZB_FLAG_CONSTANT_RAY_W: any projection without a perspective shear), every ray's
// two points have the same w, whose reciprocals the CPU divides once (params.ray_scales): the same
// correctly rounded quotients, without two of shared_divide's corrections a ray.
CameraRay corner_ray(vec2 pixel_corner) {
  HomogeneousRay h = pixel_corner_points(pixel_corner, vec2(params.extent.xy), params.inverse_view_projection);
  if (izb_flag(IZB_FLAG_CONSTANT_RAY_W)) return camera_ray_scaled(h, params.ray_scales.x, params.ray_scales.y);
  return camera_ray(h);
}

// The μQuad corners of `pixel` with the shadow-ray offset applied (world space).
void micro_quad_corners(ivec2 pixel, PixelPoint p, out vec3 c[4]) {
  float offset = izb_ray_offset(p.position);
  for (int k = 0; k < 4; ++k)
    c[k] = shadow_ray_origin(micro_quad_corner_on(corner_ray(vec2(pixel + ivec2(k & 1, k >> 1))), p.position, p.normal),
                             p.normal, offset);
}

// IZB_FLAG_BOUNDED_FIT: raises [lo, hi] to hold the light-view x and y of every corner
// micro_quad_corners makes for `pixel` (a candidate at `position` with geometric normal `normal`),
// with the shadow-ray offset. The corners come from the affine camera rays of
// params.corner_ray_origin / _direction in fast arithmetic, widened by how far rounding can move them
// from the build's: the two rays' distance (the bounds in the w components: origin, and direction
// times the ray parameter t) and each computation's dot products, quotient and sum (4 units of 2^-23
// on each magnitude, twice), through the intersection's conditioning 1 + |n| |d| / |n . d|; the
// magnitudes of the rays' origins and directions are the frame's bounds (the w components of [1]).
// Within kBoundedFitGrazing of grazing, or where the rays' distance could reach a tenth of n . d,
// that bound is loose or its first order fails: such a pixel makes its exact corners (one lane's cost,
// where micro_quad_corners is four rays a pixel).
const float kBoundedFitGrazing = 1.0 / 16.0;
const float kUnitRounding = 1.0 / 8388608.0;  // 2^-23, twice float's unit roundoff
void bound_micro_quad(ivec2 pixel, vec3 position, vec3 normal, mat4 light_view, inout vec2 lo, inout vec2 hi) {
  float origin_error = params.corner_ray_origin[0].w, direction_error = params.corner_ray_direction[0].w;
  float origin_size = params.corner_ray_origin[1].w, direction_size = params.corner_ray_direction[1].w;
  float normal_squared = dot(normal, normal);
  float least_denom = max(10.0 * sqrt(normal_squared) * direction_error, 1.0e-11);
  vec3 c[4];
  float conditioning_squared = 0.0, farthest_t = 0.0;
  bool fast = true;
  for (int k = 0; k < 4; ++k) {
    vec2 corner = vec2(pixel + ivec2(k & 1, k >> 1));
    vec3 o = params.corner_ray_origin[0].xyz + corner.x * params.corner_ray_origin[1].xyz + corner.y * params.corner_ray_origin[2].xyz;
    vec3 d = params.corner_ray_direction[0].xyz + corner.x * params.corner_ray_direction[1].xyz +
             corner.y * params.corner_ray_direction[2].xyz;
    float denom = dot(normal, d);
    float inverse = 1.0 / denom;
    float reach_squared = normal_squared * dot(d, d);
    fast = fast && denom * denom >= kBoundedFitGrazing * kBoundedFitGrazing * reach_squared && abs(denom) >= least_denom;
    float t = dot(normal, position - o) * inverse;
    c[k] = o + d * t;
    conditioning_squared = max(conditioning_squared, reach_squared * inverse * inverse);
    farthest_t = max(farthest_t, abs(t));
  }
  float widen = 0.0;
  if (!fast) {
    PixelPoint p;
    p.position = position;
    p.normal = normal;
    micro_quad_corners(pixel, p, c);
  } else {
    float reach = origin_size + farthest_t * direction_size;  // no corner farther from the origin
    float ray_error = origin_error + farthest_t * direction_error;
    float rounding = 8.0 * kUnitRounding * (length(position) + reach);
    widen = (ray_error + rounding) * (1.0 + sqrt(conditioning_squared)) + 2.0 * kUnitRounding * reach;
    widen *= 1.1;  // the terms of second order; a light view is a rotation and a translation: distances carry over
    float offset = izb_ray_offset(position);
    for (int k = 0; k < 4; ++k) c[k] = shadow_ray_origin(c[k], normal, offset);
  }
  for (int k = 0; k < 4; ++k) {
    vec2 v = (light_view * vec4(c[k], 1.0)).xy;
    lo = min(lo, v - widen);
    hi = max(hi, v + widen);
  }
}

#ifdef IZB_RAY_BLOCK
// 32 spp: the camera rays through the corners of a block of IZB_RAY_BLOCK x IZB_RAY_BLOCK pixels (one
// an invocation), each made once for the workgroup, not once for each of the four pixels around it (a
// ray takes eight of shared_divide's exact quotients). The same arithmetic as micro_quad_corners, so
// the same corners.
const uint kRayBlockSide = IZB_RAY_BLOCK + 1u;
shared vec3 block_ray_origin[kRayBlockSide * kRayBlockSide];
shared vec3 block_ray_direction[kRayBlockSide * kRayBlockSide];
// Every invocation calls it, in uniform control flow; the barriers order the previous block's reads
// before these writes, and these writes before the reads.
void make_block_rays(ivec2 block_origin) {
  barrier();
  // (Included before the shader's local size is declared: its IZB_RAY_BLOCK x IZB_RAY_BLOCK
  // invocations, not gl_WorkGroupSize.)
  for (uint i = gl_LocalInvocationIndex; i < kRayBlockSide * kRayBlockSide; i += IZB_RAY_BLOCK * IZB_RAY_BLOCK) {
    CameraRay ray = corner_ray(vec2(block_origin + ivec2(i % kRayBlockSide, i / kRayBlockSide)));
    block_ray_origin[i] = ray.origin;
    block_ray_direction[i] = ray.direction;
  }
  barrier();
}
// micro_quad_corners for a pixel of the block make_block_rays last made.
void block_micro_quad_corners(ivec2 pixel, ivec2 block_origin, PixelPoint p, out vec3 c[4]) {
  ivec2 local = pixel - block_origin;
  float offset = izb_ray_offset(p.position);
  for (int k = 0; k < 4; ++k) {
    uint i = uint(local.y + (k >> 1)) * kRayBlockSide + uint(local.x + (k & 1));
    CameraRay ray;
    ray.origin = block_ray_origin[i];
    ray.direction = block_ray_direction[i];
    c[k] = shadow_ray_origin(micro_quad_corner_on(ray, p.position, p.normal), p.normal, offset);
  }
}
#endif

// A point light's face, or a spot light on a CPU device (IZB_FLAG_FACE_TILES): this invocation's pixel
// in the face's (the spot's) list of 8x8 tiles (izb_face_tiles.comp), a workgroup of 8x8 a tile;
// false for a workgroup past the list's end, which then leaves whole, before any barrier.
bool face_tile_pixel(out ivec2 pixel) {
  return light_tile_pixel(point_light_face_pass() ? point_light_face() : 0u, params.extent.xy, pixel);
}
// The resolve list's pixel of this invocation (one a thread, in rows of kIzbDispatchRow workgroups of
// 64: IZB_COUNTER_RESOLVE_LIST's dispatch); false past the list's end.
bool listed_pixel(out uint index) {
  uint entry = IZB_ROW_DISPATCH_GROUP * 64u + gl_LocalInvocationIndex;
  bool listed = entry < counters[IZB_COUNTER_RESOLVE_LIST];
  index = listed ? resolve_list[entry] : 0u;
  return listed;
}

// Hybrid: the pixels that take any of the cascades' term, with their weight (izb_resolve.comp).
layout(set = 0, binding = IZB_BINDING_HYBRID_LIST) writeonly buffer HybridList { uvec4 hybrid_list[]; };

// The shadow term of a classified pixel (`state`, IZB_PIXEL_*) from its visibility mask, written where
// it applies; returns the visibility. With `hybrid` the term blends toward the cascades' over the
// last tenth of the IZB's range, and beyond it is the cascades' alone: the pixels that take any of the
// cascades' term are listed with their weight, so that the cascades filter only those (a CPU device
// pays every pixel of a full-screen pass) and izb_hybrid_blend.comp mixes them. Called by every lane
// of the subgroup (the list takes one atomic per subgroup on a GPU); `has_pixel` false for a lane with none.
float write_pixel_term(ivec2 pixel, bool has_pixel, uint state, uint mask, vec3 position, bool hybrid,
                       out bool written) {
  written = false;
  bool covered = has_pixel && (state & IZB_PIXEL_COVERED) != 0u;
  bool candidate = (state & IZB_PIXEL_CANDIDATE) != 0u;
  bool facing = (state & IZB_PIXEL_FACING) != 0u;
  bool beyond = false;  // past the IZB's range: the cascades' term alone
  float visibility = 1.0;
  if (candidate) {
    visibility = 1.0 - float(bitCount(mask)) / float(izb_samples());
  } else if (!facing) {
    visibility = 0.0;
  } else if ((state & IZB_PIXEL_BEYOND) != 0u) {
    beyond = true;
    visibility = 0.0;
  }  // else: does not receive shadows, lit
  if (hybrid) {
    // Near the IZB's range limit the cascades take over. Surfaces facing away are 0 in both terms, so
    // they need no blend. (Unlimited range: reach is huge and the fade 0.)
    float reach = izb_reach();
    float dist = distance(position, params.camera_position.xyz);
    float fade = beyond ? 1.0 : clamp((dist - kIzbHybridFadeStart * reach) / (kIzbHybridFadeWidth * reach), 0.0, 1.0);
    bool listed = covered && facing && fade > 0.0;
    // One atomic per subgroup; the dispatch over the list grows with it. A CPU device: an atomic per
    // lane, and the dispatch after the resolve (izb_list_dispatch.comp).
    uint slot = 0u;
    if (izb_flag(IZB_FLAG_CPU_DEVICE)) {
      if (listed) slot = atomicAdd(counters[IZB_COUNTER_HYBRID], 1u);
    } else {
      uint total = subgroupAdd(listed ? 1u : 0u);
      uint base = 0u;
      if (subgroupElect() && total != 0u) {
        base = atomicAdd(counters[IZB_COUNTER_HYBRID], total);
        atomicMax(counters[IZB_COUNTER_HYBRID + 1u], (base + total + kIzbHybridEntriesPerGroup - 1u) / kIzbHybridEntriesPerGroup);
      }
      slot = subgroupBroadcastFirst(base) + subgroupExclusiveAdd(listed ? 1u : 0u);
    }
    if (listed)
      hybrid_list[slot] = uvec4(uint(pixel.x) | (uint(pixel.y) << 16u), 0u, floatBitsToUint(fade), 0u);
  }
  if (!covered) return visibility;
  if (beyond && !hybrid) return visibility;  // beyond the IZB: the term already there stays
  // One face of a point light: only the points in its cone are this pass's (the build marked the
  // others); they keep what the other faces write.
  if ((state & IZB_PIXEL_OTHER_FACE) != 0u) return visibility;
  written = true;
  // The sun's term starts lit (ContextImpl::clear_term_and_overlay, host_inputs.glsl) and only the IZB
  // writes it before the trace and resolve: storing a lit pixel's 1 would rewrite what is there (a
  // CPU device pays for every store it makes, a GPU for the bandwidth). Spot lights and point-light
  // faces (IZB_FLAG_SPOT) store every point: a point light's faces overlap, and a later face's lit
  // point must overwrite an earlier face's term.
  if (visibility < 1.0 || spot_light()) imageStore(shadow_term, pixel, vec4(visibility));
  return visibility;
}
