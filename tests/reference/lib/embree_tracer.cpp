#include "reference/embree_tracer.hpp"

#include "engine/core/skinning.hpp"

#include <embree3/rtcore.h>
#include <shared/local_light.h>
#include <shared/shadow_common.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>

#include "engine/core/components.hpp"
#include "engine/core/material_textures.hpp"

namespace reference {
namespace {

const char* error_name(RTCError e) {
  switch (e) {
    case RTC_ERROR_NONE:
      return "none";
    case RTC_ERROR_UNKNOWN:
      return "unknown";
    case RTC_ERROR_INVALID_ARGUMENT:
      return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION:
      return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY:
      return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU:
      return "unsupported CPU";
    case RTC_ERROR_CANCELLED:
      return "cancelled";
  }
  return "unrecognised";
}

struct DeviceDeleter {
  void operator()(RTCDevice d) const { rtcReleaseDevice(d); }
};
struct SceneDeleter {
  void operator()(RTCScene s) const { rtcReleaseScene(s); }
};
using DeviceHandle = std::unique_ptr<RTCDeviceTy, DeviceDeleter>;
using SceneHandle = std::unique_ptr<RTCSceneTy, SceneDeleter>;

constexpr int kPacket = 16;
constexpr float kInf = std::numeric_limits<float>::infinity();

glm::vec3 to_light_dir(glm::vec3 light_direction) {
  const float len = glm::length(light_direction);
  if (!(len > 0.0f) || !std::isfinite(len)) {
    throw std::invalid_argument("light direction must be finite and non-zero");
  }
  return -light_direction / len;
}

void check_points(const ShadingPoints& points) {
  const size_t n = points.pixel_count();
  if (points.position.size() != n || points.normal.size() != n) {
    throw std::invalid_argument(
        "shading points: position/normal sizes differ from width * height (" +
        std::to_string(points.width) + "x" + std::to_string(points.height) + ")");
  }
}

// Runs row_fn(y) for every row, rows handed out one at a time so uneven rows balance.
template <typename Fn>
void for_each_row(uint32_t height, Fn&& row_fn) {
  const uint32_t workers = std::max(1u, std::min(std::thread::hardware_concurrency(), height));
  std::atomic<uint32_t> next{0};
  auto work = [&] {
    for (uint32_t y = next.fetch_add(1); y < height; y = next.fetch_add(1)) row_fn(y);
  };
  std::vector<std::thread> threads;
  for (uint32_t i = 1; i < workers; ++i) threads.emplace_back(work);
  work();
  for (auto& t : threads) t.join();
}

}  // namespace

// What the occlusion filter needs to alpha-test one triangle (the IZB's CasterAlpha).
struct TriangleAlpha {
  uint32_t threshold = 0;  // engine::alpha_threshold; 0: not alpha-tested
  uint32_t texture = 0;
  glm::vec2 uv[3]{};
};

struct AlphaScene {
  engine::MaterialTextureTable textures;
  std::vector<TriangleAlpha> triangles;  // by Embree primitive id
};

// Rejects hits where an alpha-tested triangle is transparent: the texture coordinate at the hit
// (Embree's barycentrics u, v weight vertices 1 and 2) read by the shared nearest-texel rule, as the
// GPU techniques do.
void alpha_filter(const RTCFilterFunctionNArguments* args) {
  const auto* scene = static_cast<const AlphaScene*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const TriangleAlpha& t = scene->triangles[RTCHitN_primID(args->hit, args->N, i)];
    if (t.threshold == 0) continue;
    const float u = RTCHitN_u(args->hit, args->N, i);
    const float v = RTCHitN_v(args->hit, args->N, i);
    const glm::vec2 uv = (1.0f - u - v) * t.uv[0] + u * t.uv[1] + v * t.uv[2];
    if (!scene->textures.alpha_kept(t.texture, t.threshold, uv)) args->valid[i] = 0;
  }
}

struct EmbreeTracer::Impl {
  glm::dvec3 shift{0.0};
  DeviceHandle device;
  std::unique_ptr<AlphaScene> alpha;
  SceneHandle scene;
  uint32_t triangles = 0;
  bool packets = false;
  // The triangle soup Embree holds, kept for the independent reference's double-precision hits.
  std::vector<glm::vec3> vertices;
  std::vector<uint32_t> indices;
  std::string last_message;  // filled by the device error callback

