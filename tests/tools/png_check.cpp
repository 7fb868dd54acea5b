// png_check FILE.png [--min-size WxH] [--min-colors N] [--min-spread S]: exits 0 when the PNG exists, decodes, is at
// least the given size and is not trivial (at least N distinct colours and a luminance spread of at
// least S (default 40) of 255 between its 1st and 99th percentile); otherwise prints one line saying why and exits 1.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <set>
#include <string>
#include <vector>

#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: png_check FILE.png [--min-size WxH] [--min-colors N] [--min-spread S]\n");
    return 2;
  }
  unsigned min_w = 1, min_h = 1, min_colors = 16;
  int min_spread = 40;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--min-size")) std::sscanf(argv[i + 1], "%ux%u", &min_w, &min_h);
    else if (!std::strcmp(argv[i], "--min-colors")) min_colors = unsigned(std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--min-spread")) min_spread = std::atoi(argv[i + 1]);
  }
  int w = 0, h = 0, n = 0;
  unsigned char* data = stbi_load(argv[1], &w, &h, &n, 4);
  if (!data) {
    std::printf("png_check: %s: cannot read (%s)\n", argv[1], stbi_failure_reason());
    return 1;
  }
  std::set<unsigned> colors;
  std::vector<int> luma;
  for (int i = 0; i < w * h; ++i) {
    const unsigned char* p = data + 4 * i;
    colors.insert(unsigned(p[0]) << 16 | unsigned(p[1]) << 8 | p[2]);
    luma.push_back((p[0] * 3 + p[1] * 6 + p[2]) / 10);
  }
  stbi_image_free(data);
  std::sort(luma.begin(), luma.end());
  const int spread = luma[size_t(luma.size() * 0.99)] - luma[size_t(luma.size() * 0.01)];
  std::printf("png_check: %s: %dx%d, %zu colours, luminance spread %d\n", argv[1], w, h, colors.size(), spread);
  if (unsigned(w) < min_w || unsigned(h) < min_h) return std::printf("png_check: too small\n"), 1;
  if (colors.size() < min_colors) return std::printf("png_check: too few colours\n"), 1;
  if (spread < min_spread) return std::printf("png_check: nearly uniform image\n"), 1;
  return 0;
}
