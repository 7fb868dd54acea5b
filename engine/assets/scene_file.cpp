#include "engine/assets/scene_file.hpp"
#include "engine/assets/procedural_textures.hpp"
#include "portable_random.hpp"

#include <cmath>
#include <fstream>
#include <random>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtx/matrix_decompose.hpp>
#include <glm/gtx/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "engine/assets/procedural_scenes.hpp"
#include "engine/core/animation.hpp"
#include "engine/core/transform_system.hpp"

namespace engine {

namespace {

using nlohmann::json;
using namespace procedural;

class Reader {
 public:
  explicit Reader(std::filesystem::path file) : file_(std::move(file)) {}
  [[noreturn]] void fail(const std::string& field, const std::string& problem) const {
    throw SceneError(file_.string() + ": " + field + ": " + problem);
  }
  const std::filesystem::path& file() const { return file_; }

  float number(const json& j, const std::string& field, float lo = -1e6f, float hi = 1e6f) const {
    if (!j.is_number()) fail(field, "expected a number");
    const float v = j.get<float>();
    if (!std::isfinite(v) || v < lo || v > hi)
      fail(field, "value " + j.dump() + " out of range [" + fmt(lo) + ", " + fmt(hi) + "]");
    return v;
  }
  glm::vec3 vec3(const json& j, const std::string& field) const {
    if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() || !j[2].is_number())
      fail(field, "expected an array of 3 numbers");
    return {number(j[0], field), number(j[1], field), number(j[2], field)};
  }
  glm::vec2 vec2(const json& j, const std::string& field) const {
    if (!j.is_array() || j.size() != 2 || !j[0].is_number() || !j[1].is_number())
      fail(field, "expected an array of 2 numbers");
    return {number(j[0], field), number(j[1], field)};
  }
  const json& required(const json& obj, const char* key, const std::string& field) const {
    if (!obj.contains(key)) fail(field + "." + key, "missing");
    return obj.at(key);
  }
  float number_or(const json& obj, const char* key, const std::string& field, float fallback, float lo = -1e6f,
                  float hi = 1e6f) const {
    return obj.contains(key) ? number(obj.at(key), field + "." + key, lo, hi) : fallback;
  }
  bool boolean_or(const json& obj, const char* key, const std::string& field, bool fallback) const {
    if (!obj.contains(key)) return fallback;
    if (!obj.at(key).is_boolean()) fail(field + "." + key, "expected true or false");
    return obj.at(key).get<bool>();
  }
  std::string string(const json& j, const std::string& field) const {
    if (!j.is_string()) fail(field, "expected a string");
    return j.get<std::string>();
  }
  void only_keys(const json& obj, std::initializer_list<const char*> keys, const std::string& field) const {
    if (!obj.is_object()) fail(field, "expected an object");
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      bool known = false;
      for (const char* k : keys) known |= it.key() == k;
      if (!known) fail(field + "." + it.key(), "unknown field");
    }
  }

 private:
  static std::string fmt(float v) {
    char b[32];
    std::snprintf(b, sizeof(b), "%g", v);
    return b;
  }
  std::filesystem::path file_;
};

using Random = detail::PortableRandom;

