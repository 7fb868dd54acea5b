// Material textures as every pass and the reference read them, shared by C++ and GLSL.
//
// All of a scene's textures live in one array of 32-bit words (a storage buffer on the GPU):
//   word 0: texture count N
//   words 1 + 4i .. 4 + 4i: texture i's header {first texel word, width, height, wrap_s | wrap_t << 8}
//   then the texels, one word each, RGBA8 (r in the low byte), rows top to bottom.
// The sampling rule is the nearest texel of the single level stored: texel (floor(u * width),
// floor(v * height)) folded by the wrap mode. No filtering, no mips: a shadow technique's alpha test
// and the reference's then read the same texel for the same texture coordinate.
#ifndef MATERIAL_H
#define MATERIAL_H
#include "shared_prelude.h"

SHARED_BEGIN

SHARED_CONST uint kNoTexture = 0xffffffffu;
SHARED_CONST uint kTextureHeaderWords = 4u;
SHARED_CONST uint kWrapRepeat = 0u;
SHARED_CONST uint kWrapClampToEdge = 1u;
SHARED_CONST uint kWrapMirroredRepeat = 2u;

// Folds texel index i into [0, size) (size > 0). Written with non-negative operands of % only, whose
// result GLSL and C++ define alike.
SHARED_INLINE int wrap_texel(int i, int size, uint mode) {
  if (mode == kWrapClampToEdge) return clamp(i, 0, size - 1);
  int period = mode == kWrapMirroredRepeat ? 2 * size : size;
  int m = i >= 0 ? i % period : period - 1 - ((-i - 1) % period);
  return m < size ? m : period - 1 - m;
}

// The word holding the texel that texture coordinate uv selects, from the texture's header.
SHARED_INLINE uint texel_word(SHARED_IN(uvec4) header, SHARED_IN(vec2) uv) {
  int width = int(header.y);
  int height = int(header.z);
  // Clamped before the conversion so absurd coordinates stay defined; far beyond any texture size.
  int x = int(clamp(floor(uv.x * float(width)), -1.0e8f, 1.0e8f));
  int y = int(clamp(floor(uv.y * float(height)), -1.0e8f, 1.0e8f));
  x = wrap_texel(x, width, header.w & 0xffu);
  y = wrap_texel(y, height, (header.w >> 8u) & 0xffu);
  return header.x + uint(y) * uint(width) + uint(x);
}

// The least texel alpha byte (0..255) an alpha test keeps for a texture alpha scaled by `scale` (the
// base colour's alpha) against `cutoff`: scale * byte / 255 >= cutoff. 256: nothing is kept; 0:
// everything. Computed once on the CPU so that every shader and the reference compare integers.
SHARED_INLINE uint alpha_threshold_byte(float cutoff, float scale) {
  for (uint byte = 0u; byte < 256u; ++byte)
    if (scale * float(byte) / 255.0f >= cutoff) return byte;
  return 256u;
}

// An alpha test's answer from the texel's alpha byte: kept when alpha >= threshold
// (alpha_threshold_byte; 0 keeps everything, 256 nothing).
SHARED_INLINE bool alpha_byte_kept(uint texel, uint threshold) { return (texel >> 24u) >= threshold; }

SHARED_END
#endif
