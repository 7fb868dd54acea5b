// Declarations shared by the IZB passes. Include after "izb.h", "frame.h" and "shadow_common.h".
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_ballot : require

layout(set = 0, binding = IZB_BINDING_PARAMS) uniform Params { IzbParams params; };
layout(set = 0, binding = IZB_BINDING_FRAME, std140) uniform FrameBuffer { IzbFrame izb; };  // (the same offsets as std430)
layout(set = 0, binding = IZB_BINDING_COUNTERS, std430) buffer Counters { uint counters[]; };
layout(set = 0, binding = IZB_BINDING_HEADS, std430) buffer Heads { uint heads[]; };
layout(set = 0, binding = IZB_BINDING_FARTHEST, std430) buffer Farthest { uint farthest[]; };
layout(set = 0, binding = IZB_BINDING_NODES, std430) buffer Nodes { uvec2 nodes[]; };
layout(set = 0, binding = IZB_BINDING_MASK, std430) buffer Mask { uint visibility_mask[]; };
layout(set = 0, binding = IZB_BINDING_PIXEL_STATE, std430) buffer PixelState { uint pixel_state[]; };
layout(set = 0, binding = IZB_BINDING_SHADOW_TERM, r32f) uniform image2D shadow_term;
uint tiles_per_side() { return params.capacities.y; }
// This frame's shape of the compute work's step 1 (izb.h, kIzbStepOne*).
uint step_one_triangles() { return params.capacities.w & 0xffffu; }
uint step_one_texel_bound() { return params.capacities.w >> 16u; }
layout(set = 0, binding = IZB_BINDING_QUADS, std430) buffer Quads { float quads[]; };
// The same buffer a vec4 at a time, for the build's stores and the traces' loads (a pixel's points are 4
// or 12 floats, whole vec4s).
layout(set = 0, binding = IZB_BINDING_QUADS, std430) buffer QuadVectors { vec4 quad_vectors[]; };
layout(set = 0, binding = IZB_BINDING_TRIANGLES, std430) readonly buffer Casters { IzbCasterTriangle casters[]; };
layout(set = 0, binding = IZB_BINDING_OVERFLOW_LIST, std430) buffer OverflowList { uint overflow_pixels[]; };
layout(set = 0, binding = IZB_BINDING_OCCLUDER_DISTANCE, std430) buffer OccluderDistance { uint occluder_distance[]; };
layout(set = 0, binding = IZB_BINDING_GRID_TRIANGLES, std430) buffer GridTriangles { vec4 grid_triangles[]; };
layout(set = 0, binding = IZB_BINDING_CSM_TEXELS, std430) buffer CsmTexels { uint csm_texels[]; };
// The same buffer four words a load: the lit map's tile records (lit_tile_record).
layout(set = 0, binding = IZB_BINDING_CSM_TEXELS, std430) readonly buffer LitTileWords { uvec4 lit_tile_words[]; };
// And as a texel buffer (IZB_FLAG_LIT_FETCH).
layout(set = 0, binding = IZB_BINDING_LIT_WORDS) uniform usamplerBuffer lit_words;
layout(set = 0, binding = IZB_BINDING_LIST_COUNTS, std430) buffer ListCounts { uint list_counts[]; };
layout(set = 0, binding = IZB_BINDING_LIST_CURSOR, std430) buffer ListCursor { uint list_cursor[]; };
layout(set = 0, binding = IZB_BINDING_CASTER_DRAWS, std430) buffer CasterDraws { uint caster_draw_words[]; };

#define MATERIAL_TEXTURES_BINDING IZB_BINDING_MATERIAL_TEXTURES
#include "material_textures.glsl"

// The sample count and the IZB_FLAG_* bits are specialization constants: a pipeline per combination,
// so a device that executes both sides of a branch (a CPU driver) runs only the code a frame needs.
layout(constant_id = 10) const uint kIzbSamples = 1u;
layout(constant_id = 11) const uint kIzbFlags = 0u;

uint izb_resolution() { return params.extent.z; }
// Per light-space tile (kIzbTile² texels), after the texels' words in `farthest`: its farthest node
// depth (float bits, 0: no node), raised by the build for the compute trace's tile-level cull.
uint tile_farthest_index(uint tile) { return izb_resolution() * izb_resolution() + tile; }
uint izb_samples() { return kIzbSamples; }
bool izb_flag(uint flag) { return (kIzbFlags & flag) != 0u; }
#define UNIFORM_BRANCH_CPU izb_flag(IZB_FLAG_CPU_DEVICE)
#include "shadows/uniform_branch.glsl"

// A spot light (else the sun): its grid is a perspective one from its position (izb_setup.comp), in
// which rays toward the light run along the depth axis as the sun's do in its orthographic grid.
bool spot_light() { return izb_flag(IZB_FLAG_SPOT); }

// World position -> (grid x, grid y, light depth): grid in texels of the IZB, depth in [0,1]. A spot
// light's points lie in front of it (w > 0: the build takes only points it reaches, and caster
// triangles reaching behind its near plane are traced apart, izb_triangles.comp). clip_to_grid takes
// the light clip position (izb.light_view_projection) where the caller also needs its w.
vec3 clip_to_grid(vec4 clip) {
  if (spot_light()) clip.xyz /= clip.w;
  float res = float(izb_resolution());
  return vec3((clip.xy * 0.5 + 0.5) * res, clip.z);
}
vec3 to_grid(vec3 world) { return clip_to_grid(izb.light_view_projection * vec4(world, 1.0)); }

// A straddler's grid bounds (izb_triangles.glsl's straddler_grid_bounds) packed for its ray tests
// (izb_straddlers.glsl): whole texels, widened by kStraddlerBoundsMargin texels for the rounding of
// the projections (near the light a vertex's projection rounds most), clamped just outside the grid
// and offset to stay positive, so a packed bound is never 0 (0: unbounded). `widen` < 0 for the low
// corner.
const float kStraddlerBoundsMargin = 2.0;
const float kStraddlerBoundsOffset = 8.0;
uint pack_straddler_bound(vec2 g, float widen) {
  float res = float(izb_resolution());
  vec2 q = clamp(widen < 0.0 ? floor(g + widen) : ceil(g + widen), vec2(-4.0), vec2(res + 4.0)) + kStraddlerBoundsOffset;
  return uint(q.x) | (uint(q.y) << 16u);
}
vec2 unpack_straddler_bound(uint packed) {
  return vec2(float(packed & 0xffffu), float(packed >> 16u)) - kStraddlerBoundsOffset;
}

