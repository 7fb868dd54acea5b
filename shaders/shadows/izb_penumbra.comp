#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 8, local_size_y = 8) in;  // kPenumbraTile²: the filter and apply steps take a workgroup a tile

// The hybrid's penumbrae, after the IZB wrote its exact hard term (1 spp: 0 or 1; 32 spp: the lit
// fraction) and, per pixel it found shadowed, the light depth from the point up to an occluder it
// found (IZB_FLAG_GAPS). A sun of angular radius a seen from a point an occluder's height g below it
// (along the light) is blocked over a disc of radius g tan(a) around the hard shadow's edge: for a
// planar receiver and an occluder at one height, the lit fraction is the hard term averaged over that
// disc, measured across the light (in the plane perpendicular to it). So each pixel near a shadow
// edge (1) finds the blockers whose penumbra reaches it among the pixels around it (their occluder
// heights, averaged), and (2) averages the hard term of the pixels within that radius on its own
// plane, both with taps laid across the light and mapped onto the pixel's tangent plane and into the
// image. A lit pixel whose lists held a caster edge within the sun's tangent takes the share of the
// disc beyond that edge instead (the trace keeps the smallest tangent). Where the penumbra is narrower
// than a pixel the IZB's term stays as it is, exact.
//
// Four steps, specialized apart (a CPU device runs every branch):
//  kStepTiles:  a thread a row of a tile: the range of the hard term and the widest penumbra its shadowed
//               pixels cast (in pixels);
//  kStepDilate: a thread a tile: whether any tile within kPenumbraMaxRadius casts a penumbra that
//               reaches it over a term that varies; if so it is listed, with that reach and
//               whether its 3x3 tiles hold both lit and shadowed terms (else no edge fit can be made);
//  kStepFilter: a workgroup a listed tile (an indirect dispatch): its pixels' filtered terms, stored
//               beside the list (the term itself is read by the neighbours' taps);
//  kStepApply:  the same workgroups: the filtered terms into the term.
const uint kStepTiles = 0u;
const uint kStepDilate = 1u;
const uint kStepFilter = 2u;
const uint kStepApply = 3u;
layout(constant_id = 14) const uint kStep = kStepTiles;

layout(set = 0, binding = IZB_BINDING_WORLD_POSITION, rgba32f) readonly uniform image2D positions;
layout(set = 0, binding = IZB_BINDING_GEOMETRIC_NORMAL, rgba16f) readonly uniform image2D normals;
layout(set = 0, binding = IZB_BINDING_ALBEDO, rgba8) readonly uniform image2D receivers;  // a > 0.5: receives
layout(set = 0, binding = IZB_BINDING_HYBRID_LIST, std430) buffer HybridList { uvec4 entries[]; };

const uint kNoValue = 0xffffffffu;
const int kWindow = int((kPenumbraMaxRadius + kPenumbraTile - 1u) / kPenumbraTile);  // tiles either side

ivec2 extent() { return ivec2(params.extent.xy); }
uint tiles_x() { return penumbra_tiles_x(params.extent.x); }
float tan_half_angle() { return params.penumbra.x; }
// The IZB's range (izb_pixel.glsl's izb_reach, which comes with bindings this pass names otherwise).
bool range_limited() { return params.camera_position.w > 0.0; }
float range_limit() { return range_limited() ? params.camera_position.w : 3.0e38; }
// Where this pass's parts lie in the hybrid list (izb.h): the tile summaries, the listed tiles, their
// filtered terms.
uint summaries_at() { return izb_penumbra_tiles_at(params.extent.x, params.extent.y, range_limited()); }
uint listed_at() { return izb_penumbra_list_at(params.extent.x, params.extent.y, range_limited()); }
uint values_at() { return izb_penumbra_values_at(params.extent.x, params.extent.y, range_limited()); }
// A pixel's width in world units at `p`.
float footprint(vec3 p) { return max(distance(p, params.camera_position.xyz) * params.penumbra.y, 1.0e-30); }

