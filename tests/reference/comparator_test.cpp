// The comparator's counts, thresholds, masks, edge distances and diff image, checked by hand.
#include "reference/comparator.hpp"

#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "reference/embree_tracer.hpp"
#include "reference/synthetic.hpp"

namespace {

using reference::compare_visibility;
using reference::Comparison;

constexpr glm::vec3 kUp(0.0f, 1.0f, 0.0f);
constexpr glm::vec3 kDown(0.0f, -1.0f, 0.0f);

// Ground y = 0 over [-4, 4]^2 and the occluder y = 1 over [-1, 1]^2, optionally missing its second
// triangle (the half with z >= x).
reference::EmbreeTracer make_tracer(bool drop_second_triangle) {
  engine::Registry reg;
  reference::add_mesh_entity(reg, reference::make_quad_y(0.0f, glm::vec2(-4.0f), glm::vec2(4.0f)));
  auto occluder = reference::make_quad_y(1.0f, glm::vec2(-1.0f), glm::vec2(1.0f));
  if (drop_second_triangle) occluder->indices.resize(3);
  reference::add_mesh_entity(reg, occluder);
  return reference::EmbreeTracer(reg);
}

// 16 x 16 ground points, 0.5 units apart, shifted by 0.1 in x so no pixel centre sits on the
// occluder's diagonal: x centres under it are -0.65, -0.15, 0.35, 0.85 (columns 6..9), z centres
// -0.75, -0.25, 0.25, 0.75 (rows 6..9). Row 0 is background.
reference::ShadingPoints ground_points() {
  reference::ShadingPoints sp = reference::plane_shading_points(
      16, 16, reference::top_down_inv_view_proj(glm::vec2(0.1f, 0.0f), glm::vec2(4.0f)),
      glm::vec3(0.0f), kUp);
  for (uint32_t x = 0; x < 16; ++x) sp.position[sp.index(x, 0)].w = 0.0f;
  return sp;
}

TEST(Comparator, IdenticalInputsAgree) {
  const auto sp = ground_points();
  const std::vector<float> ref = make_tracer(false).visibility_1spp(sp, kDown);
  const Comparison c = compare_visibility(ref, ref);
  EXPECT_EQ(c.pixels, 240u);
  EXPECT_EQ(c.mismatched, 0u);
  EXPECT_EQ(c.false_shadowed, 0u);
  EXPECT_EQ(c.false_lit, 0u);
  EXPECT_EQ(c.coverage_disagreements, 0u);
  EXPECT_EQ(c.mismatch_rate, 0.0);
  EXPECT_EQ(c.coverage_mae, 0.0);
  EXPECT_EQ(c.coverage_max_error, 0.0);
}

TEST(Comparator, MissingOccluderTriangleGivesHandCountedFalseLit) {
  const auto sp = ground_points();
  const std::vector<float> ref = make_tracer(false).visibility_1spp(sp, kDown);
  const std::vector<float> wrong = make_tracer(true).visibility_1spp(sp, kDown);
  const Comparison c = compare_visibility(wrong, ref);
  // Centres with z > x under the occluder: x=-0.65: 3, x=-0.15: 2, x=0.35: 1, x=0.85: 0.
  EXPECT_EQ(c.pixels, 240u);
  EXPECT_EQ(c.false_lit, 6u);
  EXPECT_EQ(c.false_shadowed, 0u);
  EXPECT_EQ(c.mismatched, 6u);
  EXPECT_DOUBLE_EQ(c.mismatch_rate, 6.0 / 240.0);
  EXPECT_DOUBLE_EQ(c.coverage_mae, 6.0 / 240.0);
  EXPECT_DOUBLE_EQ(c.coverage_max_error, 1.0);

  // Only the 2x2 interior of the 4x4 shadow lies farther than 1.5 px from its edge; of the six
  // false-lit pixels just (7, 8) is interior.
  const std::vector<uint8_t> far = reference::edge_distance_mask(ref, 16, 16, 1.5f);
  const Comparison interior = compare_visibility(wrong, ref, far);
  EXPECT_EQ(interior.false_lit, 1u);
  EXPECT_EQ(interior.false_shadowed, 0u);
}

TEST(Comparator, FlippedLightGivesHandCountedFalseShadow) {
  const auto sp = ground_points();
  const auto tracer = make_tracer(false);
  const std::vector<float> ref = tracer.visibility_1spp(sp, kDown);
  // From below every ground point faces away from the sun: all shadowed.
  const std::vector<float> wrong = tracer.visibility_1spp(sp, kUp);
  const Comparison c = compare_visibility(wrong, ref);
  EXPECT_EQ(c.pixels, 240u);
  EXPECT_EQ(c.false_shadowed, 240u - 16u);
  EXPECT_EQ(c.false_lit, 0u);
  EXPECT_EQ(c.mismatched, 224u);
}

const std::vector<float> kTechnique = {1.0f, 0.5f, 0.49f, 0.51f, 0.0f, 0.25f, -1.0f, 0.7f, -1.0f};
const std::vector<float> kReference = {1.0f, 1.0f, 1.0f, 0.0f, 0.0f, 0.75f, -1.0f, -1.0f, 0.3f};

TEST(Comparator, ThresholdClassifiesFractionalValues) {
  const Comparison c = compare_visibility(kTechnique, kReference);
  EXPECT_EQ(c.pixels, 6u);  // the last three have background on at least one side
  EXPECT_EQ(c.coverage_disagreements, 2u);
  EXPECT_EQ(c.false_shadowed, 2u);  // 0.49 vs 1, 0.25 vs 0.75
  EXPECT_EQ(c.false_lit, 1u);       // 0.51 vs 0
  EXPECT_EQ(c.mismatched, 3u);
  EXPECT_DOUBLE_EQ(c.mismatch_rate, 0.5);
  EXPECT_NEAR(c.coverage_mae, (0.5 + 0.51 + 0.51 + 0.5) / 6.0, 1e-6);
  EXPECT_NEAR(c.coverage_max_error, 0.51, 1e-6);

  const Comparison low = compare_visibility(kTechnique, kReference, 0.3f);
  EXPECT_EQ(low.false_shadowed, 1u);  // 0.25 vs 0.75
  EXPECT_EQ(low.false_lit, 1u);       // 0.51 vs 0
  const Comparison high = compare_visibility(kTechnique, kReference, 0.8f);
  EXPECT_EQ(high.false_shadowed, 2u);  // 0.5 vs 1, 0.49 vs 1
  EXPECT_EQ(high.false_lit, 0u);
}

TEST(Comparator, MaskSkipsExcludedPixels) {
  const std::vector<uint8_t> mask = {1, 1, 0, 0, 1, 1, 1, 1, 1};
  const Comparison c = compare_visibility(kTechnique, kReference, mask);
  EXPECT_EQ(c.pixels, 4u);
  EXPECT_EQ(c.false_shadowed, 1u);
  EXPECT_EQ(c.false_lit, 0u);
  EXPECT_DOUBLE_EQ(c.mismatch_rate, 0.25);
  EXPECT_NEAR(c.coverage_mae, 1.0 / 4.0, 1e-6);
  EXPECT_THROW(compare_visibility(kTechnique, kReference, std::vector<uint8_t>(3, 1)),
               std::invalid_argument);
  EXPECT_THROW(compare_visibility(kTechnique, std::vector<float>(2, 1.0f)), std::invalid_argument);
}

TEST(Comparator, DistanceToReferenceEdge) {
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<float> line = {1.0f, 1.0f, 0.0f, 0.2f, 0.4f, -1.0f, 0.0f};
  EXPECT_EQ(reference::distance_to_reference_edge(line, 7, 1),
            (std::vector<float>{2.0f, 1.0f, 1.0f, 2.0f, 3.0f, inf, 5.0f}));
  EXPECT_EQ(reference::distance_to_reference_edge(std::vector<float>(6, 1.0f), 3, 2),
            std::vector<float>(6, inf));

  // One shadowed pixel in the middle of a lit 5x5 block.
  std::vector<float> block(25, 1.0f);
  block[2 * 5 + 2] = 0.0f;
  const std::vector<float> d = reference::distance_to_reference_edge(block, 5, 5);
  EXPECT_FLOAT_EQ(d[2 * 5 + 2], 1.0f);
  EXPECT_FLOAT_EQ(d[0], std::sqrt(8.0f));
  EXPECT_FLOAT_EQ(d[2 * 5 + 4], 2.0f);
  EXPECT_FLOAT_EQ(d[1 * 5 + 3], std::sqrt(2.0f));
  EXPECT_FLOAT_EQ(d[4 * 5 + 1], std::sqrt(5.0f));

  const std::vector<uint8_t> mask = reference::edge_distance_mask(block, 5, 5, 2.0f);
  int included = 0;
  for (uint8_t m : mask) included += m;
  EXPECT_EQ(included,
            12);  // distances sqrt(5) and sqrt(8): the four corners and eight knights' moves
}

TEST(Comparator, DiffImageColours) {
  // One pixel of each case: agree lit, agree shadowed, false shadow, false lit, background,
  // one-sided.
  const std::vector<float> technique = {1.0f, 0.0f, 0.0f, 1.0f, -1.0f, -1.0f};
  const std::vector<float> ref = {1.0f, 0.0f, 1.0f, 0.0f, -1.0f, 1.0f};
  const std::filesystem::path path =
      std::filesystem::path(testing::TempDir()) / "reference_diff_test.png";
  std::filesystem::remove(path);
  reference::write_diff_png(path, 3, 2, technique, ref);
  int w = 0, h = 0, channels = 0;
  unsigned char* pixels = stbi_load(path.string().c_str(), &w, &h, &channels, 3);
  ASSERT_NE(pixels, nullptr);
  ASSERT_EQ(w, 3);
  ASSERT_EQ(h, 2);
  const uint8_t* expected[] = {reference::kDiffAgreeLit,    reference::kDiffAgreeShadowed,
                               reference::kDiffFalseShadow, reference::kDiffFalseLit,
                               reference::kDiffBackground,  reference::kDiffCoverage};
  for (int i = 0; i < 6; ++i) {
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(pixels[i * 3 + c], expected[i][c]) << "pixel " << i << " channel " << c;
  }
  stbi_image_free(pixels);
  EXPECT_EQ(expected[2][0], 255);  // red
  EXPECT_EQ(expected[3][2], 255);  // blue
  EXPECT_THROW(reference::write_diff_png(path, 4, 2, technique, ref), std::invalid_argument);
  std::filesystem::remove(path);
}

}  // namespace