ivec2 grid_texel(vec3 g) {
  int res = int(izb_resolution());
  return clamp(ivec2(floor(g.xy)), ivec2(0), ivec2(res - 1));
}

uint texel_index(ivec2 t) { return uint(t.y) * izb_resolution() + uint(t.x); }

// 32 spp, a μQuad with grid-space corners g:
const float kBlendSlackTexels = 1.0 / 64.0;  // a blend of grid coordinates (< 2^14) rounds by a few ulps
// The μQuad corners' bounds [lo, hi] in grid coordinates, widened past any rounding of a sample's
// blend: every sample lies inside.
void quad_sample_bounds(vec3 g[4], out vec2 lo, out vec2 hi) {
  lo = min(min(g[0].xy, g[1].xy), min(g[2].xy, g[3].xy)) - kBlendSlackTexels;
  hi = max(max(g[0].xy, g[1].xy), max(g[2].xy, g[3].xy)) + kBlendSlackTexels;
}
// The texels [first, last] of quad_sample_bounds: every sample lies in one of them.
void quad_texel_bounds(vec3 g[4], out ivec2 first, out ivec2 last) {
  vec2 lo, hi;
  quad_sample_bounds(g, lo, hi);
  first = grid_texel(vec3(lo, 0.0));
  last = grid_texel(vec3(hi, 0.0));
}

uint quad_stride() { return izb_samples() == 32u ? kIzbQuadFloats32 : kIzbQuadFloats1; }
// A candidate's grid point (1 spp) or μQuad corner `corner` (32 spp: 00, 10, 01, 11), stored by the
// build (a vec4 at a time, through quad_vectors).
vec3 quad_point(uint pixel, uint corner) {
  uint base = pixel * quad_stride() + corner * 3u;
  return vec3(quads[base], quads[base + 1u], quads[base + 2u]);
}

// What a node test needs to alpha-test a caster triangle: its material's threshold (0: not
// alpha-tested, and nothing else is read) and texture, and its vertices' texture coordinates.
struct CasterAlpha {
  uint threshold;
  uint texture;
  vec2 uv0, uv1, uv2;
  vec3 inv_w;  // a spot light: 1 / light-view depth of each vertex (perspective-correct barycentrics)
};

uint caster_draw(uint t) { return floatBitsToUint(casters[t].p0.w); }

// The caster draws' words (IZB_BINDING_CASTER_DRAWS): where each section starts.
uint caster_draw_count() { return params.capacities.z; }
uint draw_bounds_word(uint draw) { return caster_draw_count() + 8u * draw; }
uint frustum_draw_word(uint slot) { return 9u * caster_draw_count() + params.face_sections.x + 2u * slot; }
uint listed_triangle_word(uint slot) { return 11u * caster_draw_count() + params.face_sections.x + slot; }
// The triangles listed this frame (izb_triangles.comp): those of draws in the light frustum that reach
// the grid, in no particular order. Every pass that walks caster triangles walks these.
uint listed_triangle_count() { return counters[IZB_COUNTER_LISTED_TRIANGLES]; }
uint listed_triangle(uint slot) { return caster_draw_words[listed_triangle_word(slot)]; }
// A thread's index in a dispatch in rows of kIzbDispatchRow workgroups of `group_size` threads.
uint row_dispatch_index(uvec3 workgroup, uint local_index, uint group_size) {
  return (workgroup.y * kIzbDispatchRow + workgroup.x) * group_size + local_index;
}
// Writes the indirect dispatch of `groups` workgroups, in such rows, at counters[at..at+2].
void write_row_dispatch(uint at, uint groups) {
  counters[at] = min(groups, kIzbDispatchRow);
  counters[at + 1u] = (groups + kIzbDispatchRow - 1u) / kIzbDispatchRow;
  counters[at + 2u] = 1u;
}
// Raises the indirect dispatch at counters[at..at+2] (zeroed each frame) to rows of kIzbDispatchRow
// workgroups that cover `items` items of `per_group` each. x and y grow with the items alone, so the
// largest of several producers' raises is what they leave.
void raise_row_dispatch(uint at, uint items, uint per_group) {
  uint groups = (items + per_group - 1u) / per_group;
  if (groups == 0u) return;
  uint x = min(groups, kIzbDispatchRow), y = (groups + kIzbDispatchRow - 1u) / kIzbDispatchRow;
  // Atomics on one address serialize: raise only what is short. A stale read is never above the value
  // (they only grow), so at worst it costs an atomic more.
  uvec3 now = uvec3(counters[at], counters[at + 1u], counters[at + 2u]);  // read together: one round trip
  if (x > now.x) atomicMax(counters[at], x);
  if (y > now.y) atomicMax(counters[at + 1u], y);
  if (now.z == 0u) counters[at + 2u] = 1u;  // every writer writes 1
}
// Reserves `count` consecutive slots of the counter counters[counter] for this invocation, with one
// atomic per subgroup (a single address would serialize every lane's); returns the first. Every lane
// of the subgroup calls it together. With `raise`, also raises the indirect dispatch at `dispatch_at`
// over the counter's items (at most `capacity`) in workgroups of `per_group`.
uint reserve_slots_raising(uint counter, uint count, bool raise, uint dispatch_at, uint capacity, uint per_group) {
  if (izb_flag(IZB_FLAG_CPU_DEVICE)) {
    uint first = 0u;
    if (count > 0u) {
      first = atomicAdd(counters[counter], count);
      // The lane whose slots take a workgroup's first raises the dispatch to hold it.
      uint next_group_start = (first + per_group - 1u) / per_group * per_group;
      if (raise && next_group_start < first + count) raise_row_dispatch(dispatch_at, min(first + count, capacity), per_group);
    }
    return first;
  }
  uint offset = subgroupExclusiveAdd(count);
  uint total = subgroupAdd(count);
  uint base = 0u;
  if (subgroupElect() && total > 0u) {
    base = atomicAdd(counters[counter], total);
    if (raise) raise_row_dispatch(dispatch_at, min(base + total, capacity), per_group);
  }
  return subgroupBroadcastFirst(base) + offset;
}
uint reserve_slots(uint counter, uint count) { return reserve_slots_raising(counter, count, false, 0u, 0u, 1u); }
// Adds every lane's `value` to the sharded counter `counter` (IZB_COUNTER_SHARDS), one atomic per
// subgroup; `seed` picks the shard, so that subgroups far apart in the frame hit different addresses
// (statistics would otherwise slow the frames they measure).
void add_sharded(uint counter, uint value, uint seed) {
  uint sum = subgroupAdd(value);
  if (subgroupElect() && sum > 0u)
    atomicAdd(counters[izb_shard_word(counter, seed % kIzbCounterShards)], sum);
}
// A compute invocation's shard seed.
#define IZB_SHARD_SEED (gl_WorkGroupID.x * 7u + gl_WorkGroupID.y * 13u + gl_SubgroupID)
// A compute invocation's workgroup in a dispatch laid out in rows of kIzbDispatchRow workgroups
// (raise_row_dispatch).
#define IZB_ROW_DISPATCH_GROUP (gl_WorkGroupID.y * kIzbDispatchRow + gl_WorkGroupID.x)


