#include "barriers.hpp"
#include "csm_pass.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <set>
#include <sstream>
#include <tuple>

#include "gpu/profiler.hpp"
#include "light_space.hpp"
#include "shared/csm.h"
#include "shared/izb.h"

namespace shadows::detail {

using namespace engine::gpu;

CsmChoiceMeasure measure_csm_suitability(std::span<const glm::vec3> positions, std::span<const uint32_t> indices,
                                         const glm::mat4& world,
                                         const glm::vec3& light_direction, float texel_size) {
  CsmChoiceMeasure out;
  const glm::mat3 to_light = glm::mat3(light_view_matrix(light_direction));
  const double circumradius = 0.70710678 * texel_size;
  double coverable = 0.0;
  for (size_t i = 0; i + 2 < indices.size(); i += 3) {
    glm::dvec2 p[3];
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 w = glm::vec3(world * glm::vec4(positions[indices[i + k]], 1.0f));
      p[k] = glm::dvec2(to_light * w);
    }
    const double area = 0.5 * std::abs((p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[2].x - p[0].x) * (p[1].y - p[0].y));
    const double perimeter = glm::length(p[1] - p[0]) + glm::length(p[2] - p[1]) + glm::length(p[0] - p[2]);
    ++out.triangles;
    if (area <= 0.0 || perimeter <= 0.0) continue;
    out.projected_area += area;
    // Shrinking a triangle by distance d scales it about its incentre by (r - d) / r.
    const double inradius = 2.0 * area / perimeter;
    if (inradius > circumradius) {
      const double scale = (inradius - circumradius) / inradius;
      coverable += area * scale * scale;
    }
  }
  out.coverable_share = out.projected_area > 0.0 ? coverable / out.projected_area : 0.0;
  return out;
}

namespace {
std::vector<Binding> csm_bindings() {
  return {{gpu_shared::CSM_BINDING_FRAME, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
          {gpu_shared::CSM_BINDING_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER},
          {gpu_shared::CSM_BINDING_DEPTH, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER}};
}
}  // namespace

struct CsmPass::Impl {
  Context& ctx;
  Image depth;
  Sampler nearest;
  Buffer counters;
  ReadbackRing readback;
  std::map<CsmTest, Pipeline> pipelines;
  Pipeline coverage;
  // The automatic choice's measure, taken on the GPU (csm_measure.comp) and read back when the frame
  // that took it completes. Taken again when the light, the texel size or the instance's matrix
  // changes; meanwhile the last one stands (an instance never measured stays out: a mesh left out
  // costs culling, never a wrong shadow).
  struct MeasureKey {
    glm::mat4 world;
    glm::vec3 light;
    float texel;
    bool operator==(const MeasureKey&) const = default;
  };
  struct Cached {
    MeasureKey key{};  // of `measure`
    CsmChoiceMeasure measure;
    bool measured = false;
    bool pending = false;  // a measure is in flight
  };
  // By instance id, mesh and the IZB record of the frame (instances sharing all three share a measure;
  // each light of a frame, and each cone of a point light, keeps its own).
  using CacheKey = std::tuple<uint64_t, uint32_t, uint32_t>;
  uint64_t plan_frame = ~0ull;
  uint32_t record_in_frame = 0;  // the IZB records of plan_frame planned so far, less one
  std::map<CacheKey, Cached> cache;
  struct Job {
    CacheKey instance;
    MeasureKey key;
    uint64_t triangles;
  };
  // Per frame-in-flight slot: the jobs its frame measured and the buffers it used, one batch per
  // record of the IZB (a frame records one per light, six for a point light). A slot's previous frame
  // has completed when it records again, so its buffers are rewritten or replaced freely.
  struct MeasureBatch {
    Buffer jobs, partials;
    std::vector<Job> pending;
    uint32_t groups_per_job = 0;
  };
  struct MeasureSlot {
    std::vector<MeasureBatch> batches;
    uint32_t count = 0;  // batches recorded and not yet read
    uint64_t frame = 0;
  };
  std::vector<MeasureSlot> measure_slots;
  std::vector<Job> wanted;  // this frame's jobs
  std::vector<gpu_shared::CsmMeasureJob> wanted_gpu;
  Pipeline measure;
  std::vector<CsmDecision> decisions;
  std::vector<bool> in_csm;  // per draw, this frame
  bool ran = false;
  bool automatic_only = true;  // no caster in the CSM by CsmChoice::On (plan())
  std::string status = "off";
  // Adaptive skipping under Auto, per IZB record of a frame (each light, each cone of a point light).
  struct Adaptive {
    double last_yield = 1.0;
    bool have_yield = false;
    uint32_t frames_since_probe = 0;
    std::vector<bool> last_choice;
    glm::vec3 last_light{0.0f};
    uint32_t last_resolution = 0;
    uint64_t generation = 0;  // counts changes of choice, light or resolution
  };
  std::vector<Adaptive> adaptive;
  // Per frame-in-flight slot and record: whether the prepass ran there, and under which generation. A
  // yield comes back frames_in_flight frames after its record, perhaps under another choice; only one
  // measured under the current choice may decide to skip (a stale 0 % would skip a useful prepass).
  struct SlotRun {
    bool ran = false;
    uint64_t generation = 0;
  };
  std::vector<std::vector<SlotRun>> slot_runs;
  uint32_t plan_slot = 0;
  void note_run(bool ran) {
    if (slot_runs.size() <= plan_slot) slot_runs.resize(plan_slot + 1);
    std::vector<SlotRun>& runs = slot_runs[plan_slot];
    if (runs.size() <= record_in_frame) runs.resize(record_in_frame + 1);
    runs[record_in_frame] = {ran, record_in_frame < adaptive.size() ? adaptive[record_in_frame].generation : 0};
  }