  void check(const char* what) {
    const RTCError e = rtcGetDeviceError(device.get());
    if (e == RTC_ERROR_NONE) return;
    std::string msg = std::string("Embree error (") + error_name(e) + ") while " + what;
    if (!last_message.empty()) msg += ": " + last_message;
    std::replace(msg.begin(), msg.end(), '\n', ' ');
    throw std::runtime_error(msg);
  }

  // Tests `count` (<= 16) rays sharing a direction; writes 1 to hit[i] when ray i is occluded.
  void occluded_batch(int count, const glm::vec3* origins, glm::vec3 dir, uint8_t* hit) const {
    if (!packets) {
      for (int i = 0; i < count; ++i) hit[i] = occluded1(origins[i], dir) ? 1 : 0;
      return;
    }
    alignas(64) int valid[kPacket];
    alignas(64) RTCRay16 rays;
    for (int i = 0; i < kPacket; ++i) {
      const bool on = i < count;
      valid[i] = on ? -1 : 0;
      set_ray(rays, i, on ? origins[i] : glm::vec3(0.0f), dir, kInf);
    }
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    // Rays of one pixel or one row segment share a direction and nearly an origin.
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    rtcOccluded16(valid, scene.get(), &ctx, &rays);
    // Embree sets tfar to -inf for every occluded ray.
    for (int i = 0; i < count; ++i) hit[i] = rays.tfar[i] < 0.0f ? 1 : 0;
  }

  static void set_ray(RTCRay16& rays, int i, glm::vec3 origin, glm::vec3 dir, float t_far) {
    rays.org_x[i] = origin.x;
    rays.org_y[i] = origin.y;
    rays.org_z[i] = origin.z;
    rays.tnear[i] = 0.0f;
    rays.dir_x[i] = dir.x;
    rays.dir_y[i] = dir.y;
    rays.dir_z[i] = dir.z;
    rays.time[i] = 0.0f;
    rays.tfar[i] = t_far;
    rays.mask[i] = 0xFFFFFFFFu;
    rays.id[i] = static_cast<unsigned>(i);
    rays.flags[i] = 0;
  }

  // Of `count` rays from `origin`, ray i along the unit dirs[i] up to t_far[i], how many no triangle
  // occludes; a ray with t_far[i] <= 0 is lit without a trace (it ends before it starts).
  uint32_t lit_rays(glm::vec3 origin, const glm::vec3* dirs, const float* t_far, uint32_t count) const {
    uint32_t lit = 0;
    for (uint32_t first = 0; first < count; first += kPacket) {
      const int n = int(std::min<uint32_t>(kPacket, count - first));
      if (!packets) {
        for (int i = 0; i < n; ++i)
          lit += t_far[first + i] <= 0.0f || !occluded1(origin, dirs[first + i], t_far[first + i]) ? 1u : 0u;
        continue;
      }
      alignas(64) int valid[kPacket];
      alignas(64) RTCRay16 rays;
      for (int i = 0; i < kPacket; ++i) {
        const bool on = i < n && t_far[first + i] > 0.0f;
        valid[i] = on ? -1 : 0;
        set_ray(rays, i, origin, on ? dirs[first + i] : glm::vec3(0.0f, 1.0f, 0.0f), on ? t_far[first + i] : kInf);
      }
      RTCIntersectContext ctx;
      rtcInitIntersectContext(&ctx);
      // One pixel's rays share their origin and spread over a small cone.
      ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
      rtcOccluded16(valid, scene.get(), &ctx, &rays);
      for (int i = 0; i < n; ++i) lit += valid[i] == 0 || rays.tfar[i] >= 0.0f ? 1u : 0u;
    }
    return lit;
  }

  bool occluded1(glm::vec3 origin, glm::vec3 dir, float t_far = kInf) const {
    RTCRay ray{};
    ray.org_x = origin.x;
    ray.org_y = origin.y;
    ray.org_z = origin.z;
    ray.tnear = 0.0f;
    ray.dir_x = dir.x;
    ray.dir_y = dir.y;
    ray.dir_z = dir.z;
    ray.time = 0.0f;
    ray.tfar = t_far;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcOccluded1(scene.get(), &ctx, &ray);
    return ray.tfar < 0.0f;
  }

  // The triangle the ray from `origin` along `dir` meets first, or -1.
  int64_t first_hit(glm::vec3 origin, glm::vec3 dir) const {
    RTCRayHit rh{};
    rh.ray.org_x = origin.x;
    rh.ray.org_y = origin.y;
    rh.ray.org_z = origin.z;
    rh.ray.dir_x = dir.x;
    rh.ray.dir_y = dir.y;
    rh.ray.dir_z = dir.z;
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = kInf;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcIntersect1(scene.get(), &ctx, &rh);
    return rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? -1 : int64_t(rh.hit.primID);
  }
};