CasterAlpha load_caster_alpha(uint t) {
  CasterAlpha ca;
  ca.threshold = izb_flag(IZB_FLAG_ALPHA) ? floatBitsToUint(casters[t].p1.w) : 0u;
  ca.texture = izb_flag(IZB_FLAG_ALPHA) ? floatBitsToUint(casters[t].p2.w) : 0u;
  ca.inv_w = vec3(1.0);
  if (ca.threshold != 0u) {
    ca.uv0 = casters[t].uv01.xy;
    ca.uv1 = casters[t].uv01.zw;
    ca.uv2 = casters[t].uv2.xy;
    if (spot_light()) ca.inv_w = vec3(grid_triangles[3u * t].w, grid_triangles[3u * t + 1u].w, grid_triangles[3u * t + 2u].w);
  }
  return ca;
}

// Whether the caster is solid where the light ray meets it: `w` are the barycentrics of the sample's
// projection along the light in the grid-space triangle, which (the projection being parallel) are
// those of the ray's hit on the world triangle, hence its texture coordinate there.
// (Without IZB_FLAG_ALPHA the test compiles away: a CPU device would run it for every node otherwise.)
// A spot light's grid is a perspective projection: the world barycentrics are the grid ones weighted
// by each vertex's 1 / depth.
bool caster_solid_at(CasterAlpha ca, vec3 w) {
  if (!izb_flag(IZB_FLAG_ALPHA) || ca.threshold == 0u) return true;
  if (spot_light()) w = w * ca.inv_w / dot(w, ca.inv_w);
  return material_alpha_kept(ca.texture, ca.threshold, w.x * ca.uv0 + w.y * ca.uv1 + w.z * ca.uv2);
}

// Shadowed-sample bits that a grid-space triangle (a, b, c) casts on `pixel`. A sample is shadowed
// when its projection along the light lies inside the triangle (edges inclusive) and the triangle is
// nearer the light there: exactly the reference ray's hit with t > 0.
// `precise` throughout the node test: a GPU compiler may fuse the products and differences into
// fused multiply-adds, which moves samples on a triangle's edge to the other side of it than the
// unfused arithmetic of the CPU device and the Embree reference.
float edge_fn(vec2 p, vec2 a, vec2 b) {
  precise float e = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
  return e;
}

// mix() written out, so that `precise` covers its arithmetic.
vec3 blend3(vec3 x, vec3 y, float t) {
  precise vec3 r = x * (1.0 - t) + y * t;
  return r;
}
float blend1(float x, float y, float t) {
  precise float r = x * (1.0 - t) + y * t;
  return r;
}

// The hybrid's penumbra pass places a lit pixel's soft edge by the caster edges its lists held: the
// smallest tangent (across-light distance over height, both in world units) from the point to a
// triangle it lies outside of, where it is below the sun's (a wider one leaves the whole disc lit).
// shadows_point lowers it as the triangles go by; trace_node resets and records it. (Kept here, not
// passed along: the fallback and the 32 spp paths share shadows_point and read no tangent.)
float lit_tangent_seen = 3.0e38;

// The smallest tangent from `s` to segment ab's points nearer the light, of its closest point across
// the light, its ends and its middle (the height varies along it). `texel`: a grid texel's world
// size (the sun's texels are square); `depth_scale`: light depth to world.
float segment_tangent(vec3 s, vec3 a, vec3 b, float texel, float depth_scale) {
  vec2 ab = (b.xy - a.xy) * texel;
  vec2 as = (s.xy - a.xy) * texel;
  float closest = clamp(dot(as, ab) / max(dot(ab, ab), 1.0e-30), 0.0, 1.0);
  float best = 3.0e38;
  for (int k = 0; k < 4; ++k) {
    float t = k == 0 ? closest : k == 1 ? 0.0 : k == 2 ? 1.0 : 0.5;
    float height = (s.z - mix(a.z, b.z, t)) * depth_scale;
    if (height > 0.0) best = min(best, length(as - t * ab) / height);
  }
  return best;
}

// `w`: the point's barycentrics, one below 0 at least (it lies outside the triangle).
void note_lit_tangent(vec3 s, vec3 a, vec3 b, vec3 c, vec3 w, float inv_area) {
  float depth_scale = params.depth_range.y - params.depth_range.x;
  float highest = (s.z - min(min(a.z, b.z), c.z)) * depth_scale;
  if (highest <= 0.0) return;  // no point of it nearer the light
  float texel = izb.grid.z;
  // Most pairs are settled by a bound: the point is at least as far across the light as the line of
  // an edge it lies outside of, and the triangle at most `highest` above it.
  vec2 edge = w.x <= min(w.y, w.z) ? c.xy - b.xy : w.y <= w.z ? a.xy - c.xy : b.xy - a.xy;
  float outside = -min(min(w.x, w.y), w.z) / (abs(inv_area) * max(length(edge), 1.0e-30));
  if (outside * texel >= params.penumbra.x * highest) return;
  float tangent = min(segment_tangent(s, a, b, texel, depth_scale),
                      min(segment_tangent(s, b, c, texel, depth_scale), segment_tangent(s, c, a, texel, depth_scale)));
  lit_tangent_seen = min(lit_tangent_seen, tangent);
}

// `gap` keeps the smallest light-depth distance from an occluded sample up to the triangle.
bool shadows_point(vec3 s, CasterAlpha ca, vec3 a, vec3 b, vec3 c, float inv_area, inout float gap) {
  precise float w0 = edge_fn(s.xy, b.xy, c.xy) * inv_area;
  precise float w1 = edge_fn(s.xy, c.xy, a.xy) * inv_area;
  precise float w2 = edge_fn(s.xy, a.xy, b.xy) * inv_area;
  if (w0 < 0.0 || w1 < 0.0 || w2 < 0.0) {
    // (An alpha-tested caster's outline is not its shadow's: its texture's edges are.)
    if (ca.threshold == 0u && izb_flag(IZB_FLAG_GAPS) && izb_samples() == 1u) note_lit_tangent(s, a, b, c, vec3(w0, w1, w2), inv_area);
    return false;
  }
  precise float depth = w0 * a.z + w1 * b.z + w2 * c.z;
  if (depth >= s.z) return false;
  if (!caster_solid_at(ca, vec3(w0, w1, w2))) return false;
  gap = min(gap, s.z - depth);
  return true;
}

