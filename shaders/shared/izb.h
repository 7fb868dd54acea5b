// The irregular z-buffer's data layout and bindings, shared by C++ and GLSL.
#ifndef IZB_H
#define IZB_H
#include "shared_prelude.h"
#include "light_tiles.h"

SHARED_BEGIN

SHARED_CONST uint kIzbEndOfList = 0xffffffffu;

// Written on the GPU by the light-frustum pass each frame; read by every later IZB pass. It opens the
// buffer of the fit's per-workgroup bounds (kIzbPartialsAt): the fit writes it there, through
// IZB_BINDING_BOUNDS_PARTIALS, and the passes after it read it as a uniform buffer (IZB_BINDING_FRAME),
// which a CPU device loads once per invocation batch, not a lane at a time as it does a storage
// buffer's words.
struct IzbFrame {
  mat4 light_view_projection;  // world -> light clip space (orthographic, depth 0 nearest the light)
  vec4 grid;                   // x: resolution (texels per side), y: 1/resolution, z: world size of a texel, w: points found (as float)
};

// Per-frame constants from the CPU.
struct IzbParams {
  mat4 light_view;           // world -> light view, looking along the light (a spot light: from its position)
  mat4 inverse_view_projection;
  vec4 light_direction;      // xyz: travel direction
  vec4 camera_position;      // xyz; w: max IZB distance from the camera (0: unlimited)
  vec4 depth_range;          // x: near, y: far light-view distance of the casters (for the projection)
  uvec4 extent;              // x,y: render size; z: grid resolution; w: samples per pixel (also a specialization constant)
  uvec4 limits;              // x: node pool size; y: flags (IZB_FLAG_*, also a specialization constant); z: record capacity; w: pair capacity
  uvec4 capacities;          // x: tile pair capacity; y: tiles per side; z: caster draws; w: step 1's shape (kIzbStepOne*)
  vec4 light_position;       // a spot light: xyz its position, w its range (0: the sun)
  vec4 light_cone;           // a spot light: x cosine of its outer cone, y tangent of its grid's half angle; z 1: a face of a point light
  vec4 ray_scales;           // IZB_FLAG_CONSTANT_RAY_W: x, y 1 / w of every camera ray's near and far point (pixel_corner_points)
  // IZB_FLAG_BOUNDED_FIT: camera_ray's origin and direction at pixel corner (x, y) as affine functions,
  // [0] + x [1] + y [2] (xyz); in [0].w a bound on how far rounding can take the build's and the fit's
  // origin or direction apart, in [1].w a bound on the origin's or direction's length anywhere in the
  // view (world units); [2].w unused.
  vec4 corner_ray_origin[3];
  vec4 corner_ray_direction[3];
  // The hybrid's penumbrae (izb_penumbra.comp): world -> clip of the camera; x: the sun's tangent of
  // its angular radius (0: no penumbra pass), y: a pixel's width in world units per unit of distance
  // from the camera (2 tan(fov_y / 2) / height).
  mat4 view_projection;
  vec4 penumbra;
  // A point light's faces recorded together (their passes interleaved): x, this face's section of the
  // caster draws' words (its frustum draws, then its listed triangles) starts this many words after the
  // first face's; 0 for any other record.
  uvec4 face_sections;
};