// The light depth from the pixel up to the occluder the IZB found, in world units (-1: none found).
// (The trace keeps a shadowed pixel's gap, or a lit pixel's edge tangent with the high bit set:
// izb_common.glsl's note_lit_tangent.)
float occluder_height(uint index) {
  uint bits = occluder_distance[index];
  float gap = uintBitsToFloat(bits);
  return bits < kIzbLitTangentBit && gap < 1.0e20 ? gap * (params.depth_range.y - params.depth_range.x) : -1.0;
}

// A lit pixel's smallest tangent (across-light distance over height) to the edges of the caster
// triangles its lists held, or -1 where the trace tested none (izb_common.glsl's note_lit_tangent).
float lit_tangent(uint index) {
  uint bits = occluder_distance[index];
  return bits >= kIzbLitTangentBit && bits != kIzbNoOccluder ? uintBitsToFloat(bits & ~kIzbLitTangentBit) : -1.0;
}

struct Receiver {
  bool valid;     // covered, receiving, facing the light and inside the IZB's range
  vec3 position;
  vec3 normal;
  float term;     // the IZB's
  float height;   // occluder_height
};

bool inside(ivec2 pixel) { return all(greaterThanEqual(pixel, ivec2(0))) && all(lessThan(pixel, extent())); }

// The pixel whose penumbra is being found: its surface in full.
Receiver load_receiver(ivec2 pixel) {
  Receiver r;
  r.valid = false;
  r.term = 1.0;
  r.height = -1.0;
  r.position = vec3(0.0);
  r.normal = vec3(0.0, 1.0, 0.0);
  if (!inside(pixel)) return r;
  vec4 p = imageLoad(positions, pixel);
  vec4 n = imageLoad(normals, pixel);
  r.position = p.xyz;
  r.normal = n.xyz;
  r.valid = p.w > 0.5 && faces_light(n) && imageLoad(receivers, pixel).a > 0.5 &&
            distance(p.xyz, params.camera_position.xyz) <= range_limit();
  if (!r.valid) return r;
  r.term = imageLoad(shadow_term, pixel).r;
  r.height = r.term < 1.0 ? occluder_height(uint(pixel.y) * params.extent.x + uint(pixel.x)) : -1.0;
  return r;
}

// A tap's pixel: its point and term (and with `heights`, its occluder's height), no more. A tap on the
// receiver's own plane (same_surface) shares its facing; one on a surface that receives no shadow
// reads as lit, which its term is. On a GPU every load goes out at once (at the pixel clamped into the
// image), none waiting on another's value: the filter's taps are bound by the loads' round trips (H200,
// 4K, `hybrid+csm` against loads that waited on the point's validity: atrium 0.506 -> 0.498 ms, canopy
// 0.589 -> 0.586; the taps' loads in batches of four held in registers were slower, 0.507 / 0.610). A
// CPU device, which hides no latency, loads only what the tap's validity and term ask for.
Receiver load_tap(ivec2 pixel, bool heights) {
  bool cpu = izb_flag(IZB_FLAG_CPU_DEVICE);
  ivec2 at = clamp(pixel, ivec2(0), extent() - 1);
  vec4 p = cpu && !inside(pixel) ? vec4(0.0) : imageLoad(positions, at);
  Receiver t;
  t.normal = vec3(0.0);
  t.position = p.xyz;
  t.valid = inside(pixel) && p.w > 0.5 && distance(p.xyz, params.camera_position.xyz) <= range_limit();
  float term = cpu && !t.valid ? 1.0 : imageLoad(shadow_term, at).r;
  t.term = t.valid ? term : 1.0;
  bool height_read = heights && (!cpu || t.term < 1.0);
  float height = height_read ? occluder_height(uint(at.y) * params.extent.x + uint(at.x)) : -1.0;
  t.height = t.term < 1.0 ? height : -1.0;
  return t;
}

// ---- kStepTiles ----------------------------------------------------------------------------------
// A workgroup summarizes kPenumbraSummaryTiles tiles side by side, a thread a row of kPenumbraTile
// pixels: the row's loads go out together (a thread a pixel waits on one load chain at a time, and a
// workgroup a tile pays two barriers per 64 pixels).
// (Each step's shared arrays are sized by its specialization, 1 in the other steps: a GPU gives a
// workgroup the shared memory of every array the shader declares, which sets how many workgroups
// share a core and how much of its cache is left for loads: H200, 4K, atrium v0, the four steps
// 0.129 -> 0.107 ms.)
const uint kRowSummaries = kStep == kStepTiles ? 64u : 1u;
shared uvec3 row_summary[kRowSummaries];