namespace {

// Soft metrics counted by hand: background in both is skipped, background in one is a coverage
// disagreement, and the penumbra bounds are exclusive.
TEST(Comparator, SoftMetricsCountedByHand) {
  const std::vector<float> technique{-1.0f, 0.5f, 1.0f, 0.2f, -1.0f, 0.0f, 0.0f, 1.0f, 0.7f};
  const std::vector<float> reference{-1.0f, 0.4f, 1.0f, 0.0f, 0.3f, 0.5f, 0.02f, 0.98f, -1.0f};
  const reference::SoftComparison c = reference::compare_soft(technique, reference);
  EXPECT_EQ(c.pixels, 6u);
  EXPECT_EQ(c.penumbra_pixels, 2u);  // 0.4 and 0.5
  EXPECT_EQ(c.coverage_disagreements, 2u);
  EXPECT_NEAR(c.soft_mae, (0.1 + 0.0 + 0.2 + 0.5 + 0.02 + 0.02) / 6.0, 1e-6);
  EXPECT_NEAR(c.penumbra_mae, (0.1 + 0.5) / 2.0, 1e-6);

  // Wider penumbra bounds take in 0.02 and 0.98.
  const reference::SoftComparison wide = reference::compare_soft(technique, reference, 0.01f, 0.99f);
  EXPECT_EQ(wide.penumbra_pixels, 4u);
  EXPECT_NEAR(wide.penumbra_mae, (0.1 + 0.5 + 0.02 + 0.02) / 4.0, 1e-6);

  const reference::SoftComparison same = reference::compare_soft(reference, reference);
  EXPECT_EQ(same.pixels, 7u);
  EXPECT_EQ(same.soft_mae, 0.0);
  EXPECT_EQ(same.penumbra_mae, 0.0);

  const reference::SoftComparison none = reference::compare_soft({-1.0f}, {-1.0f});
  EXPECT_EQ(none.pixels, 0u);
  EXPECT_EQ(none.soft_mae, 0.0);
  EXPECT_THROW(reference::compare_soft({0.0f}, {0.0f, 1.0f}), std::invalid_argument);
}

}  // namespace