// (For the raster trace, depth culling and the rasterizer choice are pipeline state.)
SHARED_CONST uint IZB_FLAG_CSM = 1u;
SHARED_CONST uint IZB_FLAG_PROGRESSIVE = 4u;
SHARED_CONST uint IZB_FLAG_STATS = 16u;
SHARED_CONST uint IZB_FLAG_NO_DEPTH_CULL = 32u;  // compute trace: test every touched texel's list
SHARED_CONST uint IZB_FLAG_CSM_BUFFER = 64u;     // the CSM is the compute pass's buffer, not the depth image
SHARED_CONST uint IZB_FLAG_SORTED_LISTS = 128u;  // lists are contiguous node ranges (counting sort), not linked
SHARED_CONST uint IZB_FLAG_ALPHA = 256u;         // some caster is alpha-tested (else the node test skips that code)
SHARED_CONST uint IZB_FLAG_GAPS = 512u;          // keep each pixel's nearest occluder distance found (hybrid penumbrae)
SHARED_CONST uint IZB_FLAG_DIRECT_NODES = 1024u; // 1 spp, linked lists, pool >= pixels: a pixel's node is its own index
SHARED_CONST uint IZB_FLAG_LIT = 2048u;          // the build culls points the lit map proves lit
// 1 spp, the sun, no hybrid range nor debug view: the build settles every pixel's term (on a GPU it
// stores every pixel's 1 or 0; on a CPU device the term starts lit and it stores the shadowed ones'
// zeros) and the trace darkens each pixel it finds shadowed, so no resolve pass reads every pixel again.
SHARED_CONST uint IZB_FLAG_DIRECT_TERM = 4096u;
// With IZB_FLAG_DIRECT_NODES on a GPU: each run of a workgroup row's pixels sharing a texel enters
// its list with one exchange (a CPU device pays more for the workgroup barriers than it saves).
SHARED_CONST uint IZB_FLAG_ROW_RUNS = 8192u;
// At most kIzbAllTrianglesLimit caster triangles: every one is set up (izb_triangles.comp), in a
// dispatch sized on the CPU, with no cull of the caster draws before it (izb_setup.glsl): that cull's
// serial step costs more than setting up a few triangles it would skip.
SHARED_CONST uint IZB_FLAG_ALL_TRIANGLES = 16384u;
SHARED_CONST uint kIzbAllTrianglesLimit = 8192u;
// With IZB_FLAG_ALL_TRIANGLES, the sun and the compute trace, where nothing before the trace reads the
// triangles (no CSM, no lit map): the trace's step 1 sets up its triangles itself (izb_records.comp),
// reading the casters' vertices where it would read the grid triangles, so no pass of their own.
SHARED_CONST uint IZB_FLAG_TRIANGLES_IN_TRACE = 32768u;
// A CPU device, which runs every branch of a shader and runs subgroup operations as loops over the
// lanes:
//  - the fit's second step (izb_setup.glsl) runs as a single-workgroup dispatch of its own after the
//    fit, not in the fit's last workgroup: the barrier that finds the last one in every workgroup
//    costs a CPU driver more than the dispatch;
//  - appends to a list take an atomic a lane, not a subgroup's scan and one atomic, and the per-pixel
//    passes leave their lists' dispatches to izb_list_dispatch.comp.
SHARED_CONST uint IZB_FLAG_CPU_DEVICE = 65536u;
// Where a resolve runs (hybrid, 32 spp) with no debug view and the sun: the build writes the term (and
// the hybrid's list entry) of every pixel it settles, which is every pixel without a node, and lists
// the pixels with nodes; the resolve reads only those, in a dispatch sized by the list, not the frame.
SHARED_CONST uint IZB_FLAG_LISTED_RESOLVE = 131072u;
SHARED_CONST uint IZB_FLAG_HYBRID = 262144u;  // the hybrid technique (its blend's list, with IZB_FLAG_LISTED_RESOLVE)
SHARED_CONST uint IZB_FLAG_SPOT = 524288u;    // a spot light, or a face of a point light (params.light_position)
// The compute trace runs: the build raises each light-space tile's farthest node depth, which its
// tile cull reads (the raster trace reads only the texels').
SHARED_CONST uint IZB_FLAG_TILE_FARTHEST = 2097152u;
// The build's lit test, and the read before each atomicMin of the lit map and compute CSM, go through
// IZB_BINDING_LIT_WORDS. Set on a CPU device, whose driver loads a
// storage buffer's words lane by lane but gathers a texel buffer's fetches across the lanes; only
// where the view reaches the whole buffer (maxTexelBufferElements).
SHARED_CONST uint IZB_FLAG_LIT_FETCH = 4194304u;
// The inverse view-projection's w row ignores x and y (exact zeros), so every camera ray's near and far
// points have one w each, whose reciprocals the CPU divides once (IzbParams::ray_scales).
SHARED_CONST uint IZB_FLAG_CONSTANT_RAY_W = 1048576u;
// 32 spp, the sun, IZB_FLAG_CONSTANT_RAY_W: the fit bounds each μQuad from corners made in fast float
// arithmetic (IzbParams::corner_ray_*), widened past the distance rounding can put between them and
// the build's exact corners; near grazing, where that bound is loose, it makes the exact corners.
SHARED_CONST uint IZB_FLAG_BOUNDED_FIT = 8388608u;
// 32 spp, the compute trace: a pixel's node goes only into the lowest texel (its anchor) of each 2x2
// block of texels its samples fill, the blocks counted from the first texel of its corners' bounds
// (one node where the samples span at most 2x2 texels, the common case, instead of one in each
// texel); the trace pairs a triangle with a texel where it touches the 2x2 block from that texel up
// and right.
SHARED_CONST uint IZB_FLAG_ANCHORED_NODES = 16777216u;
// A point light's faces on a GPU, the term written directly (IZB_FLAG_DIRECT_TERM): before the first
// face izb_face_tiles.comp lists each face's 8x8 tiles of pixels (those holding a point its cone
// reaches) and writes the term of the points no face reaches; each face's build then runs a
// workgroup per tile of its list, not over the whole frame.
SHARED_CONST uint IZB_FLAG_FACE_TILES = 33554432u;
// The sun on a GPU: the light frustum's fit, whose workgroups read every pixel, also empties the grid
// (its lists' heads or counts and the farthest depths, a slice a workgroup) in place of record_izb_reset's
// transfer fills, which cost more than the stores (a fill each, a barrier after).
SHARED_CONST uint IZB_FLAG_FIT_CLEARS_GRID = 67108864u;

