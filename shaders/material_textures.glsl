// The material texture lookups of every pass that alpha-tests or colours by texture (G-buffer, shadow
// depth passes, the IZB's node tests, any ray tracing pass). Define MATERIAL_TEXTURES_BINDING (and
// optionally MATERIAL_TEXTURES_SET, default 0) before including; layout and sampling rule in
// shared/material.h.
#include "material.h"

#ifndef MATERIAL_TEXTURES_SET
#define MATERIAL_TEXTURES_SET 0
#endif
layout(set = MATERIAL_TEXTURES_SET, binding = MATERIAL_TEXTURES_BINDING, std430) readonly buffer MaterialTextures {
  uint material_words[];
};

uvec4 material_texture_header(uint texture) {
  uint base = 1u + texture * kTextureHeaderWords;
  return uvec4(material_words[base], material_words[base + 1u], material_words[base + 2u], material_words[base + 3u]);
}

// The texel (RGBA8 packed, r low) at uv; opaque white without a texture.
uint material_texel(uint texture, vec2 uv) {
  if (texture == kNoTexture) return 0xffffffffu;
  return material_words[texel_word(material_texture_header(texture), uv)];
}

// The alpha test of every technique: whether an alpha-tested surface is solid at uv. `threshold`
// 0 means not alpha-tested (always solid), without touching the texture.
bool material_alpha_kept(uint texture, uint threshold, vec2 uv) {
  if (threshold == 0u) return true;
  return alpha_byte_kept(material_texel(texture, uv), threshold);
}
