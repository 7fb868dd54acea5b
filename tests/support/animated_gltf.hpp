#pragma once
// Small glTF 2.0 files with skins, morph targets and animations, written on the fly so tests need no
// binary assets: a bending skinned cylinder, a flapping morphed plate, and two malformed skins for the
// loader's refusals. Each is a .gltf (JSON) with a side .bin buffer.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtx/quaternion.hpp>
#include <nlohmann/json.hpp>

namespace support {

namespace gltf_detail {

using nlohmann::json;

constexpr int kFloat = 5126;
constexpr int kUnsignedShort = 5123;
constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;

// Accumulates one binary buffer and the JSON that describes it.
struct Builder {
  json doc = {{"asset", {{"version", "2.0"}}}, {"scene", 0}, {"scenes", json::array({{{"nodes", json::array()}}})},
              {"nodes", json::array()}, {"meshes", json::array()}, {"accessors", json::array()},
              {"bufferViews", json::array()}};
  std::string bin;

  // A tightly packed accessor of `count` elements of `type` ("SCALAR", "VEC3", ...).
  int accessor(const void* data, size_t bytes, int component_type, const char* type, size_t count, int target = 0) {
    while (bin.size() % 4) bin.push_back('\0');
    json view = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}};
    if (target) view["target"] = target;
    bin.append(static_cast<const char*>(data), bytes);
    doc["bufferViews"].push_back(view);
    doc["accessors"].push_back({{"bufferView", doc["bufferViews"].size() - 1}, {"componentType", component_type},
                                {"count", count}, {"type", type}});
    return int(doc["accessors"].size()) - 1;
  }
  // Float data with min/max (required for POSITION and animation inputs; harmless elsewhere).
  int floats(const std::vector<float>& v, const char* type, int components, int target = 0) {
    const size_t count = v.size() / size_t(components);
    const int a = accessor(v.data(), v.size() * sizeof(float), kFloat, type, count, target);
    json lo = json::array(), hi = json::array();
    for (int c = 0; c < components; ++c) {
      float mn = v[size_t(c)], mx = v[size_t(c)];
      for (size_t i = 0; i < count; ++i) mn = std::min(mn, v[i * size_t(components) + size_t(c)]), mx = std::max(mx, v[i * size_t(components) + size_t(c)]);
      lo.push_back(mn), hi.push_back(mx);
    }
    doc["accessors"][size_t(a)]["min"] = lo;
    doc["accessors"][size_t(a)]["max"] = hi;
    return a;
  }
  int vec3s(const std::vector<glm::vec3>& v, int target = kArrayBuffer) {
    std::vector<float> f;
    for (const glm::vec3& p : v) f.insert(f.end(), {p.x, p.y, p.z});
    return floats(f, "VEC3", 3, target);
  }
  int indices(const std::vector<uint16_t>& v) {
    return accessor(v.data(), v.size() * sizeof(uint16_t), kUnsignedShort, "SCALAR", v.size(), kElementArrayBuffer);
  }
  int node(json n, bool in_scene) {
    doc["nodes"].push_back(std::move(n));
    const int index = int(doc["nodes"].size()) - 1;
    if (in_scene) doc["scenes"][0]["nodes"].push_back(index);
    return index;
  }
  int mesh(json primitive, json extra = json::object()) {
    extra["primitives"] = json::array({std::move(primitive)});
    doc["meshes"].push_back(std::move(extra));
    return int(doc["meshes"].size()) - 1;
  }
  std::string write(const std::filesystem::path& dir, const std::string& stem) {
    std::filesystem::create_directories(dir);
    while (bin.size() % 4) bin.push_back('\0');
    doc["buffers"] = json::array({{{"byteLength", bin.size()}, {"uri", stem + ".bin"}}});
    std::ofstream(dir / (stem + ".bin"), std::ios::binary).write(bin.data(), std::streamsize(bin.size()));
    const std::filesystem::path path = dir / (stem + ".gltf");
    std::ofstream(path) << doc.dump(1);
    return path.string();
  }
};

