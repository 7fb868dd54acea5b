#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_pixel.glsl"
// 64 invocations a workgroup, 8x8 or a row of 64 pixels (IzbPipelineCache::with_pixel_group).
layout(local_size_x = 8, local_size_y = 8, local_size_x_id = 20, local_size_y_id = 21) in;

layout(push_constant) uniform Push { IzbComputePush push; };
#include "shadows/izb_straddlers.glsl"
layout(set = 0, binding = IZB_BINDING_CSM_DEPTH) uniform sampler2D csm_depth;

// IZB_FLAG_ROW_RUNS: the workgroup's texels (none: 0xffffffff), node depths and the list heads its
// runs replaced (see main).
shared uint run_texel[8 * 8];
shared uint run_depth_bits[8 * 8];
shared uint run_old_head[8 * 8];

// Depths are clamped into [0,1], where float order is bit order: the texels' buffer copies straight
// into the raster trace's depth attachment.
uint depth_bits(float depth) { return floatBitsToUint(clamp(depth, 0.0, 1.0)); }
uint tile_of(uint texel) {
  uint res = izb_resolution();
  return (texel / res / kIzbTile) * tiles_per_side() + (texel % res) / kIzbTile;
}
// Raises a texel's farthest node depth and its tile's.
void raise_farthest(uint texel, float depth) {
  uint bits = depth_bits(depth);
  if (bits > farthest[texel]) atomicMax(farthest[texel], bits);  // most nodes are not their texel's farthest
  if (!izb_flag(IZB_FLAG_TILE_FARTHEST)) return;
  uint tile = tile_of(texel);
  uint slot = tile_farthest_index(tile);
  if (bits > farthest[slot]) atomicMax(farthest[slot], bits);
}
// 1 spp: every lane of the subgroup together (`has`: the lane's pixel has a node in `texel`). The
// lanes' pixels neighbour one another, so mostly one tile takes one atomic (on a GPU; a CPU device
// takes the lanes' atomics, IZB_FLAG_CPU_DEVICE).
void raise_tiles_farthest(uint texel, float depth, bool has) {
  if (!izb_flag(IZB_FLAG_TILE_FARTHEST)) return;
  uint tile = has ? tile_of(texel) : 0xffffffffu;
  uint bits = has ? depth_bits(depth) : 0u;
  uint slot = tile_farthest_index(tile);  // (read only where `has`)
  if (!izb_flag(IZB_FLAG_CPU_DEVICE) && subgroupMin(tile) == subgroupMax(tile)) {  // (arithmetic subgroup operations only)
    uint highest = subgroupMax(bits);
    if (subgroupElect() && has && highest > farthest[slot]) atomicMax(farthest[slot], highest);
  } else if (has && bits > farthest[slot]) {
    atomicMax(farthest[slot], bits);
  }
}

// The CSM holds, where one triangle fully covers a texel, a depth no nearer the light than that
// triangle anywhere over the texel: a point beyond it (plus the shared offset already in `g`) is
// certainly shadowed.
float csm_stored_depth(ivec2 texel) {
  return izb_flag(IZB_FLAG_CSM_BUFFER) ? uintBitsToFloat(csm_texels[texel_index(texel)]) : texelFetch(csm_depth, texel, 0).r;
}
bool csm_proves_shadowed_in(vec3 g, ivec2 texel) { return izb_flag(IZB_FLAG_CSM) && g.z > csm_stored_depth(texel); }
bool csm_proves_shadowed(vec3 g) { return csm_proves_shadowed_in(g, grid_texel(g)); }

// micro_quad_blend's x and y, and its z: it blends each component on its own, so these are its bits.
vec2 micro_quad_blend_xy(vec3 g[4], vec2 offset) {
  precise vec2 xy = (g[0].xy * (1.0 - offset.x) + g[1].xy * offset.x) * (1.0 - offset.y) +
                    (g[2].xy * (1.0 - offset.x) + g[3].xy * offset.x) * offset.y;
  return xy;
}
float micro_quad_blend_z(vec3 g[4], vec2 offset) {
  precise float z = (g[0].z * (1.0 - offset.x) + g[1].z * offset.x) * (1.0 - offset.y) +
                    (g[2].z * (1.0 - offset.x) + g[3].z * offset.x) * offset.y;
  return z;
}

