#include <algorithm>
#include <cmath>
#include <set>

#include "engine/assets/procedural_scenes.hpp"
#include "gpu/profiler.hpp"
#include "gpu_fixture.hpp"

namespace {

using namespace engine::procedural;

// Depth the rasterizer must produce for the ground plane (y = 0) at the centre of pixel (x, y).
float analytic_ground_depth(const engine::FrameView& view, uint32_t x, uint32_t y) {
  const glm::vec2 ndc = (glm::vec2(x, y) + 0.5f) / glm::vec2(view.extent.width, view.extent.height) * 2.0f - 1.0f;
  const glm::dvec4 near_h = glm::dmat4(view.inverse_view_projection) * glm::dvec4(ndc.x, ndc.y, 1.0, 1.0);
  const glm::dvec4 far_h = glm::dmat4(view.inverse_view_projection) * glm::dvec4(ndc.x, ndc.y, 0.5, 1.0);
  const glm::dvec3 o = glm::dvec3(near_h) / near_h.w;
  const glm::dvec3 d = glm::dvec3(far_h) / far_h.w - o;
  const double t = -o.y / d.y;
  const glm::dvec3 hit = o + d * t;
  const glm::dvec4 clip = glm::dmat4(view.view_projection) * glm::dvec4(hit, 1.0);
  return float(clip.z / clip.w);
}

}  // namespace