glm::vec3 any_perpendicular(const glm::vec3& n) {
  const glm::vec3 helper = std::abs(n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  return glm::normalize(glm::cross(n, helper));
}

// A plant: a stem, a few branches and leaf cards around them. Low detail draws the same random
// numbers (so every plant stands where it does at full detail) but keeps every fourth leaf card at
// twice the size, makes it one-sided (every pass draws both sides of a triangle, and the G-buffer
// turns the normal toward the camera, so the back copy only doubles the rasterizer's work), and
// tessellates the stems more coarsely.
void make_plant(Random& rng, const glm::vec3& origin, float height, Detail detail, MeshData& stems, MeshData& leaves) {
  const bool low = detail == Detail::Low;
  const int leaf_stride = low ? 4 : 1;
  const float leaf_scale = low ? 2.0f : 1.0f;
  const float trunk_top = height * 0.6f;
  append_mesh(stems, make_cylinder(origin, origin + glm::vec3(0, trunk_top, 0), 0.02f + 0.02f * height, low ? 4 : 6, true));
  const int branches = 5;
  for (int b = 0; b <= branches; ++b) {
    glm::vec3 start = origin + glm::vec3(0, trunk_top * rng.uniform(0.5f, 1.0f), 0), end;
    if (b == branches) {
      end = origin + glm::vec3(rng.uniform(-0.1f, 0.1f), height, rng.uniform(-0.1f, 0.1f));
    } else {
      const float angle = 6.2831853f * (float(b) + rng.uniform(0.0f, 0.6f)) / float(branches);
      end = start + glm::normalize(glm::vec3(std::cos(angle), rng.uniform(0.4f, 1.0f), std::sin(angle))) *
                        rng.uniform(0.3f, 0.6f) * height;
    }
    append_mesh(stems, make_cylinder(start, end, 0.015f, low ? 3 : 5, false));
    for (int l = 0; l < 24; ++l) {
      const glm::vec3 c = glm::mix(start, end, rng.uniform(0.35f, 1.0f)) + rng.unit_vector() * rng.uniform(0.02f, 0.25f);
      const glm::vec3 n = rng.unit_vector();
      const glm::vec3 u = any_perpendicular(n), v = glm::cross(n, u);
      const float half = rng.uniform(0.06f, 0.15f) * leaf_scale;
      if (l % leaf_stride != 0) continue;
      append_mesh(leaves, low ? make_quad(c, u * half, v * half * 0.6f) : make_double_sided_quad(c, u * half, v * half * 0.6f));
    }
  }
}

CsmChoice parse_csm(const Reader& rd, const json& j, const std::string& field) {
  const std::string s = rd.string(j, field);
  if (s == "on") return CsmChoice::On;
  if (s == "off") return CsmChoice::Off;
  if (s == "auto") return CsmChoice::Auto;
  rd.fail(field, "'" + s + "' is not one of on, off, auto");
}

// One shape of an object, as a mesh in the object's local frame.
MeshData make_shape(const Reader& rd, const json& shape, const std::string& field) {
  if (!shape.is_object() || shape.size() != 1) rd.fail(field, "expected one of box, cylinder, sphere, ground, quad");
  const std::string kind = shape.begin().key();
  const json& p = shape.begin().value();
  const std::string f = field + "." + kind;
  if (kind == "box") {
    rd.only_keys(p, {"min", "max", "center", "half_extent"}, f);
    if (p.contains("min") || p.contains("max")) {
      const glm::vec3 lo = rd.vec3(rd.required(p, "min", f), f + ".min"), hi = rd.vec3(rd.required(p, "max", f), f + ".max");
      if (!(lo.x < hi.x && lo.y < hi.y && lo.z < hi.z)) rd.fail(f + ".max", "must exceed min on every axis");
      return make_box((hi - lo) * 0.5f, (hi + lo) * 0.5f);
    }
    const glm::vec3 half = rd.vec3(rd.required(p, "half_extent", f), f + ".half_extent");
    if (!(half.x > 0 && half.y > 0 && half.z > 0)) rd.fail(f + ".half_extent", "must be positive");
    return make_box(half, p.contains("center") ? rd.vec3(p.at("center"), f + ".center") : glm::vec3(0.0f));
  }
  if (kind == "cylinder") {
    rd.only_keys(p, {"base", "top", "radius", "segments", "caps"}, f);
    const glm::vec3 base = rd.vec3(rd.required(p, "base", f), f + ".base");
    const glm::vec3 top = rd.vec3(rd.required(p, "top", f), f + ".top");
    if (glm::length(top - base) < 1e-5f) rd.fail(f + ".top", "must differ from base");
    return make_cylinder(base, top, rd.number(rd.required(p, "radius", f), f + ".radius", 1e-4f, 1e4f),
                         int(rd.number_or(p, "segments", f, 16, 3, 256)), rd.boolean_or(p, "caps", f, true));
  }
  if (kind == "sphere") {
    rd.only_keys(p, {"center", "radius", "segments"}, f);
    const int seg = int(rd.number_or(p, "segments", f, 24, 4, 256));
    return make_uv_sphere(p.contains("center") ? rd.vec3(p.at("center"), f + ".center") : glm::vec3(0.0f),
                          rd.number(rd.required(p, "radius", f), f + ".radius", 1e-4f, 1e4f), seg, seg / 2);
  }
  if (kind == "ground") {
    rd.only_keys(p, {"half_size", "y", "subdivisions"}, f);
    const glm::vec2 half = rd.vec2(rd.required(p, "half_size", f), f + ".half_size");
    if (!(half.x > 0 && half.y > 0)) rd.fail(f + ".half_size", "must be positive");
    return make_ground(half.x, half.y, rd.number_or(p, "y", f, 0.0f), int(rd.number_or(p, "subdivisions", f, 1, 1, 256)));
  }
  if (kind == "quad") {
    rd.only_keys(p, {"center", "u", "v", "double_sided"}, f);
    const glm::vec3 c = rd.vec3(rd.required(p, "center", f), f + ".center");
    const glm::vec3 u = rd.vec3(rd.required(p, "u", f), f + ".u"), v = rd.vec3(rd.required(p, "v", f), f + ".v");
    if (glm::length(glm::cross(u, v)) < 1e-8f) rd.fail(f + ".v", "must not be parallel to u");
    return rd.boolean_or(p, "double_sided", f, false) ? make_double_sided_quad(c, u, v) : make_quad(c, u, v);
  }
  rd.fail(f, "unknown shape (box, cylinder, sphere, ground, quad)");
}

// An alpha-tested cut-out over a shape's texture coordinates (quads span [0,1]^2): "grate" with
// `cells` [u, v] openings across the shape and `bar` the bars' width as a share of a cell. Scales the
// mesh's texture coordinates to repeat one generated cell.
std::shared_ptr<const Texture> make_cutout(const Reader& rd, const json& c, const std::string& field, MeshData& mesh) {
  if (!c.is_object() || c.size() != 1 || !c.contains("grate")) rd.fail(field, "expected {\"grate\": {...}}");
  const json& g = c.at("grate");
  const std::string f = field + ".grate";
  rd.only_keys(g, {"cells", "bar"}, f);
  const glm::vec2 cells = rd.vec2(rd.required(g, "cells", f), f + ".cells");
  if (!(cells.x >= 1.0f && cells.y >= 1.0f && cells.x <= 1000.0f && cells.y <= 1000.0f))
    rd.fail(f + ".cells", "expected [u, v] between 1 and 1000");
  const float bar = rd.number_or(g, "bar", f, 0.15f, 0.01f, 0.9f);
  for (Vertex& v : mesh.vertices) v.uv *= cells;
  return procedural::make_grate_texture(64, 1, bar);
}

struct Loaded {
  Scene* scene;
  const Reader* rd;
};

Entity add_entity(Scene& scene, const std::string& name, MeshData mesh, const glm::vec4& color, const Transform& t,
                  const ShadowCaster& shadow) {
  Registry& r = scene.registry;
  const Entity e = r.create();
  mesh.name = name;
  mesh.compute_bounds();
  r.emplace<Name>(e, Name{name});
  r.emplace<Transform>(e, t);
  r.emplace<Mesh>(e, Mesh{std::make_shared<const MeshData>(std::move(mesh))});
  Material m;
  m.base_color = color;
  r.emplace<Material>(e, m);
  r.emplace<ShadowCaster>(e, shadow);
  return e;
}

void add_animation(const Reader& rd, Registry& r, Entity e, const json& a, const std::string& f) {
  rd.only_keys(a, {"swing", "spin", "walk"}, f);
  if (a.size() != 1) rd.fail(f, "expected one of swing, spin, walk");
  Animated anim;
  const std::string kind = a.begin().key();
  const json& p = a.begin().value();
  const std::string g = f + "." + kind;
  if (kind == "swing") {
    rd.only_keys(p, {"axis", "amplitude_deg", "period", "phase"}, g);
    anim.kind = Animated::Kind::Swing;
    anim.axis = p.contains("axis") ? rd.vec3(p.at("axis"), g + ".axis") : glm::vec3(1, 0, 0);
    anim.amplitude = glm::radians(rd.number_or(p, "amplitude_deg", g, 30.0f, 0.0f, 180.0f));
    anim.period = rd.number_or(p, "period", g, 3.0f, 0.05f, 1000.0f);
    anim.phase = rd.number_or(p, "phase", g, 0.0f);
  } else if (kind == "spin") {
    rd.only_keys(p, {"axis", "degrees_per_second", "phase"}, g);
    anim.kind = Animated::Kind::Spin;
    anim.axis = p.contains("axis") ? rd.vec3(p.at("axis"), g + ".axis") : glm::vec3(0, 1, 0);
    anim.speed = glm::radians(rd.number_or(p, "degrees_per_second", g, 90.0f));
    anim.phase = rd.number_or(p, "phase", g, 0.0f);
  } else {
    rd.only_keys(p, {"path", "speed", "phase"}, g);
    anim.kind = Animated::Kind::Walk;
    const json& path = rd.required(p, "path", g);
    if (!path.is_array() || path.size() < 2) rd.fail(g + ".path", "expected at least 2 points");
    for (size_t i = 0; i < path.size(); ++i) anim.path.push_back(rd.vec3(path[i], g + ".path[" + std::to_string(i) + "]"));
    anim.speed = rd.number_or(p, "speed", g, 1.2f, 0.0f, 100.0f);
    anim.phase = rd.number_or(p, "phase", g, 0.0f);
  }
  if (glm::length(anim.axis) < 1e-6f) rd.fail(g + ".axis", "must not be zero");
  make_animated(r, e, anim);
}

// A glTF file's meshes placed as the object: one entity per mesh, flattened to world placements.
void add_gltf_meshes(Scene& scene, const Reader& rd, const json& o, const std::string& f, const std::string& name,
                     const Transform& t, const glm::vec4& color, const ShadowCaster& shadow,
                     std::vector<Entity>& created) {
  const std::filesystem::path gltf = rd.file().parent_path() / rd.string(o.at("gltf"), f + ".gltf");
  std::unique_ptr<Scene> sub;
  try {
    sub = load_gltf_scene(gltf);
  } catch (const SceneError& e) {
    rd.fail(f + ".gltf", e.what());
  }
  update_world_transforms(sub->registry);
  const glm::mat4 root = t.local_matrix();
  sub->registry.each<Mesh, Transform>([&](Entity e, Mesh& m, Transform& st) {
    if (!m.data) return;
    glm::vec3 scale(1.0f), translation(0.0f), skew(0.0f);
    glm::vec4 perspective(0.0f);
    glm::quat rotation(1.0f, 0.0f, 0.0f, 0.0f);
    Transform placed;
    glm::decompose(root * st.world, scale, rotation, translation, skew, perspective);
    placed.translation = translation;
    placed.rotation = rotation;
    placed.scale = scale;
    const Entity n = scene.registry.create();
    const Name* sub_name = sub->registry.try_get<Name>(e);
    scene.registry.emplace<Name>(n, Name{name + "/" + (sub_name ? sub_name->value : m.data->name)});
    scene.registry.emplace<Transform>(n, placed);
    scene.registry.emplace<Mesh>(n, Mesh{m.data});
    Material mat;
    if (const Material* sm = sub->registry.try_get<Material>(e)) mat = *sm;
    if (o.contains("color")) mat.base_color = color;
    scene.registry.emplace<Material>(n, mat);
    scene.registry.emplace<ShadowCaster>(n, shadow);
    created.push_back(n);
  });
}

// A walking figure (procedural_character.cpp) placed by the object's transform. Returns its root, which
// an "animate" moves.
Entity add_character(Scene& scene, const Reader& rd, const json& o, const std::string& f, const std::string& name,
                     const Transform& t, const glm::vec4& color, const ShadowCaster& shadow, Detail detail,
                     std::vector<Entity>& created) {
  const json& c = o.at("character");
  const std::string g = f + ".character";
  rd.only_keys(c, {"tessellation"}, g);
  auto tessellation = uint32_t(rd.number_or(c, "tessellation", g, 32.0f, 6.0f, 128.0f));
  // Low detail (a CPU device): a quarter of the slices, about a sixteenth of the triangles.
  if (detail == Detail::Low) tessellation = std::max(6u, tessellation / 4);
  const Entity root = add_walking_figure(scene, t.translation, 0.0f, tessellation, name);
  Transform& placed = scene.registry.get<Transform>(root);
  placed.rotation = t.rotation;
  placed.scale = t.scale;
  scene.registry.each<Mesh, Transform>([&](Entity e, Mesh&, Transform& mt) {
    if (mt.parent == root) created.push_back(e);
  });
  for (Entity e : created) {
    scene.registry.get<ShadowCaster>(e) = shadow;
    if (o.contains("color")) scene.registry.get<Material>(e).base_color = color;
  }
  return root;
}

void add_object(Scene& scene, const Reader& rd, const json& o, size_t index, Detail detail) {
  const std::string f = "objects[" + std::to_string(index) + "]";
  rd.only_keys(o, {"name", "shape", "shapes", "plants", "gltf", "character", "translation", "rotation_deg", "scale",
                   "color", "leaf_color", "shadow", "animate", "collide", "cutout"},
               f);
  const std::string name = o.contains("name") ? rd.string(o.at("name"), f + ".name") : "object" + std::to_string(index);
  Transform t;
  if (o.contains("translation")) t.translation = rd.vec3(o.at("translation"), f + ".translation");
  if (o.contains("rotation_deg")) t.rotation = glm::quat(glm::radians(rd.vec3(o.at("rotation_deg"), f + ".rotation_deg")));
  if (o.contains("scale")) {
    t.scale = rd.vec3(o.at("scale"), f + ".scale");
    if (!(t.scale.x > 0 && t.scale.y > 0 && t.scale.z > 0)) rd.fail(f + ".scale", "must be positive");
  }
  glm::vec4 color{0.75f, 0.73f, 0.68f, 1.0f};
  if (o.contains("color")) color = glm::vec4(rd.vec3(o.at("color"), f + ".color"), 1.0f);
  ShadowCaster shadow;
  if (o.contains("shadow")) {
    const json& s = o.at("shadow");
    rd.only_keys(s, {"cast", "receive", "csm"}, f + ".shadow");
    shadow.casts_shadow = rd.boolean_or(s, "cast", f + ".shadow", true);
    shadow.receives_shadow = rd.boolean_or(s, "receive", f + ".shadow", true);
    if (s.contains("csm")) shadow.csm = parse_csm(rd, s.at("csm"), f + ".shadow.csm");
  }
  const int sources = int(o.contains("shape")) + int(o.contains("shapes")) + int(o.contains("plants")) +
                      int(o.contains("gltf")) + int(o.contains("character"));
  if (sources != 1) rd.fail(f, "needs exactly one of shape, shapes, plants, gltf, character");
  if (o.contains("cutout") && !o.contains("shape") && !o.contains("shapes")) rd.fail(f + ".cutout", "applies to shape or shapes only");

  std::vector<Entity> created;
  Entity animated = kNullEntity;  // what an "animate" moves: the single mesh, or a character's root
  if (o.contains("shape") || o.contains("shapes")) {
    MeshData mesh;
    if (o.contains("shape")) {
      mesh = make_shape(rd, o.at("shape"), f + ".shape");
    } else {
      const json& list = o.at("shapes");
      if (!list.is_array() || list.empty()) rd.fail(f + ".shapes", "expected a non-empty array of shapes");
      for (size_t i = 0; i < list.size(); ++i)
        append_mesh(mesh, make_shape(rd, list[i], f + ".shapes[" + std::to_string(i) + "]"));
    }
    std::shared_ptr<const Texture> cutout;
    if (o.contains("cutout")) cutout = make_cutout(rd, o.at("cutout"), f + ".cutout", mesh);
    created.push_back(add_entity(scene, name, std::move(mesh), color, t, shadow));
    if (cutout) {
      Material& m = scene.registry.get<Material>(created.back());
      m.alpha_mode = AlphaMode::Mask;
      m.alpha_cutoff = 0.5f;
      m.base_color_texture = std::move(cutout);
    }
  } else if (o.contains("plants")) {
    const json& p = o.at("plants");
    const std::string g = f + ".plants";
    rd.only_keys(p, {"count", "area_min", "area_max", "height", "seed"}, g);
    const int count = int(rd.number(rd.required(p, "count", g), g + ".count", 1, 2000));
    const glm::vec2 lo = rd.vec2(rd.required(p, "area_min", g), g + ".area_min");
    const glm::vec2 hi = rd.vec2(rd.required(p, "area_max", g), g + ".area_max");
    const glm::vec2 height = p.contains("height") ? rd.vec2(p.at("height"), g + ".height") : glm::vec2(1.0f, 2.0f);
    if (!(height.x > 0.0f && height.y >= height.x)) rd.fail(g + ".height", "expected [min, max] with 0 < min <= max");
    Random rng(uint32_t(rd.number_or(p, "seed", g, 1.0f, 0.0f, 1e6f)));
    MeshData stems, leaves;
    for (int i = 0; i < count; ++i) {
      const glm::vec3 at{rng.uniform(lo.x, hi.x), 0.0f, rng.uniform(lo.y, hi.y)};
      make_plant(rng, at, rng.uniform(height.x, height.y), detail, stems, leaves);
    }
    glm::vec4 leaf{0.25f, 0.5f, 0.16f, 1.0f};
    if (o.contains("leaf_color")) leaf = glm::vec4(rd.vec3(o.at("leaf_color"), f + ".leaf_color"), 1.0f);
    created.push_back(add_entity(scene, name + "_stems", std::move(stems), {0.4f, 0.28f, 0.17f, 1.0f}, t, shadow));
    created.push_back(add_entity(scene, name + "_leaves", std::move(leaves), leaf, t, shadow));
  } else if (o.contains("gltf")) {
    add_gltf_meshes(scene, rd, o, f, name, t, color, shadow, created);
  } else {
    animated = add_character(scene, rd, o, f, name, t, color, shadow, detail, created);
  }
  const bool solid = rd.boolean_or(o, "collide", f, !o.contains("plants"));
  for (Entity e : created) scene.registry.emplace<Collider>(e, Collider{solid});
  if (!animated.valid() && created.size() == 1) animated = created[0];
  if (o.contains("animate")) {
    if (!animated.valid()) rd.fail(f + ".animate", "only single-mesh objects (shape, shapes) and characters can be animated");
    add_animation(rd, scene.registry, animated, o.at("animate"), f + ".animate");
  }
}

SceneView read_view(const Reader& rd, const json& v, const std::string& f, const glm::vec3& sun) {
  rd.only_keys(v, {"name", "eye", "target", "fov_deg", "sun"}, f);
  SceneView view;
  view.name = v.contains("name") ? rd.string(v.at("name"), f + ".name") : "view";
  view.eye = rd.vec3(rd.required(v, "eye", f), f + ".eye");
  view.target = rd.vec3(rd.required(v, "target", f), f + ".target");
  if (glm::length(view.target - view.eye) < 1e-4f) rd.fail(f + ".target", "must differ from eye");
  view.vertical_fov = glm::radians(rd.number_or(v, "fov_deg", f, 60.0f, 10.0f, 150.0f));
  view.light_direction = v.contains("sun") ? rd.vec3(v.at("sun"), f + ".sun") : sun;
  if (glm::length(view.light_direction) < 1e-6f) rd.fail(f + ".sun", "must not be zero");
  return view;
}

}  // namespace

