// glTF 2.0 (.gltf / .glb) into a Scene. tinygltf parses; everything it leaves unchecked (ranges,
// component types, index bounds, finite values) is validated here so a bad file produces one
// SceneError line instead of undefined behaviour later in the renderer.
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <sstream>

#include <stb_image.h>
#include <glm/gtc/constants.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "engine/assets/scene.hpp"
#include "engine/core/skinning.hpp"
#include "engine/core/transform_system.hpp"

namespace engine {

namespace {

// tinygltf messages span several lines; what() must stay on one.
std::string one_line(const std::string& text) {
  std::string out;
  bool pending_separator = false;
  for (char c : text) {
    if (c == '\n' || c == '\r') {
      pending_separator = !out.empty();
      continue;
    }
    if (pending_separator) {
      while (!out.empty() && (out.back() == ' ' || out.back() == '\t')) out.pop_back();
      if (!out.empty() && out.back() != ';' && out.back() != '.') out += ';';
      out += ' ';
      pending_separator = false;
    }
    out += c;
  }
  while (!out.empty() && (out.back() == ' ' || out.back() == ';')) out.pop_back();
  return out;
}

// External buffers: the path exactly as written, relative to the glTF's folder (older tinygltf
// releases expanded URIs with wordexp, which runs "$(command)"; these callbacks do not depend on the
// release), and only regular files of bounded size (no devices or pipes).
constexpr uintmax_t kMaxExternalFileBytes = uintmax_t(1) << 31;

bool external_file_exists(const std::string& path, void*) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}

std::string external_file_path(const std::string& path, void*) { return path; }

bool read_external_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void*) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    if (err) *err += "'" + path + "' is not a regular file. ";
    return false;
  }
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec || size > kMaxExternalFileBytes) {
    if (err) *err += "'" + path + "' is unreadable or larger than 2 GiB. ";
    return false;
  }
  std::ifstream in(path, std::ios::binary);
  out->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) {
    if (err) *err += "cannot read '" + path + "'. ";
    return false;
  }
  return true;
}

bool refuse_file_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "writing files is not supported. ";
  return false;
}

class Loader {
 public:
  explicit Loader(const std::filesystem::path& path) : path_(path), file_(path.string()) {}
  // Bytes already in memory; `name` stands for the file in errors, external files resolve in `base_dir`.
  Loader(std::string bytes, const std::string& name, const std::filesystem::path& base_dir)
      : path_(base_dir / name), file_(name), bytes_(std::move(bytes)), in_memory_(true) {}

  std::unique_ptr<Scene> load();

 private:
  [[noreturn]] void fail(const std::string& problem) const { throw SceneError(file_ + ": " + one_line(problem)); }

  void parse();
  struct AccessorSpan {
    const unsigned char* data = nullptr;
    size_t count = 0;
    size_t stride = 0;
    int component_type = 0;
    int components = 0;
    bool normalized = false;
  };
  AccessorSpan resolve_accessor(int index, const std::string& what) const;
  std::vector<glm::vec3> read_vec3(int accessor, const std::string& what) const;
  std::vector<glm::vec2> read_texcoords(int accessor, const std::string& what) const;
  std::vector<uint32_t> read_indices(int accessor, const std::string& what) const;
  std::vector<float> read_floats(int accessor, const std::string& what, int components) const;
  std::shared_ptr<const MeshData> build_primitive(int mesh_index, int primitive_index);
  std::shared_ptr<const DeformData> build_deform(int mesh_index, int primitive_index, const std::vector<uint32_t>& source,
                                                 const std::vector<Vertex>& vertices);
  void read_skin_weights(const tinygltf::Primitive& prim, const std::string& label, size_t gltf_vertices,
                         std::vector<glm::uvec4>& joints, std::vector<glm::vec4>& weights) const;
  void add_skins_and_weights(Registry& r);
  void add_animations(Scene& scene);
  AnimationClip::Channel read_channel(const tinygltf::Animation& a, const tinygltf::AnimationChannel& c,
                                      const std::string& label, size_t components) const;
  Transform node_transform(const tinygltf::Node& node, int node_index) const;
  Material material_for(int material_index, const std::string& what);
  std::shared_ptr<const Texture> texture_for(int texture_index, int material_index);
  void add_nodes(Scene& scene);
  void add_light(Registry& r, Entity node_entity, int node_index, const tinygltf::Value& extension);
  void add_views(Scene& scene);

  std::filesystem::path path_;
  std::string file_;
  std::string bytes_;
  bool in_memory_ = false;
  tinygltf::Model model_;
  std::map<std::pair<int, int>, std::shared_ptr<const MeshData>> primitive_cache_;
  std::vector<Entity> node_entities_;               // by node index (kNullEntity: not in the scene)
  std::vector<std::vector<Entity>> node_meshes_;   // by node index: the entities holding its primitives
  std::vector<std::pair<Entity, int>> camera_nodes_;  // node entity, camera index
  std::vector<Entity> sun_nodes_;                     // nodes holding a directional light
  size_t local_lights_ = 0;                           // spot and point lights
  size_t skipped_primitives_ = 0;
  size_t skipped_cameras_ = 0;
  std::map<int, std::shared_ptr<const Texture>> texture_cache_;  // by glTF texture index (null: unusable)
};

// Decodes an image (PNG, JPEG, ... through stb_image) to RGBA8. An image that does not decode is left
// empty and the load goes on: the materials using it fall back to their factors (texture_for warns).
bool decode_image(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                  const unsigned char* bytes, int size, void*) {
  int width = 0, height = 0, components = 0;
  stbi_uc* pixels = stbi_load_from_memory(bytes, size, &width, &height, &components, 4);
  if (!pixels) return true;
  image->width = width;
  image->height = height;
  image->component = 4;
  image->bits = 8;
  image->pixel_type = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
  image->image.assign(pixels, pixels + size_t(width) * size_t(height) * 4);
  stbi_image_free(pixels);
  return true;
}

TextureWrap wrap_mode(int gltf_wrap) {
  switch (gltf_wrap) {
    case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE: return TextureWrap::ClampToEdge;
    case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT: return TextureWrap::MirroredRepeat;
    default: return TextureWrap::Repeat;
  }
}