// A quad 8 x 8 units at y = 0 facing up: what the shadows fall on.
inline void add_ground(Builder& b) {
  const std::vector<glm::vec3> p = {{-4, 0, -4}, {-4, 0, 4}, {4, 0, 4}, {4, 0, -4}};
  const std::vector<glm::vec3> n(4, glm::vec3(0, 1, 0));
  const int m = b.mesh({{"attributes", {{"POSITION", b.vec3s(p)}, {"NORMAL", b.vec3s(n)}}},
                        {"indices", b.indices({0, 1, 2, 0, 2, 3})}});
  b.node({{"name", "ground"}, {"mesh", m}}, true);
}

// A sun at about 45 degrees (long shadows) and a camera 4 units off and 2 up looking at `target`.
inline void add_light_and_camera(Builder& b, const glm::vec3& target) {
  b.doc["extensionsUsed"] = json::array({"KHR_lights_punctual"});
  b.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array({{{"type", "directional"}, {"intensity", 3.0}}});
  const glm::quat sun = glm::rotation(glm::vec3(0, 0, -1), glm::normalize(glm::vec3(-0.8f, -1.0f, -0.3f)));
  b.node({{"name", "sun"}, {"rotation", {sun.x, sun.y, sun.z, sun.w}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}},
         true);
  b.doc["cameras"] = json::array({{{"type", "perspective"}, {"name", "view"},
                                   {"perspective", {{"yfov", 0.9}, {"znear", 0.05}, {"zfar", 100.0}}}}});
  const glm::vec3 eye = target + glm::vec3(0.6f, 2.0f, 4.0f);
  const glm::quat look = glm::quatLookAtRH(glm::normalize(target - eye), glm::vec3(0, 1, 0));
  b.node({{"name", "camera"}, {"camera", 0}, {"translation", {eye.x, eye.y, eye.z}}, {"rotation", {look.x, look.y, look.z, look.w}}},
         true);
}

// Joint nodes in a chain along +y at `heights` (each a child of the one before); returns their indices.
inline std::vector<int> add_joint_chain(Builder& b, const std::vector<float>& heights, const char* prefix) {
  std::vector<int> joints;
  for (size_t k = 0; k < heights.size(); ++k) {
    const float dy = heights[k] - (k ? heights[k - 1] : 0.0f);
    joints.push_back(b.node({{"name", std::string(prefix) + std::to_string(k)}, {"translation", {0.0f, dy, 0.0f}}}, k == 0));
    if (k) b.doc["nodes"][size_t(joints[k - 1])]["children"].push_back(joints[k]);
  }
  return joints;
}

// The skin over `joints` standing at `heights` (bind pose: translations only).
inline int add_skin(Builder& b, const std::vector<int>& joints, const std::vector<float>& heights) {
  std::vector<float> inverse_bind;
  for (float h : heights) {
    const glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, -h, 0.0f));
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) inverse_bind.push_back(m[c][r]);  // glTF matrices are column-major
  }
  const int ibm = b.accessor(inverse_bind.data(), inverse_bind.size() * sizeof(float), kFloat, "MAT4", heights.size());
  b.doc["skins"].push_back({{"joints", joints}, {"inverseBindMatrices", ibm}, {"skeleton", joints[0]}});
  return int(b.doc["skins"].size()) - 1;
}

// An animation sampler + channel: `values` per key (`type` VEC4 rotations or SCALAR weights).
inline void add_channel(Builder& b, json& animation, int node, const char* path, const std::vector<float>& times,
                        const std::vector<float>& values, const char* type, int components) {
  const int input = b.floats(times, "SCALAR", 1);
  const int output = b.accessor(values.data(), values.size() * sizeof(float), kFloat, type, values.size() / size_t(components));
  animation["samplers"].push_back({{"input", input}, {"output", output}, {"interpolation", "LINEAR"}});
  animation["channels"].push_back({{"sampler", animation["samplers"].size() - 1}, {"target", {{"node", node}, {"path", path}}}});
}

