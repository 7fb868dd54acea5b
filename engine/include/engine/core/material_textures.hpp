#pragma once
// A scene's material textures packed into the one word array the shaders read (shared/material.h),
// with the same lookups on the CPU for the reference and the tests.
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "engine/core/components.hpp"

namespace engine {

class MaterialTextureTable {
 public:
  MaterialTextureTable() = default;
  // Every distinct texture of the registry's Materials, in registry order.
  explicit MaterialTextureTable(Registry& registry);

  const std::vector<uint32_t>& words() const { return words_; }
  uint32_t texture_count() const { return words_.empty() ? 0 : words_[0]; }
  // The material's base-colour texture's index, or gpu_shared::kNoTexture.
  uint32_t index_of(const Material& m) const;
  // The texel (RGBA8 packed, r low) at uv; opaque white for kNoTexture.
  uint32_t texel(uint32_t texture, glm::vec2 uv) const;
  // Whether an alpha-tested surface is solid at uv (threshold from alpha_threshold; 0: always).
  bool alpha_kept(uint32_t texture, uint32_t threshold, glm::vec2 uv) const;

 private:
  std::vector<uint32_t> words_{0u};
  std::unordered_map<const Texture*, uint32_t> index_;
};

}  // namespace engine
