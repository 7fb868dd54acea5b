#include "reference/comparator.hpp"

#include <stb/stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace reference {
namespace {

enum class Class : uint8_t { Background, Shadowed, Lit };

Class classify(float v, float threshold) {
  if (v < 0.0f) return Class::Background;
  return v >= threshold ? Class::Lit : Class::Shadowed;
}

void check_sizes(size_t a, size_t b, const char* what) {
  if (a != b) {
    throw std::invalid_argument(std::string(what) + ": sizes differ (" + std::to_string(a) +
                                " vs " + std::to_string(b) + ")");
  }
}

Comparison compare(const std::vector<float>& technique, const std::vector<float>& reference,
                   const std::vector<uint8_t>* include, float threshold) {
  check_sizes(technique.size(), reference.size(), "compare_visibility");
  if (include) check_sizes(include->size(), reference.size(), "compare_visibility mask");
  Comparison c;
  double abs_sum = 0.0;
  for (size_t i = 0; i < reference.size(); ++i) {
    if (include && !(*include)[i]) continue;
    const Class r = classify(reference[i], threshold);
    const Class t = classify(technique[i], threshold);
    if (r == Class::Background || t == Class::Background) {
      if (r != t) ++c.coverage_disagreements;
      continue;
    }
    ++c.pixels;
    if (r == Class::Lit && t == Class::Shadowed) ++c.false_shadowed;
    if (r == Class::Shadowed && t == Class::Lit) ++c.false_lit;
    const double err = std::abs(double(technique[i]) - double(reference[i]));
    abs_sum += err;
    c.coverage_max_error = std::max(c.coverage_max_error, err);
  }
  c.mismatched = c.false_shadowed + c.false_lit;
  if (c.pixels > 0) {
    c.mismatch_rate = double(c.mismatched) / double(c.pixels);
    c.coverage_mae = abs_sum / double(c.pixels);
  }
  return c;
}

}  // namespace

SoftComparison compare_soft(const std::vector<float>& technique, const std::vector<float>& reference,
                            float penumbra_low, float penumbra_high) {
  check_sizes(technique.size(), reference.size(), "compare_soft");
  SoftComparison c;
  double sum = 0.0, penumbra_sum = 0.0;
  for (size_t i = 0; i < reference.size(); ++i) {
    const bool covered = reference[i] >= 0.0f;
    if (covered != (technique[i] >= 0.0f)) ++c.coverage_disagreements;
    if (!covered || technique[i] < 0.0f) continue;
    const double err = std::abs(double(technique[i]) - double(reference[i]));
    ++c.pixels;
    sum += err;
    if (reference[i] > penumbra_low && reference[i] < penumbra_high) {
      ++c.penumbra_pixels;
      penumbra_sum += err;
    }
  }
  if (c.pixels > 0) c.soft_mae = sum / double(c.pixels);
  if (c.penumbra_pixels > 0) c.penumbra_mae = penumbra_sum / double(c.penumbra_pixels);
  return c;
}

