// Textures and alpha-tested materials without a GPU: glTF images and samplers, the one sampling rule
// (shared/material.h) and alpha thresholds, the generated masks, and bad images falling back.
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>

#include <shared/material.h>

#include "engine/assets/procedural_textures.hpp"
#include "engine/assets/scene.hpp"
#include "engine/assets/scene_file.hpp"
#include "engine/core/material_textures.hpp"

namespace {

using namespace engine;
namespace fs = std::filesystem;

fs::path test_gltf(const std::string& name) { return fs::path(ENGINE_SOURCE_DIR) / "content" / "test_gltf" / name; }

const Material& material_of(Scene& scene, const std::string& name) {
  const Material* found = nullptr;
  scene.registry.each<Name, Material>([&](Entity, Name& n, Material& m) {
    if (n.value == name) found = &m;
  });
  if (!found) throw std::runtime_error("no material on " + name);
  return *found;
}

TEST(Materials, GltfMaskMaterialLoadsItsTextureAndSampler) {
  auto scene = load_gltf_scene(test_gltf("masked_quad.gltf"));
  const Material& mask = material_of(*scene, "masked");
  EXPECT_EQ(mask.alpha_mode, AlphaMode::Mask);
  ASSERT_TRUE(mask.base_color_texture);
  const Texture& t = *mask.base_color_texture;
  EXPECT_EQ(t.width, 4u);
  EXPECT_EQ(t.height, 2u);
  EXPECT_EQ(t.wrap_s, TextureWrap::ClampToEdge);
  EXPECT_EQ(t.wrap_t, TextureWrap::MirroredRepeat);
  EXPECT_NE(t.name.find("mask_4x2.png"), std::string::npos);
  EXPECT_EQ(t.rgba[3], 255);       // (0, 0) opaque
  EXPECT_EQ(t.rgba[3 * 4 + 3], 0); // (3, 0) transparent
  const Material& blend = material_of(*scene, "masked_again");
  EXPECT_EQ(blend.alpha_mode, AlphaMode::Blend);
  ASSERT_TRUE(blend.base_color_texture);
  EXPECT_EQ(blend.base_color_texture->wrap_s, TextureWrap::Repeat);

  // The table every pass and the reference read: nearest texel, wrap modes, integer thresholds.
  MaterialTextureTable table(scene->registry);
  EXPECT_EQ(table.texture_count(), 2u);
  const uint32_t tex = table.index_of(mask);
  const uint32_t threshold = alpha_threshold(mask);
  EXPECT_EQ(threshold, 128u);  // 1.0 * byte / 255 >= 0.5
  EXPECT_EQ(alpha_threshold(blend), 160u);  // BLEND tests at 0.5 with its factor's 0.8
  EXPECT_TRUE(table.alpha_kept(tex, threshold, {0.1f, 0.25f}));
  EXPECT_FALSE(table.alpha_kept(tex, threshold, {0.9f, 0.25f}));
  EXPECT_TRUE(table.alpha_kept(tex, threshold, {0.9f, 0.75f}));
  EXPECT_FALSE(table.alpha_kept(tex, threshold, {1.7f, 0.25f}));  // clamped to column 3
  EXPECT_TRUE(table.alpha_kept(tex, threshold, {0.9f, 1.25f}));   // mirrored back to row 1
  EXPECT_TRUE(table.alpha_kept(tex, 0, {0.9f, 0.25f}));           // threshold 0: not alpha-tested
  EXPECT_TRUE(table.alpha_kept(gpu_shared::kNoTexture, threshold, {0.9f, 0.25f}));  // no texture: alpha 1
}

TEST(Materials, WrapModesFoldEveryTexelIndex) {
  using gpu_shared::wrap_texel;
  EXPECT_EQ(wrap_texel(-1, 4, gpu_shared::kWrapRepeat), 3);
  EXPECT_EQ(wrap_texel(-4, 4, gpu_shared::kWrapRepeat), 0);
  EXPECT_EQ(wrap_texel(9, 4, gpu_shared::kWrapRepeat), 1);
  EXPECT_EQ(wrap_texel(-1, 4, gpu_shared::kWrapMirroredRepeat), 0);
  EXPECT_EQ(wrap_texel(4, 4, gpu_shared::kWrapMirroredRepeat), 3);
  EXPECT_EQ(wrap_texel(-5, 4, gpu_shared::kWrapMirroredRepeat), 3);
  EXPECT_EQ(wrap_texel(-7, 4, gpu_shared::kWrapClampToEdge), 0);
  EXPECT_EQ(wrap_texel(7, 4, gpu_shared::kWrapClampToEdge), 3);
}

TEST(Materials, MissingOrUndecodableImagesWarnAndFallBackToTheFactor) {
  testing::internal::CaptureStderr();
  auto scene = load_gltf_scene(test_gltf("masked_quad_bad_images.gltf"));
  const std::string warnings = testing::internal::GetCapturedStderr();
  EXPECT_FALSE(material_of(*scene, "masked").base_color_texture);
  EXPECT_FALSE(material_of(*scene, "masked_again").base_color_texture);
  EXPECT_EQ(material_of(*scene, "masked_again").base_color.a, 0.8f);
  for (const char* file : {"absent.png", "not_an_image.png"}) {
    std::istringstream lines(warnings);
    std::string line;
    bool found = false;
    while (std::getline(lines, line))
      found = found || (line.find(file) != std::string::npos && line.find("base colour factor") != std::string::npos);
    EXPECT_TRUE(found) << file << " in:\n" << warnings;
  }
}

TEST(Materials, GeneratedMasksHaveHolesAndSolidParts) {
  for (const auto& t : {procedural::make_leaf_spray_texture(64, 7), procedural::make_grate_texture(32, 1, 0.2f)}) {
    size_t solid = 0, clear = 0;
    for (size_t i = 3; i < t->rgba.size(); i += 4) (t->rgba[i] == 255 ? solid : clear) += t->rgba[i] == 255 || t->rgba[i] == 0;
    EXPECT_GT(solid, t->rgba.size() / 4 / 10) << t->name;
    EXPECT_GT(clear, t->rgba.size() / 4 / 10) << t->name;
    EXPECT_EQ(solid + clear, t->rgba.size() / 4) << t->name;
  }
  auto canopy = load_scene("canopy");
  size_t cards = 0;
  canopy->registry.each<Name, Material>([&](Entity, Name& n, Material& m) {
    if (n.value.rfind("leaf_cards", 0) != 0) return;
    ++cards;
    EXPECT_TRUE(alpha_tested(m));
    EXPECT_TRUE(m.base_color_texture);
  });
  EXPECT_GT(cards, 0u);
}

TEST(Materials, CourtyardHasAnAlphaTestedFence) {
  auto scene = load_scene_file(fs::path(ENGINE_SOURCE_DIR) / "content" / "levels" / "courtyard.json");
  const Material& fence = material_of(*scene, "grate_fence");
  EXPECT_TRUE(alpha_tested(fence));
  ASSERT_TRUE(fence.base_color_texture);
}

}  // namespace