void Loader::parse() {
  if (!in_memory_) {
    std::error_code ec;
    if (!std::filesystem::exists(path_, ec)) fail("file not found");
    if (!std::filesystem::is_regular_file(path_, ec)) fail("not a regular file");
    std::ifstream in(path_, std::ios::binary);
    if (!in) fail("cannot open file");
    bytes_.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const std::string& bytes = bytes_;
  if (bytes.empty()) fail("file is empty");
  if (bytes.size() > UINT32_MAX) fail("file is larger than 4 GiB");

  tinygltf::TinyGLTF gltf;
  gltf.SetImageLoader(decode_image, nullptr);
  gltf.SetFsCallbacks({external_file_exists, external_file_path, read_external_file, refuse_file_write, nullptr});
  std::string err, warn;
  const std::string base_dir = path_.parent_path().string();
  const bool is_binary = bytes.compare(0, 4, "glTF") == 0;
  bool ok = false;
  try {
    if (is_binary) {
      ok = gltf.LoadBinaryFromMemory(&model_, &err, &warn, reinterpret_cast<const unsigned char*>(bytes.data()),
                                     static_cast<unsigned int>(bytes.size()), base_dir);
    } else {
      ok = gltf.LoadASCIIFromString(&model_, &err, &warn, bytes.data(), static_cast<unsigned int>(bytes.size()),
                                    base_dir);
    }
  } catch (const std::exception& e) {
    fail(std::string("parse error: ") + e.what());
  }
  if (!ok) fail(err.empty() ? std::string("not a valid glTF file") : err);
  // Image problems are reported once, per material that needs the image, by texture_for.
  std::string kept, line;
  for (std::istringstream lines(warn); std::getline(lines, line);)
    if (line.find("image[") == std::string::npos && line.rfind("File not found", 0) != 0) kept += line + "\n";
  if (!one_line(kept).empty()) std::cerr << file_ << ": warning: " << one_line(kept) << "\n";
}

Loader::AccessorSpan Loader::resolve_accessor(int index, const std::string& what) const {
  const std::string label = what + " accessor " + std::to_string(index);
  if (index < 0 || size_t(index) >= model_.accessors.size()) {
    fail(label + " out of range (" + std::to_string(model_.accessors.size()) + " accessors)");
  }
  const tinygltf::Accessor& acc = model_.accessors[size_t(index)];
  if (acc.sparse.isSparse) fail(label + " is sparse, which is not supported");
  if (acc.bufferView < 0 || size_t(acc.bufferView) >= model_.bufferViews.size()) {
    fail(label + " refers to bufferView " + std::to_string(acc.bufferView) + " out of range (" +
         std::to_string(model_.bufferViews.size()) + " bufferViews)");
  }
  const tinygltf::BufferView& view = model_.bufferViews[size_t(acc.bufferView)];
  const std::string view_label = "bufferView " + std::to_string(acc.bufferView);
  if (view.buffer < 0 || size_t(view.buffer) >= model_.buffers.size()) {
    fail(view_label + " refers to buffer " + std::to_string(view.buffer) + " out of range");
  }
  const tinygltf::Buffer& buffer = model_.buffers[size_t(view.buffer)];
  if (view.byteOffset > buffer.data.size() || view.byteLength > buffer.data.size() - view.byteOffset) {
    fail(view_label + " (offset " + std::to_string(view.byteOffset) + ", length " +
         std::to_string(view.byteLength) + ") exceeds buffer " + std::to_string(view.buffer) + " of " +
         std::to_string(buffer.data.size()) + " bytes");
  }
  const int component_size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.componentType));
  const int components = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(acc.type));
  if (component_size <= 0) fail(label + " has invalid componentType " + std::to_string(acc.componentType));
  if (components <= 0) fail(label + " has invalid type " + std::to_string(acc.type));
  const size_t element = size_t(component_size) * size_t(components);
  const size_t stride = view.byteStride ? view.byteStride : element;
  if (stride < element) fail(view_label + " byteStride " + std::to_string(stride) + " is smaller than an element");

  AccessorSpan span;
  span.count = acc.count;
  span.stride = stride;
  span.component_type = acc.componentType;
  span.components = components;
  span.normalized = acc.normalized;
  if (acc.count > 0) {
    // Overflow-safe form of: offset + (count - 1) * stride + element <= length.
    const size_t length = view.byteLength;
    const bool fits = acc.byteOffset <= length && element <= length - acc.byteOffset &&
                      (acc.count - 1) <= (length - acc.byteOffset - element) / stride;
    if (!fits) {
      fail(label + " (" + std::to_string(acc.count) + " elements at offset " + std::to_string(acc.byteOffset) +
           ") reads past the end of " + view_label + " (" + std::to_string(length) + " bytes)");
    }
    span.data = buffer.data.data() + view.byteOffset + acc.byteOffset;
  }
  return span;
}

std::vector<glm::vec3> Loader::read_vec3(int accessor, const std::string& what) const {
  const AccessorSpan s = resolve_accessor(accessor, what);
  if (s.components != 3 || s.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT) {
    fail(what + " accessor " + std::to_string(accessor) + " must be VEC3 of FLOAT (componentType " +
         std::to_string(s.component_type) + ", " + std::to_string(s.components) + " components)");
  }
  std::vector<glm::vec3> out(s.count);
  for (size_t i = 0; i < s.count; ++i) {
    std::memcpy(&out[i], s.data + i * s.stride, sizeof(glm::vec3));  // glTF data need not be aligned
    if (!std::isfinite(out[i].x) || !std::isfinite(out[i].y) || !std::isfinite(out[i].z)) {
      fail(what + " accessor " + std::to_string(accessor) + " has a non-finite value at element " +
           std::to_string(i));
    }
  }
  return out;
}