// The range of the term over the tile's pixels (every pixel's: a wider range only lists more tiles),
// and the widest penumbra radius, in pixels, of its pixels with an occluder height.
void summarize_tiles() {
  uint lane = gl_LocalInvocationIndex;
  uint tile_x = gl_WorkGroupID.x * kPenumbraSummaryTiles + lane / kPenumbraTile;
  ivec2 first = ivec2(tile_x * kPenumbraTile, gl_WorkGroupID.y * kPenumbraTile + lane % kPenumbraTile);
  float terms[kPenumbraTile];
  for (uint i = 0u; i < kPenumbraTile; ++i) {
    ivec2 pixel = first + ivec2(i, 0);
    terms[i] = inside(pixel) ? imageLoad(shadow_term, pixel).r : 1.0;
  }
  // Terms in [0, 1] and radii >= 0: their bits order as they do.
  uint low = floatBitsToUint(1.0), high = 0u, widest = 0u;
  for (uint i = 0u; i < kPenumbraTile; ++i) {
    low = min(low, floatBitsToUint(terms[i]));
    high = max(high, floatBitsToUint(terms[i]));
    if (terms[i] >= 1.0) continue;
    ivec2 pixel = first + ivec2(i, 0);
    float height = occluder_height(uint(pixel.y) * params.extent.x + uint(pixel.x));
    if (height > 0.0)
      widest = max(widest, floatBitsToUint(height * tan_half_angle() / footprint(imageLoad(positions, pixel).xyz)));
  }
  row_summary[lane] = uvec3(low, high, widest);
  barrier();
  if (lane % kPenumbraTile != 0u || tile_x >= tiles_x()) return;
  uvec3 tile = row_summary[lane];
  for (uint r = 1u; r < kPenumbraTile; ++r) {
    uvec3 row = row_summary[lane + r];
    tile = uvec3(min(tile.x, row.x), max(tile.y, row.y), max(tile.z, row.z));
  }
  entries[summaries_at() + gl_WorkGroupID.y * tiles_x() + tile_x] =
      uvec4(tile, 0u);
}

// ---- kStepDilate ---------------------------------------------------------------------------------
// Tiles `offset` apart lie in ring max(|offset| - 1, 0) of each other (0 for a tile and its
// neighbours); ring_gap is the pixels between their nearest pixels.
ivec2 tile_ring(ivec2 offset) { return max(abs(offset) - 1, ivec2(0)); }
float ring_gap(ivec2 ring) { return length(vec2(ring * int(kPenumbraTile))); }

// The workgroup's 8x8 tiles and kWindow tiles around them, read once (clamped into the grid: a tile
// outside it reads the nearest edge tile, which its own offset, nearer, already counts).
const int kDilateBlock = 8 + 2 * kWindow;
const uint kBlockSummaries = kStep == kStepDilate ? uint(kDilateBlock * kDilateBlock) : 1u;
shared uvec3 block_summary[kBlockSummaries];

uvec3 block_tile(ivec2 tile, ivec2 block_origin) {
  return block_summary[(tile.y - block_origin.y) * kDilateBlock + (tile.x - block_origin.x)];
}