// A list node is a uvec2 {next node, pixel}. Linked lists: heads[texel] is the first node, chained
// through .x; with IZB_FLAG_DIRECT_NODES a node's index is its pixel's (the trace reads it so). Sorted
// lists (counting sort): heads[texel] is the first of list_counts[texel] contiguous nodes (.x
// unused). Each pixel's light-space data lives once in the "quads" buffer: 1 spp: its ray origin
// (grid x, grid y, light depth); 32 spp: the four μQuad corners (c00, c10, c01, c11) as 12 floats,
// from which the trace rebuilds every sample.
SHARED_CONST uint kIzbQuadFloats1 = 4u;
SHARED_CONST uint kIzbQuadFloats32 = 12u;

// Counters read back for statistics (and the node allocator).
SHARED_CONST uint IZB_COUNTER_NODES = 0u;          // nodes requested (may exceed the pool)
SHARED_CONST uint IZB_COUNTER_OVERFLOW = 1u;       // insertions refused: pool full
SHARED_CONST uint IZB_COUNTER_CANDIDATES = 2u;     // lit candidates (facing, receiving, in range): sharded
SHARED_CONST uint IZB_COUNTER_SHADING_POINTS = 3u; // covered pixels: sharded
SHARED_CONST uint IZB_COUNTER_FRAGMENTS = 4u;      // trace fragments before depth culling: sharded
SHARED_CONST uint IZB_COUNTER_FRAGMENTS_KEPT = 5u; // after depth culling: sharded
SHARED_CONST uint IZB_COUNTER_TRIANGLE_TESTS = 6u; // node-triangle tests: sharded
SHARED_CONST uint IZB_COUNTER_CSM_CULLED = 7u;     // candidates proved shadowed by the CSM: sharded
SHARED_CONST uint IZB_COUNTER_OVERFLOW_PIXELS = 8u;// pixels resolved by the fallback
SHARED_CONST uint IZB_COUNTER_LIST_MAX = 9u;
SHARED_CONST uint IZB_COUNTER_LIST_SUM = 10u;
SHARED_CONST uint IZB_COUNTER_NONEMPTY = 11u;
// Compute trace and compute CSM (each counter pair: [trace, CSM]).
SHARED_CONST uint IZB_COUNTER_RECORDS = 12u;       // 2 uints: tile-row records requested
SHARED_CONST uint IZB_COUNTER_TILE_PAIRS = 14u;    // 2 uints: (triangle, tile) pairs requested
SHARED_CONST uint IZB_COUNTER_PAIRS = 16u;         // trace: (triangle, texel) pairs requested
SHARED_CONST uint IZB_COUNTER_LIT_CULLED = 17u;    // candidates the lit map proved lit: sharded
SHARED_CONST uint IZB_COUNTER_LIT_RECORDS = 18u;   // lit map: tile-row records requested
SHARED_CONST uint IZB_COUNTER_LIT_TILE_PAIRS = 19u;// lit map: (triangle, tile) pairs requested
SHARED_CONST uint IZB_COUNTER_DISPATCH = 20u;      // 3 uints: indirect dispatch of the fallback
SHARED_CONST uint IZB_COUNTER_STRADDLERS = 23u;     // spot light: caster triangles across the near plane
// IZB_FLAG_LISTED_RESOLVE: the pixels listed for the resolve, then 3 uints: its indirect dispatch, one
// entry a thread in rows of kIzbDispatchRow workgroups (raise_row_dispatch).
SHARED_CONST uint IZB_COUNTER_RESOLVE_LIST = 24u;
// izb_list_dispatch.comp's push.mode: which list's dispatch it sizes.
SHARED_CONST uint IZB_LIST_RESOLVE = 0u;
SHARED_CONST uint IZB_LIST_HYBRID = 1u;
// Hybrid penumbrae: the tiles the filter step listed, then 3 uints: the apply step's indirect
// dispatch over them (a workgroup a tile).
SHARED_CONST uint IZB_COUNTER_PENUMBRA_TILES = 28u;
SHARED_CONST uint IZB_COUNTER_PAIR_DISPATCH = 32u;      // 3 uints: over texel pairs
// Hybrid: the pixels the resolve listed for the cascades, then 3 uints: indirect dispatch over them in
// workgroups of kIzbHybridEntriesPerGroup entries.
SHARED_CONST uint IZB_COUNTER_HYBRID = 36u;
// Casters in the light frustum (izb_setup.comp, izb_triangles.comp): the triangles listed (those
// reaching the grid), the caster draws whose bounds reach it and their triangles, then 3 uints: the
// indirect dispatch over those draws' triangles, 64 per workgroup (the grid setup's, and a CPU
// device's first step of the compute passes, whose threads past the listed triangles exit).
SHARED_CONST uint IZB_COUNTER_LISTED_TRIANGLES = 40u;
SHARED_CONST uint IZB_COUNTER_FRUSTUM_DRAWS = 41u;
SHARED_CONST uint IZB_COUNTER_FRUSTUM_TRIANGLES = 42u;
SHARED_CONST uint IZB_COUNTER_FIT_GROUPS_DONE = 43u;  // the fit's workgroups finished: the last fits the grid
SHARED_CONST uint IZB_COUNTER_GRID_SETUP_DISPATCH = 44u;
// The build's per-pixel counts and the trace's statistics, added once per subgroup, go to one of
// kIzbCounterShards slots each (a single address would serialize hundreds of thousands of atomics);
// the CPU sums the shards. Shard s of counter k (a sharded IZB_COUNTER_*, k < kIzbShardStride) lives at
// izb_shard_word(k, s): a shard's counters share one 128-byte line and the shards spread over
// kIzbCounterShards lines. (Atomics on one line serialize in the cache: with each counter's shards
// side by side, two lines a counter, the build's three counts took 0.13 ms at 4K on an H200.)
SHARED_CONST uint kIzbCounterShards = 64u;
SHARED_CONST uint kIzbShardStride = 32u;      // words: one 128-byte line
SHARED_CONST uint IZB_COUNTER_SHARDS = 64u;   // line-aligned
SHARED_INLINE uint izb_shard_word(uint counter, uint shard) {
  return IZB_COUNTER_SHARDS + shard * kIzbShardStride + counter;
}
// After the shards: per tile work (trace, CSM, lit map: 6 uints each), the indirect dispatches of its
// steps 2 and 3 (3 uints each), raised by steps 1 and 2 as they append (izb_group_reserve.glsl), so no
// pass between computes them; then 3 uints: step 1's indirect dispatch over the listed triangles, in
// workgroups of its shape's (kIzbStepOne*).
SHARED_CONST uint IZB_COUNTER_STEP_DISPATCH = IZB_COUNTER_SHARDS + kIzbCounterShards * kIzbShardStride;
SHARED_CONST uint IZB_COUNTER_STEP_ONE_DISPATCH = IZB_COUNTER_STEP_DISPATCH + 18u;
SHARED_CONST uint IZB_COUNTER_COUNT = IZB_COUNTER_STEP_DISPATCH + 21u;