EmbreeTracer::EmbreeTracer(engine::Registry& registry, const glm::dvec3& shift) : impl_(std::make_unique<Impl>()) {
  Impl& im = *impl_;
  im.shift = shift;
  im.device.reset(rtcNewDevice(nullptr));
  if (!im.device) {
    throw std::runtime_error(std::string("Embree error (") +
                             error_name(rtcGetDeviceError(nullptr)) +
                             ") while creating the device");
  }
  rtcSetDeviceErrorFunction(
      im.device.get(),
      [](void* user, RTCError, const char* str) {
        static_cast<Impl*>(user)->last_message = str ? str : "";
      },
      &im);

  // All casters go into one world-space triangle soup: the reference needs no instancing.
  std::vector<glm::vec3> vertices;
  std::vector<uint32_t> indices;
  im.alpha = std::make_unique<AlphaScene>();
  im.alpha->textures = engine::MaterialTextureTable(registry);
  bool any_alpha_tested = false;
  registry.each<engine::Mesh, engine::Transform>(
      [&](engine::Entity e, engine::Mesh& mesh, engine::Transform& transform) {
        if (const auto* caster = registry.try_get<engine::ShadowCaster>(e);
            caster && !caster->casts_shadow) {
          return;
        }
        if (!mesh.data) return;
        const engine::MeshData& data = *mesh.data;
        const size_t base = vertices.size();
        const glm::mat4 world = engine::rebased(transform.world, shift);
        // A skinned or morphed mesh in its current pose, deformed on the CPU as skinning.comp does.
        const std::vector<engine::Vertex> posed =
            data.deform ? engine::posed_vertices(registry, e) : std::vector<engine::Vertex>{};
        for (const engine::Vertex& v : data.deform ? posed : data.vertices) {
          vertices.push_back(glm::vec3(world * glm::vec4(v.position, 1.0f)));
        }
        const size_t whole = data.indices.size() / 3 * 3;
        TriangleAlpha alpha;
        if (const auto* material = registry.try_get<engine::Material>(e)) {
          alpha.threshold = engine::alpha_threshold(*material);
          alpha.texture = im.alpha->textures.index_of(*material);
        }
        any_alpha_tested = any_alpha_tested || alpha.threshold != 0;
        for (size_t i = 0; i < whole; ++i) {
          const uint32_t idx = data.indices[i];
          if (idx >= data.vertices.size()) {
            throw std::runtime_error("mesh '" + data.name + "': index " + std::to_string(idx) +
                                     " out of range (" + std::to_string(data.vertices.size()) +
                                     " vertices)");
          }
          indices.push_back(static_cast<uint32_t>(base + idx));
          alpha.uv[i % 3] = data.vertices[idx].uv;
          if (i % 3 == 2) im.alpha->triangles.push_back(alpha);
        }
      });
  if (vertices.size() > UINT32_MAX)
    throw std::runtime_error("reference scene has too many vertices");

  im.scene.reset(rtcNewScene(im.device.get()));
  im.check("creating the scene");
  rtcSetSceneFlags(im.scene.get(), RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(im.scene.get(), RTC_BUILD_QUALITY_HIGH);

  im.triangles = static_cast<uint32_t>(indices.size() / 3);
  if (im.triangles > 0) {
    RTCGeometry geom = rtcNewGeometry(im.device.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
    im.check("creating the triangle geometry");
    rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_HIGH);
    // rtcSetNewGeometryBuffer pads the allocation as Embree's SIMD loads require.
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertices.size()));
    auto* ib = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), im.triangles));
    if (!vb || !ib) {
      rtcReleaseGeometry(geom);
      im.check("allocating geometry buffers");
      throw std::runtime_error("Embree error while allocating geometry buffers");
    }
    for (size_t i = 0; i < vertices.size(); ++i) {
      vb[3 * i + 0] = vertices[i].x;
      vb[3 * i + 1] = vertices[i].y;
      vb[3 * i + 2] = vertices[i].z;
    }
    std::copy(indices.begin(), indices.end(), ib);
    if (any_alpha_tested) {
      rtcSetGeometryUserData(geom, im.alpha.get());
      rtcSetGeometryOccludedFilterFunction(geom, alpha_filter);
      rtcSetGeometryIntersectFilterFunction(geom, alpha_filter);  // primary rays see through the same texels
    }
    im.vertices = std::move(vertices);
    im.indices = std::move(indices);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(im.scene.get(), geom);
    rtcReleaseGeometry(geom);  // the scene keeps its own reference
    im.check("adding the triangle geometry");
  }
  rtcCommitScene(im.scene.get());
  im.check("building the scene");

  // Packets of 16 depend on how Embree was built; probe once and fall back to single rays.
  im.packets = true;
  const glm::vec3 probe_origin(0.0f);
  uint8_t probe_hit[kPacket];
  im.occluded_batch(1, &probe_origin, glm::vec3(0.0f, 1.0f, 0.0f), probe_hit);
  if (rtcGetDeviceError(im.device.get()) != RTC_ERROR_NONE) {
    im.packets = false;
    im.last_message.clear();
  }
}