// A node's light-space point(s): 1 spp q[0].xyz; 32 spp the four corners (quad_point's layout) in
// three vec4s.
struct NodePoints {
  vec4 q[3];
};
NodePoints load_node_points(uint pixel) {
  NodePoints n;
  if (izb_samples() == 1u) {
    n.q[0] = quad_vectors[pixel];
    n.q[1] = n.q[2] = vec4(0.0);
  } else {
    n.q[0] = quad_vectors[3u * pixel];
    n.q[1] = quad_vectors[3u * pixel + 1u];
    n.q[2] = quad_vectors[3u * pixel + 2u];
  }
  return n;
}

uint occluded_samples_of(NodePoints n, CasterAlpha ca, vec3 a, vec3 b, vec3 c, float inv_area, inout float gap) {
  if (izb_samples() == 1u) return shadows_point(n.q[0].xyz, ca, a, b, c, inv_area, gap) ? 1u : 0u;
  vec4 q0 = n.q[0], q1 = n.q[1], q2 = n.q[2];
  vec3 c00 = q0.xyz;
  vec3 c10 = vec3(q0.w, q1.xy);
  vec3 c01 = vec3(q1.zw, q2.x);
  vec3 c11 = q2.yzw;
  // Whole-quad reject: no sample can be inside if the quad's bounds miss the triangle's bounds.
  vec2 qmin = min(min(c00.xy, c10.xy), min(c01.xy, c11.xy));
  vec2 qmax = max(max(c00.xy, c10.xy), max(c01.xy, c11.xy));
  vec2 tmin = min(min(a.xy, b.xy), c.xy);
  vec2 tmax = max(max(a.xy, b.xy), c.xy);
  if (any(lessThan(qmax, tmin)) || any(greaterThan(qmin, tmax))) return 0u;
  // Every sample is a convex blend of the four corners, and the triangle's edge functions and the
  // depth gap are affine in position, so the corners decide the whole quad when they agree: all
  // outside one edge -> no sample shadowed; all inside and behind -> every sample shadowed (unless
  // the caster is alpha-tested: then each sample's texel decides).
  vec3 corner[4] = vec3[4](c00, c10, c01, c11);
  precise vec3 w[4];
  precise float corner_gap[4];
  vec3 inside_all = vec3(1.0), outside_all = vec3(1.0);
  float nearest_gap = 1.0e30;
  bool all_behind = true;
  for (int k = 0; k < 4; ++k) {
    w[k] = vec3(edge_fn(corner[k].xy, b.xy, c.xy), edge_fn(corner[k].xy, c.xy, a.xy),
                edge_fn(corner[k].xy, a.xy, b.xy)) * inv_area;
    inside_all = min(inside_all, vec3(greaterThanEqual(w[k], vec3(0.0))));
    outside_all = min(outside_all, vec3(lessThan(w[k], vec3(0.0))));
    corner_gap[k] = corner[k].z - dot(w[k], vec3(a.z, b.z, c.z));
    all_behind = all_behind && corner_gap[k] > 0.0;
    nearest_gap = min(nearest_gap, corner_gap[k]);
  }
  if (any(greaterThan(outside_all, vec3(0.5)))) return 0u;
  bool all_front = true;  // no corner behind: no sample is (a blend of values <= 0 with weights >= 0 is <= 0)
  for (int k = 0; k < 4; ++k) all_front = all_front && corner_gap[k] <= 0.0;
  if (all_front) return 0u;
  if (all(greaterThan(inside_all, vec3(0.5))) && all_behind && ca.threshold == 0u) {
    gap = min(gap, nearest_gap);
    return 0xffffffffu;
  }
  // Otherwise each sample's barycentrics and depth gap are the same bilinear blend of the corners'.
  // (Not on a CPU device: it runs every lane through every function anyway, and Mesa 22.3's lavapipe
  // has given the brute-force fallback lane-dependent bits from this loop.)
  if (ca.threshold == 0u && !izb_flag(IZB_FLAG_GAPS) && !izb_flag(IZB_FLAG_CPU_DEVICE)) {
    // Neither the sample's barycentrics (alpha) nor its gap (occluder distance) is read: only the
    // four signs. A function no corner has below zero (the gap: at or below) has no sample there
    // either, by the same argument, so only the edges and gap the quad straddles are blended, each
    // as the full loop would blend it (blend1 is blend3's arithmetic on one component): the same
    // bits, a quarter to a half of the work.
    uint straddled = (inside_all.x > 0.5 ? 0u : 1u) | (inside_all.y > 0.5 ? 0u : 2u) | (inside_all.z > 0.5 ? 0u : 4u) |
                     (all_behind ? 0u : 8u);
    uint bits = 0xffffffffu;
    for (int f = 0; f < 4; ++f) {
      if ((straddled & (1u << uint(f))) == 0u) continue;
      vec4 v = vec4(corner_gap[0], corner_gap[1], corner_gap[2], corner_gap[3]);
      if (f == 0) v = vec4(w[0].x, w[1].x, w[2].x, w[3].x);
      if (f == 1) v = vec4(w[0].y, w[1].y, w[2].y, w[3].y);
      if (f == 2) v = vec4(w[0].z, w[1].z, w[2].z, w[3].z);
      uint side = 0u;
      for (uint i = 0u; i < 32u; ++i) {
        vec2 o = kSamplePattern[i];
        precise float s = blend1(blend1(v.x, v.y, o.x), blend1(v.z, v.w, o.x), o.y);
        if (f == 3 ? s > 0.0 : s >= 0.0) side |= 1u << i;
      }
      bits &= side;
    }
    return bits;
  }
  uint bits = 0u;
  for (uint i = 0u; i < 32u; ++i) {
    vec2 o = kSamplePattern[i];
    vec3 ws = blend3(blend3(w[0], w[1], o.x), blend3(w[2], w[3], o.x), o.y);
    float gs = blend1(blend1(corner_gap[0], corner_gap[1], o.x), blend1(corner_gap[2], corner_gap[3], o.x), o.y);
    if (all(greaterThanEqual(ws, vec3(0.0))) && gs > 0.0 && caster_solid_at(ca, ws)) {
      bits |= 1u << i;
      gap = min(gap, gs);
    }
  }
  return bits;
}

