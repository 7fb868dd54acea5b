#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_tiles.glsl"
layout(local_size_x = 1) in;

layout(push_constant) uniform Push { IzbComputePush push; };

// The indirect dispatch of step 3 of the tile work push.mode over its (triangle, tile) pairs. Step 2
// does not raise it as it appends: a tile step's workgroup appends once, so raising there would
// double its atomics on one address.
void main() {
  write_row_dispatch(tile_pair_dispatch_at(push.mode),
                     (tile_pair_count(push.mode) + kIzbTilePairsPerGroup - 1u) / kIzbTilePairsPerGroup);
}