// Compute trace, compute CSM and lit map, hierarchically over light-space tiles of kIzbTile² texels
// (each tile knows its farthest node, so the trace culls a triangle from a whole tile at once):
//  1. a thread per listed caster triangle finds its rows of tiles, or its few texels when it is small
//     (kIzbStepOne*); the workgroup then works all its triangles' texels (the CSM and lit map
//     write them, the trace lists its pairs for step 4) and cuts each row's exact span into records
//     (triangle, tile row, first tile, last tile) of at most kIzbRecordTiles tiles, a thread per texel
//     or row (the trace on a CPU device: a thread per row of a small triangle's texels, izb_records.comp);
//  2. a thread per (record, tile) keeps the (triangle, tile) pairs the triangle touches (and, for the
//     trace, does not lie behind every node of);
//  3. a workgroup per (triangle, tile), a thread per texel: the CSM writes fully covered texels, the
//     lit map touched texels (a small triangle's already in step 1), the trace keeps the (triangle,
//     texel) pairs that touch and survive the texel's farthest-node cull;
//  4. trace only: a thread per (triangle, texel) walks the texel's list.
// Each step's output is appended densely (one atomic per workgroup, izb_group_reserve.glsl), so a
// large triangle spreads over many workgroups instead of serializing a thread. Step 2's workgroup shape is specialization
// constants (ids 0, 1, 4): on a GPU kIzbTileStepRecordsGpu records side by side, 32 lanes each, so a
// workgroup appends its pairs with one atomic; on a CPU device, which pays for every workgroup, many
// records per workgroup one after another; likewise step 3's tile pairs per workgroup (id 2), where the
// trace on a CPU device takes a thread per row of a pair's tile instead (izb_texel_bin.comp).
// Dispatches use rows of kIzbDispatchRow workgroups (the portable limit per dimension is 65535).
SHARED_CONST uint kIzbTile = 16u;
SHARED_CONST uint kIzbRecordTiles = 32u;
SHARED_CONST uint kIzbRecordsPerGroupGpu = 1u;
SHARED_CONST uint kIzbRecordsPerGroupCpu = 64u;
SHARED_CONST uint kIzbTilePairsPerGroupGpu = 1u;
SHARED_CONST uint kIzbTileStepRecordsGpu = 4u;  // step 2's records side by side on a GPU
SHARED_CONST uint kIzbTilePairsPerGroupCpu = 16u;
SHARED_CONST uint kIzbDispatchRow = 32768u;
// The light frustum fit's workgroup (16x16 invocations) covers a block of this many pixels, so each
// invocation (kIzbFitBlockWidth / 16) x (kIzbFitBlockHeight / 16), with its loads in flight together.
SHARED_CONST uint kIzbFitBlockWidth = 32u;
SHARED_CONST uint kIzbFitBlockHeight = 64u;
SHARED_CONST uint kIzbPairGroup = 64u;             // pairs per workgroup of the compute trace