namespace {

// Squared distance transform of one line (lower envelope of parabolas rooted at each sample):
// out[q] = min_p (q - p)^2 + f[p]. `v` and `z` are scratch of size n and n + 1.
constexpr double kFar = 1.0e20;
void distance_1d(const double* f, double* out, size_t n, std::vector<size_t>& v,
                 std::vector<double>& z) {
  const double inf = std::numeric_limits<double>::infinity();
  size_t k = 0;
  v[0] = 0;
  z[0] = -inf;
  z[1] = inf;
  for (size_t q = 1; q < n; ++q) {
    const double fq = f[q] + double(q) * double(q);
    auto meet = [&] {  // where the parabola at q overtakes the one at v[k]
      const double p = double(v[k]);
      return (fq - (f[v[k]] + p * p)) / (2.0 * double(q) - 2.0 * p);
    };
    double s = meet();
    while (s <= z[k]) {  // terminates: z[0] is -inf
      --k;
      s = meet();
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = inf;
  }
  k = 0;
  for (size_t q = 0; q < n; ++q) {
    while (z[k + 1] < double(q)) ++k;
    const double d = double(q) - double(v[k]);
    out[q] = d * d + f[v[k]];
  }
}

// Squared Euclidean distance from every pixel to the nearest pixel with seed[i] set.
std::vector<double> squared_distance(const std::vector<uint8_t>& seed, uint32_t width,
                                     uint32_t height) {
  std::vector<double> grid(seed.size());
  for (size_t i = 0; i < seed.size(); ++i) grid[i] = seed[i] ? 0.0 : kFar;
  const size_t longest = std::max(width, height);
  std::vector<double> f(longest), d(longest), z(longest + 1);
  std::vector<size_t> v(longest);
  for (uint32_t x = 0; x < width; ++x) {
    for (uint32_t y = 0; y < height; ++y) f[y] = grid[size_t(y) * width + x];
    distance_1d(f.data(), d.data(), height, v, z);
    for (uint32_t y = 0; y < height; ++y) grid[size_t(y) * width + x] = d[y];
  }
  for (uint32_t y = 0; y < height; ++y) {
    double* row = grid.data() + size_t(y) * width;
    std::copy(row, row + width, f.begin());
    distance_1d(f.data(), row, width, v, z);
  }
  return grid;
}

}  // namespace

Comparison compare_visibility(const std::vector<float>& technique,
                              const std::vector<float>& reference, float threshold) {
  return compare(technique, reference, nullptr, threshold);
}

Comparison compare_visibility(const std::vector<float>& technique,
                              const std::vector<float>& reference,
                              const std::vector<uint8_t>& include, float threshold) {
  return compare(technique, reference, &include, threshold);
}

void write_diff_png(const std::filesystem::path& path, uint32_t width, uint32_t height,
                    const std::vector<float>& technique, const std::vector<float>& reference,
                    float threshold) {
  check_sizes(technique.size(), size_t(width) * height, "write_diff_png technique");
  check_sizes(reference.size(), size_t(width) * height, "write_diff_png reference");
  std::vector<uint8_t> rgb(size_t(width) * height * 3);
  for (size_t i = 0; i < reference.size(); ++i) {
    const Class r = classify(reference[i], threshold);
    const Class t = classify(technique[i], threshold);
    const uint8_t* colour = kDiffCoverage;
    if (r == Class::Background && t == Class::Background)
      colour = kDiffBackground;
    else if (r == Class::Background || t == Class::Background)
      colour = kDiffCoverage;
    else if (r == t)
      colour = r == Class::Lit ? kDiffAgreeLit : kDiffAgreeShadowed;
    else
      colour = r == Class::Lit ? kDiffFalseShadow : kDiffFalseLit;
    std::copy(colour, colour + 3, rgb.begin() + std::ptrdiff_t(i * 3));
  }
  const std::string file = path.string();
  if (width == 0 || height == 0 ||
      !stbi_write_png(file.c_str(), int(width), int(height), 3, rgb.data(), int(width * 3))) {
    throw std::runtime_error("could not write diff image " + file);
  }
}

std::vector<float> distance_to_reference_edge(const std::vector<float>& reference, uint32_t width,
                                              uint32_t height, float threshold) {
  check_sizes(reference.size(), size_t(width) * height, "distance_to_reference_edge");
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<float> out(reference.size(), inf);
  if (reference.empty()) return out;
  std::vector<uint8_t> lit(reference.size()), shadowed(reference.size());
  for (size_t i = 0; i < reference.size(); ++i) {
    const Class c = classify(reference[i], threshold);
    lit[i] = c == Class::Lit;
    shadowed[i] = c == Class::Shadowed;
  }
  // A lit pixel's edge is the nearest shadowed pixel and vice versa.
  const std::vector<double> to_lit = squared_distance(lit, width, height);
  const std::vector<double> to_shadowed = squared_distance(shadowed, width, height);
  for (size_t i = 0; i < reference.size(); ++i) {
    const double d2 = lit[i] ? to_shadowed[i] : shadowed[i] ? to_lit[i] : kFar;
    if (d2 < kFar * 0.5) out[i] = float(std::sqrt(d2));
  }
  return out;
}

std::vector<uint8_t> edge_distance_mask(const std::vector<float>& reference, uint32_t width,
                                        uint32_t height, float min_distance, float threshold) {
  const std::vector<float> dist = distance_to_reference_edge(reference, width, height, threshold);
  std::vector<uint8_t> mask(reference.size(), 0);
  for (size_t i = 0; i < reference.size(); ++i)
    mask[i] = reference[i] >= 0.0f && dist[i] > min_distance;
  return mask;
}

}  // namespace reference