EmbreeTracer::~EmbreeTracer() = default;
EmbreeTracer::EmbreeTracer(EmbreeTracer&&) noexcept = default;
EmbreeTracer& EmbreeTracer::operator=(EmbreeTracer&&) noexcept = default;

uint32_t EmbreeTracer::triangle_count() const { return impl_->triangles; }

bool EmbreeTracer::occluded(glm::vec3 origin, glm::vec3 dir_to_light) const {
  return impl_->occluded1(origin, dir_to_light);
}

const glm::dvec3& EmbreeTracer::shift() const { return impl_->shift; }

bool EmbreeTracer::occluded_within(glm::vec3 origin, glm::vec3 dir_to_light, float distance) const {
  return impl_->occluded1(origin, glm::normalize(dir_to_light), distance);
}

std::vector<float> EmbreeTracer::visibility_1spp(const ShadingPoints& points,
                                                 glm::vec3 light_direction) const {
  check_points(points);
  const glm::vec3 to_light = to_light_dir(light_direction);
  std::vector<float> out(points.pixel_count(), -1.0f);
  for_each_row(points.height, [&](uint32_t y) {
    // Lit-facing pixels of the row are gathered into packets; the rest are settled without a ray.
    glm::vec3 origins[kPacket];
    size_t slots[kPacket];
    uint8_t hit[kPacket];
    int count = 0;
    auto flush = [&] {
      impl_->occluded_batch(count, origins, to_light, hit);
      for (int i = 0; i < count; ++i) out[slots[i]] = hit[i] ? 0.0f : 1.0f;
      count = 0;
    };
    for (uint32_t x = 0; x < points.width; ++x) {
      const size_t i = points.index(x, y);
      if (!points.covered(i)) continue;
      const glm::vec3 p(points.position[i]);
      const glm::vec3 n(points.normal[i]);
      if (!points.faces(i, to_light)) {
        out[i] = 0.0f;
        continue;
      }
      origins[count] = gpu_shared::shadow_ray_origin(p, n, gpu_shared::shadow_ray_offset(p, points.eye));
      slots[count] = i;
      if (++count == kPacket) flush();
    }
    if (count > 0) flush();
  });
  return out;
}

std::vector<float> EmbreeTracer::visibility_32spp(const ShadingPoints& points,
                                                  glm::vec3 light_direction) const {
  check_points(points);
  const glm::vec3 to_light = to_light_dir(light_direction);
  static_assert(gpu_shared::kSamplesPerPixel % kPacket == 0);
  constexpr uint32_t kSamples = gpu_shared::kSamplesPerPixel;
  const glm::vec2 viewport{float(points.width), float(points.height)};
  std::vector<float> out(points.pixel_count(), -1.0f);
  for_each_row(points.height, [&](uint32_t y) {
    glm::vec3 origins[kSamples];
    uint8_t hit[kSamples];
    for (uint32_t x = 0; x < points.width; ++x) {
      const size_t i = points.index(x, y);
      if (!points.covered(i)) continue;
      const glm::vec3 p(points.position[i]);
      const glm::vec3 n(points.normal[i]);
      if (!points.faces(i, to_light)) {
        out[i] = 0.0f;
        continue;
      }
      // The μQuad's corners once per pixel; every sample is their blend (micro_quad_sample's definition).
      const glm::vec2 pixel{float(x), float(y)};
      glm::vec3 corner[4];
      for (int k = 0; k < 4; ++k)
        corner[k] = gpu_shared::micro_quad_corner(pixel + glm::vec2(float(k & 1), float(k >> 1)), viewport,
                                                  points.inv_view_proj, p, n);
      const float offset = gpu_shared::shadow_ray_offset(p, points.eye);
      for (uint32_t s = 0; s < kSamples; ++s) {
        const glm::vec3 q = gpu_shared::micro_quad_blend(corner[0], corner[1], corner[2], corner[3],
                                                         gpu_shared::kSamplePattern[s]);
        origins[s] = gpu_shared::shadow_ray_origin(q, n, offset);
      }
      for (uint32_t s = 0; s < kSamples; s += kPacket)
        impl_->occluded_batch(kPacket, origins + s, to_light, hit + s);
      uint32_t lit = 0;
      for (uint32_t s = 0; s < kSamples; ++s) lit += hit[s] ? 0u : 1u;
      out[i] = float(lit) / float(kSamples);
    }
  });
  return out;
}