// A tile's reach (the widest penumbra in pixels that some tile within WINDOW tiles casts over it),
// whether the term varies within that reach, and whether ring 0 (the tile and its neighbours) holds
// terms on both sides of 0.5 (mixed_around). The window's tiles fall in rings (tile_ring): one
// pass over the window keeps each ring's range of the term beside the reach, and the rings within
// the reach then give the range (the window read once, not twice, at offsets known when the shader is
// compiled: H200, 4K, the step 0.017 -> 0.014 ms on contact, atrium and canopy, the same pixels).
#define DILATE_WITHIN(NAME, WINDOW)                                                                 \
  bool NAME(ivec2 tile, ivec2 block_origin, out float reach, out bool mixed_around) {               \
    uint ring_low[WINDOW * WINDOW], ring_high[WINDOW * WINDOW];                                     \
    for (int r = 0; r < WINDOW * WINDOW; ++r) {                                                     \
      ring_low[r] = floatBitsToUint(1.0);                                                           \
      ring_high[r] = 0u;                                                                            \
    }                                                                                               \
    reach = 0.0;                                                                                    \
    for (int dy = -WINDOW; dy <= WINDOW; ++dy)                                                      \
      for (int dx = -WINDOW; dx <= WINDOW; ++dx) {                                                  \
        ivec2 offset = ivec2(dx, dy);                                                               \
        uvec3 summary = block_tile(tile + offset, block_origin);                                    \
        ivec2 ring = tile_ring(offset);                                                             \
        float radius = min(uintBitsToFloat(summary.z), float(kPenumbraMaxRadius));                  \
        if (radius >= 0.5 && radius >= ring_gap(ring)) reach = max(reach, radius);                  \
        int r = ring.y * WINDOW + ring.x;                                                           \
        ring_low[r] = min(ring_low[r], summary.x);                                                  \
        ring_high[r] = max(ring_high[r], summary.y);                                                \
      }                                                                                             \
    mixed_around = ring_low[0] < floatBitsToUint(0.5) && ring_high[0] >= floatBitsToUint(0.5);       \
    uint low = floatBitsToUint(1.0), high = 0u;                                                     \
    if (reach > 0.0)                                                                                \
      for (int r = 0; r < WINDOW * WINDOW; ++r) {                                                   \
        if (ring_gap(ivec2(r % WINDOW, r / WINDOW)) > reach) continue;                              \
        low = min(low, ring_low[r]);                                                                \
        high = max(high, ring_high[r]);                                                             \
      }                                                                                             \
    return low < high;                                                                              \
  }
// Penumbrae under kNarrowWindow tiles' width reach no tile in ring kNarrowWindow or beyond (its
// nearest pixels are that far apart): a workgroup whose block casts none wider reads the narrow
// window, with the same result. (The window for kPenumbraMaxRadius = 48, which 4K needs, read
// throughout cost every row 0.015 ms on the H200 against 24's.)
const int kNarrowWindow = 3;
DILATE_WITHIN(varies_within_narrow, kNarrowWindow)
DILATE_WITHIN(varies_within_full, kWindow)
shared uint block_widest;

// A thread a tile: listed, with its reach, where some tile in reach casts a penumbra over it and the
// term varies within that reach.
void dilate_tile() {
  ivec2 tile = ivec2(gl_GlobalInvocationID.xy);
  ivec2 tiles = ivec2(tiles_x(), penumbra_tiles_y(params.extent.y));
  ivec2 block_origin = ivec2(gl_WorkGroupID.xy) * 8 - kWindow;
  if (gl_LocalInvocationIndex == 0u) block_widest = 0u;
  barrier();
  uint widest = 0u;
  for (uint k = gl_LocalInvocationIndex; k < uint(kDilateBlock * kDilateBlock); k += 64u) {
    ivec2 at = block_origin + ivec2(int(k) % kDilateBlock, int(k) / kDilateBlock);
    uint index = uint(clamp(at.y, 0, tiles.y - 1)) * tiles_x() + uint(clamp(at.x, 0, tiles.x - 1));
    block_summary[k] = entries[summaries_at() + index].xyz;
    widest = max(widest, block_summary[k].z);  // radii >= 0: their bits order as they do
  }
  widest = subgroupMax(widest);
  if (subgroupElect()) atomicMax(block_widest, widest);
  barrier();
  bool needed = false, mixed_around = false;
  float reach = 0.0;
  if (all(lessThan(tile, tiles))) {
    bool narrow = uintBitsToFloat(block_widest) < float(kNarrowWindow * int(kPenumbraTile));
    needed = narrow ? varies_within_narrow(tile, block_origin, reach, mixed_around)
                    : varies_within_full(tile, block_origin, reach, mixed_around);
  }
  // One atomic per subgroup; the filter and apply steps' dispatch in rows of kIzbDispatchRow.
  uint count = subgroupAdd(needed ? 1u : 0u);
  uint base = 0u;
  if (subgroupElect() && count != 0u) {
    base = atomicAdd(counters[IZB_COUNTER_PENUMBRA_TILES], count);
    uint last = base + count - 1u;
    // The dispatch widens only within its first row and grows a row only where a subgroup's slots
    // enter one: the others skip the atomics on those three words.
    if (base < kIzbDispatchRow) atomicMax(counters[IZB_COUNTER_PENUMBRA_TILES + 1u], min(last + 1u, kIzbDispatchRow));
    if (base == 0u || last / kIzbDispatchRow != (base - 1u) / kIzbDispatchRow)
      atomicMax(counters[IZB_COUNTER_PENUMBRA_TILES + 2u], last / kIzbDispatchRow + 1u);
    if (base == 0u) counters[IZB_COUNTER_PENUMBRA_TILES + 3u] = 1u;
  }
  uint slot = subgroupBroadcastFirst(base) + subgroupExclusiveAdd(needed ? 1u : 0u);
  if (needed)
    entries[listed_at() + slot] =
        uvec4(uint(tile.y) * tiles_x() + uint(tile.x), floatBitsToUint(reach), mixed_around ? 1u : 0u, 0u);
}

