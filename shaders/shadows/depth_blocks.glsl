// Depth blocks: a depth map cut into blocks of kSmBlock² texels, each kept as the plane that fits its
// depths best (least squares over the texels' centres) and the largest distance of a stored depth
// from it: vec4(depth at the block's centre, slope per texel along x and y, distance). A receiver's
// tap at texel T compares z(T) = z + dot(g, T + 0.5 - t) (its tangent plane) with depth(T) + bias;
// over a block depth(T) lies within the distance of the block's plane, and z(T) minus that plane is
// linear in T, so over the block's tap texels its extremes lie at their rectangle's corners. Where
// they lie on one side for every block a receiver's footprint touches, every tap there has the same
// result, which is then known without reading any. A planar surface's block fits it to a rounding
// step, so a receiver on it settles; a block across an occluder's edge or a crease fits loosely and
// settles nothing. Used by sm's PCSS (shadow_map_blocks.comp, shadow_map_resolve.glsl) and the
// cascades' masking (cascade_edges.comp, cascade_filter.comp).
//
// Before including, define DEPTH_BLOCKS_FIT and declare `float depth_block_texel(ivec2 texel)` (the
// stored depth) for fit_depth_block, and/or define DEPTH_BLOCKS_SETTLE and declare
// `vec4 depth_block(int layer, ivec2 block)` (a block's vec4, with an infinite distance where it is
// not known) for depth_blocks_settled.
#ifndef DEPTH_BLOCKS_GLSL
#define DEPTH_BLOCKS_GLSL

#ifdef DEPTH_BLOCKS_FIT
// The block at `block` (in blocks) of a map of `size` texels; one reaching past the map's edge holds
// an infinite distance: it settles nothing.
vec4 fit_depth_block(ivec2 block, ivec2 size) {
  ivec2 origin = block * int(kSmBlock);
  if (any(greaterThan(origin + int(kSmBlock), size))) return vec4(0.0, 0.0, 0.0, 3.0e38);
  // Offsets from the block's centre: -3.5 .. 3.5 along each axis.
  float half_span = 0.5 * float(kSmBlock - 1u);
  vec3 moments = vec3(0.0);
  for (int y = 0; y < int(kSmBlock); ++y)
    for (int x = 0; x < int(kSmBlock); ++x) {
      float depth = depth_block_texel(origin + ivec2(x, y));
      moments += vec3(depth, (vec2(x, y) - half_span) * depth);
    }
  // Least squares over a full grid: the mean, and each slope the moment over the sum of u² (the
  // block's kSmBlock columns of 2 * (0.5² + 1.5² + 2.5² + 3.5²) = 42 each).
  float u_squares = float(kSmBlock) * float(kSmBlock * (kSmBlock * kSmBlock - 1u)) / 12.0;
  float centre = moments.x / float(kSmBlock * kSmBlock);
  vec2 slope = moments.yz / u_squares;
  float distance = 0.0;
  for (int y = 0; y < int(kSmBlock); ++y)
    for (int x = 0; x < int(kSmBlock); ++x) {
      float depth = depth_block_texel(origin + ivec2(x, y));
      distance = max(distance, abs(depth - (centre + dot(slope, vec2(x, y) - half_span))));
    }
  return vec4(centre, slope, distance);
}
#endif

#ifdef DEPTH_BLOCKS_SETTLE
// Whether the blocks settle every tap a receiver (map texel coordinates t, light depth z, tangent
// plane `gradient` in depth per texel, `bias`) makes within `reach` texels of t, in map `layer` of
// `size` texels: 1 every tap lit, 0 every tap shadowed, -1 not settled (or too wide a footprint, or
// one reaching past the map's edge, where taps are clamped). kSettleMargin covers the two
// evaluations' rounding (depths in [0, 1]).
const float kSettleMargin = 1.0e-5;
const int kMaxSettleBlocks = 4;  // a side
int depth_blocks_settled(int layer, vec2 t, float z, vec2 gradient, float bias, vec2 reach, int size) {
  ivec2 lo = ivec2(floor(t - reach)), hi = ivec2(floor(t + reach));
  if (any(lessThan(lo, ivec2(0))) || any(greaterThanEqual(hi, ivec2(size)))) return -1;
  int block = int(kSmBlock);
  ivec2 first = lo / block, last = hi / block;
  if (any(greaterThanEqual(last - first, ivec2(kMaxSettleBlocks)))) return -1;
  bool lit = true, shadowed = true;
  for (int by = first.y; by <= last.y; ++by)
    for (int bx = first.x; bx <= last.x; ++bx) {
      vec4 plane = depth_block(layer, ivec2(bx, by));
      ivec2 origin = ivec2(bx, by) * block;
      vec2 centre = vec2(origin) + 0.5 * float(block - 1);
      float at_centre = z + dot(gradient, centre + 0.5 - t) - plane.x;
      vec2 slope = gradient - plane.yz;
      vec2 near = vec2(max(lo, origin)) - centre, far = vec2(min(hi, origin + block - 1)) - centre;
      vec2 highest = max(slope * near, slope * far), lowest = min(slope * near, slope * far);
      lit = lit && at_centre + highest.x + highest.y + plane.w + kSettleMargin <= bias;
      shadowed = shadowed && at_centre + lowest.x + lowest.y - plane.w - kSettleMargin > bias;
    }
  return lit ? 1 : shadowed ? 0 : -1;
}
#endif

#endif
