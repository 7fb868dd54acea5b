#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <unistd.h>

#include <tiny_gltf.h>

#include "animated_gltf.hpp"

namespace {

tinygltf::Model parse(const std::string& path) {
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string err, warn;
  const bool ok = loader.LoadASCIIFromFile(&model, &err, &warn, path);
  EXPECT_TRUE(ok) << path << ": " << err;
  EXPECT_TRUE(err.empty()) << err;
  EXPECT_TRUE(warn.empty()) << warn;
  return model;
}

// Every accessor lies inside its buffer view, and every view inside its buffer.
void expect_consistent_buffers(const tinygltf::Model& m) {
  for (const tinygltf::BufferView& v : m.bufferViews) {
    ASSERT_LT(size_t(v.buffer), m.buffers.size());
    EXPECT_LE(v.byteOffset + v.byteLength, m.buffers[size_t(v.buffer)].data.size());
  }
  for (const tinygltf::Accessor& a : m.accessors) {
    ASSERT_LT(size_t(a.bufferView), m.bufferViews.size());
    const size_t bytes = a.count * size_t(tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType))) *
                         size_t(tinygltf::GetNumComponentsInType(uint32_t(a.type)));
    EXPECT_LE(a.byteOffset + bytes, m.bufferViews[size_t(a.bufferView)].byteLength);
  }
  for (const tinygltf::Mesh& mesh : m.meshes)
    for (const tinygltf::Primitive& p : mesh.primitives) {
      const tinygltf::Accessor& pos = m.accessors[size_t(p.attributes.at("POSITION"))];
      EXPECT_EQ(pos.minValues.size(), 3u);
      EXPECT_EQ(pos.maxValues.size(), 3u);
    }
}

}  // namespace

TEST(AnimatedGltf, WrittenFilesParse) {
  const auto dir = std::filesystem::temp_directory_path() / ("animated_gltf_" + std::to_string(getpid()));

  const tinygltf::Model cylinder = parse(support::write_bending_cylinder_gltf(dir));
  expect_consistent_buffers(cylinder);
  ASSERT_EQ(cylinder.skins.size(), 1u);
  EXPECT_EQ(cylinder.skins[0].joints.size(), 3u);
  ASSERT_EQ(cylinder.animations.size(), 1u);
  EXPECT_EQ(cylinder.animations[0].name, "bend");
  EXPECT_EQ(cylinder.animations[0].channels.size(), 2u);
  EXPECT_EQ(cylinder.cameras.size(), 1u);
  EXPECT_EQ(cylinder.lights.size(), 1u);
  const auto& cylinder_attributes = cylinder.meshes[1].primitives[0].attributes;
  EXPECT_EQ(cylinder.accessors[size_t(cylinder_attributes.at("JOINTS_0"))].componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
  EXPECT_EQ(cylinder.accessors[size_t(cylinder_attributes.at("WEIGHTS_0"))].componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);

  const tinygltf::Model morph = parse(support::write_morph_gltf(dir));
  expect_consistent_buffers(morph);
  ASSERT_EQ(morph.meshes.size(), 2u);
  EXPECT_EQ(morph.meshes[1].primitives[0].targets.size(), 2u);
  EXPECT_EQ(morph.meshes[1].weights, (std::vector<double>{0.0, 0.0}));
  ASSERT_EQ(morph.animations.size(), 1u);
  EXPECT_EQ(morph.animations[0].name, "flap");
  EXPECT_EQ(morph.animations[0].channels[0].target_path, "weights");

  const tinygltf::Model eight = parse(support::write_skinned_gltf_with_eight_weights(dir));
  expect_consistent_buffers(eight);
  EXPECT_EQ(eight.skins[0].joints.size(), 8u);
  EXPECT_TRUE(eight.meshes[0].primitives[0].attributes.count("JOINTS_1"));
  EXPECT_TRUE(eight.meshes[0].primitives[0].attributes.count("WEIGHTS_1"));

  const tinygltf::Model bad = parse(support::write_skinned_gltf_with_bad_joint(dir));
  expect_consistent_buffers(bad);
  EXPECT_EQ(bad.skins[0].joints.size(), 2u);
  std::filesystem::remove_all(dir);
}