// ---- kStepFilter ---------------------------------------------------------------------------------
// A per-pixel turn of the tap pattern, fixed over time (a still frame stays still).
float pixel_turn(ivec2 pixel) {
  return 6.2831853 * fract(52.9829189 * fract(0.06711056 * float(pixel.x) + 0.00583715 * float(pixel.y)));
}

// Tap k of n, spread evenly over the unit disc (a golden-angle spiral, equal area a tap).
vec2 disc_tap(uint k, uint n, float turn) {
  float radius = sqrt((float(k) + 0.5) / float(n));
  float angle = float(k) * 2.39996323 + turn;
  return radius * vec2(cos(angle), sin(angle));
}

struct Across {
  vec3 u, v;   // unit, perpendicular to the light and to each other
  vec3 light;  // the direction light travels
};

Across across_light() {
  Across f;
  f.light = normalize(params.light_direction.xyz);
  vec3 helper = abs(f.light.y) < 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
  f.u = normalize(cross(helper, f.light));
  f.v = cross(f.light, f.u);
  return f;
}

// The pixel showing the point of `r`'s tangent plane that lies `offset` across the light from it.
ivec2 tap_pixel(Receiver r, Across f, vec2 offset) {
  vec3 across = offset.x * f.u + offset.y * f.v;
  float facing = dot(f.light, r.normal);
  facing = facing < 0.0 ? min(facing, -0.1) : max(facing, 0.1);  // grazing light: bounded stretch
  vec3 point = r.position + across - (dot(across, r.normal) / facing) * f.light;
  vec4 clip = params.view_projection * vec4(point, 1.0);
  if (clip.w <= 0.0) return ivec2(-1);
  return ivec2(floor((clip.xy / clip.w * 0.5 + 0.5) * vec2(extent())));
}

// A tap's pixel counts where it lies on the receiver's own surface (near its tangent plane).
bool same_surface(Receiver r, Receiver t, float pixel_width) {
  vec3 d = t.position - r.position;
  return t.valid && abs(dot(d, r.normal)) <= 2.0 * pixel_width + 0.1 * length(d);
}

float across_distance(Across f, vec3 d) { return length(d - dot(d, f.light) * f.light); }

// The share of the unit disc below the line at `t` (-1..1) along any axis.
float disc_below(float t) {
  t = clamp(t, -1.0, 1.0);
  return 0.5 + (t * sqrt(1.0 - t * t) + asin(t)) / 3.14159265;
}

// At 1 spp the disc's taps each take a whole pixel's term, so its average places the edge to a pixel
// (on a surface seen at a grazing angle, to a pixel that spans much of the disc one way) and, with a
// few taps over a wide disc, with noise. The pixels around (fit_half_window, on this surface) place a
// straight edge better: their points across the light are exact, and of the lines that separate the lit ones
// from the shadowed ones, the one along kFitDirections directions (a half turn, either way) that
// leaves the widest gap between the two sits halfway across that gap. The lit share of the disc of
// `radius` on this pixel's side of it is the term. False (the disc's average stands) where the pixels
// are all lit or all shadowed, or no line separates them (a corner, a thin caster). (Lavapipe, 256²,
// a 2-degree sun, soft_mae against the line perpendicular to the difference of the two sides' means,
// both fitted only where the disc's average was strictly between 0 and 1: atrium v0 0.00154 ->
// 0.00121, v1 0.00058 -> 0.00049, contact v1 0.00045 -> 0.00042, Sponza v1 0.00368 -> 0.00338, the
// other views of Views/SoftShadowsTest within 0.00003; 8 directions 0.00130 on atrium v0, 3 directions
// 0.00061 on atrium v1. H200, 4K, the default sun, the pass against that line's: contact 0.073 ->
// 0.070 ms, atrium 0.106 -> 0.106, canopy 0.121 -> 0.118, Sponza v1 0.105 -> 0.109; its 16 floats
// of ranges cost less than 8 directions' 32, which took 0.01-0.02 ms more.)
const uint kFitDirections = 4u;

