#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
layout(local_size_x = 8, local_size_y = 8) in;  // kPenumbraTile²: a workgroup a tile

// The hybrid's penumbrae, after the IZB wrote its exact hard term (1 spp: 0 or 1; 32 spp: the lit
// fraction) and, per pixel it found shadowed, the light depth from the point up to an occluder it
// found (IZB_FLAG_GAPS). A sun of angular radius a seen from a point an occluder's height g below it
// (along the light) is blocked over a disc of radius g tan(a) around the hard shadow's edge: for a
// planar receiver and an occluder at one height, the lit fraction is the hard term averaged over that
// disc, measured across the light (in the plane perpendicular to it). So each pixel near a shadow
// edge (1) finds the blockers whose penumbra reaches it among the pixels around it (their occluder
// heights, averaged), and (2) averages the hard term of the pixels within that radius on its own
// plane, both with taps laid across the light and mapped onto the pixel's tangent plane and into the
// image. Where the penumbra is narrower than a pixel the IZB's term stays as it is, exact.
//
// Three steps, specialized apart (a CPU device runs every branch):
//  kStepTiles:  per tile, the range of the hard term and the widest penumbra its shadowed pixels cast
//               (in pixels);
//  kStepFilter: per tile, whether any tile within kPenumbraMaxRadius casts a penumbra that reaches it
//               over a term that varies; if so, the tile is listed and its pixels' filtered terms
//               stored beside the list (the term itself is read by the neighbours' taps);
//  kStepApply:  over the listed tiles (an indirect dispatch), the filtered terms into the term.
const uint kStepTiles = 0u;
const uint kStepFilter = 1u;
const uint kStepApply = 2u;
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
float range_limit() { return params.camera_position.w > 0.0 ? params.camera_position.w : 3.0e38; }
// A pixel's width in world units at `p`.
float footprint(vec3 p) { return max(distance(p, params.camera_position.xyz) * params.penumbra.y, 1.0e-30); }

// The light depth from the pixel up to the occluder the IZB found, in world units (-1: none found).
float occluder_height(uint index) {
  float gap = uintBitsToFloat(occluder_distance[index]);
  return gap < 1.0e20 ? gap * (params.depth_range.y - params.depth_range.x) : -1.0;
}

struct Receiver {
  bool valid;     // covered, receiving, facing the light and inside the IZB's range
  vec3 position;
  vec3 normal;
  float term;     // the IZB's
  float height;   // occluder_height
};