// 32 spp: the CSM's verdict on all of a μQuad's samples at once, where its corners' bounds, widened
// past any rounding of a sample's blend, span at most 2x2 texels: kCsmAllShadowed if even its nearest
// corner lies beyond every one of those texels' depths, kCsmNoneShadowed if even its farthest lies in
// front of all of them, else kCsmPerSample. Each sample, a convex blend of the corners in its own
// texel, would decide the same (so most shadowed pixels take four fetches, not 32).
const uint kCsmPerSample = 0u;
const uint kCsmAllShadowed = 1u;
const uint kCsmNoneShadowed = 2u;
uint csm_quad_verdict(vec3 g[4], ivec2 first, ivec2 last) {
  if (!izb_flag(IZB_FLAG_CSM)) return kCsmNoneShadowed;
  if (any(greaterThan(last - first, ivec2(1)))) return kCsmPerSample;
  float nearest = 1.0e30, farthest = -1.0e30;
  for (int k = 0; k < 4; ++k) {
    float stored = csm_stored_depth(min(first + ivec2(k & 1, k >> 1), last));
    nearest = min(nearest, stored);
    farthest = max(farthest, stored);
  }
  float z_lowest = min(min(g[0].z, g[1].z), min(g[2].z, g[3].z));
  float z_highest = max(max(g[0].z, g[1].z), max(g[2].z, g[3].z));
  float slack = 1.0e-5 * (1.0 + max(abs(z_lowest), abs(z_highest)));  // the same for depth
  if (z_lowest - slack > farthest) return kCsmAllShadowed;
  if (z_highest + slack <= nearest) return kCsmNoneShadowed;
  return kCsmPerSample;
}

// 32 spp: whether every sample of a μQuad is proved lit (lit_map_proves_lit), for a μQuad whose texels
// [first, last] (quad_texel_bounds) span at most 2x2 texels; false unless its samples all lie inside
// the grid. Each texel's bounds and planes are tested once for all the samples in it
// (lit_map_proves_lit_in), against the farthest corner's depth widened past a blend's rounding (as
// csm_quad_verdict's). So at most four texels' words, not 32 samples' proofs one after another.
bool lit_quad_verdict(vec3 g[4], ivec2 first, ivec2 last) {
  vec2 lo, hi;
  quad_sample_bounds(g, lo, hi);
  if (any(lessThan(lo, vec2(0.0))) || any(greaterThanEqual(hi, vec2(float(izb_resolution()))))) return false;
  float z_highest = max(max(g[0].z, g[1].z), max(g[2].z, g[3].z));
  float z = z_highest + 1.0e-5 * (1.0 + abs(z_highest));
  bool lit = true;
  for (int k = 0; k < 4; ++k) {
    ivec2 texel = first + ivec2(k & 1, k >> 1);
    if (lit && all(lessThanEqual(texel, last))) lit = lit_map_proves_lit_in(texel, g, z, true);
  }
  return lit;
}

// 32 spp: a pixel's node texels as bits of the kSampleWindow x kSampleWindow texels from `origin` (bit
// x + kSampleWindow * y), which holds every sample of a μQuad up to about two texels wide; the list
// node_texels makes (local memory) only for a sample outside it.
const int kSampleWindow = 4;
ivec2 sample_window_origin(vec3 g[4]) {
  vec2 lowest = min(min(g[0].xy, g[1].xy), min(g[2].xy, g[3].xy));
  return max(grid_texel(vec3(lowest, 0.0)) - 1, ivec2(0));  // a blend may round across a texel border
}
uint sample_window_bit(ivec2 origin, ivec2 texel, inout bool outside) {
  ivec2 offset = texel - origin;
  if (any(lessThan(offset, ivec2(0))) || any(greaterThanEqual(offset, ivec2(kSampleWindow)))) {
    outside = true;
    return 0u;
  }
  return 1u << uint(offset.x + kSampleWindow * offset.y);
}
// The lowest texel left in `cells` (sample_window_bit's bits), which it clears.
uint take_window_texel(ivec2 origin, inout uint cells) {
  int cell = findLSB(cells);
  cells &= cells - 1u;
  return texel_index(origin + ivec2(cell % kSampleWindow, cell / kSampleWindow));
}