// On a GPU, the filter's tile and the kFitBorder pixels around it, each pixel's point and term (-1:
// not valid), loaded once a workgroup: the fit windows overlap, 196 pixels for a tile's 1600 to 3136
// loads. (A CPU device reads the window's pixels where a fit is made: loading every listed tile's
// window and the barrier after it cost lavapipe more than the loads they spare.)
const int kFitBorder = 3;
const int kFitWindow = int(kPenumbraTile) + 2 * kFitBorder;
const uint kFitWindowPixels = kStep == kStepFilter ? uint(kFitWindow * kFitWindow) : 1u;
shared vec4 fit_window[kFitWindowPixels];
// (Sized by the step alone: an array size that also reads kIzbFlags made lavapipe's
// vkCreateComputePipelines fail, so a CPU device declares the window and leaves it unused.)
bool fit_window_shared() { return !izb_flag(IZB_FLAG_CPU_DEVICE); }

void load_fit_window(ivec2 tile_origin) {
  if (!fit_window_shared()) return;
  for (uint k = gl_LocalInvocationIndex; k < uint(kFitWindow * kFitWindow); k += kPenumbraTile * kPenumbraTile) {
    ivec2 pixel = tile_origin - kFitBorder + ivec2(int(k) % kFitWindow, int(k) / kFitWindow);
    Receiver t = load_tap(pixel, false);
    fit_window[k] = vec4(t.position, t.valid ? t.term : -1.0);
  }
  barrier();
}

Receiver fit_tap(ivec2 pixel, ivec2 offset) {
  if (!fit_window_shared()) return load_tap(pixel + offset, false);
  vec4 w = fit_window[(int(gl_LocalInvocationID.y) + kFitBorder + offset.y) * kFitWindow +
                      int(gl_LocalInvocationID.x) + kFitBorder + offset.x];
  Receiver t;
  t.position = w.xyz;
  t.valid = w.w >= 0.0;
  t.term = t.valid ? w.w : 1.0;
  t.normal = vec3(0.0);
  t.height = -1.0;
  return t;
}

// The fit's window grows with the disc: 5x5 pixels, 7x7 where its radius is over 1.5 pixels, so that
// a wider penumbra's edge is placed by pixels on both of its sides. (Lavapipe, 256², a 2-degree sun,
// with the lit pixels' tangents, against 5x5 throughout: atrium v0 soft_mae 0.00117 -> 0.00094, Sponza
// v1 0.00334 -> 0.00321, the other views of Views/SoftShadowsTest within 0.0001. 9x9 over 3 pixels
// took Sponza v1 to 0.00306 and the filter step on the H200 at 4K from 0.045 to 0.077 ms on atrium;
// 7x7 reading only half of its outer ring, atrium v0 0.00106.)
int fit_half_window(float radius, float pixel_width) { return radius > 1.5 * pixel_width ? 3 : 2; }