// A spot or point light of a scene file: {"type": "spot"|"point", "position", "direction" (spot: the
// way it shines), "range", "inner_cone_deg"/"outer_cone_deg" (spot: half angles), "color",
// "intensity", "name"}, an entity placed (and, for a spot, aimed down its local -Z) by its Transform.
void add_light(Scene& scene, const Reader& rd, const json& j, const std::string& field) {
  rd.only_keys(j, {"type", "name", "position", "direction", "range", "inner_cone_deg", "outer_cone_deg", "color",
                   "intensity", "radius"},
               field);
  const std::string type = rd.string(rd.required(j, "type", field), field + ".type");
  if (type != "spot" && type != "point") rd.fail(field + ".type", "expected \"spot\" or \"point\"");
  Registry& r = scene.registry;
  const Entity e = r.create();
  r.emplace<Name>(e, Name{j.contains("name") ? rd.string(j.at("name"), field + ".name") : type + " light"});
  Transform t;
  t.translation = rd.vec3(rd.required(j, "position", field), field + ".position");
  const glm::vec3 color = j.contains("color") ? rd.vec3(j.at("color"), field + ".color") : glm::vec3(1.0f);
  if (glm::any(glm::lessThan(color, glm::vec3(0.0f)))) rd.fail(field + ".color", "must not be negative");
  const float intensity = rd.number_or(j, "intensity", field, 10.0f, 0.0f, 1e6f);
  const float range = rd.number(rd.required(j, "range", field), field + ".range", 1e-3f, 1e5f);
  const float radius = rd.number_or(j, "radius", field, 0.0f, 0.0f, 1e4f);
  if (type == "point") {
    r.emplace<PointLight>(e, PointLight{color, intensity, range, true, radius});
  } else {
    glm::vec3 direction = rd.vec3(rd.required(j, "direction", field), field + ".direction");
    if (glm::length(direction) < 1e-6f) rd.fail(field + ".direction", "must not be zero");
    direction = glm::normalize(direction);
    // The rotation taking local -Z onto the direction.
    t.rotation = glm::rotation(glm::vec3(0.0f, 0.0f, -1.0f), direction);
    const float inner = rd.number_or(j, "inner_cone_deg", field, 0.0f, 0.0f, 90.0f);
    const float outer = rd.number_or(j, "outer_cone_deg", field, 45.0f, 0.0f, 90.0f);
    if (!(inner < outer)) rd.fail(field + ".inner_cone_deg", "must be less than outer_cone_deg");
    r.emplace<SpotLight>(e, SpotLight{color, intensity, range, glm::radians(inner), glm::radians(outer), true, radius});
  }
  r.emplace<Transform>(e, t);
}