// Per-pixel state bits beside the visibility mask.
SHARED_CONST uint IZB_PIXEL_CANDIDATE = 1u;
SHARED_CONST uint IZB_PIXEL_OVERFLOW = 2u;
SHARED_CONST uint IZB_PIXEL_CSM_CULLED = 4u;
SHARED_CONST uint IZB_PIXEL_LIT_CULLED = 8u;
// The surface as the build classified it, so the resolve reads 4 bytes per pixel, not the surface:
SHARED_CONST uint IZB_PIXEL_COVERED = 16u;
SHARED_CONST uint IZB_PIXEL_FACING = 32u;   // faces the light (a spot light: and lies in its reach)
SHARED_CONST uint IZB_PIXEL_BEYOND = 64u;   // farther from the camera than the IZB's range
SHARED_CONST uint IZB_PIXEL_OTHER_FACE = 128u;  // a point-light face's pass: outside its cone (another face's point)

// Bindings (one layout shared by all IZB passes, so every pass sees the same buffers).
SHARED_CONST uint IZB_BINDING_PARAMS = 0u;
SHARED_CONST uint IZB_BINDING_FRAME = 1u;
SHARED_CONST uint IZB_BINDING_COUNTERS = 2u;
SHARED_CONST uint IZB_BINDING_HEADS = 3u;
// Per texel its farthest node depth (float bits), then per tile (tile_farthest_index): one binding for
// both, since push descriptors allow no more than 32.
SHARED_CONST uint IZB_BINDING_FARTHEST = 4u;
SHARED_CONST uint IZB_BINDING_NODES = 5u;
SHARED_CONST uint IZB_BINDING_MASK = 6u;
SHARED_CONST uint IZB_BINDING_PIXEL_STATE = 7u;
SHARED_CONST uint IZB_BINDING_QUADS = 8u;
SHARED_CONST uint IZB_BINDING_WORLD_POSITION = 9u;
SHARED_CONST uint IZB_BINDING_GEOMETRIC_NORMAL = 10u;
SHARED_CONST uint IZB_BINDING_ALBEDO = 11u;
// Hybrid: the resolve writes the hard term and lists the pixels that blend toward the cascades; the
// cascades then filter only those (into the soft term), and a last pass blends them.
// From entry 0: the pixels in the fade band, uvec4 {pixel x | y << 16, -, fade bits, -}; from entry
// width * height: the penumbra pass's tiles (izb_penumbra_*_at).
SHARED_CONST uint IZB_BINDING_HYBRID_LIST = 12u;
SHARED_CONST uint IZB_BINDING_SOFT_TERM = 13u;    // R32F: the cascades' term of listed pixels, -1 elsewhere
SHARED_CONST uint IZB_BINDING_SHADOW_TERM = 14u;
SHARED_CONST uint IZB_BINDING_OVERLAY = 15u;
SHARED_CONST uint IZB_BINDING_TRIANGLES = 16u;          // per caster triangle: IzbCasterTriangle
SHARED_CONST uint IZB_BINDING_OVERFLOW_LIST = 17u;
SHARED_CONST uint IZB_BINDING_CSM_DEPTH = 18u;
SHARED_CONST uint IZB_BINDING_OCCLUDER_DISTANCE = 19u;  // per pixel: nearest occluder's light depth above it
// An occluder_distance word: a shadowed pixel's gap (a float's bits, below kIzbLitTangentBit); a lit
// pixel's edge tangent (a float's bits with kIzbLitTangentBit set); kIzbNoOccluder where neither was
// found. atomicMin keeps a gap over any tangent, and the smallest of each.
SHARED_CONST uint kIzbLitTangentBit = 0x80000000u;
SHARED_CONST uint kIzbNoOccluder = 0xffffffffu;
SHARED_CONST uint IZB_BINDING_GRID_TRIANGLES = 20u;     // per caster triangle: 3 vec4 (grid x, grid y, light depth, -)
SHARED_CONST uint IZB_BINDING_RECORDS = 21u;             // uvec4 records {triangle, tile row, first tile, last tile}
SHARED_CONST uint IZB_BINDING_PAIRS = 22u;              // uvec2 {triangle, texel} surviving the depth cull
// The frame's IzbFrame (vec4s 0-4), then from vec4 kIzbPartialsAt per fit workgroup: vec4 (min x, min y, max x, max y).
SHARED_CONST uint IZB_BINDING_BOUNDS_PARTIALS = 23u;
SHARED_CONST uint kIzbPartialsAt = 16u;  // vec4s (256 bytes) after the buffer's start
SHARED_CONST uint IZB_BINDING_MATERIAL_TEXTURES = 24u;  // the scene's material textures (shared/material.h)
// Per caster draw, in caster-draw order, as 32-bit words (D caster draws, capacities.z; T caster
// triangles): [0, D) its IZB_DRAW_* bits for this frame; [D, 9D) IzbDrawBounds; [9D, 11D) the draws
// in the light frustum this frame, {first triangle, first slot in the frustum's triangles}; then up to
// T listed triangles (caster triangle indices). One binding, since push descriptors allow 32.
SHARED_CONST uint IZB_BINDING_CASTER_DRAWS = 25u;
// Compute CSM: depth bits per texel in [0, res^2); then the lit map in [res^2, 2 res^2): per texel the
// nearest depth (ordered bits, izb_common.glsl) of every caster touching it; then its (res+1)^2 texel
// corners: the nearest plane depth there of every caster touching a texel at it. One binding for all,
// since push descriptors allow no more than 32.
SHARED_CONST uint IZB_BINDING_CSM_TEXELS = 26u;
SHARED_CONST uint IZB_BINDING_TILE_PAIRS = 27u;         // uvec2 {triangle, tile}
// IZB_FLAG_LIT_FETCH: IZB_BINDING_CSM_TEXELS's words again, as an R32_UINT uniform texel buffer.
SHARED_CONST uint IZB_BINDING_LIT_WORDS = 28u;
// Sorted lists (counting sort): per texel its node count, and a fill cursor; after the cursors, per
// scan block a sum (one binding for both, since push descriptors allow no more than 32).
SHARED_CONST uint IZB_BINDING_LIST_COUNTS = 29u;
SHARED_CONST uint IZB_BINDING_LIST_CURSOR = 30u;
// IZB_FLAG_LISTED_RESOLVE: the pixels with nodes (row-major indices), which the resolve alone reads.
SHARED_CONST uint IZB_BINDING_RESOLVE_LIST = 31u;
// IZB_FLAG_FACE_TILES keeps its tile lists there instead (light_tiles.h; a point light's faces list
// no resolve).
SHARED_CONST uint kIzbScanBlock = 1024u;  // texels per block of the prefix sum (256 threads x 4)
SHARED_CONST uint kIzbHybridEntriesPerGroup = 256u;  // hybrid list entries per workgroup (64 threads x 4)
// With a limited range the hybrid fades from the IZB's term to the cascades' over the range's last
// tenth: the pixels from kIzbHybridFadeStart of it on are listed for the cascades.
SHARED_CONST float kIzbHybridFadeStart = 0.9f;
SHARED_CONST float kIzbHybridFadeWidth = 0.1f;