uint occluded_samples(uint pixel, CasterAlpha ca, vec3 a, vec3 b, vec3 c, float inv_area, inout float gap) {
  return occluded_samples_of(load_node_points(pixel), ca, a, b, c, inv_area, gap);
}

uint full_mask() { return izb_samples() == 32u ? 0xffffffffu : 1u; }

// Records the nearest occluder seen for `pixel` (light depth units; the hybrid blend reads it).
void note_occluder_gap(uint pixel, float gap) {
  if (!izb_flag(IZB_FLAG_GAPS)) return;
  uint bits = floatBitsToUint(max(gap, 0.0));
  // On a GPU an atomic whose result goes unread is sent without waiting for it, where a load first
  // holds each occluding pair on a round trip to memory (H200, 4K, canopy: the hybrid's trace pairs
  // step 0.180 -> 0.118 ms, `izb+csm`'s 0.107). On a CPU device the load spares most atomics.
  if (!izb_flag(IZB_FLAG_CPU_DEVICE)) atomicMin(occluder_distance[pixel], bits);
  else if (bits < occluder_distance[pixel]) atomicMin(occluder_distance[pixel], bits);
}

// A pair that left `pixel` lit: the tangent shadows_point saw, kept against the pixel's others (a gap
// found by any pair outranks them all: kIzbLitTangentBit).
void record_lit_tangent(uint pixel) {
  if (izb_flag(IZB_FLAG_GAPS) && lit_tangent_seen < params.penumbra.x)
    atomicMin(occluder_distance[pixel], kIzbLitTangentBit | floatBitsToUint(lit_tangent_seen));
}

// A caster triangle in grid space, transformed once per frame by izb_triangles.comp: every trace
// (raster, compute, fallback) reads the same floats, so their answers agree bit for bit.
void load_grid_triangle(uint t, out vec3 a, out vec3 b, out vec3 c) {
  a = grid_triangles[3u * t].xyz;
  b = grid_triangles[3u * t + 1u].xyz;
  c = grid_triangles[3u * t + 2u].xyz;
}

// How far inside the triangle the rectangle [lo, hi] reaches: over the three edges, the least of the
// distances (positive inward) of the rectangle's corner deepest inside that edge.
float rect_depth_inside(vec2 lo, vec2 hi, vec3 a, vec3 b, vec3 c, float orientation) {
  vec2 p[3] = vec2[3](a.xy, b.xy, c.xy);
  float least = 1.0e30;
  for (int i = 0; i < 3; ++i) {
    vec2 e0 = p[i];
    vec2 e1 = p[(i + 1) % 3];
    float best = -1.0e30;
    best = max(best, orientation * edge_fn(vec2(lo.x, lo.y), e0, e1));
    best = max(best, orientation * edge_fn(vec2(hi.x, lo.y), e0, e1));
    best = max(best, orientation * edge_fn(vec2(lo.x, hi.y), e0, e1));
    best = max(best, orientation * edge_fn(vec2(hi.x, hi.y), e0, e1));
    least = min(least, best / length(e1 - e0));
  }
  return least;
}

// Separating-axis test of the rectangle [lo, hi] against the triangle, inclusive, widened by `slack`
// texels.
bool rect_touches_triangle_within(vec2 lo, vec2 hi, vec3 a, vec3 b, vec3 c, float orientation, float slack) {
  vec2 tmin = min(min(a.xy, b.xy), c.xy);
  vec2 tmax = max(max(a.xy, b.xy), c.xy);
  if (any(lessThan(tmax, lo - slack)) || any(greaterThan(tmin, hi + slack))) return false;
  return rect_depth_inside(lo, hi, a, b, c, orientation) >= -slack;
}

// The traces' touch test: a little slack so a sample exactly on a texel border is never lost.
bool rect_touches_triangle(vec2 lo, vec2 hi, vec3 a, vec3 b, vec3 c, float orientation) {
  return rect_touches_triangle_within(lo, hi, a, b, c, orientation, 1.0e-3);
}

// A lower bound of the triangle's light depth over the rectangle [lo, hi]: its plane's minimum over
// the corners, never below its nearest vertex, less a rounding margin; clamped to [0,1] as the raster
// trace's depth clamp does.
// The triangle's depth slopes (d depth / dx, d depth / dy) in grid space; `area` from edge_fn(c, a, b).
vec2 plane_slopes(vec3 a, vec3 b, vec3 c, float area) {
  return vec2((b.z - a.z) * (c.y - a.y) - (c.z - a.z) * (b.y - a.y),
              (c.z - a.z) * (b.x - a.x) - (b.z - a.z) * (c.x - a.x)) / area;
}

float triangle_nearest_depth(vec2 lo, vec2 hi, vec3 a, vec3 b, vec3 c, float area) {
  vec2 slope = plane_slopes(a, b, c, area);
  float dzdx = slope.x, dzdy = slope.y;
  vec2 corner = vec2(dzdx >= 0.0 ? lo.x : hi.x, dzdy >= 0.0 ? lo.y : hi.y);
  float plane = a.z + dzdx * (corner.x - a.x) + dzdy * (corner.y - a.y);
  float nearest = max(plane, min(min(a.z, b.z), c.z));
  return clamp(nearest - 1.0e-6 - 1.0e-6 * abs(nearest), 0.0, 1.0);
}