bool fitted_edge(ivec2 pixel, Receiver r, Across f, float pixel_width, float radius, out float value) {
  // One pass over the window's pixels: along each of kFitDirections directions (a half turn), the
  // range of the lit pixels' and of the shadowed pixels' points; the direction (either way along it)
  // that leaves the widest gap between the two separates them best.
  value = 1.0;
  float lit_low[kFitDirections], lit_high[kFitDirections], dark_low[kFitDirections], dark_high[kFitDirections];
  for (uint j = 0u; j < kFitDirections; ++j) {
    lit_low[j] = dark_low[j] = 3.0e38;
    lit_high[j] = dark_high[j] = -3.0e38;
  }
  bool lit_seen = false, dark_seen = false;
  int half_window = fit_half_window(radius, pixel_width);
  for (int dy = -half_window; dy <= half_window; ++dy)
    for (int dx = -half_window; dx <= half_window; ++dx) {
      Receiver t = fit_tap(pixel, ivec2(dx, dy));
      if (!same_surface(r, t, pixel_width)) continue;
      vec3 d = t.position - r.position;
      vec2 across = vec2(dot(d, f.u), dot(d, f.v));
      bool lit = t.term >= 0.5;
      lit_seen = lit_seen || lit;
      dark_seen = dark_seen || !lit;
      for (uint j = 0u; j < kFitDirections; ++j) {
        float angle = 3.14159265 * float(j) / float(kFitDirections);
        float along = dot(across, vec2(cos(angle), sin(angle)));
        if (lit) {
          lit_low[j] = min(lit_low[j], along);
          lit_high[j] = max(lit_high[j], along);
        } else {
          dark_low[j] = min(dark_low[j], along);
          dark_high[j] = max(dark_high[j], along);
        }
      }
    }
  if (!lit_seen || !dark_seen) return false;
  float darkest = 0.0, lightest = 0.0, widest = 0.0;  // along the best direction, lit side positive
  for (uint j = 0u; j < kFitDirections; ++j) {
    if (lit_low[j] - dark_high[j] > widest) {
      widest = lit_low[j] - dark_high[j];
      darkest = dark_high[j];
      lightest = lit_low[j];
    }
    if (dark_low[j] - lit_high[j] > widest) {
      widest = dark_low[j] - lit_high[j];
      darkest = -dark_low[j];
      lightest = -lit_high[j];
    }
  }
  if (widest <= 0.0) return false;
  value = 1.0 - disc_below(0.5 * (darkest + lightest) / radius);
  return true;
}

// The filtered term of `r` (at `pixel`; `reach`: the widest penumbra in reach, in pixels), or
// kNoValue where the IZB's term stays.
uint filtered_term(ivec2 pixel, Receiver r, float reach, bool fit_possible) {
  if (!r.valid) return kNoValue;
  Across f = across_light();
  float pixel_width = footprint(r.position);
  float turn = pixel_turn(pixel);
  // (1) Blockers: shadowed pixels around whose penumbra reaches this one, their heights averaged.
  float search = reach * pixel_width;
  float heights = 0.0, blockers = 0.0;
  if (r.height > 0.0) {
    heights += r.height;
    blockers += 1.0;
  }
  // A tap stands for its pixel's whole footprint, which a surface seen at a grazing angle stretches
  // away from the eye: half of it is the slack past the blocker's penumbra, up to a pixel's width
  // (wider, a penumbra under half a pixel would soften pixels it does not reach). (Lavapipe, 256², a
  // 2-degree sun, against half a pixel's width: atrium v1 soft_mae 0.00049 -> 0.00047 with the fit's
  // condition below, canopy v1 0.00754 -> 0.00746, the other views of Views/SoftShadowsTest within
  // 0.00005, each lower or equal.)
  vec3 to_eye = normalize(params.camera_position.xyz - r.position);
  float slack = min(0.5 * pixel_width / max(abs(dot(to_eye, r.normal)), 0.1), pixel_width);
  // A shadowed pixel's own occluder is its blocker; a lit one searches.
  for (uint k = 0u; k < (r.height > 0.0 ? 0u : kPenumbraSearchTaps); ++k) {
    Receiver t = load_tap(tap_pixel(r, f, search * disc_tap(k, kPenumbraSearchTaps, turn)), true);
    if (!same_surface(r, t, pixel_width) || t.height <= 0.0) continue;
    if (across_distance(f, t.position - r.position) > t.height * tan_half_angle() + slack) continue;
    heights += t.height;
    blockers += 1.0;
  }
  if (blockers == 0.0) return kNoValue;
  float radius = heights / blockers * tan_half_angle();
  if (radius < 0.5 * pixel_width) return kNoValue;  // narrower than a pixel: the exact term
  radius = min(radius, float(kPenumbraMaxRadius) * pixel_width);
  // A lit pixel whose lists held a caster's edge in reach knows where that edge is: the share of the
  // sun's disc beyond it (an edge straight over the disc) is what the pixel loses; no disc or fit.
  // (Lavapipe, 256², a 2-degree sun, with the 7x7 fit window, against none: contact v1 soft_mae
  // 0.00042 -> 0.00035, atrium v0 0.00098 -> 0.00094, foliage v1 0.00649 -> 0.00627, canopy v0 0.00728
  // -> 0.00712, the other views lower or within 0.00001.)
  if (params.extent.w == 1u && r.term >= 0.5) {
    float tangent = lit_tangent(uint(pixel.y) * params.extent.x + uint(pixel.x));
    if (tangent >= 0.0) return floatBitsToUint(disc_below(tangent / tan_half_angle()));
  }
  // (2) The term averaged over the disc across the light, on this surface: each tap takes the term of
  // the pixel it falls in (the IZB's term held over the pixel's square), so even a disc of a pixel or
  // two weighs its neighbours by how much of them it covers.
  float sum = 0.0, weight = 0.0;
  for (uint k = 0u; k < kPenumbraFilterTaps; ++k) {
    Receiver t = load_tap(tap_pixel(r, f, radius * disc_tap(k, kPenumbraFilterTaps, turn + 1.0)), false);
    if (!same_surface(r, t, pixel_width)) continue;
    sum += t.term;
    weight += 1.0;
  }
  if (weight == 0.0) return kNoValue;
  // (Where every tap agrees the edge lies beyond the disc: nothing to fit; but a disc of two pixels'
  // radius or less falls between the pixels' centres, where its taps may all miss an edge within it.)
  float average = sum / weight, fitted;
  bool edge_within = (average > 0.0 && average < 1.0) || radius <= 2.0 * pixel_width;
  if (params.extent.w == 1u && fit_possible && edge_within && fitted_edge(pixel, r, f, pixel_width, radius, fitted))
    return floatBitsToUint(fitted);
  return floatBitsToUint(average);
}

