// The host input pass (FrameDesc's inputs into the module's own images), included by host_inputs.comp
// and, with SHADOWS_WITHOUT_SUBGROUP_OPS defined, by host_inputs_portable.comp for a device without
// subgroup ballot (uniform_branch.glsl's broadcast is then left out).
#include "host.h"
layout(local_size_x = 8, local_size_y = 8) in;
// A CPU device (uniform_branch.glsl: the flags and the depth step decide branches).
layout(constant_id = 0) const bool kCpuDevice = false;
#define UNIFORM_BRANCH_CPU kCpuDevice
#include "shadows/uniform_branch.glsl"

layout(set = 0, binding = HOST_INPUTS_BINDING_PARAMS) uniform Params { HostInputs params; };
layout(set = 0, binding = HOST_INPUTS_BINDING_DEPTH) uniform sampler2D depth_image;
layout(set = 0, binding = HOST_INPUTS_BINDING_NORMAL) uniform sampler2D normal_image;
layout(set = 0, binding = HOST_INPUTS_BINDING_GEOMETRIC) uniform sampler2D geometric_image;
layout(set = 0, binding = HOST_INPUTS_BINDING_OFFSET) uniform sampler2D offset_image;
layout(set = 0, binding = HOST_INPUTS_BINDING_RECEIVER) uniform sampler2D receiver_image;
layout(set = 0, binding = HOST_INPUTS_BINDING_WORLD_POSITION, rgba32f) writeonly uniform image2D world_position;
layout(set = 0, binding = HOST_INPUTS_BINDING_GEOMETRIC_OUT, rgba16f) writeonly uniform image2D geometric_out;
layout(set = 0, binding = HOST_INPUTS_BINDING_ALBEDO_OUT, rgba8) writeonly uniform image2D albedo_out;
layout(set = 0, binding = HOST_INPUTS_BINDING_TERM_OUT, r32f) writeonly uniform image2D term_out;
layout(set = 0, binding = HOST_INPUTS_BINDING_OVERLAY_OUT, rgba8) writeonly uniform image2D overlay_out;

vec3 octahedral_decode(vec2 e) {
  vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
  if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
  return n;
}

// A host normal texel in world space, unit length, turned toward the camera (unless the host said it
// already is: then it is taken bit for bit, as the engine's own G-buffer normals are).
vec3 decode_normal(vec4 texel, uint bits, float scale, float bias, vec3 position) {
  vec4 v = texel * scale + bias;
  vec3 n = (bits & HOST_NORMAL_OCTAHEDRAL) != 0u ? octahedral_decode(v.xy) : v.xyz;
  if ((bits & HOST_NORMAL_AS_GIVEN) != 0u) return n;
  if ((bits & HOST_NORMAL_VIEW_SPACE) != 0u) n = mat3(params.view_to_world) * n;
  n = normalize(n);
  return dot(n, params.camera_position.xyz - position) < 0.0 ? -n : n;
}

void main() {
  ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(uvec2(pixel), params.extent.xy))) return;
  uint flags = uniform_branch(params.extent.z);
  imageStore(term_out, pixel, vec4(1.0));
  // Only a debug view draws into the overlay; without one the output pass writes the host's zeros.
  if ((flags & HOST_CLEAR_OVERLAY) != 0u) imageStore(overlay_out, pixel, vec4(0.0));
  float host_depth = texelFetch(depth_image, pixel, 0).r;
  bool reversed = (flags & HOST_REVERSED_Z) != 0u;
  // The module works in reversed Z; background is the host's clear depth.
  float depth = reversed ? host_depth : 1.0 - host_depth;
  if (reversed ? host_depth <= 0.0 : host_depth >= 1.0) {
    imageStore(world_position, pixel, vec4(0.0));
    imageStore(geometric_out, pixel, vec4(0.0));
    imageStore(albedo_out, pixel, vec4(0.0));
    return;
  }
  // `precise`: the same arithmetic as the engine's shading points (shading_points.comp), unfused in
  // both, so a host handing over the engine's own depth gets its points bit for bit.
  precise vec2 ndc = (vec2(pixel) + 0.5) / vec2(params.extent.xy) * 2.0 - 1.0;
  precise vec4 world = params.inverse_view_projection * vec4(ndc, depth, 1.0);
  vec3 offset = (flags & HOST_HAS_OFFSET) != 0u ? texelFetch(offset_image, pixel, 0).xyz : vec3(0.0);
  precise vec3 position = world.xyz / world.w + offset;
  // A UNORM depth is rounded to half a step, so the point may lie that far along the view ray behind
  // the surface, where its own surface would shadow it (a 16-bit standard-Z buffer: about 5 mm 8
  // units out). It is pushed off the surface by the distance that rounding spans, below. (A float
  // depth's rounding is far below the shadow-ray offset, which covers it.)
  float step = uniform_branch(params.camera_position.w);
  float uncertainty = 0.0;
  if (step > 0.0) {
    vec4 nearer = params.inverse_view_projection * vec4(ndc, depth + 0.5 * step, 1.0);
    vec4 farther = params.inverse_view_projection * vec4(ndc, depth - 0.5 * step, 1.0);
    vec3 unrounded = world.xyz / world.w;
    uncertainty = max(distance(nearer.xyz / nearer.w, unrounded), distance(farther.xyz / farther.w, unrounded));
  }

  vec3 shading = decode_normal(texelFetch(normal_image, pixel, 0), (flags >> HOST_NORMAL_SHIFT) & 0xfu,
                               params.normal_scale_bias.x, params.normal_scale_bias.y, position);
  vec3 geometric = shading;
  float facing = dot(shading, -params.light_direction.xyz) > 0.0 ? 1.0 : 0.0;
  if ((flags & HOST_HAS_GEOMETRIC) != 0u) {
    vec4 texel = texelFetch(geometric_image, pixel, 0);
    geometric = decode_normal(texel, (flags >> HOST_GEOMETRIC_SHIFT) & 0xfu, params.normal_scale_bias.z,
                              params.normal_scale_bias.w, position);
    if ((flags & HOST_FACING_IN_ALPHA) != 0u) facing = texel.a > 0.5 ? 1.0 : 0.0;
  }
  imageStore(world_position, pixel, vec4(position + geometric * uncertainty, 1.0));
  imageStore(geometric_out, pixel, vec4(geometric, facing));
  float receives = 1.0;
  if ((flags & HOST_HAS_RECEIVER_MASK) != 0u) receives = texelFetch(receiver_image, pixel, 0)[params.extent.w] > 0.5 ? 1.0 : 0.0;
  imageStore(albedo_out, pixel, vec4(0.0, 0.0, 0.0, receives));
}