std::unique_ptr<Scene> load_scene_file(const std::filesystem::path& path, Detail detail) {
  const Reader rd(path);
  std::ifstream in(path);
  if (!in) throw SceneError(path.string() + ": cannot open scene file");
  json doc;
  try {
    doc = json::parse(in);
  } catch (const json::parse_error& e) {
    std::string what = e.what();
    for (char& c : what)
      if (c == '\n') c = ' ';
    throw SceneError(path.string() + ": not valid JSON (" + what + ")");
  }
  rd.only_keys(doc, {"name", "description", "sun", "camera", "player", "views", "objects", "lights"}, "(top level)");
  auto scene = std::make_unique<Scene>();
  scene->name = doc.contains("name") ? rd.string(doc.at("name"), "name") : path.stem().string();

  DirectionalLight light;
  if (doc.contains("sun")) {
    const json& s = doc.at("sun");
    rd.only_keys(s, {"direction", "color", "intensity", "angular_diameter_deg"}, "sun");
    light.direction = rd.vec3(rd.required(s, "direction", "sun"), "sun.direction");
    if (glm::length(light.direction) < 1e-6f) rd.fail("sun.direction", "must not be zero");
    light.direction = glm::normalize(light.direction);
    if (s.contains("color")) light.color = rd.vec3(s.at("color"), "sun.color");
    light.intensity = rd.number_or(s, "intensity", "sun", light.intensity, 0.0f, 1000.0f);
    light.angular_diameter_degrees =
        rd.number_or(s, "angular_diameter_deg", "sun", light.angular_diameter_degrees, 0.0f, 10.0f);
  }
  Camera camera;
  if (doc.contains("camera")) {
    const json& c = doc.at("camera");
    rd.only_keys(c, {"near", "far"}, "camera");
    camera.near_plane = rd.number_or(c, "near", "camera", camera.near_plane, 1e-4f, 100.0f);
    camera.far_plane = rd.number_or(c, "far", "camera", camera.far_plane, 1.0f, 1e6f);
    if (camera.far_plane <= camera.near_plane) rd.fail("camera.far", "must exceed camera.near");
  }

  const json& objects = rd.required(doc, "objects", "(top level)");
  if (!objects.is_array() || objects.empty()) rd.fail("objects", "expected a non-empty array");
  for (size_t i = 0; i < objects.size(); ++i) add_object(*scene, rd, objects[i], i, detail);

  const json& views = rd.required(doc, "views", "(top level)");
  if (!views.is_array() || views.empty()) rd.fail("views", "expected a non-empty array of views (the tour)");
  for (size_t i = 0; i < views.size(); ++i)
    scene->views.push_back(read_view(rd, views[i], "views[" + std::to_string(i) + "]", light.direction));
  if (doc.contains("player")) scene->start = read_view(rd, doc.at("player"), "player", light.direction);

  Registry& r = scene->registry;
  scene->camera = r.create();
  r.emplace<Name>(scene->camera, Name{"camera"});
  r.emplace<Transform>(scene->camera);
  r.emplace<Camera>(scene->camera, camera);
  scene->light = r.create();
  r.emplace<Name>(scene->light, Name{"sun"});
  r.emplace<DirectionalLight>(scene->light, light);
  if (doc.contains("lights")) {
    const json& lights = doc.at("lights");
    if (!lights.is_array()) rd.fail("lights", "expected an array");
    for (size_t i = 0; i < lights.size(); ++i) add_light(*scene, rd, lights[i], "lights[" + std::to_string(i) + "]");
  }
  update_world_transforms(r);
  scene->apply_view(0);
  update_world_transforms(r);
  return scene;
}

}  // namespace engine