// The lit map, the dual of the CSM: per texel a depth no farther from the light than any caster
// triangle (alpha-tested ones too: a hole only lets more light through) over any point of the texel
// where the node test could find the triangle. A point in the texel no farther than that is shadowed
// by nothing (the node test shadows only where the triangle is strictly nearer): lit, without a node.
// It must hold for the node test's float arithmetic, not only for exact geometry, so each triangle
//  - widens its footprint by lit_slack() texels: the node test's barycentrics are off by about 8 units
//    of rounding times the distance to a vertex (a triangle's extent, plus a μQuad's at 32 spp), and
//    a 32 spp sample's texel comes from a float blend of its corners (rounding ~ resolution);
//  - takes its plane's minimum over the widened texel, never below its nearest vertex, less the depth
//    those barycentric errors can move the node test's depth: error / least height * sum |depth|,
//    plus a relative margin for the interpolation's own rounding.
// Depths are stored as ordered bits (negative depths too: unlike the CSM, clamping to [0,1] would not
// be on the safe side) so atomicMin takes the nearest.
uint lit_map_index(uint texel) { return izb_resolution() * izb_resolution() + texel; }
uint ordered_depth_bits(float d) {
  uint b = floatBitsToUint(d);
  return (b & 0x80000000u) != 0u ? ~b : (b | 0x80000000u);
}
float ordered_depth(uint bits) {
  return uintBitsToFloat((bits & 0x80000000u) != 0u ? (bits & 0x7fffffffu) : ~bits);
}
// The lit map's word at `index` of IZB_BINDING_CSM_TEXELS, or four from a multiple of four (a tile
// record's half), read through the texel buffer view where IZB_FLAG_LIT_FETCH says so.
uint lit_word(uint index) { return izb_flag(IZB_FLAG_LIT_FETCH) ? texelFetch(lit_words, int(index)).r : csm_texels[index]; }
uvec4 lit_words4(uint index) {
  if (!izb_flag(IZB_FLAG_LIT_FETCH)) return lit_tile_words[index / 4u];
  return uvec4(lit_word(index), lit_word(index + 1u), lit_word(index + 2u), lit_word(index + 3u));
}
// Lowers the CSM's or lit map's word at `index` to `bits` (an order-preserving encoding); the read
// first, since most writes would not lower it. The words only fall, so a read that misses a write of
// this pass (the texel view's may) costs at most an atomic that changes nothing.
void lower_stored_bits(uint index, uint bits) {
  if (bits < lit_word(index)) atomicMin(csm_texels[index], bits);
}
float lit_quad_reach() { return izb_samples() == 32u ? kIzbLitQuadReach : 0.0; }
// A bound of the triangle's extent (sum of its bounds' sides: at least any edge, at least the distance
// between any two of its points).
float triangle_extent(vec3 a, vec3 b, vec3 c) {
  vec2 e = max(max(a.xy, b.xy), c.xy) - min(min(a.xy, b.xy), c.xy);
  return e.x + e.y;
}
float lit_slack(vec3 a, vec3 b, vec3 c) {
  return 1.0e-3 + 2.0e-6 * (triangle_extent(a, b, c) + lit_quad_reach() + 2.0) + 5.0e-7 * float(izb_resolution());
}
// The depth the node test's barycentric rounding can move the triangle's interpolated depth.
float lit_barycentric_rounding(vec3 a, vec3 b, vec3 c, float area) {
  float extent = triangle_extent(a, b, c);
  // |area| / extent is at most the triangle's least height.
  float barycentric_error = 2.0e-6 * (extent + lit_quad_reach() + 2.0) * extent / abs(area);
  return barycentric_error * (abs(a.z) + abs(b.z) + abs(c.z));
}
float lit_nearest_depth(vec2 lo, vec2 hi, vec3 a, vec3 b, vec3 c, float area, float slack) {
  vec2 slope = plane_slopes(a, b, c, area);
  float dzdx = slope.x, dzdy = slope.y;
  vec2 corner = vec2(dzdx >= 0.0 ? lo.x - slack : hi.x + slack, dzdy >= 0.0 ? lo.y - slack : hi.y + slack);
  float plane = a.z + dzdx * (corner.x - a.x) + dzdy * (corner.y - a.y);
  float nearest = max(plane, min(min(a.z, b.z), c.z));
  float bound = nearest - 1.0e-6 - 1.0e-6 * abs(nearest) - lit_barycentric_rounding(a, b, c, area);
  // A near-degenerate triangle's arithmetic may overflow (inf, or NaN from inf * 0): then no bound.
  return abs(bound) < 3.0e38 ? bound : -3.0e38;
}
// The lit map's second half, its planes: per texel corner (a (res+1)² grid after the two texel
// maps) a depth no farther than the plane of any caster touching a texel at that corner, evaluated at
// the corner. A plane is affine, so its value at a point of the texel is the bilinear blend of its
// values at the four corners, and the blend of the corners' minimums bounds every touching caster's
// plane there, not only its nearest point over the whole texel. That proves lit the points of a
// receiver that is itself a caster (a floor): its own plane passes through them, and the shadow-ray
// offset lifts them in front of it, where no texel-wide bound reaches.
uint lit_corner_index(ivec2 corner) {
  return 2u * izb_resolution() * izb_resolution() + uint(corner.y) * (izb_resolution() + 1u) + uint(corner.x);
}
// The triangle's plane as the lit map's corners bound it (lit_plane, lower_lit_corner).
struct LitPlane {
  float dzdx, dzdy;                    // plane_slopes
  float slope_error_x, slope_error_y;  // their rounding, per texel of run
  float rounding;                      // lit_barycentric_rounding
};
LitPlane lit_plane(vec3 a, vec3 b, vec3 c, float area) {
  LitPlane q;
  vec2 slope = plane_slopes(a, b, c, area);
  q.dzdx = slope.x;
  q.dzdy = slope.y;
  q.slope_error_x = 1.0e-6 * (abs((b.z - a.z) * (c.y - a.y)) + abs((c.z - a.z) * (b.y - a.y))) / abs(area);
  q.slope_error_y = 1.0e-6 * (abs((c.z - a.z) * (b.x - a.x)) + abs((b.z - a.z) * (c.x - a.x))) / abs(area);
  q.rounding = lit_barycentric_rounding(a, b, c, area);
  return q;
}
// Lowers the bound at `index` to a lower bound of the triangle's plane at `point` as the node test
// computes depths (the same margins as lit_nearest_depth, plus the rounding of the plane's own
// evaluation, and of its slopes, whose numerators cancel for a triangle nearly edge-on).
void lower_lit_plane_at(vec2 point, uint index, vec3 a, LitPlane q) {
  vec2 run = abs(point - a.xy);
  float plane = a.z + q.dzdx * (point.x - a.x) + q.dzdy * (point.y - a.y);
  float bound = plane - 1.0e-6 - 1.0e-6 * (abs(plane) + abs(a.z) + abs(q.dzdx) * run.x + abs(q.dzdy) * run.y) -
                q.slope_error_x * run.x - q.slope_error_y * run.y - q.rounding;
  lower_stored_bits(index, ordered_depth_bits(abs(bound) < 3.0e38 ? bound : -3.0e38));
}
void lower_lit_corner(ivec2 corner, vec3 a, LitPlane q) { lower_lit_plane_at(vec2(corner), lit_corner_index(corner), a, q); }

