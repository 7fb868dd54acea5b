// The module's shadow term (and overlay) into the host's images; HOST_OUTPUT_FORMAT is the output's
// storage format qualifier (one shader per accepted format).
#include "host.h"
#include "shadow_common.h"
#include "local_light.h"
// Several pixels a thread, 256 threads a workgroup: with a thread a pixel and 64 a workgroup, a GPU
// spends longer starting workgroups than storing (0.08 ms at 4K on an H200 for this pass).
layout(local_size_x = HOST_OUTPUT_GROUP_X, local_size_y = HOST_OUTPUT_GROUP_Y) in;

layout(set = 0, binding = HOST_OUTPUT_BINDING_TERM, r32f) readonly uniform image2D term;
layout(set = 0, binding = HOST_OUTPUT_BINDING_OVERLAY, rgba8) readonly uniform image2D overlay;
layout(set = 0, binding = HOST_OUTPUT_BINDING_OUT, HOST_OUTPUT_FORMAT) writeonly uniform image2D out_term;
layout(set = 0, binding = HOST_OUTPUT_BINDING_OVERLAY_OUT, rgba8) writeonly uniform image2D out_overlay;
layout(set = 0, binding = HOST_OUTPUT_BINDING_WORLD_POSITION, rgba32f) readonly uniform image2D world_position;
layout(set = 0, binding = HOST_OUTPUT_BINDING_GEOMETRIC_NORMAL, rgba16f) readonly uniform image2D geometric_normal;
layout(push_constant) uniform Push { HostOutputPush push; };
// HOST_OUTPUT_* bits: a specialization constant, not a push constant, so that a CPU device (which runs
// every branch) loads and stores only what this frame writes.
layout(constant_id = 0) const uint kWhat = 0u;

// Whether the light reaches and faces the point: the same tests, on the same inputs, as every
// technique's passes (local_light.h, shadow_common.h), so a point they wrote 0 for that reason alone
// is told apart from an occluded one.
bool lit_by_light(ivec2 pixel) {
  vec4 p = imageLoad(world_position, pixel);
  if (p.w <= 0.5) return true;  // background
  vec4 normal = imageLoad(geometric_normal, pixel);
  uint kind = push.extent.z;
  if (kind == HOST_OUTPUT_LIGHT_DIRECTIONAL) return faces_light(normal);
  return local_light_reaches(push.light_position.xyz, push.light_position.w, push.light_direction.xyz,
                             push.light_direction.w, kind == HOST_OUTPUT_LIGHT_SPOT, p.xyz) &&
         faces_local_light(normal.xyz, p.xyz, push.light_position.xyz);
}

void write_pixel(ivec2 pixel) {
  if (any(greaterThanEqual(uvec2(pixel), push.extent.xy))) return;
  vec4 value = vec4(1.0);
  if ((kWhat & HOST_OUTPUT_UNREACHED) != 0u) {
    // Every covered point lies out of the light's reach (ContextImpl::reaches_view): 0, as every
    // technique's passes would have written; the background lit.
    value = vec4(imageLoad(world_position, pixel).w > 0.5 ? 0.0 : 1.0);
  } else if ((kWhat & HOST_OUTPUT_ALL_LIT) == 0u) {
    // Occlusion: a point the light does not reach or face is not occluded: 1.
    bool unlit = (kWhat & HOST_OUTPUT_OCCLUSION) != 0u && !lit_by_light(pixel);
    value = unlit ? vec4(1.0) : imageLoad(term, pixel);
  }
  imageStore(out_term, pixel, value);
  if ((kWhat & HOST_OUTPUT_COPY_OVERLAY) != 0u) imageStore(out_overlay, pixel, imageLoad(overlay, pixel));
  if ((kWhat & HOST_OUTPUT_ZERO_OVERLAY) != 0u) imageStore(out_overlay, pixel, vec4(0.0));
}

void main() {
  const uvec2 group = uvec2(HOST_OUTPUT_GROUP_X, HOST_OUTPUT_GROUP_Y);
  const uvec2 steps = uvec2(HOST_OUTPUT_BLOCK) / group;
  uvec2 origin = gl_WorkGroupID.xy * HOST_OUTPUT_BLOCK + gl_LocalInvocationID.xy;
  for (uint y = 0u; y < steps.y; ++y)
    for (uint x = 0u; x < steps.x; ++x) write_pixel(ivec2(origin + uvec2(x, y) * group));
}
