#version 460
#extension GL_GOOGLE_include_directive : require
#include "cascades.h"
#include "shadows.h"
layout(local_size_x = 8, local_size_y = 8) in;

// Three pipelines: kNeighbourhoods 0 builds each mask texel from the depth map; 1 then combines each
// texel with its right, lower and lower-right neighbours, so the filter reads one entry whatever the
// (at most 2x2) mask texels its kernel covers. 2 (CASCADE_MASKING_PLANES, whose mask level is that of
// kSmBlock² texels) builds each block's plane (depth_blocks.glsl) into the neighbourhoods' buffer.
layout(constant_id = 0) const uint kNeighbourhoods = 0u;

layout(push_constant) uniform Push { CascadeMaskPush push; };
layout(set = 0, binding = CASCADE_MASK_BINDING_PARAMS) uniform Params { CascadeParams params; };
layout(set = 0, binding = CASCADE_MASK_BINDING_DEPTH) uniform sampler2DArray depth_map;
// Per mask texel of the cascade's rectangle, in rows of its width from params.mask_offset[cascade]:
// x edge flag, y packed depth extent.
layout(set = 0, binding = CASCADE_MASK_BINDING_MASKS) buffer Masks { uvec2 masks[]; };
// Four entries per mask texel, for the texels lo..hi with hi - lo = (k & 1, k >> 1): x whether any is
// an edge, y the union of their depth extents.
layout(set = 0, binding = CASCADE_MASK_BINDING_NEIGHBOURHOODS) writeonly buffer Neighbourhoods { uvec2 neighbourhoods[]; };
// The same buffer a block's plane an entry (kNeighbourhoods 2).
layout(set = 0, binding = CASCADE_MASK_BINDING_NEIGHBOURHOODS) writeonly buffer Planes { vec4 planes[]; };

float depth_block_texel(ivec2 texel) { return texelFetch(depth_map, ivec3(texel, int(push.cascade)), 0).r; }
#define DEPTH_BLOCKS_FIT
#include "depth_blocks.glsl"

// One cascade's masks at the only level the filter reads (mask_level), straight from the depth map.
// A map texel is an edge when any 3x3 neighbour's depth differs by more than a slope of two texels
// per texel could explain (both sides of a step are flagged); a mask texel is an edge when any map
// texel of its footprint is. Its depth extent is the [min, max] over the footprint plus a one-texel
// border, i.e. the union of every footprint texel's 3x3 range. Footprint + border is read once, in
// 2x2 gathers (a quarter of the lookups), as strips of two rows: every adjacent pair is compared once
// and counts when either end lies in the footprint. Clamping at the map's border only repeats
// adjacent texels, so the result equals the per-texel 3x3 definition exactly.
const int kMaxRow = (2 << CASCADE_MASK_MAX_LEVEL) + 2;

uint mask_index(int c, ivec2 id) { return cascade_mask_entry(params.mask_rect[c], params.mask_offset[c], id); }

uvec2 combine(uvec2 a, uvec2 b) {
  return uvec2(a.x | b.x, (min(a.y >> 16u, b.y >> 16u) << 16u) | max(a.y & 0xffffu, b.y & 0xffffu));
}

void build_neighbourhood(int c, ivec2 id) {
  // Neighbours past the rectangle are never read together with this texel (the filter takes the
  // kernel for footprints leaving the rectangle): clamping only keeps the reads inside.
  ivec2 far = min(id + 1, params.mask_rect[c].zw);
  uvec2 self = masks[mask_index(c, id)];
  uvec2 right = combine(self, masks[mask_index(c, ivec2(far.x, id.y))]);
  uvec2 down = combine(self, masks[mask_index(c, ivec2(id.x, far.y))]);
  uvec2 all4 = combine(combine(right, down), masks[mask_index(c, far)]);
  uint at = mask_index(c, id) * 4u;
  neighbourhoods[at] = self;
  neighbourhoods[at + 1u] = right;
  neighbourhoods[at + 2u] = down;
  neighbourhoods[at + 3u] = all4;
}