namespace {
// Whether a local light reaches the point (range, cone) and its geometric normal faces the light.
bool local_light_shines_on(const LocalLight& light, glm::vec3 p, glm::vec3 n) {
  return gpu_shared::local_light_reaches(light.position, light.range, light.spot_direction, light.cos_outer, light.spot,
                                         p) &&
         gpu_shared::faces_local_light(n, p, light.position);
}

// The pixels' shared rule for a local light: -1 background, 0 unreached or turned away, else the lit
// fraction of `samples` rays (the μQuad's, or the shading point's alone).
template <typename Occluded>
std::vector<float> local_visibility(const ShadingPoints& points, const LocalLight& light, uint32_t samples,
                                    Occluded occluded) {
  std::vector<float> out(points.pixel_count(), -1.0f);
  const glm::vec2 viewport{float(points.width), float(points.height)};
  for_each_row(points.height, [&](uint32_t y) {
    for (uint32_t x = 0; x < points.width; ++x) {
      const size_t i = points.index(x, y);
      if (!points.covered(i)) continue;
      const glm::vec3 p(points.position[i]);
      const glm::vec3 n(points.normal[i]);
      if (!local_light_shines_on(light, p, n)) {
        out[i] = 0.0f;
        continue;
      }
      glm::vec3 corner[4];
      if (samples == 32)
        for (int k = 0; k < 4; ++k)
          corner[k] = gpu_shared::micro_quad_corner(glm::vec2(float(x + (k & 1)), float(y + (k >> 1))), viewport,
                                                    points.inv_view_proj, p, n);
      uint32_t lit = 0;
      const float offset = gpu_shared::shadow_ray_offset(p, points.eye);
      for (uint32_t s = 0; s < samples; ++s) {
        const glm::vec3 q = samples == 32 ? gpu_shared::micro_quad_blend(corner[0], corner[1], corner[2], corner[3],
                                                                         gpu_shared::kSamplePattern[s])
                                          : p;
        const glm::vec3 origin = gpu_shared::shadow_ray_origin(q, n, offset);
        const float length = gpu_shared::local_shadow_ray_length(origin, light.position, light.range);
        lit += length <= 0.0f || !occluded(origin, light.position - origin, length) ? 1u : 0u;
      }
      out[i] = float(lit) / float(samples);
    }
  });
  return out;
}
}  // namespace

std::vector<float> EmbreeTracer::visibility_1spp(const ShadingPoints& points, const LocalLight& light) const {
  check_points(points);
  return local_visibility(points, light, 1, [&](glm::vec3 o, glm::vec3 d, float t) { return occluded_within(o, d, t); });
}

std::vector<float> EmbreeTracer::visibility_32spp(const ShadingPoints& points, const LocalLight& light) const {
  check_points(points);
  return local_visibility(points, light, gpu_shared::kSamplesPerPixel,
                          [&](glm::vec3 o, glm::vec3 d, float t) { return occluded_within(o, d, t); });
}

