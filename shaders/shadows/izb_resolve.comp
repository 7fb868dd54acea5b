#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows/izb_prelude.glsl"
#include "shadows/izb_pixel.glsl"
// 64 invocations a workgroup, 8x8 or a row of 64 pixels (IzbPipelineCache::with_pixel_group).
layout(local_size_x = 8, local_size_y = 8, local_size_x_id = 20, local_size_y_id = 21) in;

layout(push_constant) uniform Push { IzbComputePush push; };
#include "shadows/izb_straddlers.glsl"
layout(set = 0, binding = IZB_BINDING_OVERLAY, rgba8) uniform image2D overlay;

const uint kDebugVisibility = 1u;
const uint kDebugListLength = 2u;
const uint kDebugCsm = 4u;

vec3 heat(float t) {
  t = clamp(t, 0.0, 1.0);
  return clamp(vec3(1.5 - abs(4.0 * t - 3.0), 1.5 - abs(4.0 * t - 2.0), 1.5 - abs(4.0 * t - 1.0)), 0.0, 1.0);
}

// Specialized per debug view and hybrid (a CPU driver would otherwise run every branch).
layout(constant_id = 12) const uint kDebug = 0u;
layout(constant_id = 13) const uint kHybrid = 0u;

// Visibility mask -> shadow term (write_pixel_term). With kHybrid the resolve runs before the
// cascades: it writes the hard term and lists the pixels that blend toward the cascades' term. With
// IZB_FLAG_LISTED_RESOLVE the build has written every pixel without a node and listed the others, one
// a thread; otherwise one thread per pixel of the frame.
void resolve(ivec2 pixel, bool inside) {
  uint index = uint(pixel.y) * params.extent.x + uint(pixel.x);
  // The build classified every pixel (IZB_PIXEL_*). The surface itself is read only where the blend's
  // distance or a local light's rays need it: the rays only where casters straddle its near plane.
  uint state = inside ? pixel_state[index] : 0u;
  bool covered = (state & IZB_PIXEL_COVERED) != 0u;
  bool candidate = (state & IZB_PIXEL_CANDIDATE) != 0u;
  uint mask = candidate ? visibility_mask[index] : 0u;
  bool rays = candidate && spot_light() && mask != full_mask() && counters[IZB_COUNTER_STRADDLERS] != 0u;
  bool surface = covered && (kHybrid != 0u || rays);
  PixelPoint p = surface ? load_surface(pixel) : PixelPoint(false, false, vec3(0.0), vec3(0.0), false);
  if (rays) mask |= straddler_samples(pixel, p);
  bool written;
  float visibility = write_pixel_term(pixel, inside, state, mask, p.position, kHybrid != 0u, written);
  if (!written) return;

  if (kDebug == kDebugVisibility && (state & IZB_PIXEL_CANDIDATE) != 0u) {
    imageStore(overlay, pixel, vec4(mix(vec3(1.0, 0.2, 0.1), vec3(0.1, 1.0, 0.2), visibility), 0.6));
  } else if (kDebug == kDebugListLength && (state & IZB_PIXEL_CANDIDATE) != 0u) {
    // A pixel culled whole (by the CSM or the lit map) has no node nor stored points: no list.
    bool has_nodes = (state & (IZB_PIXEL_CSM_CULLED | IZB_PIXEL_LIT_CULLED)) == 0u;
    // (Anchored nodes: the list of the texel its samples' bounds start in, which holds its node.)
    ivec2 texel = grid_texel(quad_point(index, 0u));
    if (izb_flag(IZB_FLAG_ANCHORED_NODES) && has_nodes) {
      vec3 g[4] = vec3[4](quad_point(index, 0u), quad_point(index, 1u), quad_point(index, 2u), quad_point(index, 3u));
      ivec2 last;
      quad_texel_bounds(g, texel, last);
    }
    uint length = has_nodes ? list_length(texel_index(texel), 64u) : 0u;
    imageStore(overlay, pixel, vec4(heat(log2(float(length) + 1.0) / 6.0), 0.7));
  } else if (kDebug == kDebugCsm && (state & IZB_PIXEL_CSM_CULLED) != 0u) {
    imageStore(overlay, pixel, vec4(0.1, 0.4, 1.0, 0.6));
  }
}

void main() {
  if (izb_flag(IZB_FLAG_FACE_TILES)) {
    // A point light's face, or a spot light on a CPU device: the tiles its build ran over (the other
    // pixels are another face's, or izb_face_tiles.comp wrote them).
    ivec2 pixel;
    if (!face_tile_pixel(pixel)) return;
    resolve(pixel, all(lessThan(uvec2(pixel), params.extent.xy)));
    return;
  }
  if (!izb_flag(IZB_FLAG_LISTED_RESOLVE)) {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    resolve(pixel, all(lessThan(uvec2(pixel), params.extent.xy)));
    return;
  }
  uint index;
  bool listed = listed_pixel(index);
  resolve(ivec2(index % params.extent.x, index / params.extent.x), listed);
}