// The listed tile of this workgroup (the filter's and the apply's indirect dispatch), or false.
bool listed_tile(out uint slot, out uvec4 entry) {
  slot = gl_WorkGroupID.y * kIzbDispatchRow + gl_WorkGroupID.x;
  if (slot >= counters[IZB_COUNTER_PENUMBRA_TILES]) return false;
  entry = entries[listed_at() + slot];
  return true;
}

ivec2 tile_pixel(uint tile) {
  return ivec2(tile % tiles_x(), tile / tiles_x()) * int(kPenumbraTile) + ivec2(gl_LocalInvocationID.xy);
}

// Where a listed tile's filtered terms are kept: 4 an entry.
uint value_entry(uint slot) {
  return values_at() + slot * (kPenumbraTile * kPenumbraTile / 4u) +
         gl_LocalInvocationIndex / 4u;
}

void filter_tile() {
  uint slot;
  uvec4 entry;
  if (!listed_tile(slot, entry)) return;
  ivec2 pixel = tile_pixel(entry.x);
  // Where the tile and its neighbours hold only lit or only shadowed terms, no fit window (within
  // kFitBorder of the tile) holds both sides, and no fit is made: the window is not loaded either.
  bool fit_possible = params.extent.w == 1u && entry.z != 0u;
  if (fit_possible) load_fit_window(pixel - ivec2(gl_LocalInvocationID.xy));
  entries[value_entry(slot)][gl_LocalInvocationIndex % 4u] =
      filtered_term(pixel, load_receiver(pixel), uintBitsToFloat(entry.y), fit_possible);
}

// ---- kStepApply ----------------------------------------------------------------------------------
void apply_tile() {
  uint slot;
  uvec4 entry;
  if (!listed_tile(slot, entry)) return;
  ivec2 pixel = tile_pixel(entry.x);
  uint value = entries[value_entry(slot)][gl_LocalInvocationIndex % 4u];
  if (value != kNoValue && inside(pixel)) imageStore(shadow_term, pixel, vec4(uintBitsToFloat(value)));
}

void main() {
  if (kStep == kStepTiles) summarize_tiles();
  else if (kStep == kStepDilate) dilate_tile();
  else if (kStep == kStepFilter) filter_tile();
  else apply_tile();
}
