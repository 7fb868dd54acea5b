#pragma once
// Shared set-up for GPU tests: a lavapipe context with the validation layer on, and a check that no
// validation message was raised during the test.
#include <gtest/gtest.h>

#include <memory>

#include "engine/assets/scene.hpp"
#include "engine/gpu/context.hpp"
#include "engine/render/renderer.hpp"
#include "shadows_engine/shadows_engine.hpp"

class GpuTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ctx_ = std::make_unique<engine::gpu::Context>(engine::gpu::ContextOptions{.device = "lavapipe", .validation = true});
    ASSERT_TRUE(ctx_->validation_enabled()) << "the Khronos validation layer must be installed for GPU tests";
  }
  void TearDown() override {
    renderer_.reset();
    if (ctx_) {
      EXPECT_EQ(ctx_->validation_message_count(), 0u) << "validation messages were raised";
    }
    scene_.reset();
    ctx_.reset();
  }

  // Loads `scene_name` at `view` into a renderer of the given size.
  engine::Renderer& make_renderer(const std::string& scene_name, size_t view, uint32_t width, uint32_t height) {
    scene_ = engine::load_scene(scene_name);
    scene_->apply_view(view);
    renderer_ = std::make_unique<engine::Renderer>(*ctx_, VkExtent2D{width, height});
    renderer_->set_scene(*scene_);
    return *renderer_;
  }

  std::unique_ptr<engine::gpu::Context> ctx_;
  std::unique_ptr<engine::Scene> scene_;
  std::unique_ptr<engine::Renderer> renderer_;
};