// The lit map's tile level, after the texel corners: per tile of kIzbTile² texels a record of eight
// words (izb.h, izb_lit_tile_records_at), read in two loads: the least of its texels' bounds (below),
// its own bound, its own four corners' plane bounds (c00, c10, c01, c11), as the texel level's but
// over the tile. A caster triangle that covers a whole tile lowers the tile's (izb_tile_bin.comp)
// instead of its kIzbTile² texels and their corners. Any caster touching the tile would be sound there
// (its nearest point over the tile bounds it over each texel, and the blend of its plane from the
// tile's corners is the plane itself); the whole-tile test keeps at the texel level the casters that
// touch part of a tile, whose planes would otherwise bound the rest of it. A point is proved lit where
// both levels prove it, each against its own casters.
//
// The least of the tile's texels' bounds (lit_map_index) is lowered with them. A point no farther than
// it is proved at the texel level by its texel's bound without loading it: where a tile's texels hold
// no caster (open ground under the sun, its floor at the tile level) the texel level is answered from
// the small tile records (a CPU device otherwise waits on every pixel's load from the texels' megabytes).
const uint kLitTileLeast = 0u, kLitTileBound = 1u, kLitTileCorners = 2u;  // word offsets in the record
uint lit_tile_record(uvec2 tile) {
  return izb_lit_tile_records_at(izb_resolution()) + 8u * (tile.y * tiles_per_side() + tile.x);
}
// A tile corner's grid position (the last tiles end at the grid's edge).
vec2 lit_tile_corner_point(uvec2 corner) { return min(vec2(corner * kIzbTile), vec2(float(izb_resolution()))); }

// Lowers each of the four corners of `texel` (lower_lit_corner).
void lower_lit_corners(ivec2 texel, vec3 a, vec3 b, vec3 c, float area) {
  LitPlane q = lit_plane(a, b, c, area);
  for (int k = 0; k < 4; ++k) lower_lit_corner(texel + ivec2(k & 1, k >> 1), a, q);
}
// Whether `g` lies no farther than the bilinear blend of a cell's corners' plane bounds (`d`: c00,
// c10, c01, c11 over [lo, hi]; less that blend's own rounding). `texel_cell`: hi - lo is exactly 1, so
// the division that places g in the cell is left out (the same quotient; a CPU device pays for every
// division of every pixel).
bool lit_planes_prove(vec3 g, vec4 d, vec2 lo, vec2 hi, bool texel_cell) {
  vec2 f = clamp(texel_cell ? g.xy - lo : (g.xy - lo) / (hi - lo), vec2(0.0), vec2(1.0));
  float blend = mix(mix(d.x, d.y, f.x), mix(d.z, d.w, f.x), f.y);
  float largest = max(max(abs(d.x), abs(d.y)), max(abs(d.z), abs(d.w)));
  return g.z <= blend - 1.0e-6 * largest;  // false for NaN (an empty corner: inf - inf)
}
// 32 spp: lit_planes_prove for every sample of a μQuad (a convex blend of its corners' grid points
// `g`, rounded) that lies in the cell [lo, hi], from the corners alone. Over the cell the blend is its
// affine part L (through c00, c10 and c01) plus the twist c00 - c10 - c01 + c11 times f.x f.y, so at
// least L + min(twist, 0) (zero twist: the four corners on one caster's plane). Depth less L is affine,
// so a sample's lies below the largest of the corners' (L extended past the cell), up to the rounding
// of the sample's blend and of L: the margin.
bool lit_planes_prove_quad(vec3 g[4], vec4 d, vec2 lo, vec2 hi, bool texel_cell) {
  vec2 scale = texel_cell ? vec2(1.0) : 1.0 / (hi - lo);
  vec2 slope = vec2(d.y - d.x, d.z - d.x);  // per cell
  float farthest_above = -3.0e38, largest_z = 0.0, largest_f = 0.0;
  for (int i = 0; i < 4; ++i) {
    vec2 f = (g[i].xy - lo) * scale;
    farthest_above = max(farthest_above, g[i].z - (d.x + slope.x * f.x + slope.y * f.y));
    largest_z = max(largest_z, abs(g[i].z));
    largest_f = max(largest_f, max(abs(f.x), abs(f.y)));
  }
  float largest = max(max(abs(d.x), abs(d.y)), max(abs(d.z), abs(d.w)));
  float margin = 4.0e-6 * (largest * (1.0 + largest_f) + largest_z) + 1.0e-3 * (abs(slope.x) + abs(slope.y));
  return farthest_above <= min(d.x - d.y - d.z + d.w, 0.0) - margin;  // false for NaN (an empty corner)
}
// Whether the points `g` are proved lit in `texel` (inside the grid), at both levels, each by its
// bound or its corners' planes: with `quad` false the one point g[0] (the bounds compared with its
// depth, `z`); with `quad` true every sample of the μQuad with corners g that lies in the texel (the
// bounds compared with `z`, no nearer than any such sample; the planes by lit_planes_prove_quad).
// Each load waits until the tests before it have failed (a CPU device then loads for fewer lanes).
bool lit_map_proves_lit_in(ivec2 texel, vec3 g[4], float z, bool quad) {
  uvec2 tile = uvec2(texel) / kIzbTile;
  uint record = lit_tile_record(tile);
  uvec4 head = lit_words4(record);  // least texel bound, tile bound, c00, c10
  if (!(z <= ordered_depth(head.x) || z <= ordered_depth(lit_word(lit_map_index(texel_index(texel)))))) {
    vec4 d = vec4(ordered_depth(lit_word(lit_corner_index(texel))),
                  ordered_depth(lit_word(lit_corner_index(texel + ivec2(1, 0)))),
                  ordered_depth(lit_word(lit_corner_index(texel + ivec2(0, 1)))),
                  ordered_depth(lit_word(lit_corner_index(texel + ivec2(1, 1)))));
    vec2 lo = vec2(texel), hi = vec2(texel + 1);
    if (!(quad ? lit_planes_prove_quad(g, d, lo, hi, true) : lit_planes_prove(g[0], d, lo, hi, true))) return false;
  }
  if (z <= ordered_depth(head.y)) return true;
  uvec2 tail = lit_words4(record + 4u).xy;  // c01, c11
  vec4 d = vec4(ordered_depth(head.z), ordered_depth(head.w), ordered_depth(tail.x), ordered_depth(tail.y));
  vec2 lo = lit_tile_corner_point(tile), hi = lit_tile_corner_point(tile + 1u);
  return quad ? lit_planes_prove_quad(g, d, lo, hi, false) : lit_planes_prove(g[0], d, lo, hi, false);
}
// Whether grid point `g` is proved lit: inside the grid (outside it the texel clamp would compare it
// with a texel that is not its own) and proved at both levels (lit_map_proves_lit_in).
bool lit_map_proves_lit(vec3 g) {
  if (!(all(greaterThanEqual(g.xy, vec2(0.0))) && all(lessThan(g.xy, vec2(float(izb_resolution())))))) return false;
  vec3 point[4] = vec3[4](g, g, g, g);
  return lit_map_proves_lit_in(grid_texel(g), point, g.z, false);
}