// A CPU device with one node a pixel and a listed resolve builds in two steps, specialized apart (it
// runs every branch of a shader): kBuildClassify, over the frame, classifies every pixel, settles
// those without a node, and lists the others with their grid points and states; kBuildInsert, over
// that list, inserts their nodes from what the first step stored (not classifying again, so both
// steps agree whatever the compiler makes of the arithmetic). kBuildWhole does both at once.
const uint kBuildWhole = 0u;
const uint kBuildClassify = 1u;
const uint kBuildInsert = 2u;
layout(constant_id = 14) const uint kBuildStep = kBuildWhole;

// kBuildInsert: one listed pixel a thread.
void insert_listed_node() {
  uint index;
  if (!listed_pixel(index)) return;
  vec3 g = quad_point(index, 0u);
  uint texel = texel_index(grid_texel(g));
  nodes[index] = uvec2(atomicExchange(heads[texel], index), index);
  raise_farthest(texel, g.z);
  // What the whole build leaves for a pixel with a node: no sample settled.
  visibility_mask[index] = 0u;
}

void main() {
  if (kBuildStep == kBuildInsert) {
    insert_listed_node();
    return;
  }
  const bool inserts = kBuildStep != kBuildClassify;
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (izb_flag(IZB_FLAG_FACE_TILES) && !face_tile_pixel(pixel)) return;
  bool inside = all(lessThan(uvec2(pixel), params.extent.xy));
  uint covered = 0u, candidate = 0u, culled = 0u, lit_culled = 0u;
  uint index = uint(pixel.y) * params.extent.x + uint(pixel.x);
  uint state = 0u;
  uint mask = 0u;  // samples the CSM settled (shadowed)
  uint texels[32];  // 32 spp, only for a sample outside the window
  ivec2 window = ivec2(0);
  uint window_cells = 0u;  // the window's texels holding samples the CSM did not settle
  bool outside_window = false;
  ivec2 first = ivec2(0), last = ivec2(-1);  // 32 spp: the texels the μQuad's samples lie in (quad_texel_bounds)
  uint texel0 = 0u;
  uint count = 0u;
  float node_depth = 0.0;
  vec3 position = vec3(0.0);
  if (inside) {
    PixelPoint p = load_pixel(pixel);
    position = p.position;
    covered = p.covered ? 1u : 0u;
    if (p.covered) {
      state = IZB_PIXEL_COVERED | (p.facing ? IZB_PIXEL_FACING : 0u);
      if (outside_light_face(p.position)) state |= IZB_PIXEL_OTHER_FACE;
      if (distance(p.position, params.camera_position.xyz) > izb_reach()) state |= IZB_PIXEL_BEYOND;
    }
    if (p.candidate) {
      candidate = 1u;
      state |= IZB_PIXEL_CANDIDATE;
      vec3 g[4];
      if (izb_samples() == 1u) {
        g[0] = to_grid(shadow_ray_origin(p.position, p.normal, izb_ray_offset(p.position)));
        node_depth = g[0].z;
        if (csm_proves_shadowed(g[0])) mask = 1u;
      } else {
        vec3 c[4];
        micro_quad_corners(pixel, p, c);
        node_depth = -1.0e30;
        for (int i = 0; i < 4; ++i) {
          g[i] = to_grid(c[i]);
          node_depth = max(node_depth, g[i].z);
        }
        // The CSM's verdict on the whole quad, else each sample's point and texel once, for the CSM
        // and for the node's texels.
        window = sample_window_origin(g);
        quad_texel_bounds(g, first, last);
        uint verdict = csm_quad_verdict(g, first, last);
        // Anchored nodes (node_anchor): samples within 2x2 texels take one node, in `first`, whichever
        // of the four hold them (so no sample's texel is needed unless the CSM tests it).
        bool one_anchor = single_anchor(first, last);
        if (verdict == kCsmAllShadowed) {
          mask = full_mask();
        } else if (verdict == kCsmNoneShadowed && (first == last || one_anchor)) {
          // Every sample in one texel, or (one_anchor) in the 2x2 block from it.
          window_cells = sample_window_bit(window, first, outside_window);
        } else {
          for (uint s = 0u; s < 32u; ++s) {
            // A sample's depth only where the CSM tests it one by one.
            vec2 q = micro_quad_blend_xy(g, kSamplePattern[s]);
            ivec2 texel = grid_texel(vec3(q, 0.0));
            bool shadowed = false;
            if (verdict == kCsmPerSample)
              shadowed = csm_proves_shadowed_in(vec3(q, micro_quad_blend_z(g, kSamplePattern[s])), texel);
            if (shadowed)
              mask |= 1u << s;
            else if (!one_anchor)  // (one_anchor: its one cell is set below)
              window_cells |= sample_window_bit(window, node_anchor(texel, first), outside_window);
          }
        }
        if (one_anchor) window_cells = mask != full_mask() ? sample_window_bit(window, first, outside_window) : 0u;
      }
      if (mask == full_mask()) {
        state |= IZB_PIXEL_CSM_CULLED;
        culled = 1u;
      }
      // A local light's direct term: a caster across its near plane (which the grid leaves out)
      // shadows the point here, so it needs no node and no resolve follows. (Not the CSM's count.)
      if (izb_flag(IZB_FLAG_DIRECT_TERM) && spot_light() && mask == 0u && straddler_samples(pixel, p) != 0u) mask = 1u;
      // Lit culling (izb_common.glsl): every sample no farther than its texel's nearest caster is lit,
      // so the pixel needs no node; its mask stays 0 and its occluder distance unset, as the trace
      // would leave them. Only pixels the CSM settled nothing of: a partly shadowed pixel keeps its
      // nodes, through which the trace also finds its occluder distance.
      bool lit = false;
      if (izb_flag(IZB_FLAG_LIT) && mask == 0u) {
        if (izb_samples() == 1u) {
          lit = lit_map_proves_lit(g[0]);
        } else if (all(lessThanEqual(last - first, ivec2(1)))) {
          lit = lit_quad_verdict(g, first, last);
        } else {
          // A wider μQuad (grazing): sample by sample.
          vec2 qmin = min(min(g[0].xy, g[1].xy), min(g[2].xy, g[3].xy));
          vec2 qmax = max(max(g[0].xy, g[1].xy), max(g[2].xy, g[3].xy));
          lit = all(lessThanEqual(qmax - qmin, vec2(kIzbLitQuadReach)));
          for (uint s = 0u; s < 32u && lit; ++s)
            lit = lit_map_proves_lit(micro_quad_blend(g[0], g[1], g[2], g[3], kSamplePattern[s]));
        }
        if (lit) {
          state |= IZB_PIXEL_LIT_CULLED;
          lit_culled = 1u;
        }
      }
      // 1 spp keeps its one texel in a register (texels[] is local memory, used at 32 spp).
      if (izb_samples() == 1u) {
        count = mask == 0u && !lit ? 1u : 0u;
        texel0 = texel_index(grid_texel(g[0]));
      } else {
        count = lit ? 0u : outside_window ? node_texels(g, mask, texels) : bitCount(window_cells);
      }
      // Only a pixel with nodes is read again (by the trace, and the sorted lists' scatter).
      if (count != 0u) {  // (quad_point's layout, in whole vec4s)
        if (izb_samples() == 1u) {
          quad_vectors[index] = vec4(g[0], 0.0);
        } else {
          quad_vectors[3u * index] = vec4(g[0], g[1].x);
          quad_vectors[3u * index + 1u] = vec4(g[1].yz, g[2].xy);
          quad_vectors[3u * index + 2u] = vec4(g[2].z, g[3]);
        }
      }
    }
  }
  uint refused = 0u;  // nodes past the pool
  if (izb_flag(IZB_FLAG_DIRECT_NODES) && !inserts) {
    // kBuildClassify: the nodes are kBuildInsert's; the statistics count them here.
    if (izb_flag(IZB_FLAG_STATS)) {
      uint requested = subgroupAdd(count);
      if (subgroupElect() && requested > 0u) atomicAdd(counters[IZB_COUNTER_NODES], requested);
    }
  } else if (izb_flag(IZB_FLAG_DIRECT_NODES)) {
    // A pixel has at most one node and the pool holds one per pixel: no allocation, no overflow (a
    // CPU device would otherwise run every atomic of the general path below for every pixel).
    if (izb_flag(IZB_FLAG_ROW_RUNS)) {
      // Neighbours along a row often share a texel: each run of them enters its list at once, heads ->
      // first -> ... -> last -> the old head, with one exchange and one raise (atomics on one address
      // serialize).
      const uint row = gl_WorkGroupSize.x;
      uint lane = gl_LocalInvocationIndex;
      uint x = gl_LocalInvocationID.x;
      uint key = count != 0u ? texel0 : 0xffffffffu;
      run_texel[lane] = key;
      run_depth_bits[lane] = depth_bits(node_depth);
      barrier();
      if (count != 0u && (x == 0u || run_texel[lane - 1u] != key)) {
        uint highest = run_depth_bits[lane];
        for (uint i = lane + 1u; i % row != 0u && run_texel[i] == key; ++i) highest = max(highest, run_depth_bits[i]);
        run_old_head[lane] = atomicExchange(heads[texel0], index);
        if (highest > farthest[texel0]) atomicMax(farthest[texel0], highest);
      }
      barrier();
      if (count != 0u) {
        uint next = index + 1u;  // the next pixel of the row (a node's index is its pixel's)
        if (x == row - 1u || run_texel[lane + 1u] != key) {
          uint first = lane;
          while (first % row != 0u && run_texel[first - 1u] == key) --first;
          next = run_old_head[first];
        }
        nodes[index] = uvec2(next, index);  // whole nodes: a half-written one costs more than its bytes
      }
    } else if (count != 0u) {
      nodes[index] = uvec2(atomicExchange(heads[texel0], index), index);
      uint bits = depth_bits(node_depth);
      if (bits > farthest[texel0]) atomicMax(farthest[texel0], bits);
    }
    raise_tiles_farthest(texel0, node_depth, count != 0u);
    if (izb_flag(IZB_FLAG_STATS)) {
      uint requested = subgroupAdd(count);
      if (subgroupElect() && requested > 0u) atomicAdd(counters[IZB_COUNTER_NODES], requested);
    }
  } else {
    // One atomic per subgroup reserves every lane's nodes. Every texel is requested even past the
    // pool, so the counter measures the true demand the pool is grown to.
    uint base = reserve_slots(IZB_COUNTER_NODES, count);
    if (sorted_lists()) {
      // Counting sort, step 1: count each texel's nodes (izb_scatter.comp places them after the
      // prefix sum). A pixel takes all its nodes or, past the pool, none.
      if (base + count <= params.limits.x) {
        for (uint k = 0u; k < count; ++k) {
          uint texel = izb_samples() == 1u ? texel0 : outside_window ? texels[k] : take_window_texel(window, window_cells);
          atomicAdd(list_counts[texel], 1u);
          raise_farthest(texel, node_depth);
        }
      } else {
        refused = count;
      }
    } else {
      for (uint k = 0u; k < count; ++k) {
        uint node = base + k;
        uint texel = izb_samples() == 1u ? texel0 : outside_window ? texels[k] : take_window_texel(window, window_cells);
        if (node >= params.limits.x) {
          ++refused;
          continue;
        }
        nodes[node] = uvec2(atomicExchange(heads[texel], node), index);
        raise_farthest(texel, node_depth);
      }
    }
  }
  if (inside) {
    if (refused > 0u) {
      // The fallback pass resolves this pixel exactly by testing every caster triangle.
      state |= IZB_PIXEL_OVERFLOW;
      atomicAdd(counters[IZB_COUNTER_OVERFLOW], refused);
      uint slot = atomicAdd(counters[IZB_COUNTER_OVERFLOW_PIXELS], 1u);
      overflow_pixels[slot] = index;
      atomicMax(counters[IZB_COUNTER_DISPATCH], slot / 64u + 1u);
    }
    // Only the resolve and the sorted lists' scatter read the state (a listed resolve: of the pixels
    // with nodes). With the term written here and in the trace, the mask is read only by the scatter,
    // the fallback (a pixel past the pool) and the progressive removal (a pixel with a node).
    bool direct_term = izb_flag(IZB_FLAG_DIRECT_TERM);
    bool listed_resolve = izb_flag(IZB_FLAG_LISTED_RESOLVE);
    if ((!direct_term && (!listed_resolve || count != 0u)) || sorted_lists())
      pixel_state[index] = state;
    // What izb_resolve.comp would write before the trace: candidates lit unless the CSM settled them,
    // surfaces facing away shadowed, the others lit; beyond the range the term already there stays.
    bool facing = (state & IZB_PIXEL_FACING) != 0u;
    // Every pixel's 1 or 0, so the term needs no fill before (IzbPass::writes_every_pixel; the trace
    // then darkens the shadowed). A point-light face leaves the other faces' points alone
    // (write_pixel_term).
    bool shadowed = covered != 0u && (candidate != 0u ? mask != 0u : !facing);
    if (direct_term && (state & IZB_PIXEL_OTHER_FACE) == 0u)
      imageStore(shadow_term, pixel, vec4(shadowed ? 0.0 : 1.0));
    bool mask_read = (!direct_term && !listed_resolve) || sorted_lists() ||
                     (count != 0u && (listed_resolve || izb_flag(IZB_FLAG_PROGRESSIVE) || !izb_flag(IZB_FLAG_DIRECT_NODES)));
    // (kBuildClassify: kBuildInsert writes them, for pixels with a node.)
    if (candidate != 0u && mask_read && inserts) visibility_mask[index] = mask;  // only candidates' are read
    // The penumbra pass reads every pixel's (a lit one's edge tangent too): none found yet (only the
    // trace and the fallback find one).
    if (izb_flag(IZB_FLAG_GAPS)) occluder_distance[index] = kIzbNoOccluder;
  }
  if (izb_flag(IZB_FLAG_LISTED_RESOLVE)) {
    // A pixel without a node is settled here (no occluder distance: only the trace finds one); the
    // others, the fallback's too, are the resolve's.
    bool written;
    write_pixel_term(pixel, inside && count == 0u, state, mask, position, izb_flag(IZB_FLAG_HYBRID), written);
    bool has_nodes = inside && count != 0u;
    uint slot = reserve_slots_raising(IZB_COUNTER_RESOLVE_LIST, has_nodes ? 1u : 0u, !izb_flag(IZB_FLAG_CPU_DEVICE),
                                      IZB_COUNTER_RESOLVE_LIST + 1u, params.extent.x * params.extent.y, 64u);
    if (has_nodes) resolve_list[slot] = index;
  }
  // Counts for the statistics and for the adaptive CSM's yield: skipped in a frame that needs neither.
  if (!izb_flag(IZB_FLAG_STATS) && !izb_flag(IZB_FLAG_CSM)) return;
  uint seed = IZB_SHARD_SEED;
  add_sharded(IZB_COUNTER_SHADING_POINTS, covered, seed);
  add_sharded(IZB_COUNTER_CANDIDATES, candidate, seed);
  add_sharded(IZB_COUNTER_CSM_CULLED, culled, seed);
  if (izb_flag(IZB_FLAG_LIT)) add_sharded(IZB_COUNTER_LIT_CULLED, lit_culled, seed);
}