// A skinned vertical strip of 2 x rows vertices at x = +-0.2, y = 0, 0.2, ...: the base of the
// malformed-skin files.
inline int add_strip_mesh(Builder& b, int rows, int joints0, int weights0, int joints1 = -1, int weights1 = -1) {
  std::vector<glm::vec3> p, n;
  std::vector<uint16_t> idx;
  for (int r = 0; r < rows; ++r) {
    p.push_back({-0.2f, 0.2f * float(r), 0.0f}), p.push_back({0.2f, 0.2f * float(r), 0.0f});
    n.push_back({0, 0, 1}), n.push_back({0, 0, 1});
    if (r + 1 < rows) {
      const auto a = uint16_t(2 * r);
      idx.insert(idx.end(), {a, uint16_t(a + 1), uint16_t(a + 3), a, uint16_t(a + 3), uint16_t(a + 2)});
    }
  }
  json attributes = {{"POSITION", b.vec3s(p)}, {"NORMAL", b.vec3s(n)}, {"JOINTS_0", joints0}, {"WEIGHTS_0", weights0}};
  if (joints1 >= 0) attributes["JOINTS_1"] = joints1, attributes["WEIGHTS_1"] = weights1;
  return b.mesh({{"attributes", attributes}, {"indices", b.indices(idx)}});
}

}  // namespace gltf_detail

// dir/"bending_cylinder.gltf": a ground quad and a cylinder (radius 0.15, y 0..1.5, 24 segments x 12
// rings) skinned to joints at y = 0, 0.5, 1.0, whose animation "bend" (2 s, 5 linear keys) turns the
// middle and top joints about z from 0 to 50 degrees and back; a 45-degree sun and a camera.
inline std::string write_bending_cylinder_gltf(const std::filesystem::path& dir) {
  using namespace gltf_detail;
  Builder b;
  add_ground(b);
  const int segments = 24, rings = 12;
  std::vector<glm::vec3> p, n;
  std::vector<uint16_t> joints, idx;
  std::vector<float> weights;
  for (int i = 0; i <= rings; ++i) {
    const float y = 1.5f * float(i) / float(rings);
    // Neighbouring joints blend across 0.15 either side of each joint above the root.
    const float up1 = glm::smoothstep(0.35f, 0.65f, y), up2 = glm::smoothstep(0.85f, 1.15f, y);
    for (int j = 0; j < segments; ++j) {
      const float a = glm::two_pi<float>() * float(j) / float(segments);
      const glm::vec3 d{std::cos(a), 0.0f, std::sin(a)};
      p.push_back(d * 0.15f + glm::vec3(0, y, 0)), n.push_back(d);
      joints.insert(joints.end(), {0, 1, 2, 0});
      weights.insert(weights.end(), {1.0f - up1, up1 - up2, up2, 0.0f});
    }
  }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const auto v = [&](int r, int s) { return uint16_t(r * segments + s % segments); };
      // (up, around) is counter-clockwise seen from outside.
      idx.insert(idx.end(), {v(i, j), v(i + 1, j), v(i, j + 1), v(i, j + 1), v(i + 1, j), v(i + 1, j + 1)});
    }
  const int ja = b.accessor(joints.data(), joints.size() * sizeof(uint16_t), kUnsignedShort, "VEC4", p.size(), kArrayBuffer);
  const int wa = b.floats(weights, "VEC4", 4, kArrayBuffer);
  const int m = b.mesh({{"attributes", {{"POSITION", b.vec3s(p)}, {"NORMAL", b.vec3s(n)}, {"JOINTS_0", ja}, {"WEIGHTS_0", wa}}},
                        {"indices", b.indices(idx)}},
                       {{"name", "cylinder"}});
  const std::vector<float> heights = {0.0f, 0.5f, 1.0f};
  const std::vector<int> chain = add_joint_chain(b, heights, "joint");
  const int skin = add_skin(b, chain, heights);
  b.node({{"name", "cylinder"}, {"mesh", m}, {"skin", skin}}, true);
  json bend = {{"name", "bend"}, {"samplers", json::array()}, {"channels", json::array()}};
  const std::vector<float> times = {0.0f, 0.5f, 1.0f, 1.5f, 2.0f};
  std::vector<float> rotations;
  for (float deg : {0.0f, 25.0f, 50.0f, 25.0f, 0.0f}) {
    const glm::quat q = glm::angleAxis(glm::radians(deg), glm::vec3(0, 0, 1));
    rotations.insert(rotations.end(), {q.x, q.y, q.z, q.w});
  }
  add_channel(b, bend, chain[1], "rotation", times, rotations, "VEC4", 4);
  add_channel(b, bend, chain[2], "rotation", times, rotations, "VEC4", 4);
  b.doc["animations"] = json::array({bend});
  add_light_and_camera(b, {0.0f, 0.4f, 0.0f});
  return b.write(dir, "bending_cylinder");
}

