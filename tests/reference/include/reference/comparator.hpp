#pragma once
// Per-pixel comparison of a technique's visibility against the reference. Values: -1 background,
// otherwise visibility in [0, 1] (binary for 1 spp, k/32 for 32 spp).
#include <cstdint>
#include <filesystem>
#include <vector>

namespace reference {

struct Comparison {
  uint64_t pixels = 0;          // compared: covered in both
  uint64_t mismatched = 0;      // false_shadowed + false_lit
  uint64_t false_shadowed = 0;  // reference lit, technique shadowed
  uint64_t false_lit = 0;       // reference shadowed, technique lit
  // Covered in one input, background in the other: not compared, but a sign the inputs disagree on
  // the shading points.
  uint64_t coverage_disagreements = 0;
  double mismatch_rate = 0.0;  // mismatched / pixels, 0 when nothing was compared
  double coverage_mae = 0.0;   // mean |technique - reference| over compared pixels
  double coverage_max_error = 0.0;
};

// A value >= threshold counts as lit, so binary and fractional visibility classify alike.
// Throws std::invalid_argument when the sizes differ.
Comparison compare_visibility(const std::vector<float>& technique,
                              const std::vector<float>& reference, float threshold = 0.5f);

// As above, comparing only pixels whose include[i] is non-zero.
Comparison compare_visibility(const std::vector<float>& technique,
                              const std::vector<float>& reference,
                              const std::vector<uint8_t>& include, float threshold = 0.5f);

// A technique's fractional term against an area-light reference (EmbreeTracer::area_visibility).
struct SoftComparison {
  uint64_t pixels = 0;           // compared: covered in both (value >= 0)
  uint64_t penumbra_pixels = 0;  // of which the reference is strictly between penumbra_low and penumbra_high
  uint64_t coverage_disagreements = 0;  // covered in one input only: not compared
  double soft_mae = 0.0;      // mean |technique - reference| over the compared pixels (0 when none)
  double penumbra_mae = 0.0;  // the same over the penumbra pixels (0 when none)
};

// Inputs: one value per pixel, -1 background, else in [0, 1] (the technique's term, the reference's
// lit fraction). Throws std::invalid_argument when the sizes differ.
SoftComparison compare_soft(const std::vector<float>& technique, const std::vector<float>& reference,
                            float penumbra_low = 0.02f, float penumbra_high = 0.98f);

// Diff image (RGB PNG): agreeing lit light grey (200), agreeing shadowed dark grey (64), false
// shadow red, false lit blue, background black, covered in only one input magenta. Throws
// std::runtime_error when the file cannot be written, std::invalid_argument on size mismatch.
void write_diff_png(const std::filesystem::path& path, uint32_t width, uint32_t height,
                    const std::vector<float>& technique, const std::vector<float>& reference,
                    float threshold = 0.5f);

// Colours of write_diff_png, for readers of the image.
inline constexpr uint8_t kDiffAgreeLit[3] = {200, 200, 200};
inline constexpr uint8_t kDiffAgreeShadowed[3] = {64, 64, 64};
inline constexpr uint8_t kDiffFalseShadow[3] = {255, 0, 0};
inline constexpr uint8_t kDiffFalseLit[3] = {0, 0, 255};
inline constexpr uint8_t kDiffBackground[3] = {0, 0, 0};
inline constexpr uint8_t kDiffCoverage[3] = {255, 0, 255};

// For each pixel, the exact Euclidean distance in pixels to the nearest covered pixel whose
// thresholded reference class (lit / shadowed) differs from its own; infinity where there is none
// and for background pixels (background neither is nor makes an edge).
std::vector<float> distance_to_reference_edge(const std::vector<float>& reference, uint32_t width,
                                              uint32_t height, float threshold = 0.5f);

// Include mask for compare_visibility: 1 for covered pixels farther than min_distance pixels from a
// reference shadow edge, 0 elsewhere.
std::vector<uint8_t> edge_distance_mask(const std::vector<float>& reference, uint32_t width,
                                        uint32_t height, float min_distance,
                                        float threshold = 0.5f);

}  // namespace reference