std::vector<glm::vec2> Loader::read_texcoords(int accessor, const std::string& what) const {
  const AccessorSpan s = resolve_accessor(accessor, what);
  const bool is_float = s.component_type == TINYGLTF_COMPONENT_TYPE_FLOAT;
  const bool is_unorm = s.normalized && (s.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                         s.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
  if (s.components != 2 || !(is_float || is_unorm)) {
    fail(what + " accessor " + std::to_string(accessor) +
         " must be VEC2 of FLOAT or normalized UNSIGNED_BYTE/UNSIGNED_SHORT");
  }
  std::vector<glm::vec2> out(s.count);
  for (size_t i = 0; i < s.count; ++i) {
    const unsigned char* p = s.data + i * s.stride;
    if (is_float) {
      std::memcpy(&out[i], p, sizeof(glm::vec2));
      if (!std::isfinite(out[i].x) || !std::isfinite(out[i].y)) {
        fail(what + " accessor " + std::to_string(accessor) + " has a non-finite value at element " +
             std::to_string(i));
      }
    } else if (s.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
      out[i] = glm::vec2(p[0], p[1]) / 255.0f;
    } else {
      uint16_t v[2];
      std::memcpy(v, p, sizeof(v));
      out[i] = glm::vec2(v[0], v[1]) / 65535.0f;
    }
  }
  return out;
}

std::vector<uint32_t> Loader::read_indices(int accessor, const std::string& what) const {
  const AccessorSpan s = resolve_accessor(accessor, what);
  if (s.components != 1) fail(what + " accessor " + std::to_string(accessor) + " must be SCALAR");
  std::vector<uint32_t> out(s.count);
  for (size_t i = 0; i < s.count; ++i) {
    const unsigned char* p = s.data + i * s.stride;
    switch (s.component_type) {
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        out[i] = p[0];
        break;
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v;
        std::memcpy(&v, p, sizeof(v));
        out[i] = v;
        break;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        std::memcpy(&out[i], p, sizeof(uint32_t));
        break;
      default:
        fail(what + " accessor " + std::to_string(accessor) + " has componentType " +
             std::to_string(s.component_type) + "; indices must be UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT");
    }
  }
  return out;
}

std::shared_ptr<const MeshData> Loader::build_primitive(int mesh_index, int primitive_index) {
  const auto key = std::make_pair(mesh_index, primitive_index);
  if (auto it = primitive_cache_.find(key); it != primitive_cache_.end()) return it->second;

  const tinygltf::Mesh& mesh = model_.meshes[size_t(mesh_index)];
  const tinygltf::Primitive& prim = mesh.primitives[size_t(primitive_index)];
  const std::string label = "mesh " + std::to_string(mesh_index) + " primitive " + std::to_string(primitive_index);

  const auto attribute = [&](const char* name) {
    const auto it = prim.attributes.find(name);
    return it == prim.attributes.end() ? -1 : it->second;
  };
  const int position_accessor = attribute("POSITION");
  if (position_accessor < 0) fail(label + " has no POSITION attribute");
  const std::vector<glm::vec3> positions = read_vec3(position_accessor, label + " POSITION");
  const size_t vertex_count = positions.size();

  std::vector<glm::vec3> normals;
  if (const int a = attribute("NORMAL"); a >= 0) {
    normals = read_vec3(a, label + " NORMAL");
    if (normals.size() != vertex_count) {
      fail(label + " NORMAL has " + std::to_string(normals.size()) + " elements, POSITION has " +
           std::to_string(vertex_count));
    }
  }
  std::vector<glm::vec2> uvs;
  if (const int a = attribute("TEXCOORD_0"); a >= 0) {
    uvs = read_texcoords(a, label + " TEXCOORD_0");
    if (uvs.size() != vertex_count) {
      fail(label + " TEXCOORD_0 has " + std::to_string(uvs.size()) + " elements, POSITION has " +
           std::to_string(vertex_count));
    }
  }

  std::vector<uint32_t> indices;
  if (prim.indices >= 0) {
    indices = read_indices(prim.indices, label + " indices");
    for (size_t i = 0; i < indices.size(); ++i) {
      if (indices[i] >= vertex_count) {
        fail(label + " index " + std::to_string(indices[i]) + " at position " + std::to_string(i) +
             " is out of range (" + std::to_string(vertex_count) + " vertices)");
      }
    }
  } else {
    if (vertex_count > UINT32_MAX) fail(label + " has too many vertices");
    indices.resize(vertex_count);
    for (size_t i = 0; i < vertex_count; ++i) indices[i] = uint32_t(i);
  }
  if (indices.size() % 3 != 0) {
    fail(label + " has " + std::to_string(indices.size()) + " indices, not a multiple of 3");
  }

  auto data = std::make_shared<MeshData>();
  data->name = mesh.name.empty() ? "mesh_" + std::to_string(mesh_index) : mesh.name;
  if (mesh.primitives.size() > 1) data->name += "_" + std::to_string(primitive_index);
  std::vector<uint32_t> source;  // per vertex of the mesh, its glTF vertex (per-vertex skin and morph data)
  if (!normals.empty()) {
    data->vertices.resize(vertex_count);
    source.resize(vertex_count);
    for (size_t i = 0; i < vertex_count; ++i) {
      source[i] = uint32_t(i);
      const float len = glm::length(normals[i]);
      data->vertices[i] = {positions[i], len > 0.0f ? normals[i] / len : glm::vec3(0.0f, 1.0f, 0.0f),
                           uvs.empty() ? glm::vec2(0.0f) : uvs[i]};
    }
    data->indices = std::move(indices);
  } else {
    // The glTF spec asks for flat normals when none are given, so every triangle gets its own corners.
    data->vertices.reserve(indices.size());
    data->indices.reserve(indices.size());
    for (size_t t = 0; t < indices.size(); t += 3) {
      const glm::vec3 a = positions[indices[t]], b = positions[indices[t + 1]], c = positions[indices[t + 2]];
      glm::vec3 n = glm::cross(b - a, c - a);
      const float len = glm::length(n);
      n = (len > 0.0f && std::isfinite(len)) ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
      for (int k = 0; k < 3; ++k) {
        const uint32_t src = indices[t + size_t(k)];
        data->indices.push_back(uint32_t(data->vertices.size()));
        data->vertices.push_back({positions[src], n, uvs.empty() ? glm::vec2(0.0f) : uvs[src]});
        source.push_back(src);
      }
    }
  }
  data->compute_bounds();
  data->deform = build_deform(mesh_index, primitive_index, source, data->vertices);
  std::shared_ptr<const MeshData> result = std::move(data);
  primitive_cache_[key] = result;
  return result;
}

// An accessor's elements as floats, `components` per element: FLOAT as stored (finite), integer
// components as their value, or normalized to [0, 1] / [-1, 1] when the accessor says so.
std::vector<float> Loader::read_floats(int accessor, const std::string& what, int components) const {
  const AccessorSpan s = resolve_accessor(accessor, what);
  const std::string label = what + " accessor " + std::to_string(accessor);
  if (s.components != components) {
    fail(label + " has " + std::to_string(s.components) + " components, expected " + std::to_string(components));
  }
  std::vector<float> out(s.count * size_t(components));
  for (size_t i = 0; i < s.count; ++i) {
    const unsigned char* p = s.data + i * s.stride;
    for (int k = 0; k < components; ++k) {
      float& v = out[i * size_t(components) + size_t(k)];
      switch (s.component_type) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT:
          std::memcpy(&v, p + 4 * k, 4);
          if (!std::isfinite(v)) fail(label + " has a non-finite value at element " + std::to_string(i));
          break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: v = float(p[k]) / (s.normalized ? 255.0f : 1.0f); break;
        case TINYGLTF_COMPONENT_TYPE_BYTE: {
          const float x = float(int8_t(p[k]));
          v = s.normalized ? std::max(x / 127.0f, -1.0f) : x;
          break;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
          uint16_t x;
          std::memcpy(&x, p + 2 * k, 2);
          v = float(x) / (s.normalized ? 65535.0f : 1.0f);
          break;
        }
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
          int16_t x;
          std::memcpy(&x, p + 2 * k, 2);
          v = s.normalized ? std::max(float(x) / 32767.0f, -1.0f) : float(x);
          break;
        }
        default:
          fail(label + " has componentType " + std::to_string(s.component_type) + ", which this attribute cannot take");
      }
    }
  }
  return out;
}

