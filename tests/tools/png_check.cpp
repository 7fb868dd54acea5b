// png_check FILE.png [--min-size WxH] [--min-colors N] [--min-spread S] [--darker-than REF.png [--min-darker F]
//           [--darker-by L]]:
// exits 0 when the PNG exists, decodes, is at least the given size and is not trivial (at least N distinct
// colours and a luminance spread of at least S (default 40) of 255 between its 1st and 99th percentile);
// with --darker-than, also when at least the share F (default 0.005) of its pixels is at least L (default 8)
// luminance levels darker than the same pixel of REF.png, the same frame rendered without shadows: shadowed
// pixels are present. Otherwise prints one line saying why and exits 1; a bad command line exits 2.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <set>
#include <string>
#include <vector>

#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>

namespace {

const char* const kUsage =
    "usage: png_check FILE.png [--min-size WxH] [--min-colors N] [--min-spread S] [--darker-than REF.png "
    "[--min-darker F] [--darker-by L]]\n";

int usage(const std::string& why) {
  std::fprintf(stderr, "png_check: %s\n%s", why.c_str(), kUsage);
  return 2;
}

struct Image {
  int w = 0, h = 0;
  std::vector<int> luma;
  std::set<unsigned> colors;
};

bool load(const char* path, Image& out) {
  int n = 0;
  unsigned char* data = stbi_load(path, &out.w, &out.h, &n, 4);
  if (!data) {
    std::printf("png_check: %s: cannot read (%s)\n", path, stbi_failure_reason());
    return false;
  }
  for (int i = 0; i < out.w * out.h; ++i) {
    const unsigned char* p = data + 4 * i;
    out.colors.insert(unsigned(p[0]) << 16 | unsigned(p[1]) << 8 | p[2]);
    out.luma.push_back((p[0] * 3 + p[1] * 6 + p[2]) / 10);
  }
  stbi_image_free(data);
  return true;
}

// A whole number or a fraction, all of `text`.
bool number(const char* text, double& out) {
  char* end = nullptr;
  out = std::strtod(text, &end);
  return *text && end && !*end && out >= 0.0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') return usage("the first argument must be the PNG");
  unsigned min_w = 1, min_h = 1, min_colors = 16;
  double min_spread = 40, min_darker = 0.005, darker_by = 8;
  const char* reference = nullptr;
  for (int i = 2; i < argc; i += 2) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) return usage(flag + " needs a value");
    const char* v = argv[i + 1];
    double x = 0;
    if (flag == "--min-size") {
      char tail = 0;
      if (std::sscanf(v, "%ux%u%c", &min_w, &min_h, &tail) != 2) return usage("--min-size '" + std::string(v) + "': expected WxH");
    } else if (flag == "--min-colors" || flag == "--min-spread" || flag == "--min-darker" || flag == "--darker-by") {
      if (!number(v, x)) return usage(flag + " '" + v + "': expected a non-negative number");
      if (flag == "--min-colors") min_colors = unsigned(x);
      else if (flag == "--min-spread") min_spread = x;
      else if (flag == "--min-darker") min_darker = x;
      else darker_by = x;
    } else if (flag == "--darker-than") {
      reference = v;
    } else {
      return usage("unknown option " + flag);
    }
  }
  Image image;
  if (!load(argv[1], image)) return 1;
  std::vector<int> sorted = image.luma;
  std::sort(sorted.begin(), sorted.end());
  const int spread = sorted[size_t(sorted.size() * 0.99)] - sorted[size_t(sorted.size() * 0.01)];
  std::printf("png_check: %s: %dx%d, %zu colours, luminance spread %d\n", argv[1], image.w, image.h,
              image.colors.size(), spread);
  if (unsigned(image.w) < min_w || unsigned(image.h) < min_h) return std::printf("png_check: too small\n"), 1;
  if (image.colors.size() < min_colors) return std::printf("png_check: too few colours\n"), 1;
  if (spread < min_spread) return std::printf("png_check: nearly uniform image\n"), 1;
  if (reference) {
    Image ref;
    if (!load(reference, ref)) return 1;
    if (ref.w != image.w || ref.h != image.h)
      return std::printf("png_check: %s is %dx%d, not %dx%d\n", reference, ref.w, ref.h, image.w, image.h), 1;
    size_t darker = 0;
    for (size_t i = 0; i < image.luma.size(); ++i) darker += image.luma[i] + darker_by <= ref.luma[i];
    const double share = double(darker) / double(image.luma.size());
    std::printf("png_check: %.4f of the pixels are at least %g levels darker than in %s\n", share, darker_by, reference);
    if (share < min_darker) return std::printf("png_check: too few shadowed pixels (under %g)\n", min_darker), 1;
  }
  return 0;
}