// The hybrid's penumbra pass (izb_penumbra.comp) works in square tiles of kPenumbraTile pixels, a
// workgroup each. A penumbra is filtered over at most kPenumbraMaxRadius pixels (wider ones are
// filtered at that radius; 24 narrowed Sponza's at 4K under the real sun: soft_mae 0.00124 against
// 0.00055 on view 1), with kPenumbraSearchTaps taps to find the blockers and kPenumbraFilterTaps
// to filter.
SHARED_CONST uint kPenumbraTile = 8u;
// The tile summaries' step: a workgroup of 64 threads, a thread a row of a tile, so this many tiles
// side by side a workgroup.
SHARED_CONST uint kPenumbraSummaryTiles = 64u / kPenumbraTile;
SHARED_CONST uint kPenumbraMaxRadius = 48u;
SHARED_CONST uint kPenumbraSearchTaps = 12u;
SHARED_CONST uint kPenumbraFilterTaps = 16u;
SHARED_INLINE uint penumbra_tiles_x(uint width) { return (width + kPenumbraTile - 1u) / kPenumbraTile; }
SHARED_INLINE uint penumbra_tiles_y(uint height) { return (height + kPenumbraTile - 1u) / kPenumbraTile; }
// The hybrid list's buffer, in uvec4 entries. With a limited range (`limited`: IzbParams'
// camera_position.w > 0) it opens with width * height for the pixels the cascades take part of
// (izb_pixel.glsl); with none they are never listed and take no room (133 MB at 3840x2160). Then per
// tile its summary {min term, max term, widest penumbra radius in pixels (float bits), -}; then the
// listed tiles {tile, widest penumbra in reach in pixels (float bits), -, -}; then per listed tile
// its kPenumbraTile² filtered terms (float bits, 4 an entry).
SHARED_INLINE uint izb_penumbra_tiles_at(uint width, uint height, bool limited) { return limited ? width * height : 0u; }
SHARED_INLINE uint izb_penumbra_list_at(uint width, uint height, bool limited) {
  return izb_penumbra_tiles_at(width, height, limited) + penumbra_tiles_x(width) * penumbra_tiles_y(height);
}
SHARED_INLINE uint izb_penumbra_values_at(uint width, uint height, bool limited) {
  return izb_penumbra_tiles_at(width, height, limited) + 2u * penumbra_tiles_x(width) * penumbra_tiles_y(height);
}
SHARED_INLINE uint izb_hybrid_list_entries(uint width, uint height, bool limited) {
  return izb_penumbra_values_at(width, height, limited) +
         penumbra_tiles_x(width) * penumbra_tiles_y(height) * (kPenumbraTile * kPenumbraTile / 4u);
}