// JOINTS_n / WEIGHTS_n per glTF vertex: the four largest influences of each (more are clamped, with a
// warning line), weights normalised to sum 1 (a vertex without weight is bound to joint 0).
void Loader::read_skin_weights(const tinygltf::Primitive& prim, const std::string& label, size_t gltf_vertices,
                               std::vector<glm::uvec4>& joints, std::vector<glm::vec4>& weights) const {
  std::vector<std::vector<float>> joint_sets, weight_sets;
  for (int set = 0;; ++set) {
    const auto j = prim.attributes.find("JOINTS_" + std::to_string(set));
    const auto w = prim.attributes.find("WEIGHTS_" + std::to_string(set));
    if (j == prim.attributes.end() || w == prim.attributes.end()) break;
    const std::string n = std::to_string(set);
    joint_sets.push_back(read_floats(j->second, label + " JOINTS_" + n, 4));
    weight_sets.push_back(read_floats(w->second, label + " WEIGHTS_" + n, 4));
    if (joint_sets.back().size() != gltf_vertices * 4 || weight_sets.back().size() != gltf_vertices * 4)
      fail(label + " JOINTS_" + n + "/WEIGHTS_" + n + " do not have one element per vertex");
  }
  joints.assign(gltf_vertices, glm::uvec4(0));
  weights.assign(gltf_vertices, glm::vec4(1.0f, 0.0f, 0.0f, 0.0f));
  size_t clamped = 0;
  for (size_t v = 0; v < gltf_vertices; ++v) {
    std::vector<std::pair<float, uint32_t>> influences;
    for (size_t set = 0; set < joint_sets.size(); ++set)
      for (size_t k = 0; k < 4; ++k) {
        const float w = weight_sets[set][v * 4 + k];
        const float j = joint_sets[set][v * 4 + k];
        if (w < 0.0f) fail(label + " WEIGHTS_" + std::to_string(set) + " has a negative weight at vertex " + std::to_string(v));
        // glTF joints are unsigned bytes or shorts: anything else (a float, a normalized value) is no index.
        if (!(j >= 0.0f && j <= 65535.0f && j == std::floor(j)))
          fail(label + " JOINTS_" + std::to_string(set) + " holds no joint index at vertex " + std::to_string(v));
        if (w > 0.0f) influences.push_back({w, uint32_t(j)});
      }
    std::stable_sort(influences.begin(), influences.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    if (influences.size() > kMaxJointsPerVertex) ++clamped, influences.resize(kMaxJointsPerVertex);
    float sum = 0.0f;
    for (const auto& [w, j] : influences) sum += w;
    if (!std::isfinite(sum)) fail(label + " has weights at vertex " + std::to_string(v) + " that do not sum to a finite value");
    if (!(sum > 0.0f)) continue;
    for (size_t k = 0; k < influences.size(); ++k) {
      joints[v][int(k)] = influences[k].second;
      weights[v][int(k)] = influences[k].first / sum;
    }
    for (size_t k = influences.size(); k < 4; ++k) weights[v][int(k)] = 0.0f;
  }
  if (clamped > 0)
    std::cerr << file_ << ": warning: " << label << " has " << 4 * joint_sets.size()
              << " joint weights per vertex; kept the 4 largest of each (" << clamped << " vertices clamped)\n";
}

// The primitive's skin weights and morph targets, per vertex of the mesh built from it (`source`
// maps those to glTF vertices); null when it has neither.
std::shared_ptr<const DeformData> Loader::build_deform(int mesh_index, int primitive_index,
                                                       const std::vector<uint32_t>& source,
                                                       const std::vector<Vertex>& vertices) {
  const tinygltf::Mesh& mesh = model_.meshes[size_t(mesh_index)];
  const tinygltf::Primitive& prim = mesh.primitives[size_t(primitive_index)];
  const std::string label = "mesh " + std::to_string(mesh_index) + " primitive " + std::to_string(primitive_index);
  const bool skinned = prim.attributes.count("JOINTS_0") && prim.attributes.count("WEIGHTS_0");
  if (!skinned && prim.targets.empty()) return nullptr;
  const size_t gltf_vertices = resolve_accessor(prim.attributes.at("POSITION"), label + " POSITION").count;
  auto d = std::make_shared<DeformData>();
  if (skinned) {
    std::vector<glm::uvec4> joints;
    std::vector<glm::vec4> weights;
    read_skin_weights(prim, label, gltf_vertices, joints, weights);
    for (size_t v = 0; v < source.size(); ++v) {
      d->joints.push_back(joints[source[v]]);
      d->weights.push_back(weights[source[v]]);
      for (int k = 0; k < 4; ++k)
        if (d->weights.back()[k] > 0.0f) d->joint_count = std::max(d->joint_count, d->joints.back()[k] + 1);
    }
    d->joint_bounds.assign(d->joint_count, Aabb{});
    for (size_t v = 0; v < source.size(); ++v)
      for (int k = 0; k < 4; ++k)
        if (d->weights[v][k] > 0.0f) d->joint_bounds[d->joints[v][k]].extend(vertices[v].position);
  }
  for (size_t t = 0; t < prim.targets.size(); ++t) {
    const std::string what = label + " target " + std::to_string(t);
    MorphTarget target;
    target.name = "target " + std::to_string(t);
    const auto read = [&](const char* attribute, std::vector<glm::vec3>& out) {
      const auto it = prim.targets[t].find(attribute);
      if (it == prim.targets[t].end()) return;
      const std::vector<glm::vec3> deltas = read_vec3(it->second, what + " " + attribute);
      if (deltas.size() != gltf_vertices) fail(what + " " + attribute + " does not have one element per vertex");
      for (uint32_t v : source) out.push_back(deltas[v]);
    };
    read("POSITION", target.position_deltas);
    read("NORMAL", target.normal_deltas);
    if (target.position_deltas.empty()) target.position_deltas.assign(source.size(), glm::vec3(0.0f));
    d->morph_targets.push_back(std::move(target));
  }
  d->default_weights.assign(d->morph_targets.size(), 0.0f);
  for (size_t t = 0; t < d->default_weights.size() && t < mesh.weights.size(); ++t)
    d->default_weights[t] = std::isfinite(mesh.weights[t]) ? float(mesh.weights[t]) : 0.0f;
  return d;
}

// Skeletons for the skinned nodes' meshes (a joint index past the skin's joints is refused) and morph
// weights for the morphing ones (the node's weights, else the mesh's).
void Loader::add_skins_and_weights(Registry& r) {
  for (size_t n = 0; n < model_.nodes.size(); ++n) {
    const tinygltf::Node& node = model_.nodes[n];
    for (Entity part : node_meshes_[n]) {
      const DeformData* d = r.get<Mesh>(part).data->deform.get();
      if (!d) continue;
      if (!d->morph_targets.empty()) {
        MorphWeights w{d->default_weights};
        if (node.weights.size() == w.weights.size())
          for (size_t t = 0; t < w.weights.size(); ++t) w.weights[t] = float(node.weights[t]);
        r.emplace<MorphWeights>(part, std::move(w));
      }
      if (!d->skinned() || node.skin < 0) continue;
      const std::string label = "node " + std::to_string(n) + " skin " + std::to_string(node.skin);
      if (size_t(node.skin) >= model_.skins.size()) fail(label + " out of range (" + std::to_string(model_.skins.size()) + " skins)");
      const tinygltf::Skin& skin = model_.skins[size_t(node.skin)];
      if (d->joint_count > skin.joints.size())
        fail(label + ": mesh '" + r.get<Mesh>(part).data->name + "' uses joint index " + std::to_string(d->joint_count - 1) +
             ", but the skin has " + std::to_string(skin.joints.size()) + " joints");
      Skeleton skeleton;
      for (int j : skin.joints) {
        if (j < 0 || size_t(j) >= node_entities_.size() || node_entities_[size_t(j)] == kNullEntity)
          fail(label + " joint node " + std::to_string(j) + " is not in the scene");
        skeleton.joints.push_back(node_entities_[size_t(j)]);
      }
      skeleton.inverse_bind.assign(skin.joints.size(), glm::mat4(1.0f));
      if (skin.inverseBindMatrices >= 0) {
        const std::vector<float> m = read_floats(skin.inverseBindMatrices, label + " inverseBindMatrices", 16);
        if (m.size() != 16 * skin.joints.size()) fail(label + " inverseBindMatrices has not one matrix per joint");
        for (size_t j = 0; j < skin.joints.size(); ++j) skeleton.inverse_bind[j] = glm::make_mat4(&m[16 * j]);
      }
      r.emplace<Skeleton>(part, std::move(skeleton));
    }
  }
}

AnimationClip::Channel Loader::read_channel(const tinygltf::Animation& a, const tinygltf::AnimationChannel& c,
                                            const std::string& label, size_t components) const {
  if (c.sampler < 0 || size_t(c.sampler) >= a.samplers.size()) fail(label + " sampler out of range");
  const tinygltf::AnimationSampler& sampler = a.samplers[size_t(c.sampler)];
  AnimationClip::Channel out;
  out.interpolation = sampler.interpolation == "STEP"          ? AnimationClip::Interpolation::Step
                      : sampler.interpolation == "CUBICSPLINE" ? AnimationClip::Interpolation::CubicSpline
                                                               : AnimationClip::Interpolation::Linear;
  out.times = read_floats(sampler.input, label + " input", 1);
  for (size_t i = 1; i < out.times.size(); ++i)
    if (!(out.times[i] > out.times[i - 1])) fail(label + " input times are not increasing");
  const size_t per_key = components * (out.interpolation == AnimationClip::Interpolation::CubicSpline ? 3 : 1);
  const int element = c.target_path == "weights" ? 1 : int(components);
  out.values = read_floats(sampler.output, label + " output", element);
  if (out.times.empty() || out.values.size() != out.times.size() * per_key)
    fail(label + " output has " + std::to_string(out.values.size()) + " values for " + std::to_string(out.times.size()) +
         " keys of " + std::to_string(per_key));
  out.components = uint32_t(components);
  return out;
}

// Every glTF animation as a clip; the first plays (an AnimationPlayer on an entity of its own).
void Loader::add_animations(Scene& scene) {
  Registry& r = scene.registry;
  for (size_t ai = 0; ai < model_.animations.size(); ++ai) {
    const tinygltf::Animation& a = model_.animations[ai];
    auto clip = std::make_shared<AnimationClip>();
    clip->name = a.name.empty() ? "animation " + std::to_string(ai) : a.name;
    for (size_t ci = 0; ci < a.channels.size(); ++ci) {
      const tinygltf::AnimationChannel& c = a.channels[ci];
      const std::string label = "animation " + std::to_string(ai) + " channel " + std::to_string(ci);
      const int node = c.target_node;
      if (node < 0 || size_t(node) >= node_entities_.size() || node_entities_[size_t(node)] == kNullEntity) continue;
      using Path = AnimationClip::Path;
      Path path;
      size_t components = 3;
      std::vector<Entity> targets{node_entities_[size_t(node)]};
      if (c.target_path == "translation") path = Path::Translation;
      else if (c.target_path == "scale") path = Path::Scale;
      else if (c.target_path == "rotation") path = Path::Rotation, components = 4;
      else if (c.target_path == "weights") {
        path = Path::Weights;
        targets.clear();
        for (Entity part : node_meshes_[size_t(node)])
          if (const auto* w = r.try_get<MorphWeights>(part)) targets.push_back(part), components = w->weights.size();
        if (targets.empty() || components == 0) continue;
      } else {
        continue;  // "pointer" and other extension paths
      }
      AnimationClip::Channel channel = read_channel(a, c, label, components);
      channel.path = path;
      clip->duration = std::max(clip->duration, channel.times.back());
      for (Entity t : targets) {
        channel.target = t;
        clip->channels.push_back(channel);
      }
    }
    if (clip->channels.empty()) continue;
    const Entity player = r.create();
    r.emplace<Name>(player, Name{"animation: " + clip->name});
    r.emplace<AnimationPlayer>(player, AnimationPlayer{std::move(clip), 1.0f, 0.0f, ai == 0});
  }
}

Transform Loader::node_transform(const tinygltf::Node& node, int node_index) const {
  const std::string label = "node " + std::to_string(node_index);
  const auto all_finite = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double d) { return std::isfinite(d); });
  };
  Transform t;
  if (!node.matrix.empty()) {
    if (node.matrix.size() != 16 || !all_finite(node.matrix)) fail(label + " has an invalid matrix");
    glm::mat4 m;
    for (int i = 0; i < 16; ++i) glm::value_ptr(m)[i] = float(node.matrix[size_t(i)]);  // both column-major
    // Decompose into T * R * S (shear is not representable and is dropped).
    t.translation = glm::vec3(m[3]);
    glm::vec3 axes[3] = {glm::vec3(m[0]), glm::vec3(m[1]), glm::vec3(m[2])};
    glm::vec3 scale{glm::length(axes[0]), glm::length(axes[1]), glm::length(axes[2])};
    if (scale.x <= 0.0f || scale.y <= 0.0f || scale.z <= 0.0f) {
      // A collapsed axis has no direction; keep the scale and leave the rotation as identity.
      t.scale = scale;
      return t;
    }
    for (int i = 0; i < 3; ++i) axes[i] /= scale[i];
    if (glm::dot(glm::cross(axes[0], axes[1]), axes[2]) < 0.0f) {  // mirrored: fold into a negative scale
      scale.x = -scale.x;
      axes[0] = -axes[0];
    }
    t.rotation = glm::normalize(glm::quat_cast(glm::mat3(axes[0], axes[1], axes[2])));
    t.scale = scale;
    return t;
  }
  if (!all_finite(node.translation) || !all_finite(node.rotation) || !all_finite(node.scale)) {
    fail(label + " has a non-finite transform");
  }
  if (!node.translation.empty()) {
    if (node.translation.size() != 3) fail(label + " translation must have 3 values");
    t.translation = glm::vec3(float(node.translation[0]), float(node.translation[1]), float(node.translation[2]));
  }
  if (!node.rotation.empty()) {
    if (node.rotation.size() != 4) fail(label + " rotation must have 4 values");
    // glTF stores quaternions as x, y, z, w; glm's constructor takes w first.
    const glm::quat q(float(node.rotation[3]), float(node.rotation[0]), float(node.rotation[1]),
                      float(node.rotation[2]));
    if (glm::length(q) <= 0.0f) fail(label + " rotation is a zero quaternion");
    t.rotation = glm::normalize(q);
  }
  if (!node.scale.empty()) {
    if (node.scale.size() != 3) fail(label + " scale must have 3 values");
    t.scale = glm::vec3(float(node.scale[0]), float(node.scale[1]), float(node.scale[2]));
  }
  return t;
}

