// Percentage-closer soft shadows (PCSS) over one depth map: a blocker search around the receiver, the
// penumbra its average blocker depth gives, and a percentage-closer filter over a disc of that radius.
// shadow_map_resolve.glsl (sm, and the spot and point-light face maps) and cascade_filter.comp (in the
// pixel's cascade) use it; so may any pass that holds a light-space depth map.
//
// What the includer provides. Before `#include "pcss.glsl"`, declare
//     float pcss_map_depth(int layer, ivec2 texel);
// returning the stored light depth (0 nearest the light .. 1) of `texel`, which pcss.glsl has already
// clamped into [0, size - 1], in map `layer` (a cascade's layer; a single map ignores it). pcss.glsl
// binds nothing itself: the map's sampler, its size and scales come from the includer (PcssMap).
//
// Units. Offsets across the map are measured in map units: world units for an orthographic map (the
// sun's), world units at unit distance from the light along its axis (tangents) for a perspective map
// (a spot light's, a point light's cube-face cone). A receiver at light depth z is shadowed by an
// occluder at depth d < z only through the occluder's points within pcss_reach(z, d) map units of
// the receiver's own position in the map: the light's disc (sun: angular radius a, tan a = light_size;
// local light: a sphere of radius light_size) seen from the receiver, cut at the occluder's depth.
// That same reach, for the average blocker depth, is the receiver's penumbra radius. Every tap
// compares the receiver's tangent plane (PcssReceiver::gradient) at the tap texel's centre with the
// texel's stored depth plus the bias, so a planar receiver does not shadow itself as the taps spread.
#ifndef PCSS_GLSL
#define PCSS_GLSL

const uint kPcssSearchTaps = 16u;
const uint kPcssFilterTaps = 24u;

struct PcssMap {
  int layer;           // passed to pcss_map_depth
  int size;            // texels per side
  vec2 texel;          // map units per texel, along x and y
  float light_size;    // orthographic: tan of the sun's angular radius; perspective: the light's radius
  bool perspective;
  float depth_range;   // orthographic: world units from light depth 0 to 1
  vec2 near_far;       // perspective: the projection's near and far planes (world units; depth 0 at near)
};

struct PcssReceiver {
  vec2 t;          // map texel coordinates (texel i spans [i, i + 1))
  float z;         // light depth
  vec2 gradient;   // the receiver's tangent plane: light depth per texel, x and y
  float bias;      // added to every stored depth before comparing
};

// World distance from the light of light depth z: orthographic, from depth 0; perspective, along
// the axis from the light's position (the ratio of two such distances is that along any ray).
float pcss_distance(PcssMap m, float z) {
  if (!m.perspective) return z * m.depth_range;
  float n = m.near_far.x, f = m.near_far.y;
  return n * f / max(f - z * (f - n), 1.0e-30);
}

// Map units around the receiver (depth z) through which an occluder at depth d can block the light.
float pcss_reach(PcssMap m, float z, float d) {
  float dz = pcss_distance(m, z), dd = pcss_distance(m, d);
  float gap = max(dz - dd, 0.0);
  return m.perspective ? m.light_size * gap / max(dz * dd, 1.0e-30) : m.light_size * gap;
}

// The same reach in world units on the receiver: its penumbra radius for a blocker at depth d.
float pcss_penumbra_world(PcssMap m, float z, float d) {
  return pcss_reach(m, z, d) * (m.perspective ? pcss_distance(m, z) : 1.0);
}

// The blocker search's radius in map units: the reach of an occluder at the map's nearest depth,
// at most max_texels texels of the finer axis.
float pcss_search_radius(PcssMap m, float z, float max_texels) {
  return min(pcss_reach(m, z, 0.0), max_texels * min(m.texel.x, m.texel.y));
}

// A fixed per-pixel turn of the tap discs (cos, sin): a hash of the pixel, the same every frame.
vec2 pcss_rotation(ivec2 pixel) {
  uint h = uint(pixel.x) * 0x8da6b343u ^ uint(pixel.y) * 0xd8163841u;
  h ^= h >> 15u;
  h *= 0x2c1b3c6du;
  h ^= h >> 12u;
  h *= 0x297a2d39u;
  h ^= h >> 15u;
  float a = float(h >> 8u) * (6.2831853 / 16777216.0);
  return vec2(cos(a), sin(a));
}

// Tap k of n on a golden-angle spiral filling the unit disc evenly, turned by `rotation`.
vec2 pcss_disc(uint k, uint n, vec2 rotation) {
  float r = sqrt((float(k) + 0.5) / float(n));
  float a = float(k) * 2.39996323;
  vec2 o = r * vec2(cos(a), sin(a));
  return vec2(o.x * rotation.x - o.y * rotation.y, o.x * rotation.y + o.y * rotation.x);
}

// Whether the receiver is lit at the map texel under t + offset (texels); `depth` the texel's.
bool pcss_tap(PcssMap m, PcssReceiver r, vec2 offset, out float depth) {
  ivec2 texel = ivec2(floor(r.t + offset));
  float z = r.z + dot(r.gradient, vec2(texel) + 0.5 - r.t);
  depth = pcss_map_depth(m.layer, clamp(texel, ivec2(0), ivec2(m.size - 1)));
  return z <= depth + r.bias;
}

