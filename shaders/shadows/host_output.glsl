// The module's shadow term (and overlay) into the host's images; HOST_OUTPUT_FORMAT is the output's
// storage format qualifier (one shader per accepted format).
#include "host.h"
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = HOST_OUTPUT_BINDING_TERM, r32f) readonly uniform image2D term;
layout(set = 0, binding = HOST_OUTPUT_BINDING_OVERLAY, rgba8) readonly uniform image2D overlay;
layout(set = 0, binding = HOST_OUTPUT_BINDING_OUT, HOST_OUTPUT_FORMAT) writeonly uniform image2D out_term;
layout(set = 0, binding = HOST_OUTPUT_BINDING_OVERLAY_OUT, rgba8) writeonly uniform image2D out_overlay;
layout(push_constant) uniform Push { uvec4 extent; };  // x, y: size
// HOST_OUTPUT_* bits: a specialization constant, not a push constant, so that a CPU device (which runs
// every branch) loads and stores only what this frame writes.
layout(constant_id = 0) const uint kWhat = 0u;

void main() {
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(uvec2(pixel), extent.xy))) return;
  imageStore(out_term, pixel, (kWhat & HOST_OUTPUT_ALL_LIT) != 0u ? vec4(1.0) : imageLoad(term, pixel));
  if ((kWhat & HOST_OUTPUT_COPY_OVERLAY) != 0u) imageStore(out_overlay, pixel, imageLoad(overlay, pixel));
  if ((kWhat & HOST_OUTPUT_ZERO_OVERLAY) != 0u) imageStore(out_overlay, pixel, vec4(0.0));
}