std::shared_ptr<const Texture> Loader::texture_for(int texture_index, int material_index) {
  if (auto it = texture_cache_.find(texture_index); it != texture_cache_.end()) return it->second;
  std::shared_ptr<const Texture>& slot = texture_cache_[texture_index];
  const std::string material = "material " + std::to_string(material_index);
  auto warn = [&](const std::string& problem) {
    std::cerr << file_ << ": warning: " << problem << "; " << material << " uses its base colour factor\n";
  };
  if (texture_index < 0 || size_t(texture_index) >= model_.textures.size()) {
    warn("texture " + std::to_string(texture_index) + " out of range");
    return slot;
  }
  const tinygltf::Texture& t = model_.textures[size_t(texture_index)];
  if (t.source < 0 || size_t(t.source) >= model_.images.size()) {
    warn("texture " + std::to_string(texture_index) + " has no image");
    return slot;
  }
  const tinygltf::Image& image = model_.images[size_t(t.source)];
  const std::string image_name = !image.uri.empty() && image.uri.rfind("data:", 0) != 0
                                     ? (path_.parent_path() / image.uri).string()
                                     : "image " + std::to_string(t.source);
  if (image.image.empty() || image.width <= 0 || image.height <= 0 ||
      image.image.size() != size_t(image.width) * size_t(image.height) * 4) {
    warn("image " + image_name + " is missing or cannot be decoded");
    return slot;
  }
  auto texture = std::make_shared<Texture>();
  texture->name = image_name;
  texture->width = uint32_t(image.width);
  texture->height = uint32_t(image.height);
  texture->rgba = image.image;
  if (t.sampler >= 0 && size_t(t.sampler) < model_.samplers.size()) {
    texture->wrap_s = wrap_mode(model_.samplers[size_t(t.sampler)].wrapS);
    texture->wrap_t = wrap_mode(model_.samplers[size_t(t.sampler)].wrapT);
  }
  slot = std::move(texture);
  return slot;
}