  explicit Impl(Context& c) : ctx(c) {
    nearest = Sampler(c, VK_FILTER_NEAREST, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, "csm nearest");
    counters = Buffer(c, gpu_shared::CSM_COUNTER_COUNT * 4,
                      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                          VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                      false, "csm counters");
    PipelineFactory factory(c);
    coverage = factory.compute({"csm_coverage.comp", csm_bindings(), 0});
    const VkDescriptorType storage = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    measure = factory.compute({"csm_measure.comp",
                               {{gpu_shared::CSM_MEASURE_BINDING_VERTICES, storage},
                                {gpu_shared::CSM_MEASURE_BINDING_INDICES, storage},
                                {gpu_shared::CSM_MEASURE_BINDING_JOBS, storage},
                                {gpu_shared::CSM_MEASURE_BINDING_PARTIALS, storage}},
                               sizeof(gpu_shared::CsmMeasurePush)});
  }

  // The map is cleared to 1 (nothing stored) when made, in the frame's command stream.
  void ensure_depth(VkCommandBuffer cmd, uint32_t resolution) {
    if (depth.valid() && depth.extent().width == resolution) return;
    depth = Image(ctx, {resolution, resolution}, VK_FORMAT_D32_SFLOAT,
                  VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
                      VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                  "conservative shadow map");
    to_general(ctx, cmd, depth);
    VkClearDepthStencilValue far{1.0f, 0};
    VkImageSubresourceRange range{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
    vkCmdClearDepthStencilImage(cmd, depth.handle(), VK_IMAGE_LAYOUT_GENERAL, &far, 1, &range);
    pass_barrier(ctx, cmd);
  }

  bool supported(CsmTest test, std::string* why) const {
    const auto& f = ctx.features();
    auto fail = [&](const std::string& reason) {
      if (why) *why = reason;
      return false;
    };
    switch (test) {
      case CsmTest::Hertel:
      case CsmTest::Barycentric:
        return true;  // as compute work everywhere; as raster work with geometry shaders
      case CsmTest::BarycentricHw:
        if (!f.fragment_shader_barycentric)
          return fail("needs VK_KHR_fragment_shader_barycentric, which " + ctx.device_name() + " lacks");
        return true;
      case CsmTest::InnerHw:
        if (!f.conservative_rasterization || !f.conservative_underestimation || !f.fully_covered_fragment_input)
          return fail("needs VK_EXT_conservative_rasterization with underestimation and the fully-covered input, "
                      "which " + ctx.device_name() + " lacks");
        return true;
    }
    return fail("unknown test");
  }

  const Pipeline& pipeline(CsmTest test) {
    auto it = pipelines.find(test);
    if (it != pipelines.end()) return it->second;
    GraphicsPipelineDesc d;
    d.name = "csm " + csm_test_name(test);
    d.vertex_shader = "csm.vert";
    d.bindings = csm_bindings();
    d.push_constant_size = sizeof(gpu_shared::IzbDrawPush);
    d.vertex_input = VertexInput::PositionOnly;
    d.depth_format = VK_FORMAT_D32_SFLOAT;
    d.depth_compare = VK_COMPARE_OP_LESS;  // several covering triangles: the nearest bound culls most
    d.cull_mode = VK_CULL_MODE_NONE;
    switch (test) {
      case CsmTest::Hertel:
        d.geometry_shader = "csm.geom";
        d.fragment_shader = "csm.frag";
        d.specialization = {{0, gpu_shared::CSM_TEST_HERTEL}};
        break;
      case CsmTest::Barycentric:
        d.geometry_shader = "csm.geom";
        d.fragment_shader = "csm.frag";
        d.specialization = {{0, gpu_shared::CSM_TEST_BARYCENTRIC}};
        break;
      case CsmTest::BarycentricHw:
        d.fragment_shader = "csm_bary_hw.frag";
        break;
      case CsmTest::InnerHw:
        d.fragment_shader = "csm_inner_hw.frag";
        d.conservative = ConservativeMode::Underestimate;
        break;
    }
    return pipelines.emplace(test, PipelineFactory(ctx).graphics(d)).first->second;
  }

  // Texel size estimate for the automatic choice: the IZB window is fitted on the GPU to the visible
  // points, so the CPU uses the casters' light-space extent, an upper bound (decisions err toward
  // leaving a mesh out, never toward a wrong shadow).
  float estimate_texel_size(const Frame& frame, uint32_t resolution) const {
    const Aabb box = caster_bounds(frame);
    if (!box.valid()) return 1.0f;
    const glm::mat4 view = light_view_matrix(frame.view.light_direction);
    glm::vec2 lo(1e30f), hi(-1e30f);
    for (int i = 0; i < 8; ++i) {
      glm::vec3 corner((i & 1) ? box.max.x : box.min.x, (i & 2) ? box.max.y : box.min.y, (i & 4) ? box.max.z : box.min.z);
      const glm::vec2 v = glm::vec2(view * glm::vec4(corner, 1.0f));
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
    return std::max(hi.x - lo.x, hi.y - lo.y) / float(resolution);
  }
  std::set<uint64_t> warned_alpha_forced;  // instances already warned about

  void choose(const Frame& frame, uint32_t resolution) {
    decisions.clear();
    wanted.clear();
    wanted_gpu.clear();
    in_csm.assign(frame.draws.size(), false);
    const float texel = estimate_texel_size(frame, resolution);
    for (size_t i = 0; i < frame.draws.size(); ++i) {
      const auto& d = frame.draws[i];
      if (!d.shadow.casts_shadow) continue;
      CsmDecision decision;
      decision.instance_id = d.id;
      decision.name = d.name;
      if (d.alpha_tested()) {
        // The CSM writes a texel only where one triangle provably covers all of it; an alpha-tested
        // triangle has holes wherever its texture says so, so it can prove nothing.
        decision.automatic = d.shadow.csm == CsmChoice::Auto;
        decision.reason = "out: alpha-tested material (cut-outs cannot prove full texel coverage)";
        if (d.shadow.csm == CsmChoice::On && warned_alpha_forced.insert(d.id).second)
          std::cerr << "warning: entity '" << decision.name
                    << "' is forced into the CSM but its material is alpha-tested; it stays out\n";
      } else if (d.shadow.csm == CsmChoice::On) {
        decision.in_csm = true;
        decision.reason = "on: chosen for the entity";
      } else if (d.shadow.csm == CsmChoice::Off) {
        decision.reason = "off: chosen for the entity";
      } else if (d.shadow.deformed) {  // a shape of each frame's own: dynamic, its measure would not hold
        decision.automatic = true;
        decision.reason = "out: deformed (positions of its own every frame: dynamic)";
      } else {
        decision.automatic = true;
        const MeasureKey key{d.world, frame.view.light_direction, texel};
        const CacheKey cache_key{d.id, d.mesh, record_in_frame};
        Cached& cached = cache[cache_key];
        if ((!cached.measured || cached.key != key) && !cached.pending && wanted.size() < kMaxMeasuresPerFrame) {
          const MeshRange& range = frame.geometry.mesh(d.mesh);
          cached.pending = true;
          wanted.push_back({cache_key, key, range.index_count / 3});
          wanted_gpu.push_back({d.world, range.first_index, range.vertex_offset, range.index_count / 3, 0u});
        }
        if (!cached.measured) {
          decision.reason = "out: measuring (its light-space area is measured on the GPU)";
        } else {
          decision.large_triangle_area_share = cached.measure.coverable_share;
          decision.in_csm = cached.measure.coverable_share >= kCsmAutoThreshold;
          std::ostringstream reason;
          reason.precision(3);
          reason << "auto: " << cached.measure.coverable_share * 100.0 << "% of its light-space area can fully cover "
                 << resolution << "^2 texels of ~" << cached.key.texel << " units (" << (decision.in_csm ? ">=" : "<")
                 << " " << kCsmAutoThreshold * 100.0 << "%)";
          decision.reason = reason.str();
        }
      }
      in_csm[i] = decision.in_csm;
      decisions.push_back(std::move(decision));
    }
  }

  void record_measures(const Frame& frame);
  void take_measures(uint32_t slot);
};

void CsmPass::Impl::record_measures(const Frame& frame) {
  if (measure_slots.size() <= frame.slot) measure_slots.resize(frame.slot + 1);
  MeasureSlot& measure_slot = measure_slots[frame.slot];
  if (measure_slot.frame != frame.view.frame_index) {
    // The slot's earlier frame was never read back: ask again.
    for (uint32_t b = 0; b < measure_slot.count; ++b)
      for (const Job& job : measure_slot.batches[b].pending) cache[job.instance].pending = false;
    measure_slot.count = 0;
    measure_slot.frame = frame.view.frame_index;
  }
  if (wanted.empty()) return;
  if (measure_slot.batches.size() <= measure_slot.count) measure_slot.batches.emplace_back();
  MeasureBatch& slot = measure_slot.batches[measure_slot.count++];
  uint64_t most = 1;
  for (const Job& job : wanted) most = std::max(most, job.triangles);
  // Enough workgroups per instance that each thread sums a few dozen triangles at most.
  const uint32_t groups = uint32_t(std::clamp<uint64_t>((most + 2047) / 2048, 1, 64));
  const VkDeviceSize job_bytes = wanted_gpu.size() * sizeof(gpu_shared::CsmMeasureJob);
  const VkDeviceSize partial_bytes = VkDeviceSize(wanted.size()) * groups * sizeof(glm::vec2);
  if (!slot.jobs.valid() || slot.jobs.size() < job_bytes)
    slot.jobs = Buffer(ctx, std::max(job_bytes, slot.jobs.size() * 2), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true,
                       "csm auto-choice jobs");
  if (!slot.partials.valid() || slot.partials.size() < partial_bytes)
    slot.partials = Buffer(ctx, std::max(partial_bytes, slot.partials.size() * 2), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                           true, "csm auto-choice readback");
  slot.jobs.write(wanted_gpu.data(), job_bytes);  // made visible to the device by the submission
  slot.groups_per_job = groups;
  slot.pending = wanted;
  VkCommandBuffer cmd = frame.cmd;
  ScopedGpuRegion region(ctx, frame.profiler, cmd, "csm_choice");
  measure.bind(cmd);
  DescriptorWriter()
      .storage_buffer(gpu_shared::CSM_MEASURE_BINDING_VERTICES, frame.geometry.vertices().handle())
      .storage_buffer(gpu_shared::CSM_MEASURE_BINDING_INDICES, frame.geometry.indices().handle())
      .storage_buffer(gpu_shared::CSM_MEASURE_BINDING_JOBS, slot.jobs.handle())
      .storage_buffer(gpu_shared::CSM_MEASURE_BINDING_PARTIALS, slot.partials.handle())
      .push(ctx, cmd, measure);
  gpu_shared::CsmMeasurePush push{};
  push.to_light = glm::mat4(glm::mat3(light_view_matrix(frame.view.light_direction)));
  push.circumradius = float(0.70710678 * wanted.front().key.texel);
  push.groups_per_job = groups;
  measure.push_constants(cmd, push);
  vkCmdDispatch(cmd, groups, uint32_t(wanted.size()), 1);
  // The sums, read on the host once this frame has completed.
  memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                 VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
}

void CsmPass::Impl::take_measures(uint32_t slot_index) {
  if (slot_index >= measure_slots.size()) return;
  MeasureSlot& measure_slot = measure_slots[slot_index];
  for (uint32_t b = 0; b < measure_slot.count; ++b) {
    MeasureBatch& slot = measure_slot.batches[b];
    const auto* partials = slot.partials.as<glm::vec2>();
    for (size_t k = 0; k < slot.pending.size(); ++k) {
      const Job& job = slot.pending[k];
      double projected = 0.0, coverable = 0.0;
      for (uint32_t g = 0; g < slot.groups_per_job; ++g) {
        projected += partials[k * slot.groups_per_job + g].x;
        coverable += partials[k * slot.groups_per_job + g].y;
      }
      Cached& cached = cache[job.instance];
      cached.pending = false;
      cached.measured = true;
      cached.key = job.key;
      cached.measure = {projected > 0.0 ? coverable / projected : 0.0, projected, job.triangles};
    }
    slot.pending.clear();
  }
  measure_slot.count = 0;
}

CsmPass::CsmPass(Context& ctx) : impl_(std::make_unique<Impl>(ctx)) {}
bool CsmPass::raster_available(CsmTest test) const {
  return compute_available(test) ? impl_->ctx.features().geometry_shader : impl_->supported(test, nullptr);
}
const std::vector<bool>& CsmPass::chosen_draws() const { return impl_->in_csm; }
CsmPass::~CsmPass() = default;
void CsmPass::prepare(VkCommandBuffer cmd, uint32_t resolution) { impl_->ensure_depth(cmd, resolution); }
VkImageView CsmPass::depth_view() const { return impl_->depth.view(); }
bool CsmPass::supported(CsmTest test, std::string* why) const { return impl_->supported(test, why); }

bool CsmPass::plan(const Frame& frame, const IzbSettings& settings, uint32_t resolution) {
  Impl& m = *impl_;
  m.ran = false;
  if (!settings.csm) {
    m.status = "off";
    m.decisions.clear();
    return false;
  }
  if (m.plan_frame != frame.view.frame_index) {
    m.plan_frame = frame.view.frame_index;
    m.record_in_frame = 0;
  } else {
    ++m.record_in_frame;
  }
  m.plan_slot = frame.slot;
  m.choose(frame, resolution);
  m.record_measures(frame);
  bool any = false, explicit_on = false;
  for (const auto& d : m.decisions) {
    any = any || d.in_csm;
    explicit_on = explicit_on || (d.in_csm && !d.automatic);
  }
  m.automatic_only = !explicit_on;
  if (!any) {
    m.status = "skipped: no caster chosen for the CSM";
    m.note_run(false);
    return false;
  }
  if (m.adaptive.size() <= m.record_in_frame) m.adaptive.resize(m.record_in_frame + 1);
  Impl::Adaptive& a = m.adaptive[m.record_in_frame];
  const bool changed = m.in_csm != a.last_choice || frame.view.light_direction != a.last_light ||
                       resolution != a.last_resolution;
  a.last_choice = m.in_csm;
  a.last_light = frame.view.light_direction;
  a.last_resolution = resolution;
  if (changed) {
    a.have_yield = false;
    ++a.generation;
  }
  if (!explicit_on && a.have_yield && a.last_yield < kCsmMinimumYield && ++a.frames_since_probe < kCsmReprobeFrames) {
    std::ostringstream why;
    why.precision(3);
    why << "skipped: auto choice culled " << a.last_yield * 100.0 << "% of points when last run (< "
        << kCsmMinimumYield * 100.0 << "%)";
    m.status = why.str();
    m.note_run(false);
    return false;
  }
  a.frames_since_probe = 0;
  m.status = "ran";
  m.ran = true;
  m.note_run(true);
  return true;
}

bool CsmPass::automatic_only() const { return impl_->automatic_only; }

void CsmPass::skip(const std::string& why) {
  Impl& m = *impl_;
  m.ran = false;
  m.note_run(false);
  m.status = why;
}

void CsmPass::note_yield(uint32_t slot, uint32_t record, double culling_rate) {
  Impl& m = *impl_;
  if (slot >= m.slot_runs.size() || record >= m.slot_runs[slot].size() || record >= m.adaptive.size()) return;
  const Impl::SlotRun run = m.slot_runs[slot][record];
  Impl::Adaptive& a = m.adaptive[record];
  if (!run.ran || run.generation != a.generation) return;
  a.last_yield = culling_rate;
  a.have_yield = true;
}

void CsmPass::record(Frame& frame, const IzbSettings& settings, const Buffer& izb_frame,
                     uint32_t resolution, bool collect_stats, const std::function<void(VkCommandBuffer)>& compute_fill,
                     const Buffer* compute_texels) {
  Impl& m = *impl_;
  std::string why;
  if (!m.supported(settings.csm_test, &why))
    throw std::runtime_error("CSM test " + csm_test_name(settings.csm_test) + " is unavailable: " + why);
  if (m.depth.extent().width != resolution) throw std::logic_error("CsmPass::prepare was not called");
  VkCommandBuffer cmd = frame.cmd;
  if (compute_fill) {
    ScopedGpuRegion region(m.ctx, frame.profiler, cmd, "csm");
    compute_fill(cmd);
  } else {
    const Pipeline& p = m.pipeline(settings.csm_test);
    ScopedGpuRegion region(m.ctx, frame.profiler, cmd, "csm");
    begin_depth_rendering(cmd, m.depth.view(), {resolution, resolution}, true);
    p.bind(cmd);
    DescriptorWriter()
        .storage_buffer(gpu_shared::CSM_BINDING_FRAME, izb_frame.handle())
        .storage_buffer(gpu_shared::CSM_BINDING_COUNTERS, m.counters.handle())
        .push(m.ctx, cmd, p);
    VkDeviceSize offset = 0;
    VkBuffer vb = frame.geometry.vertices().handle();
    vkCmdBindVertexBuffers(cmd, 0, 1, &vb, &offset);
    vkCmdBindIndexBuffer(cmd, frame.geometry.indices().handle(), 0, VK_INDEX_TYPE_UINT32);
    for (size_t i = 0; i < frame.draws.size(); ++i) {
      if (!m.in_csm[i]) continue;
      const auto& d = frame.draws[i];
      const auto& range = frame.geometry.mesh(d.mesh);
      if (range.index_count == 0) continue;
      gpu_shared::IzbDrawPush push{d.world, range.first_index, range.vertex_offset, 0u, 0u};
      p.push_constants(cmd, push);
      vkCmdDrawIndexed(cmd, range.index_count, 1, range.first_index, range.vertex_offset, 0);
    }
    vkCmdEndRendering(cmd);
  }
  if (!collect_stats) return;
  // Statistics only: the covered-texel count (from the map, which the compute pass fills by a copy).
  ScopedGpuRegion region(m.ctx, frame.profiler, cmd, "csm_coverage");
  if (compute_fill) {
    // The compute CSM's depths (written by compute shaders) into the map for the coverage count.
    memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                   VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    VkBufferImageCopy copy{};
    copy.imageSubresource = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 0, 1};
    copy.imageExtent = {resolution, resolution, 1};
    vkCmdCopyBufferToImage(cmd, compute_texels->handle(), m.depth.handle(), VK_IMAGE_LAYOUT_GENERAL, 1, &copy);
  }
  vkCmdFillBuffer(cmd, m.counters.handle(), 0, VK_WHOLE_SIZE, 0);
  pass_barrier(frame.ctx, cmd);
  m.coverage.bind(cmd);
  DescriptorWriter()
      .storage_buffer(gpu_shared::CSM_BINDING_FRAME, izb_frame.handle())
      .storage_buffer(gpu_shared::CSM_BINDING_COUNTERS, m.counters.handle())
      .sampled_image(gpu_shared::CSM_BINDING_DEPTH, m.depth.view(), m.nearest.handle(), VK_IMAGE_LAYOUT_GENERAL)
      .push(m.ctx, cmd, m.coverage);
  vkCmdDispatch(cmd, (resolution + 7) / 8, (resolution + 7) / 8, 1);
  m.readback.record_copy(frame, m.counters, m.counters.size(), VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                         VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, "csm readback");
}

void CsmPass::frame_completed(uint32_t slot) { impl_->take_measures(slot); }

void CsmPass::after_frame(Stats& stats, uint32_t slot) {
  Impl& m = *impl_;
  stats.csm_decisions = m.decisions;
  stats.csm_status = m.status;
  stats.csm_texels_covered = 0;
  if (const Buffer* readback = m.readback.take(slot))
    stats.csm_texels_covered = readback->as<uint32_t>()[gpu_shared::CSM_COUNTER_TEXELS];
}

}  // namespace shadows::detail

namespace shadows::detail {
std::vector<float> CsmPass::read_depth() { return engine::gpu::read_image_as<float>(impl_->ctx, impl_->depth); }
}  // namespace shadows::detail