SHARED_CONST uint IZB_DRAW_IN_CSM = 1u;

// A caster triangle in world space, in draw order, written by izb_casters.comp when casters move.
struct IzbCasterTriangle {
  vec4 p0;    // xyz: vertex 0; w: its caster draw's ordinal (uint bits)
  vec4 p1;    // w: the material's alpha threshold (uint bits; 0: not alpha-tested)
  vec4 p2;    // w: the material's base-colour texture (uint bits; kNoTexture: none)
  vec4 uv01;  // texture coordinates of vertices 0 (xy) and 1 (zw)
  vec4 uv2;   // xy: of vertex 2
};

// A caster draw as izb_casters.comp reads it: one per draw that casts, in draw order.
SHARED_CONST uint IZB_CASTERS_BINDING_VERTICES = 0u;  // the module's vertices (engine::Vertex, 8 floats)
SHARED_CONST uint IZB_CASTERS_BINDING_INDICES = 1u;   // the module's 32-bit indices
SHARED_CONST uint IZB_CASTERS_BINDING_DRAWS = 2u;     // IzbCasterDraw per caster draw
SHARED_CONST uint IZB_CASTERS_BINDING_TRIANGLES = 3u; // IzbCasterTriangle per caster triangle (written)
struct IzbCasterDraw {
  mat4 world;
  uint first_index;      // the mesh's first index in the module's index buffer
  int vertex_offset;     // added to each of its indices
  uint triangle_count;
  uint first_triangle;   // its first triangle in the caster triangle buffer (ascending in draw order)
  uint ordinal;          // caster draw ordinal (IzbCasterTriangle::p0.w)
  uint alpha_threshold;  // IzbCasterTriangle::p1.w
  uint texture;          // IzbCasterTriangle::p2.w
  uint pad;
};
struct IzbCastersPush {
  uint draw_count;
  uint triangle_count;
  uint groups_x;  // workgroups per dispatch row
  uint pad;
};