Material Loader::material_for(int material_index, const std::string& what) {
  Material out;
  if (material_index < 0) return out;
  if (size_t(material_index) >= model_.materials.size()) {
    fail(what + " material " + std::to_string(material_index) + " out of range (" +
         std::to_string(model_.materials.size()) + " materials)");
  }
  const tinygltf::Material& m = model_.materials[size_t(material_index)];
  const std::vector<double>& c = m.pbrMetallicRoughness.baseColorFactor;
  if (c.size() == 4) {
    if (!std::all_of(c.begin(), c.end(), [](double d) { return std::isfinite(d); })) {
      fail("material " + std::to_string(material_index) + " has a non-finite baseColorFactor");
    }
    out.base_color = glm::clamp(glm::vec4(float(c[0]), float(c[1]), float(c[2]), float(c[3])), 0.0f, 1.0f);
  }
  if (m.alphaMode == "MASK") {
    out.alpha_mode = AlphaMode::Mask;
  } else if (m.alphaMode == "BLEND") {
    out.alpha_mode = AlphaMode::Blend;
  } else if (m.alphaMode == "OPAQUE" || m.alphaMode.empty()) {
    out.alpha_mode = AlphaMode::Opaque;
  } else {
    fail("material " + std::to_string(material_index) + " has unknown alphaMode '" + m.alphaMode + "'");
  }
  if (!std::isfinite(m.alphaCutoff) || m.alphaCutoff < 0.0) {
    fail("material " + std::to_string(material_index) + " has an invalid alphaCutoff");
  }
  out.alpha_cutoff = float(m.alphaCutoff);
  if (const int texture = m.pbrMetallicRoughness.baseColorTexture.index; texture >= 0) {
    if (m.pbrMetallicRoughness.baseColorTexture.texCoord != 0) {
      std::cerr << file_ << ": warning: material " << material_index
                << " samples TEXCOORD_" << m.pbrMetallicRoughness.baseColorTexture.texCoord
                << ", which the engine does not load; it uses its base colour factor\n";
    } else {
      out.base_color_texture = texture_for(texture, material_index);
    }
  }
  return out;
}