namespace {
// A fixed, well-mixed hash of a pixel, a sample and a dimension: the jitter of the area rays.
double jitter(uint32_t x, uint32_t y, uint32_t sample, uint32_t dimension) {
  const auto mix = [](uint32_t h) {
    h = (h ^ (h >> 16)) * 0x21f0aaadu;
    h = (h ^ (h >> 15)) * 0x735a2d97u;
    return h ^ (h >> 15);
  };
  uint32_t h = mix(x * 0x9e3779b9u + 0x632be5abu);
  h = mix(h ^ (y * 0x85ebca6bu + 0x2c1b3c6du));
  h = mix(h ^ (sample * 2u + dimension));
  return double(h) * (1.0 / 4294967296.0);
}

// The concentric map of the unit square onto the unit disc: squares around the centre go to rings,
// and areas are kept, so points uniform on the square are uniform on the disc.
glm::dvec2 concentric_disc(double u, double v) {
  constexpr double kQuarterPi = 0.78539816339744830962;
  const double a = 2.0 * u - 1.0, b = 2.0 * v - 1.0;
  if (a == 0.0 && b == 0.0) return glm::dvec2(0.0);
  double r, phi;
  if (std::abs(a) > std::abs(b)) {
    r = a;
    phi = kQuarterPi * (b / a);
  } else {
    r = b;
    phi = 2.0 * kQuarterPi - kQuarterPi * (a / b);
  }
  return r * glm::dvec2(std::cos(phi), std::sin(phi));
}

// Sample `sample` of `count` of pixel (x, y) on the unit disc: the unit square cut into `count` cells
// of equal area (floor(sqrt(count)) rows; the first count % rows rows one cell longer, and each row as
// tall as its share of the cells), a point jittered in the sample's cell, through concentric_disc.
glm::dvec2 stratified_disc(uint32_t x, uint32_t y, uint32_t sample, uint32_t count) {
  const uint32_t rows = std::max(1u, uint32_t(std::sqrt(double(count))));
  const uint32_t base = count / rows, long_cells = (count % rows) * (base + 1);
  const uint32_t in_row = sample < long_cells ? base + 1 : base;
  const uint32_t row_start = sample < long_cells ? sample / in_row * in_row
                                                 : long_cells + (sample - long_cells) / in_row * in_row;
  const double u = (double(sample - row_start) + jitter(x, y, sample, 0)) / double(in_row);
  const double v = (double(row_start) + jitter(x, y, sample, 1) * double(in_row)) / double(count);
  return concentric_disc(u, v);
}

// Two unit vectors perpendicular to the unit `axis` and to each other (built apart from area_light.h's
// basis, so the reference does not lean on the code it checks).
struct DiscFrame {
  glm::dvec3 u, v;
};
DiscFrame disc_frame(const glm::dvec3& axis) {
  const glm::dvec3 helper = std::abs(axis.x) < 0.6 ? glm::dvec3(1.0, 0.0, 0.0) : glm::dvec3(0.0, 1.0, 0.0);
  const glm::dvec3 u = glm::normalize(glm::cross(axis, helper));
  return {u, glm::cross(axis, u)};
}

void check_rays(uint32_t rays) {
  if (rays == 0) throw std::invalid_argument("area_visibility: rays must be at least 1");
}
}  // namespace

std::vector<float> EmbreeTracer::area_visibility(const ShadingPoints& points, glm::vec3 light_direction,
                                                 float angular_diameter_degrees, uint32_t rays) const {
  check_points(points);
  check_rays(rays);
  if (!std::isfinite(angular_diameter_degrees) || angular_diameter_degrees < 0.0f || angular_diameter_degrees >= 180.0f)
    throw std::invalid_argument("area_visibility: the angular diameter " + std::to_string(angular_diameter_degrees) +
                                " is not in [0, 180) degrees");
  if (angular_diameter_degrees == 0.0f) return visibility_1spp(points, light_direction);
  const glm::vec3 to_light = to_light_dir(light_direction);
  const glm::dvec3 axis = glm::normalize(glm::dvec3(to_light));
  const DiscFrame frame = disc_frame(axis);
  // 1 - cos(angular radius), as 2 sin^2(half of it): no cancellation for a small sun.
  const double quarter = glm::radians(double(angular_diameter_degrees)) * 0.25;
  const double cone = 2.0 * std::sin(quarter) * std::sin(quarter);
  std::vector<float> out(points.pixel_count(), -1.0f);
  for_each_row(points.height, [&](uint32_t y) {
    std::vector<glm::vec3> dirs(rays);
    const std::vector<float> t_far(rays, kInf);
    for (uint32_t x = 0; x < points.width; ++x) {
      const size_t i = points.index(x, y);
      if (!points.covered(i)) continue;
      const glm::vec3 p(points.position[i]);
      const glm::vec3 n(points.normal[i]);
      if (!points.faces(i, to_light)) {
        out[i] = 0.0f;
        continue;
      }
      const glm::vec3 origin = gpu_shared::shadow_ray_origin(p, n, gpu_shared::shadow_ray_offset(p, points.eye));
      for (uint32_t s = 0; s < rays; ++s) {
        // A disc sample of squared radius q lies at 1 - cos = q * cone from the axis: uniform in solid angle.
        const glm::dvec2 d = stratified_disc(x, y, s, rays);
        const double h = glm::dot(d, d) * cone;
        const glm::dvec3 dir = axis * (1.0 - h) + std::sqrt(cone * (2.0 - h)) * (d.x * frame.u + d.y * frame.v);
        dirs[s] = glm::vec3(glm::normalize(dir));
      }
      out[i] = float(impl_->lit_rays(origin, dirs.data(), t_far.data(), rays)) / float(rays);
    }
  });
  return out;
}

