#version 460
#extension GL_GOOGLE_include_directive : require
#include "shadows.h"
#define MATERIAL_TEXTURES_BINDING ALPHA_DEPTH_BINDING_TEXTURES
#include "material_textures.glsl"
layout(push_constant) uniform Push { AlphaDepthPush push; };
layout(location = 0) in vec2 out_uv;

// A shadow-map texel takes an alpha-tested caster only where its material is solid at the fragment's
// interpolated texture coordinate (the shared nearest-texel rule).
void main() {
  if (!material_alpha_kept(push.base_color_texture, push.alpha_threshold, out_uv)) discard;
}