// Push constants of the trace and CSM draws.
struct IzbDrawPush {
  mat4 model;
  uint first_index;
  int vertex_offset;
  uint first_triangle;  // the draw's first triangle in the caster triangle buffers
  uint debug;
};

// Push constants of compute passes.
struct IzbComputePush {
  uint mode;            // pass-specific selector
  uint debug;           // DebugView as uint
  uint triangle_count;  // caster triangles
  uint unused;
};

// push.mode of the compute trace/CSM passes: what the work is for.
SHARED_CONST uint IZB_WORK_TRACE = 0u;
SHARED_CONST uint IZB_WORK_CSM_HERTEL = 1u;
SHARED_CONST uint IZB_WORK_CSM_BARYCENTRIC = 2u;
SHARED_CONST uint IZB_WORK_LIT = 3u;  // the lit map (nearest caster depth per texel, see izb_common.glsl)
// Where work `mode`'s step 2 dispatch lives (IZB_COUNTER_STEP_DISPATCH; its step 3's follows it).
SHARED_INLINE uint izb_step_dispatch_at(uint mode) {
  return IZB_COUNTER_STEP_DISPATCH + 6u * (mode == IZB_WORK_TRACE ? 0u : (mode == IZB_WORK_LIT ? 2u : 1u));
}

// The lit map's layout in the compute CSM's buffer (IZB_BINDING_CSM_TEXELS), in words: after the CSM's
// res² depths, each texel's bound (res²), the texel corners' plane bounds ((res + 1)²), then from a
// multiple of 4 (one load of four words) each tile's record of 8 words (izb_common.glsl, lit_tile_record).
SHARED_INLINE uint izb_lit_tile_records_at(uint res) { return (2u * res * res + (res + 1u) * (res + 1u) + 3u) & ~3u; }

// Lit map: an empty texel (no caster touches it) holds the ordered bits of +infinity.
SHARED_CONST uint kIzbLitEmpty = 0xff800000u;
// A 32 spp point is lit-culled only when its μQuad spans at most this many texels per axis: the
// rounding bounds of the lit map (izb_common.glsl) assume it.
SHARED_CONST float kIzbLitQuadReach = 16.0f;
// Step 1's shape (IzbParams::capacities.w: caster triangles per 64-thread workgroup | the texel
// bound << 16). A triangle whose (widened) bounds hold at most the bound's texels is worked texel by
// texel in step 1 (the lit map and CSM write them; the trace lists its pairs for step 4), skipping
// steps 2 and 3, which give a (triangle, tile) pair a 256-lane workgroup. A CPU device pays for every
// idle lane and workgroup: many triangles per workgroup, a high bound. On a GPU the better shape
// depends on the casters: "wide" keeps each workgroup's texel walk short (many triangles of varied
// sizes, Sponza), "narrow" spreads small triangles' texels over more workgroups (few triangles, or
// many small ones: foliage); the module times both (Stats::tile_work_choice) unless
// IzbSettings::step_one_shape forces one, on any device.
SHARED_CONST uint kIzbStepOneCpu = 64u | (256u << 16);
SHARED_CONST uint kIzbStepOneWide = 64u | (16u << 16);
SHARED_CONST uint kIzbStepOneNarrow = 16u | (48u << 16);

// A caster draw's world-space bounds for the light-frustum cull, uploaded when the casters change.
// An invalid box (lo > hi) is unbounded: never culled.
struct IzbDrawBounds {
  vec4 lo;  // xyz; w: its first caster triangle (uint bits)
  vec4 hi;  // xyz; w: its triangle count (uint bits)
};
// How far (texels) outside the grid a caster's bounds or triangle must lie to be left out: beyond the
// hardware conservative rasterizer's overestimate (a draw left out is still drawn by the raster
// passes, which must find no texel of it) and the rounding of the corners' transform.
SHARED_CONST float kIzbCullMargin = 4.0f;

SHARED_END

#ifdef __cplusplus
static_assert(sizeof(gpu_shared::IzbFrame) == 80);
static_assert(sizeof(gpu_shared::IzbParams) == 128 + 3 * 16 + 3 * 16 + 3 * 16 + 6 * 16 + 64 + 16 + 16);
static_assert(sizeof(gpu_shared::IzbDrawPush) == 80);
static_assert(sizeof(gpu_shared::IzbCasterTriangle) == 80);
static_assert(sizeof(gpu_shared::IzbCasterDraw) == 96);
static_assert(sizeof(gpu_shared::IzbDrawBounds) == 32);
#endif
#endif
