#pragma once
// Shared set-up for GPU tests: a context with the validation layer on, and a check that no validation
// message was raised during the test. The device is ENGINE_DEVICE's (CTest sets lavapipe), else
// lavapipe: `ENGINE_DEVICE=gpu build/bin/gpu_tests` runs the whole suite on a GPU.
#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <memory>
#include <string>

#include "engine/assets/scene.hpp"
#include "gpu/context.hpp"
#include "engine/render/renderer.hpp"
#include "shadows_engine/shadows_engine.hpp"

inline std::string test_device() {
  const char* d = std::getenv("ENGINE_DEVICE");
  return d && *d ? d : "lavapipe";
}

// One technique of a per-technique sweep: its name, the technique, IZB samples per pixel, CSM prepass.
struct TechniqueCase {
  const char* name;
  shadows::Technique technique;
  uint32_t spp;
  bool csm;
  // `base` with this case's technique, samples and prepass.
  shadows::Settings applied_to(shadows::Settings base) const {
    base.technique = technique;
    base.izb.samples_per_pixel = spp;
    base.izb.csm = csm;
    return base;
  }
  // Frames to render before reading: the automatic CSM choice takes effect on the frame after the one
  // that measured it.
  int frames() const { return csm ? 2 : 1; }
};

class GpuTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ctx_ = std::make_unique<engine::gpu::Context>(engine::gpu::ContextOptions{.device = test_device(), .validation = true});
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

  // Loads `scene_name` at `view` into a renderer of the given size (the sun sized by sun_degrees_ where set).
  engine::Renderer& make_renderer(const std::string& scene_name, size_t view, uint32_t width, uint32_t height) {
    scene_ = engine::load_scene(scene_name);
    scene_->apply_view(view);
    if (sun_degrees_)
      scene_->registry.each<engine::DirectionalLight>(
          [&](engine::Entity, engine::DirectionalLight& l) { l.angular_diameter_degrees = *sun_degrees_; });
    renderer_ = std::make_unique<engine::Renderer>(*ctx_, VkExtent2D{width, height});
    renderer_->set_scene(*scene_);
    return *renderer_;
  }

  std::optional<float> sun_degrees_;  // the sun's angular diameter for the scenes make_renderer loads
  std::unique_ptr<engine::gpu::Context> ctx_;
  std::unique_ptr<engine::Scene> scene_;
  std::unique_ptr<engine::Renderer> renderer_;
};