void main() {
  int c = int(push.cascade);
  ivec4 rect = params.mask_rect[c];
  ivec2 id = rect.xy + ivec2(gl_GlobalInvocationID.xy);
  if (id.x > rect.z || id.y > rect.w) return;
  if (kNeighbourhoods == 2u) {
    planes[mask_index(c, id)] = fit_depth_block(id, ivec2(params.extent.z));
    return;
  }
  if (kNeighbourhoods != 0u) {
    build_neighbourhood(c, id);
    return;
  }
  int size = int(params.extent.z);
  int level = params.mask_level[c];
  int level_size = max(size >> level, 1);
  // Footprint [f0, f1]; the last mask texel of a row or column also takes any remainder of a map size
  // that isn't a power of two, as the filter clamps its lookups there.
  ivec2 f0 = id << level;
  ivec2 f1 = min(f0 + (1 << level), ivec2(size)) - 1;
  if (id.x == level_size - 1) f1.x = size - 1;
  if (id.y == level_size - 1) f1.y = size - 1;
  int width = min(f1.x - f0.x + 3, kMaxRow);  // columns of footprint + border
  float above[kMaxRow];                       // the previous strip's lower row
  float lo = 1.0e30, hi = -1.0e30;
  float step = 0.0;  // largest depth step between adjacent texels with one in the footprint
  vec2 inv_size = vec2(1.0 / float(size));
  for (int y = f0.y - 1; y <= f1.y + 1; y += 2) {
    // Rows y (a) and y + 1 (b); b lies past the border when the row count is odd.
    bool a_row = y >= f0.y && y <= f1.y;
    bool b_row = y + 1 >= f0.y && y + 1 <= f1.y;
    bool b_valid = y + 1 <= f1.y + 1;
    bool up_row = y - 1 >= f0.y && y - 1 <= f1.y;
    bool first = y == f0.y - 1;
    float left_a = 0.0, left_b = 0.0, up_left = 0.0;
    for (int i = 0; i < width; i += 2) {
      // Texels (i, y + 1), (i + 1, y + 1), (i + 1, y), (i, y) of footprint + border; clamp-to-edge.
      vec4 g = textureGather(depth_map, vec3(vec2(f0.x + i, y + 1) * inv_size, float(c)));
      for (int k = 0; k < 2; ++k) {
        int col = i + k;
        if (col >= width) break;
        float a = k == 0 ? g.w : g.z;
        float b = k == 0 ? g.x : g.y;
        bool col_in = col >= 1 && col <= width - 2;
        bool left_in = col >= 2;
        bool a_in = a_row && col_in;
        bool b_in = b_row && col_in;
        lo = min(lo, a);
        hi = max(hi, a);
        if (b_valid) {
          lo = min(lo, b);
          hi = max(hi, b);
        }
        step = max(step, (a_in || b_in) ? abs(a - b) : 0.0);
        if (col > 0) {
          step = max(step, (a_in || (a_row && left_in)) ? abs(a - left_a) : 0.0);
          step = max(step, (b_in || (b_row && left_in)) ? abs(b - left_b) : 0.0);
          step = max(step, (a_in || (b_row && left_in)) ? abs(a - left_b) : 0.0);
          step = max(step, (b_in || (a_row && left_in)) ? abs(b - left_a) : 0.0);
        }
        float up = above[col];
        if (!first) {
          step = max(step, (a_in || (up_row && col_in)) ? abs(a - up) : 0.0);
          if (col > 0) step = max(step, (a_in || (up_row && left_in)) ? abs(a - up_left) : 0.0);
          if (col + 1 < width)
            step = max(step, (a_in || (up_row && col + 1 <= width - 2)) ? abs(a - above[col + 1]) : 0.0);
        }
        up_left = up;
        above[col] = b;
        left_a = a;
        left_b = b;
      }
    }
  }
  bool edge = step > params.edge_threshold[c];
  uint extent = push.depth_extent != 0u ? cascade_pack_extent(lo, hi) : CASCADE_EXTENT_EMPTY;
  masks[mask_index(c, id)] = uvec2(edge ? 1u : 0u, extent);
}