struct PcssBlockers {
  uint count;    // taps that block part of the light
  float depth;   // their average light depth (0 when none)
};

// The blocker search: kPcssSearchTaps taps over a disc of `radius` map units. A tap counts when it
// shadows the receiver and lies within the reach of its own depth (farther out it could not hide
// any of the light from this receiver).
PcssBlockers pcss_blockers(PcssMap m, PcssReceiver r, float radius, vec2 rotation) {
  PcssBlockers b;
  b.count = 0u;
  float sum = 0.0;
  for (uint k = 0u; k < kPcssSearchTaps; ++k) {
    vec2 o = pcss_disc(k, kPcssSearchTaps, rotation) * radius;
    float depth;
    bool blocks = !pcss_tap(m, r, o / m.texel, depth) && length(o) <= pcss_reach(m, r.z, depth);
    b.count += blocks ? 1u : 0u;
    sum += blocks ? depth : 0.0;
  }
  b.depth = b.count > 0u ? sum / float(b.count) : 0.0;
  return b;
}

// The nearest light depth among kPcssSearchTaps taps over a disc of `radius` map units that shadow the
// receiver, or 2 where none does (farther than any depth).
float pcss_nearest_occluder(PcssMap m, PcssReceiver r, float radius, vec2 rotation) {
  float nearest = 2.0;
  for (uint k = 0u; k < kPcssSearchTaps; ++k) {
    float depth;
    bool shadows = !pcss_tap(m, r, pcss_disc(k, kPcssSearchTaps, rotation) * radius / m.texel, depth);
    nearest = shadows ? min(nearest, depth) : nearest;
  }
  return nearest;
}

// Lit fraction of kPcssFilterTaps taps over a disc of `radius` map units (the spiral turned the other
// way round from the search's, so the two sets of taps do not coincide).
float pcss_filter(PcssMap m, PcssReceiver r, float radius, vec2 rotation) {
  uint lit = 0u;
  vec2 turned = vec2(rotation.y, rotation.x);
  for (uint k = 0u; k < kPcssFilterTaps; ++k) {
    float depth;
    lit += pcss_tap(m, r, pcss_disc(k, kPcssFilterTaps, turned) * radius / m.texel, depth) ? 1u : 0u;
  }
  return float(lit) / float(kPcssFilterTaps);
}

// The whole PCSS term: a first search over pcss_search_radius(max_texels) for the nearest occluder,
// the blocker search over that occluder's reach (where the map's near plane lies far nearer the light
// than any caster, as a spot light's does, the first radius would spread the taps too thin for the
// reach test to keep any), then the filter over the penumbra's radius (clamped likewise; sm and
// cascades pass kPcssMaxTexels, shared/shadows.h). Returns -1 where no tap blocks or the penumbra's radius is
// below `min_texels` texels of the coarser axis: there the caller keeps its own narrower filter or
// one tap, so a small light changes nothing where its penumbra is narrower than that.
float pcss_visibility(PcssMap m, PcssReceiver r, vec2 rotation, float max_texels, float min_texels) {
  float search = pcss_search_radius(m, r.z, max_texels);
  float nearest = pcss_nearest_occluder(m, r, search, rotation);
  if (nearest > 1.0) return -1.0;
  PcssBlockers b = pcss_blockers(m, r, min(search, pcss_reach(m, r.z, nearest)), rotation);
  if (b.count == 0u) return -1.0;
  float radius = min(pcss_reach(m, r.z, b.depth), max_texels * min(m.texel.x, m.texel.y));
  if (radius < min_texels * max(m.texel.x, m.texel.y)) return -1.0;
  return pcss_filter(m, r, radius, rotation);
}

// The receiver's tangent plane in a map (`plane_matrix`: the transpose of the inverse of the map's
// world -> clip transform, which carries world planes to clip-space planes, perspective or not): light
// depth per texel along x and y, each clamped to +-max_slope. An orthographic map's plane matrix has
// zeros in its last column's first three rows, so there the slope does not depend on the plane's
// offset and only nine values are read.
vec2 pcss_plane_gradient(mat4 plane_matrix, bool perspective, vec3 p, vec3 n, int size, float max_slope) {
  vec3 plane = perspective ? (plane_matrix * vec4(n, -dot(n, p))).xyz : mat3(plane_matrix) * n;
  vec2 slope = abs(plane.z) > 1.0e-20 ? -plane.xy / plane.z * (2.0 / float(size)) : vec2(0.0);
  return clamp(slope, vec2(-max_slope), vec2(max_slope));
}

// Eight times the depth change per texel across a surface turned 45 degrees from the light at depth
// z: steeper receiver planes are clamped to it (pcss_plane_gradient).
float pcss_max_slope(PcssMap m, float z) {
  float texel = max(m.texel.x, m.texel.y);
  if (!m.perspective) return 8.0 * texel / m.depth_range;
  float n = m.near_far.x, f = m.near_far.y;
  return 8.0 * n * f * texel / max((f - n) * pcss_distance(m, z), 1.0e-30);
}

#endif