std::vector<float> EmbreeTracer::area_visibility(const ShadingPoints& points, const LocalLight& light, float radius,
                                                 uint32_t rays) const {
  check_points(points);
  check_rays(rays);
  if (!std::isfinite(radius) || radius < 0.0f)
    throw std::invalid_argument("area_visibility: the radius " + std::to_string(radius) + " is not finite and >= 0");
  if (radius == 0.0f) return visibility_1spp(points, light);
  const glm::dvec3 center(light.position);
  std::vector<float> out(points.pixel_count(), -1.0f);
  for_each_row(points.height, [&](uint32_t y) {
    std::vector<glm::vec3> dirs(rays);
    std::vector<float> t_far(rays);
    for (uint32_t x = 0; x < points.width; ++x) {
      const size_t i = points.index(x, y);
      if (!points.covered(i)) continue;
      const glm::vec3 p(points.position[i]);
      const glm::vec3 n(points.normal[i]);
      if (!local_light_shines_on(light, p, n)) {
        out[i] = 0.0f;
        continue;
      }
      const glm::vec3 origin = gpu_shared::shadow_ray_origin(p, n, gpu_shared::shadow_ray_offset(p, points.eye));
      const DiscFrame frame = disc_frame(glm::normalize(center - glm::dvec3(origin)));
      for (uint32_t s = 0; s < rays; ++s) {
        const glm::dvec2 d = stratified_disc(x, y, s, rays);
        const glm::vec3 target(center + double(radius) * (d.x * frame.u + d.y * frame.v));
        t_far[s] = gpu_shared::local_shadow_ray_length(origin, target, light.range);
        dirs[s] = t_far[s] > 0.0f ? glm::normalize(target - origin) : glm::vec3(0.0f, 1.0f, 0.0f);
      }
      out[i] = float(impl_->lit_rays(origin, dirs.data(), t_far.data(), rays)) / float(rays);
    }
  });
  return out;
}

namespace {
double max_abs(const glm::dvec3& v) { return std::max(std::max(std::abs(v.x), std::abs(v.y)), std::abs(v.z)); }

// Where the ray from `eye` along `dir` meets the plane through `point` with normal `normal` (t <= 0
// or parallel: nullopt).
std::optional<glm::dvec3> on_plane(const glm::dvec3& eye, const glm::dvec3& dir, const glm::dvec3& point,
                                   const glm::dvec3& normal) {
  const double along = glm::dot(dir, normal);
  if (along == 0.0) return std::nullopt;
  const double t = glm::dot(point - eye, normal) / along;
  if (!(t > 0.0)) return std::nullopt;
  return eye + t * dir;
}
}  // namespace