void Loader::add_nodes(Scene& scene) {
  Registry& r = scene.registry;
  const size_t node_count = model_.nodes.size();

  std::vector<int> roots;
  if (!model_.scenes.empty()) {
    const int scene_index = model_.defaultScene >= 0 ? model_.defaultScene : 0;
    if (size_t(scene_index) >= model_.scenes.size()) fail("default scene " + std::to_string(scene_index) + " out of range");
    roots = model_.scenes[size_t(scene_index)].nodes;
  } else {
    // Without a scene list every node that is nobody's child is a root.
    std::vector<bool> is_child(node_count, false);
    for (const tinygltf::Node& n : model_.nodes) {
      for (int c : n.children) {
        if (c >= 0 && size_t(c) < node_count) is_child[size_t(c)] = true;
      }
    }
    for (size_t i = 0; i < node_count; ++i) {
      if (!is_child[i]) roots.push_back(int(i));
    }
  }

  std::vector<bool> visited(node_count, false);
  node_entities_.assign(node_count, kNullEntity);
  node_meshes_.assign(node_count, {});
  std::vector<std::pair<int, Entity>> stack;  // node index, parent entity
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.push_back({*it, kNullEntity});
  while (!stack.empty()) {
    const auto [node_index, parent] = stack.back();
    stack.pop_back();
    if (node_index < 0 || size_t(node_index) >= node_count) {
      fail("node " + std::to_string(node_index) + " out of range (" + std::to_string(node_count) + " nodes)");
    }
    // glTF node graphs must be forests; a second visit means a cycle or a shared child.
    if (visited[size_t(node_index)]) fail("node " + std::to_string(node_index) + " is reachable more than once");
    visited[size_t(node_index)] = true;
    const tinygltf::Node& node = model_.nodes[size_t(node_index)];

    const Entity e = r.create();
    const std::string node_name = node.name.empty() ? "node_" + std::to_string(node_index) : node.name;
    r.emplace<Name>(e, Name{node_name});
    Transform t = node_transform(node, node_index);
    t.parent = parent;
    r.emplace<Transform>(e, t);
    node_entities_[size_t(node_index)] = e;

    if (node.mesh >= 0) {
      if (size_t(node.mesh) >= model_.meshes.size()) {
        fail("node " + std::to_string(node_index) + " mesh " + std::to_string(node.mesh) + " out of range (" +
             std::to_string(model_.meshes.size()) + " meshes)");
      }
      const tinygltf::Mesh& mesh = model_.meshes[size_t(node.mesh)];
      std::vector<std::pair<int, std::shared_ptr<const MeshData>>> parts;
      for (size_t p = 0; p < mesh.primitives.size(); ++p) {
        const int mode = mesh.primitives[p].mode;
        if (mode != -1 && mode != TINYGLTF_MODE_TRIANGLES) {
          ++skipped_primitives_;
          continue;
        }
        auto data = build_primitive(node.mesh, int(p));
        if (data->triangle_count() > 0) parts.push_back({int(p), std::move(data)});
      }
      // One primitive lives on the node itself; several become children so each keeps its material.
      for (auto& [p, data] : parts) {
        Entity target = e;
        if (parts.size() > 1) {
          target = r.create();
          r.emplace<Name>(target, Name{node_name + "_" + std::to_string(p)});
          Transform child;
          child.parent = e;
          r.emplace<Transform>(target, child);
        }
        const Material material = material_for(mesh.primitives[size_t(p)].material,
                                               "mesh " + std::to_string(node.mesh) + " primitive " + std::to_string(p));
        node_meshes_[size_t(node_index)].push_back(target);
        r.emplace<Mesh>(target, Mesh{std::move(data)});
        r.emplace<Material>(target, material);
        r.emplace<ShadowCaster>(target);
      }
    }
    if (node.camera >= 0) {
      if (size_t(node.camera) >= model_.cameras.size()) {
        fail("node " + std::to_string(node_index) + " camera " + std::to_string(node.camera) + " out of range");
      }
      if (model_.cameras[size_t(node.camera)].type == "perspective") {
        camera_nodes_.push_back({e, node.camera});
      } else {
        ++skipped_cameras_;
      }
    }
    if (const auto light = node.extensions.find("KHR_lights_punctual"); light != node.extensions.end())
      add_light(r, e, node_index, light->second);
    for (auto c = node.children.rbegin(); c != node.children.rend(); ++c) stack.push_back({*c, e});
  }
}

// A glTF light without a range reaches infinitely; shadows need a finite one: the distance where its
// intensity over distance squared falls to 1/256 (an 8-bit step), at least 1.
float default_light_range(float intensity) { return std::max(1.0f, std::sqrt(256.0f * intensity)); }

// KHR_lights_punctual: the node's light becomes a SpotLight or PointLight on the node's entity (its
// Transform places and aims it); a directional light sets the scene's sun (add_views).
void Loader::add_light(Registry& r, Entity node_entity, int node_index, const tinygltf::Value& extension) {
  const std::string where = "node " + std::to_string(node_index) + " KHR_lights_punctual";
  if (!extension.IsObject() || !extension.Has("light") || !extension.Get("light").IsNumber())
    fail(where + ": \"light\" must be a light index");
  const int index = extension.Get("light").GetNumberAsInt();
  if (index < 0 || size_t(index) >= model_.lights.size())
    fail(where + ": light " + std::to_string(index) + " out of range (" + std::to_string(model_.lights.size()) +
         " lights)");
  const tinygltf::Light& l = model_.lights[size_t(index)];
  const std::string label = "light " + std::to_string(index);
  glm::vec3 color(1.0f);
  if (!l.color.empty()) {
    if (l.color.size() != 3 || !std::all_of(l.color.begin(), l.color.end(), [](double c) { return std::isfinite(c); }))
      fail(label + " color must be 3 finite numbers");
    color = glm::vec3(float(l.color[0]), float(l.color[1]), float(l.color[2]));
    if (glm::any(glm::lessThan(color, glm::vec3(0.0f)))) fail(label + " color must not be negative");
  }
  if (!std::isfinite(l.intensity) || l.intensity < 0.0) fail(label + " intensity must be finite and >= 0");
  if (!std::isfinite(l.range) || l.range < 0.0) fail(label + " range must be finite and >= 0");
  const float intensity = float(l.intensity);
  const float range = l.range > 0.0 ? float(l.range) : default_light_range(intensity);
  if (l.type == "directional") {
    sun_nodes_.push_back(node_entity);
  } else if (l.type == "point") {
    r.emplace<PointLight>(node_entity, PointLight{color, intensity, range});
    ++local_lights_;
  } else if (l.type == "spot") {
    const double inner = l.spot.innerConeAngle, outer = l.spot.outerConeAngle;
    if (!(inner >= 0.0 && inner < outer && outer <= glm::half_pi<double>() + 1e-6))
      fail(label + " cones must satisfy 0 <= innerConeAngle < outerConeAngle <= pi/2 (got " + std::to_string(inner) +
           ", " + std::to_string(outer) + ")");
    r.emplace<SpotLight>(node_entity, SpotLight{color, intensity, range, float(inner), float(outer)});
    ++local_lights_;
  } else {
    fail(label + " has type \"" + l.type + "\" (directional, point or spot)");
  }
}

