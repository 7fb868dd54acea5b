#version 460
#extension GL_GOOGLE_include_directive : require
#include "frame.h"
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = SHADING_POINTS_BINDING_FRAME) uniform Frame { FrameUniforms frame; };
layout(set = 0, binding = SHADING_POINTS_BINDING_DEPTH) uniform sampler2D depth_image;
layout(set = 0, binding = SHADING_POINTS_BINDING_WORLD_POSITION, rgba32f) writeonly uniform image2D world_position;
layout(set = 0, binding = SHADING_POINTS_BINDING_TERMINATOR_OFFSET, rgba16f) readonly uniform image2D terminator_offset;

// World positions from depth, moved by the G-buffer's smooth-terminator offset (gbuffer.frag): the
// shading points every shadow technique and the reference start their rays from.
void main() {
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (any(greaterThanEqual(pixel, frame.extent.xy))) return;
  float depth = texelFetch(depth_image, ivec2(pixel), 0).r;
  if (depth <= 0.0) {  // reversed Z: cleared to 0 where nothing was drawn
    imageStore(world_position, ivec2(pixel), vec4(0.0));
    return;
  }
  // `precise`, as in the shadow module's input pass (host_inputs.glsl), which makes the same points from
  // a host's depth: a multiply-add fused in one shader and not in the other would move a point by a
  // rounding step, and a filter's tap at a shadow's edge with it.
  precise vec2 ndc = (vec2(pixel) + 0.5) / vec2(frame.extent.xy) * 2.0 - 1.0;
  precise vec4 world = frame.inverse_view_projection * vec4(ndc, depth, 1.0);
  vec3 offset = (frame.extent.w & FRAME_FLAG_SMOOTH_TERMINATOR) != 0u ? imageLoad(terminator_offset, ivec2(pixel)).xyz
                                                                      : vec3(0.0);
  precise vec3 position = world.xyz / world.w + offset;
  imageStore(world_position, ivec2(pixel), vec4(position, 1.0));
}