// dir/"morph_flap.gltf": a ground quad and a plate 1.2 x 0.8 x 0.05 (top and bottom 8 x 8 grids) at
// height 0.8 with two morph targets (0 folds the -x half down by up to 0.5, 1 waves the +x edge) and
// mesh.weights [0, 0]; animation "flap" (2 s, linear keys at 0, 0.5, 1, 1.5, 2) drives the weights.
inline std::string write_morph_gltf(const std::filesystem::path& dir) {
  using namespace gltf_detail;
  Builder b;
  add_ground(b);
  const int cells = 8;
  const float hx = 0.6f, hz = 0.4f, ht = 0.025f;
  std::vector<glm::vec3> p, n;
  std::vector<uint16_t> idx;
  // One face: a grid over (u, v) in [-1, 1]^2 mapped by `at`, facing `normal`.
  const auto face = [&](auto at, const glm::vec3& normal, int cu, int cv) {
    const auto base = uint16_t(p.size());
    for (int i = 0; i <= cv; ++i)
      for (int j = 0; j <= cu; ++j) p.push_back(at(-1.0f + 2.0f * float(j) / float(cu), -1.0f + 2.0f * float(i) / float(cv))), n.push_back(normal);
    for (int i = 0; i < cv; ++i)
      for (int j = 0; j < cu; ++j) {
        const auto v = [&](int r, int c) { return uint16_t(base + r * (cu + 1) + c); };
        const glm::vec3 e = glm::cross(p[v(i, j + 1)] - p[v(i, j)], p[v(i + 1, j)] - p[v(i, j)]);
        if (glm::dot(e, normal) > 0.0f)
          idx.insert(idx.end(), {v(i, j), v(i, j + 1), v(i + 1, j + 1), v(i, j), v(i + 1, j + 1), v(i + 1, j)});
        else
          idx.insert(idx.end(), {v(i, j), v(i + 1, j + 1), v(i, j + 1), v(i, j), v(i + 1, j), v(i + 1, j + 1)});
      }
  };
  face([&](float u, float v) { return glm::vec3(u * hx, ht, v * hz); }, {0, 1, 0}, cells, cells);
  face([&](float u, float v) { return glm::vec3(u * hx, -ht, v * hz); }, {0, -1, 0}, cells, cells);
  face([&](float u, float v) { return glm::vec3(u * hx, v * ht, hz); }, {0, 0, 1}, cells, 1);
  face([&](float u, float v) { return glm::vec3(u * hx, v * ht, -hz); }, {0, 0, -1}, cells, 1);
  face([&](float u, float v) { return glm::vec3(hx, v * ht, u * hz); }, {1, 0, 0}, cells, 1);
  face([&](float u, float v) { return glm::vec3(-hx, v * ht, u * hz); }, {-1, 0, 0}, cells, 1);
  std::vector<glm::vec3> fold, wave;
  for (const glm::vec3& q : p) {
    const float left = std::max(0.0f, -q.x) / hx, right = std::max(0.0f, q.x) / hx;
    fold.push_back({0.0f, -0.5f * left * left, 0.0f});
    wave.push_back({0.0f, 0.3f * right * right * std::sin(glm::pi<float>() * q.z / hz), 0.0f});
  }
  const int m = b.mesh({{"attributes", {{"POSITION", b.vec3s(p)}, {"NORMAL", b.vec3s(n)}}},
                        {"indices", b.indices(idx)},
                        {"targets", json::array({{{"POSITION", b.vec3s(fold)}}, {{"POSITION", b.vec3s(wave)}}})}},
                       {{"name", "plate"}, {"weights", {0.0, 0.0}}});
  const int plate = b.node({{"name", "plate"}, {"mesh", m}, {"translation", {0.0f, 0.8f, 0.0f}}}, true);
  json flap = {{"name", "flap"}, {"samplers", json::array()}, {"channels", json::array()}};
  add_channel(b, flap, plate, "weights", {0.0f, 0.5f, 1.0f, 1.5f, 2.0f},
              {0.0f, 0.0f, 1.0f, 0.0f, 0.5f, 1.0f, 0.0f, 0.5f, 0.0f, 0.0f}, "SCALAR", 1);
  b.doc["animations"] = json::array({flap});
  add_light_and_camera(b, {0.0f, 0.4f, 0.0f});
  return b.write(dir, "morph_flap");
}