// IZB_FLAG_ANCHORED_NODES (izb.h): the texel whose node stands for a sample in `texel`, the lowest of
// its 2x2 block, the blocks counted from `first` (quad_texel_bounds: no sample's texel is below it).
bool anchored_nodes() { return izb_samples() == 32u && izb_flag(IZB_FLAG_ANCHORED_NODES); }
ivec2 node_anchor(ivec2 texel, ivec2 first) { return anchored_nodes() ? first + ((texel - first) & ~1) : texel; }
// Anchored nodes where every sample lies in the 2x2 block from `first` (quad_texel_bounds' [first,
// last]): the pixel's one node is in `first`.
bool single_anchor(ivec2 first, ivec2 last) { return anchored_nodes() && all(lessThanEqual(last - first, ivec2(1))); }

// The texels a candidate pixel's node goes into, from its grid point(s) `g` (1 spp: g[0]): 1 spp its
// point's texel; 32 spp every texel holding one of its samples not already `settled` (bits the CSM
// proved shadowed), since a triangle shadows a sample only if it covers the sample's texel, or with
// anchored nodes those texels' anchors (one, `first`, where the samples span at most 2x2 texels). In
// a fixed order; returns how many. (The build's own loop makes the same set.)
uint node_texels(vec3 g[4], uint settled, out uint texels[32]) {
  uint count = 0u;
  if (izb_samples() == 1u) {
    if (settled == 0u) texels[count++] = texel_index(grid_texel(g[0]));
    return count;
  }
  ivec2 first, last;
  quad_texel_bounds(g, first, last);
  if (single_anchor(first, last)) {
    if (settled != full_mask()) texels[count++] = texel_index(first);
    return count;
  }
  for (uint s = 0u; s < 32u; ++s) {
    if ((settled & (1u << s)) != 0u) continue;
    uint t = texel_index(node_anchor(grid_texel(micro_quad_blend(g[0], g[1], g[2], g[3], kSamplePattern[s])), first));
    bool seen = false;
    for (uint k = 0u; k < count; ++k) seen = seen || texels[k] == t;
    if (!seen) texels[count++] = t;
  }
  return count;
}

bool sorted_lists() { return izb_flag(IZB_FLAG_SORTED_LISTS); }

// Nodes in a texel's list, counting at most `cap`.
uint list_length(uint texel, uint cap) {
  if (sorted_lists()) return min(list_counts[texel], cap);
  uint length = 0u;
  for (uint node = heads[texel]; node != kIzbEndOfList && length < cap; node = nodes[node].x) ++length;
  return length;
}

// IZB_FLAG_DIRECT_TERM: the pixel (row-major index) is shadowed; at 1 spp its one sample is all of it.
void write_shadowed_term(uint pixel) {
  imageStore(shadow_term, ivec2(pixel % params.extent.x, pixel / params.extent.x), vec4(0.0));
}

// Tests the triangle against one node's pixel and ORs its shadowed samples into the pixel's mask;
// false when skipped (progressive removal of a fully shadowed pixel).
bool trace_node(uint pixel, CasterAlpha ca, vec3 a, vec3 b, vec3 c, float inv_area) {
  if (izb_flag(IZB_FLAG_DIRECT_TERM) && !izb_flag(IZB_FLAG_PROGRESSIVE)) {
    // The term (and the hybrid's occluder distance) is all that is read afterwards, and darkening it
    // again is harmless: no mask.
    float gap = 1.0e30;
    lit_tangent_seen = 3.0e38;
    if (occluded_samples(pixel, ca, a, b, c, inv_area, gap) != 0u) {
      write_shadowed_term(pixel);
      note_occluder_gap(pixel, gap);
    } else {
      record_lit_tangent(pixel);
    }
    return true;
  }
  // The point(s) load beside the mask, not after its test: one round trip to memory, not two.
  NodePoints points = load_node_points(pixel);
  uint current = visibility_mask[pixel];
  if (izb_flag(IZB_FLAG_PROGRESSIVE) && current == full_mask()) return false;
  float gap = 1.0e30;
  lit_tangent_seen = 3.0e38;
  uint bits = occluded_samples_of(points, ca, a, b, c, inv_area, gap);
  if (bits == 0u) record_lit_tangent(pixel);
  if ((bits & ~current) != 0u) {
    atomicOr(visibility_mask[pixel], bits);
    if (izb_flag(IZB_FLAG_DIRECT_TERM)) write_shadowed_term(pixel);
  }
  if (bits != 0u) note_occluder_gap(pixel, gap);
  return true;
}

// The trace's inner loop, shared by the raster and compute traces: tests the triangle against every
// node in the texel's list. Returns the tests made.
uint trace_texel_list(uint texel, uint triangle, vec3 a, vec3 b, vec3 c, float inv_area) {
  uint tests = 0u;
  CasterAlpha ca = load_caster_alpha(triangle);
  if (sorted_lists()) {
    for (uint i = heads[texel], end = i + list_counts[texel]; i < end; ++i)
      tests += trace_node(nodes[i].y, ca, a, b, c, inv_area) ? 1u : 0u;
    return tests;
  }
  if (izb_flag(IZB_FLAG_DIRECT_NODES)) {
    // A node's index is its pixel's: the pixel's point loads beside the next link, not after it.
    for (uint node = heads[texel]; node != kIzbEndOfList;) {
      uint pixel = node;
      node = nodes[node].x;
      tests += trace_node(pixel, ca, a, b, c, inv_area) ? 1u : 0u;
    }
    return tests;
  }
  // The next node loads while this one is tested: a walk is otherwise a chain of dependent loads
  // (32 spp, Sponza v1 4K on an H200: with the early loads of trace_node, the trace's pairs step
  // 0.286 -> 0.265 ms).
  uint node = heads[texel];
  if (node == kIzbEndOfList) return 0u;
  uvec2 n = nodes[node];
  for (;;) {
    uvec2 following = n.x != kIzbEndOfList ? nodes[n.x] : uvec2(kIzbEndOfList, 0u);
    tests += trace_node(n.y, ca, a, b, c, inv_area) ? 1u : 0u;
    if (n.x == kIzbEndOfList) break;
    n = following;
  }
  return tests;
}