Receiver load_receiver(ivec2 pixel) {
  Receiver r;
  r.valid = false;
  r.term = 1.0;
  r.height = -1.0;
  r.position = vec3(0.0);
  r.normal = vec3(0.0, 1.0, 0.0);
  if (any(lessThan(pixel, ivec2(0))) || any(greaterThanEqual(pixel, extent()))) return r;
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

// ---- kStepTiles ----------------------------------------------------------------------------------
shared uint tile_min_term, tile_max_term, tile_radius;

void summarize_tile() {
  if (gl_LocalInvocationIndex == 0u) {
    tile_min_term = floatBitsToUint(1.0);
    tile_max_term = 0u;
    tile_radius = 0u;
  }
  barrier();
  Receiver r = load_receiver(ivec2(gl_GlobalInvocationID.xy));
  if (r.valid) {
    atomicMin(tile_min_term, floatBitsToUint(r.term));  // terms in [0, 1]: their bits order as they do
    atomicMax(tile_max_term, floatBitsToUint(r.term));
    if (r.height > 0.0) atomicMax(tile_radius, floatBitsToUint(r.height * tan_half_angle() / footprint(r.position)));
  }
  barrier();
  if (gl_LocalInvocationIndex == 0u) {
    uint tile = gl_WorkGroupID.y * tiles_x() + gl_WorkGroupID.x;
    entries[izb_penumbra_tiles_at(params.extent.x, params.extent.y) + tile] =
        uvec4(tile_min_term, tile_max_term, tile_radius, 0u);
  }
}

// ---- kStepFilter ---------------------------------------------------------------------------------
shared uint window_radius, window_min_term, window_max_term, listed_slot;

// Pixels between tile `t`'s nearest pixel and this tile's (0 for the tile itself and its neighbours).
float tile_gap(ivec2 offset) { return length(vec2(max(abs(offset) - 1, ivec2(0)) * int(kPenumbraTile))); }

// Whether this tile needs filtering: some tile in reach casts a penumbra over it, and the term varies
// within that reach. Sets window_radius (pixels) and listed_slot.
bool tile_in_penumbra() {
  uint i = gl_LocalInvocationIndex;
  if (i == 0u) {
    window_radius = 0u;
    window_min_term = floatBitsToUint(1.0);
    window_max_term = 0u;
  }
  barrier();
  const int side = 2 * kWindow + 1;
  ivec2 offset = ivec2(int(i) % side, int(i) / side) - kWindow;
  ivec2 tile = ivec2(gl_WorkGroupID.xy) + offset;
  bool in_window = int(i) < side * side && all(greaterThanEqual(tile, ivec2(0))) &&
                   all(lessThan(tile, ivec2(tiles_x(), penumbra_tiles_y(params.extent.y))));
  uvec4 summary = in_window ? entries[izb_penumbra_tiles_at(params.extent.x, params.extent.y) + uint(tile.y) * tiles_x() + uint(tile.x)]
                            : uvec4(floatBitsToUint(1.0), 0u, 0u, 0u);
  float radius = min(uintBitsToFloat(summary.z), float(kPenumbraMaxRadius));
  if (in_window && radius >= 0.5 && radius >= tile_gap(offset)) atomicMax(window_radius, floatBitsToUint(radius));
  barrier();
  float reach = uintBitsToFloat(window_radius);
  if (in_window && reach > 0.0 && tile_gap(offset) <= reach) {
    atomicMin(window_min_term, summary.x);
    atomicMax(window_max_term, summary.y);
  }
  barrier();
  bool needed = reach > 0.0 && window_min_term < window_max_term;
  if (needed && i == 0u) {
    listed_slot = atomicAdd(counters[IZB_COUNTER_PENUMBRA_TILES], 1u);
    // The apply step's dispatch: rows of kIzbDispatchRow workgroups (a dimension's portable limit is 65535).
    atomicMax(counters[IZB_COUNTER_PENUMBRA_TILES + 1u], min(listed_slot + 1u, kIzbDispatchRow));
    atomicMax(counters[IZB_COUNTER_PENUMBRA_TILES + 2u], listed_slot / kIzbDispatchRow + 1u);
    counters[IZB_COUNTER_PENUMBRA_TILES + 3u] = 1u;
    entries[izb_penumbra_list_at(params.extent.x, params.extent.y) + listed_slot] =
        uvec4(gl_WorkGroupID.y * tiles_x() + gl_WorkGroupID.x, 0u, 0u, 0u);
  }
  barrier();
  return needed;
}

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

struct Frame2 {
  vec3 across_u, across_v;  // unit, perpendicular to the light and to each other
  vec3 light;               // the direction light travels
};

Frame2 light_frame() {
  Frame2 f;
  f.light = normalize(params.light_direction.xyz);
  vec3 helper = abs(f.light.y) < 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
  f.across_u = normalize(cross(helper, f.light));
  f.across_v = cross(f.light, f.across_u);
  return f;
}

// The pixel showing the point of `r`'s tangent plane that lies `offset` across the light from it.
ivec2 tap_pixel(Receiver r, Frame2 f, vec2 offset) {
  vec3 across = offset.x * f.across_u + offset.y * f.across_v;
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

float across_distance(Frame2 f, vec3 d) { return length(d - dot(d, f.light) * f.light); }

// The filtered term of `r` (at `pixel`), or kNoValue where the IZB's term stays.
uint filtered_term(ivec2 pixel, Receiver r) {
  if (!r.valid) return kNoValue;
  Frame2 f = light_frame();
  float pixel_width = footprint(r.position);
  float turn = pixel_turn(pixel);
  // (1) Blockers: shadowed pixels around whose penumbra reaches this one, their heights averaged.
  float search = uintBitsToFloat(window_radius) * pixel_width;
  float heights = 0.0, blockers = 0.0;
  if (r.height > 0.0) {
    heights += r.height;
    blockers += 1.0;
  }
  for (uint k = 0u; k < kPenumbraSearchTaps; ++k) {
    Receiver t = load_receiver(tap_pixel(r, f, search * disc_tap(k, kPenumbraSearchTaps, turn)));
    if (!same_surface(r, t, pixel_width) || t.height <= 0.0) continue;
    // (Half a pixel of slack: the tap stands for its pixel's whole square.)
    if (across_distance(f, t.position - r.position) > t.height * tan_half_angle() + 0.5 * pixel_width) continue;
    heights += t.height;
    blockers += 1.0;
  }
  if (blockers == 0.0) return kNoValue;
  float radius = heights / blockers * tan_half_angle();
  if (radius < 0.5 * pixel_width) return kNoValue;  // narrower than a pixel: the exact term
  radius = min(radius, float(kPenumbraMaxRadius) * pixel_width);
  // (2) The term averaged over the disc across the light, on this surface: each tap takes the term of
  // the pixel it falls in (the IZB's term held over the pixel's square), so even a disc of a pixel or
  // two weighs its neighbours by how much of them it covers.
  float sum = 0.0, weight = 0.0;
  for (uint k = 0u; k < kPenumbraFilterTaps; ++k) {
    Receiver t = load_receiver(tap_pixel(r, f, radius * disc_tap(k, kPenumbraFilterTaps, turn + 1.0)));
    if (!same_surface(r, t, pixel_width)) continue;
    sum += t.term;
    weight += 1.0;
  }
  if (weight == 0.0) return kNoValue;
  return floatBitsToUint(sum / weight);
}

void filter_tile() {
  if (!tile_in_penumbra()) return;
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  uint value = filtered_term(pixel, load_receiver(pixel));
  uint at = izb_penumbra_values_at(params.extent.x, params.extent.y) + listed_slot * (kPenumbraTile * kPenumbraTile / 4u);
  entries[at + gl_LocalInvocationIndex / 4u][gl_LocalInvocationIndex % 4u] = value;
}

// ---- kStepApply ----------------------------------------------------------------------------------
void apply_tile() {
  uint slot = gl_WorkGroupID.y * kIzbDispatchRow + gl_WorkGroupID.x;
  if (slot >= counters[IZB_COUNTER_PENUMBRA_TILES]) return;
  uint tile = entries[izb_penumbra_list_at(params.extent.x, params.extent.y) + slot].x;
  ivec2 pixel = ivec2(tile % tiles_x(), tile / tiles_x()) * int(kPenumbraTile) + ivec2(gl_LocalInvocationID.xy);
  uint at = izb_penumbra_values_at(params.extent.x, params.extent.y) + slot * (kPenumbraTile * kPenumbraTile / 4u);
  uint value = entries[at + gl_LocalInvocationIndex / 4u][gl_LocalInvocationIndex % 4u];
  if (value != kNoValue && all(lessThan(pixel, extent()))) imageStore(shadow_term, pixel, vec4(uintBitsToFloat(value)));
}

void main() {
  if (kStep == kStepTiles) summarize_tile();
  else if (kStep == kStepFilter) filter_tile();
  else apply_tile();
}