TEST_F(GpuTest, GroundDepthMatchesAnalyticPlane) {
  auto& r = make_renderer("contact", 0, 256, 256);
  r.render_frame();
  const auto depth = r.read_depth();
  const auto positions = r.read_world_positions();
  int checked = 0;
  // Bottom rows of the front view look at open ground in front of the objects.
  for (uint32_t y : {250u, 240u, 230u}) {
    for (uint32_t x : {20u, 128u, 236u}) {
      const size_t i = size_t(y) * 256 + x;
      ASSERT_GT(positions[i].w, 0.5f) << "pixel " << x << "," << y << " should see the ground";
      ASSERT_NEAR(positions[i].y, 0.0f, 1e-3f) << "pixel " << x << "," << y << " should see the ground";
      EXPECT_NEAR(depth[i], analytic_ground_depth(r.frame_view(), x, y), 1e-4f);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 9);
}

// Without the smooth-terminator offset, a shading point is exactly the depth buffer's point at the
// pixel centre; with it, points on smooth-shaded curved meshes move by a small fraction of their size and
// points on flat meshes do not move.
TEST_F(GpuTest, WorldPositionsReconstructFromDepth) {
  auto& r = make_renderer("contact", 0, 256, 256);
  r.render_frame();
  const auto lifted = r.read_world_positions();
  r.set_smooth_terminator(false);
  r.render_frame();
  const auto depth = r.read_depth();
  const auto positions = r.read_world_positions();
  const auto& view = r.frame_view();
  int covered = 0;
  for (uint32_t y = 0; y < 256; y += 7) {
    for (uint32_t x = 0; x < 256; x += 7) {
      const size_t i = size_t(y) * 256 + x;
      if (positions[i].w == 0.0f) {
        EXPECT_EQ(depth[i], 0.0f);
        continue;
      }
      ++covered;
      const glm::vec4 clip = view.view_projection * glm::vec4(glm::vec3(positions[i]), 1.0f);
      EXPECT_NEAR(clip.z / clip.w, depth[i], 1e-5f);
      const glm::vec2 ndc = glm::vec2(clip) / clip.w;
      EXPECT_NEAR((ndc.x * 0.5f + 0.5f) * 256.0f, x + 0.5f, 0.05f);
      EXPECT_NEAR((ndc.y * 0.5f + 0.5f) * 256.0f, y + 0.5f, 0.05f);
      const float moved = glm::length(glm::vec3(lifted[i]) - glm::vec3(positions[i]));
      EXPECT_LE(moved, 0.025f);  // the unit sphere's facets sag about 0.005; the blend overshoots near the poles
      if (std::abs(positions[i].y) < 1e-4f) {
        EXPECT_EQ(moved, 0.0f) << "the flat ground";
      }
    }
  }
  EXPECT_GT(covered, 100);
}

TEST_F(GpuTest, BoxFaceNormalsAreAxisAligned) {
  auto& r = make_renderer("contact", 0, 256, 256);
  r.render_frame();
  const auto positions = r.read_world_positions();
  const auto normals = r.read_geometric_normals();
  std::set<int> faces_seen;
  int box_pixels = 0;
  for (size_t i = 0; i < positions.size(); ++i) {
    if (positions[i].w == 0.0f) continue;
    const glm::vec3 local = glm::vec3(positions[i]) - contact::kBoxCenter;
    const glm::vec3 a = glm::abs(local);
    const float h = contact::kBoxHalfSize;
    if (a.x > h + 1e-3f || a.y > h + 1e-3f || a.z > h + 1e-3f) continue;
    // On the box surface: one coordinate at the half size, the others inside.
    int axis = a.x > a.y ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
    if (std::abs(a[axis] - h) > 1e-3f || std::max({a.x, a.y, a.z}) < h - 1e-3f) continue;
    if (a[(axis + 1) % 3] > h - 0.02f || a[(axis + 2) % 3] > h - 0.02f) continue;  // skip edges
    ++box_pixels;
    const glm::vec3 n = glm::vec3(normals[i]);
    EXPECT_NEAR(std::abs(n[axis]), 1.0f, 1e-3f) << "pixel " << i;
    EXPECT_NEAR(n[axis] > 0 ? 1.0f : -1.0f, local[axis] > 0 ? 1.0f : -1.0f, 0.0f);
    faces_seen.insert(axis * 2 + (local[axis] > 0 ? 1 : 0));
  }
  EXPECT_GT(box_pixels, 50);
  EXPECT_GE(faces_seen.size(), 2u);  // the top and at least one side face
}

TEST_F(GpuTest, HeadlessImageShowsLitGeometry) {
  auto& r = make_renderer("contact", 0, 128, 128);
  r.render_frame();
  const auto rgba = r.read_output_rgba8();
  std::set<uint32_t> colours;
  for (size_t i = 0; i < rgba.size(); i += 4) colours.insert(rgba[i] | rgba[i + 1] << 8 | rgba[i + 2] << 16);
  EXPECT_GT(colours.size(), 50u);
  r.write_png("gbuffer_test_contact.png");
  EXPECT_TRUE(std::filesystem::exists("gbuffer_test_contact.png"));
}

// The profiler's history is bounded: a game left running keeps the last frames, not every frame.
// More nested regions than the pool holds: the ones past it go untimed, and no query is written outside
// the frame's segment (the validation layer would report it) nor left without its end.
TEST_F(GpuTest, ProfilerLeavesRegionsPastItsPoolUntimed) {
  engine::gpu::GpuProfiler profiler(*ctx_, 2, 8);
  ASSERT_TRUE(profiler.enabled());
  ctx_->immediate_submit([&](VkCommandBuffer cmd) {
    profiler.begin_frame(cmd);
    profiler.begin(cmd, "outer");
    profiler.begin(cmd, "middle");
    profiler.begin(cmd, "inner");
    profiler.end(cmd, "inner");
    profiler.end(cmd, "middle");
    profiler.end(cmd, "outer");
  });
  profiler.collect();
  EXPECT_EQ(profiler.history("outer").size(), 1u);
  EXPECT_EQ(profiler.history("middle").size(), 1u);  // two queries each: the pool of 4 holds outer's and middle's
  EXPECT_EQ(profiler.history("inner").size(), 0u);
}

// A region's children are the regions first recorded directly inside it (what names its time); a
// region at the top has none above it.
TEST_F(GpuTest, ProfilerNamesTheRegionsInsideEachRegion) {
  engine::gpu::GpuProfiler profiler(*ctx_, 8, 8);
  ASSERT_TRUE(profiler.enabled());
  ctx_->immediate_submit([&](VkCommandBuffer cmd) {
    profiler.begin_frame(cmd);
    profiler.begin(cmd, "module");
    profiler.begin(cmd, "first");
    profiler.begin(cmd, "step");
    profiler.end(cmd, "step");
    profiler.end(cmd, "first");
    profiler.begin(cmd, "second");
    profiler.end(cmd, "second");
    profiler.end(cmd, "module");
    profiler.begin(cmd, "after");
    profiler.end(cmd, "after");
  });
  profiler.collect();
  EXPECT_EQ(profiler.children("module"), (std::vector<std::string>{"first", "second"}));
  EXPECT_EQ(profiler.children("first"), (std::vector<std::string>{"step"}));
  EXPECT_TRUE(profiler.children("second").empty());
  EXPECT_EQ(profiler.children(""), (std::vector<std::string>{"module", "after"}));
}

TEST_F(GpuTest, ProfilerHistoryKeepsOnlyTheLastFrames) {
  engine::gpu::GpuProfiler profiler(*ctx_, 4, 3);
  ASSERT_TRUE(profiler.enabled());
  for (int frame = 0; frame < 5; ++frame) {
    ctx_->immediate_submit([&](VkCommandBuffer cmd) {
      profiler.begin_frame(cmd);
      profiler.begin(cmd, "pass");
      profiler.end(cmd, "pass");
    });
    profiler.collect();
    EXPECT_EQ(profiler.history("pass").size(), size_t(std::min(frame + 1, 3)));
  }
  profiler.clear_history();
  EXPECT_TRUE(profiler.history("pass").empty());
}