// Default framing when the file brings no camera:
//  - near = diag * 1e-3, far = diag * 3, diag = length of the world bounds' extent; the farthest
//    point seen from the overview eye is about 1.9 diag away.
//  - view 0 "overview": looks at the bounds' center from the direction normalize(0.6, 0.75, 0.8)
//    (above, outside, both horizontal axes), far enough that the bounding sphere fits the 60 degree
//    vertical field of view with 5 % margin.
//  - view 1 "inside": eye at min.y + 0.12 * extent.y above the center, backed off a quarter of the
//    extent along the longest horizontal axis and looking along it at the same height.
//  - sun for both: normalize(-0.3, -1, -0.2), steep enough to reach the floor of an enclosed atrium.
constexpr float kDefaultFov = glm::radians(60.0f);
constexpr glm::vec3 kDefaultSun{-0.3f, -1.0f, -0.2f};

void Loader::add_views(Scene& scene) {
  const Aabb bounds = scene.world_bounds();
  if (!bounds.valid()) fail("contains no triangle geometry");
  const glm::vec3 center = bounds.center();
  const glm::vec3 ext = bounds.extent();
  const float diag = std::max(glm::length(ext), 1e-3f);

  Registry& r = scene.registry;
  scene.camera = r.create();
  r.emplace<Name>(scene.camera, Name{"camera"});
  r.emplace<Transform>(scene.camera);
  Camera cam;
  cam.near_plane = diag * 1e-3f;
  cam.far_plane = diag * 3.0f;
  r.emplace<Camera>(scene.camera, cam);
  scene.light = r.create();
  r.emplace<Name>(scene.light, Name{"sun"});
  DirectionalLight sun;
  // A directional light in the file is the sun (the first, if several): it travels down its node's -Z.
  glm::vec3 sun_direction = kDefaultSun;
  if (!sun_nodes_.empty()) {
    const glm::vec3 forward = -glm::vec3(r.get<Transform>(sun_nodes_.front()).world[2]);
    if (glm::length(forward) > 1e-6f) sun_direction = glm::normalize(forward);
    sun.direction = sun_direction;
  } else if (local_lights_ > 0) {
    // A file lit by its own spot and point lights and no sun is lit by them alone: the default sun
    // stays dark (enable_default_sun brings it back).
    sun.intensity = 0.0f;
  }
  r.emplace<DirectionalLight>(scene.light, sun);

  for (const auto& [node_entity, camera_index] : camera_nodes_) {
    const tinygltf::Camera& c = model_.cameras[size_t(camera_index)];
    const glm::mat4& world = r.get<Transform>(node_entity).world;
    const glm::vec3 eye{world[3]};
    glm::vec3 forward = -glm::vec3(world[2]);  // glTF cameras look down their local -Z
    const float len = glm::length(forward);
    forward = len > 0.0f ? forward / len : glm::vec3(0.0f, 0.0f, -1.0f);
    SceneView view;
    view.name = !c.name.empty() ? c.name : r.get<Name>(node_entity).value;
    view.eye = eye;
    view.target = eye + forward * (0.5f * diag);  // camera roll is not kept: views are eye + target
    view.light_direction = sun_direction;
    const double yfov = c.perspective.yfov;
    view.vertical_fov = (std::isfinite(yfov) && yfov > 1e-3 && yfov < glm::pi<double>()) ? float(yfov) : kDefaultFov;
    scene.views.push_back(view);
  }

  if (scene.views.empty()) {
    const float radius = 0.5f * diag;
    const float distance = 1.05f * radius / std::sin(0.5f * kDefaultFov);
    const glm::vec3 direction = glm::normalize(glm::vec3(0.6f, 0.75f, 0.8f));
    scene.views.push_back({"overview", center + direction * distance, center, sun_direction, kDefaultFov});

    const glm::vec3 axis = ext.x >= ext.z ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(0.0f, 0.0f, 1.0f);
    const float along = std::max(ext.x, ext.z);
    glm::vec3 eye{center.x, bounds.min.y + 0.12f * ext.y, center.z};
    eye -= axis * (0.25f * along);
    scene.views.push_back({"inside", eye, eye + axis * (0.5f * along), sun_direction, kDefaultFov});
  }
}

std::unique_ptr<Scene> Loader::load() {
  parse();
  auto scene = std::make_unique<Scene>();
  scene->name = path_.stem().string();
  add_nodes(*scene);
  add_skins_and_weights(scene->registry);
  add_animations(*scene);
  update_world_transforms(scene->registry);
  add_views(*scene);
  // One summary line per kind rather than one per primitive: large files can have thousands.
  if (skipped_primitives_ > 0) {
    std::cerr << file_ << ": warning: skipped " << skipped_primitives_ << " non-triangle primitive(s)\n";
  }
  if (skipped_cameras_ > 0) {
    std::cerr << file_ << ": warning: skipped " << skipped_cameras_ << " non-perspective camera(s)\n";
  }
  scene->apply_view(0);
  update_world_transforms(scene->registry);
  return scene;
}

}  // namespace

std::unique_ptr<Scene> load_gltf_scene(const std::filesystem::path& path) { return Loader(path).load(); }

std::unique_ptr<Scene> load_gltf_scene_from_memory(std::string bytes, const std::string& name,
                                                   const std::filesystem::path& base_dir) {
  return Loader(std::move(bytes), name, base_dir).load();
}

}  // namespace engine