std::vector<TrueVisibility> EmbreeTracer::independent_visibility(const PinholeCamera& camera, const TrueLight& light,
                                                                 uint32_t samples, double offset_band) const {
  if (camera.width == 0 || camera.height == 0) throw std::invalid_argument("independent_visibility: a zero image size");
  if (samples != 1 && samples != gpu_shared::kSamplesPerPixel)
    throw std::invalid_argument("independent_visibility: samples must be 1 or 32");
  if (!(offset_band > 0.0)) throw std::invalid_argument("independent_visibility: the offset band must be positive");
  const Impl& im = *impl_;
  constexpr double kOpen = 1.0e-6;  // decisions this close to their threshold are left open
  const glm::dvec3 to_sun = -glm::normalize(light.direction);
  const glm::dvec3 spot_direction = light.spot ? glm::normalize(light.spot_direction) : glm::dvec3(0.0);
  const double cos_outer = std::cos(light.outer_cone);
  const double bulb = light.range / 1000.0;
  // The ray from the eye through (sx, sy) in pixels (the pixel's centre at +0.5).
  const auto eye_ray = [&](double sx, double sy) {
    const glm::dvec4 ndc(sx / camera.width * 2.0 - 1.0, sy / camera.height * 2.0 - 1.0, 0.5, 1.0);
    const glm::dvec4 far = camera.inv_view_proj * ndc;
    return glm::normalize(glm::dvec3(far) / far.w - camera.eye);
  };
  std::vector<TrueVisibility> out(size_t(camera.width) * camera.height);
  for_each_row(camera.height, [&](uint32_t y) {
    for (uint32_t x = 0; x < camera.width; ++x) {
      TrueVisibility& pixel = out[size_t(y) * camera.width + x];
      const glm::dvec3 dir = eye_ray(x + 0.5, y + 0.5);
      const int64_t prim = im.first_hit(glm::vec3(camera.eye), glm::vec3(dir));
      if (prim < 0) continue;
      glm::dvec3 v[3];
      double size = 0.0;
      for (int k = 0; k < 3; ++k) {
        v[k] = glm::dvec3(im.vertices[im.indices[3 * size_t(prim) + k]]);
        size = std::max(size, max_abs(v[k]));
      }
      glm::dvec3 n = glm::cross(v[1] - v[0], v[2] - v[0]);
      if (glm::dot(n, n) == 0.0) continue;  // a degenerate triangle draws nothing
      n = glm::normalize(n);
      if (glm::dot(n, camera.eye - v[0]) < 0.0) n = -n;
      const std::optional<glm::dvec3> p = on_plane(camera.eye, dir, v[0], n);
      if (!p) continue;
      pixel.point = *p;
      pixel.normal = n;
      pixel.lit_min = 0.0f;
      pixel.lit_max = 0.0f;
      // Seen nearly edge-on, the raster and the ray may show different surfaces.
      bool open = std::abs(glm::dot(dir, n)) < kOpen;
      // Facing and reach at the shading point.
      const glm::dvec3 toward = light.sun ? to_sun : glm::normalize(light.position - *p);
      const double facing = glm::dot(n, toward);
      if (facing <= -kOpen) continue;
      open = open || facing < kOpen;
      if (!light.sun) {
        const double distance = glm::length(*p - light.position);
        if (distance > light.range * (1.0 + kOpen)) continue;
        open = open || distance >= light.range * (1.0 - kOpen);
        if (light.spot) {
          const double cos_angle = glm::dot((*p - light.position) / distance, spot_direction);
          if (cos_angle < cos_outer - kOpen) continue;
          open = open || cos_angle < cos_outer + kOpen;
        }
      }
      // The pixel's footprint on the plane of its centre's triangle (the μQuad): where the rays through
      // its four corners meet that plane; a sample is the bilinear blend of those corners at its
      // pattern position.
      glm::dvec3 corner[4];
      for (int k = 0; k < 4 && samples > 1; ++k) {
        const std::optional<glm::dvec3> on = on_plane(camera.eye, eye_ray(x + (k & 1), y + (k >> 1)), *p, n);
        corner[k] = on ? *on : *p;
      }
      uint32_t lit_always = 0, lit_somewhere = 0;
      for (uint32_t s = 0; s < samples; ++s) {
        glm::dvec3 q = *p;
        if (samples > 1) {
          const glm::dvec2 at(gpu_shared::kSamplePattern[s]);
          q = glm::mix(glm::mix(corner[0], corner[1], at.x), glm::mix(corner[2], corner[3], at.x), at.y);
        }
        const double heights[2] = {std::ldexp(std::max(max_abs(q), size), -16),
                                   offset_band * (max_abs(q) + max_abs(q - camera.eye))};
        bool lit[2];
        for (int h = 0; h < 2; ++h) {
          const glm::dvec3 origin = q + n * std::max(heights[0], heights[h]);
          if (light.sun) {
            lit[h] = !im.occluded1(glm::vec3(origin), glm::vec3(to_sun));
          } else {
            const double length = glm::length(light.position - origin) - bulb;
            lit[h] = length <= 0.0 ||
                     !im.occluded1(glm::vec3(origin), glm::vec3(glm::normalize(light.position - origin)), float(length));
          }
        }
        lit_always += lit[0] && lit[1];
        lit_somewhere += lit[0] || lit[1];
      }
      pixel.lit_min = open ? 0.0f : float(lit_always) / float(samples);
      pixel.lit_max = float(lit_somewhere) / float(samples);
    }
  });
  return out;
}

}  // namespace reference