// dir/"eight_weights.gltf": a strip skinned to 8 joints through JOINTS_0/1 and WEIGHTS_0/1; its bottom
// vertices have all 8 influences (0.125 each), the rest one.
inline std::string write_skinned_gltf_with_eight_weights(const std::filesystem::path& dir) {
  using namespace gltf_detail;
  Builder b;
  const int rows = 3, vertices = 2 * rows;
  std::vector<uint16_t> j0, j1;
  std::vector<float> w0, w1;
  for (int v = 0; v < vertices; ++v) {
    const bool eight = v < 2;
    j0.insert(j0.end(), {0, 1, 2, 3}), j1.insert(j1.end(), {4, 5, 6, 7});
    if (eight) {
      w0.insert(w0.end(), 4, 0.125f), w1.insert(w1.end(), 4, 0.125f);
    } else {
      w0.insert(w0.end(), {1.0f, 0.0f, 0.0f, 0.0f}), w1.insert(w1.end(), 4, 0.0f);
    }
  }
  const int ja0 = b.accessor(j0.data(), j0.size() * 2, kUnsignedShort, "VEC4", size_t(vertices), kArrayBuffer);
  const int ja1 = b.accessor(j1.data(), j1.size() * 2, kUnsignedShort, "VEC4", size_t(vertices), kArrayBuffer);
  const int wa0 = b.floats(w0, "VEC4", 4, kArrayBuffer), wa1 = b.floats(w1, "VEC4", 4, kArrayBuffer);
  const int m = add_strip_mesh(b, rows, ja0, wa0, ja1, wa1);
  const std::vector<float> heights = {0.0f, 0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f, 0.7f};
  const std::vector<int> chain = add_joint_chain(b, heights, "joint");
  b.node({{"name", "strip"}, {"mesh", m}, {"skin", add_skin(b, chain, heights)}}, true);
  return b.write(dir, "eight_weights");
}

// dir/"bad_joint.gltf": a strip skinned to 2 joints, one of whose vertices names joint 5 with weight 0.5.
inline std::string write_skinned_gltf_with_bad_joint(const std::filesystem::path& dir) {
  using namespace gltf_detail;
  Builder b;
  const int rows = 2, vertices = 2 * rows;
  std::vector<uint16_t> j0;
  std::vector<float> w0;
  for (int v = 0; v < vertices; ++v) {
    j0.insert(j0.end(), {0, uint16_t(v == 3 ? 5 : 1), 0, 0});
    w0.insert(w0.end(), {0.5f, 0.5f, 0.0f, 0.0f});
  }
  const int ja = b.accessor(j0.data(), j0.size() * 2, kUnsignedShort, "VEC4", size_t(vertices), kArrayBuffer);
  const int m = add_strip_mesh(b, rows, ja, b.floats(w0, "VEC4", 4, kArrayBuffer));
  const std::vector<float> heights = {0.0f, 0.2f};
  const std::vector<int> chain = add_joint_chain(b, heights, "joint");
  b.node({{"name", "strip"}, {"mesh", m}, {"skin", add_skin(b, chain, heights)}}, true);
  return b.write(dir, "bad_joint");
}

}  // namespace support
