#pragma once
// The shadow module's settings and statistics: plain data, shared by the Vulkan host API
// (shadows/context.hpp) and every client. Only the standard library appears here.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "shadows/version.hpp"

namespace shadows {

enum class Technique {
  Off,        // everything lit
  ShadowMap,  // one plain shadow map fitted to the scene, one tap: the aliasing baseline ("sm")
  Cascades,   // cascaded filtered shadow maps ("cascades")
  Izb,        // frustum-traced irregular z-buffer hard shadows ("izb"; with IzbSettings::csm: "izb+csm")
  Hybrid,     // the IZB's exact hard shadow softened into penumbrae sized by the light ("hybrid"; see Settings)
  RayTraced,  // one hardware shadow ray per shading point or μQuad sample ("rt"; needs ray tracing)
};

// Full-coverage test of the conservative shadow map pass.
enum class CsmTest {
  Hertel,         // texel centre's distance to every edge >= circumscribed radius (geometry shader)
  Barycentric,    // barycentrics at the texel's four corners all positive (geometry shader)
  BarycentricHw,  // the same with VK_KHR_fragment_shader_barycentric
  InnerHw,        // conservative rasterization underestimation (fully covered fragments only)
};

// Where the cascades' filter (12 taps, or PCSS's) is skipped for one tap. Edge: no depth step near
// the kernel's footprint in the map (an edge mask per texel at the kernel's level, then its 2x2
// neighbourhoods); DepthExtent: also where the receiver's depth clears the footprint's depth range.
// Planes: each 8x8 block of the map kept as its least-squares plane and largest distance from it; a
// pixel is skipped where its tangent plane clears every block its taps reach, so every tap has the
// one tap's result: the unmasked term bit for bit, where Edge may differ from it by a few taps on a
// few pixels. With a sun of some size the tests cover the PCSS blocker search's footprint (which
// holds every PCSS tap), so a pixel with a wide penumbra is never skipped wrongly; wide searches just
// skip less.
// Auto: Edge where the cascades filter the whole frame; Off in the hybrid, where they filter only the
// pixels the IZB leaves them, and building masks over the whole view costs more than the taps they
// would skip (measured on lavapipe and the H200). (Planes settles more pixels than Edge but its test
// costs a CPU device's filter more than the taps it spares: BENCHMARKS, "Shadow maps and cascades".)
enum class Masking { Off, Edge, DepthExtent, Auto, Planes };

enum class DebugView { None, VisibilityMask, ListLength, Cascades, CsmCoverage, ExpensivePath };

// Which rasterizer produces the raster trace's conservative fragments.
enum class ConservativeRaster { Auto, Hardware, Software };

// How a pass that exists both as raster and as compute work runs. Both give identical results; Auto
// times each on the first frames (again after a size, scene or mode change) and keeps the faster.
enum class PassBackend { Auto, Raster, Compute };

// How the IZB's per-texel lists are built: linked lists (a node prepended per insertion) or a
// counting sort (count per texel, prefix sum, scatter into contiguous ranges).
enum class ListLayout { Linked, Sorted };

// Known-lit culling (IzbSettings::lit_culling): off, on, or chosen by timing both (Auto).
enum class LitCulling { Off, On, Auto };

// The shape of the compute trace's, CSM's and lit map's first step (IzbSettings::step_one_shape):
// Wide (64 caster triangles per workgroup, up to 16 texels each worked there), Narrow (16, up to 48),
// or Auto: a GPU times both and keeps the faster (Stats::tile_work_choice), a CPU device takes its
// own (64, up to 256). The answer is the same in every shape.
enum class StepOneShape { Auto, Wide, Narrow };

// sm: one tap, or for a light with a size (Light::angular_diameter_degrees, radius) PCSS wherever its
// penumbra is at least half a texel wide (blocker search and filter within kPcssMaxTexels, 32 texels,
// shared/shadows.h).
struct ShadowMapSettings {
  uint32_t size = 1024;
  float constant_bias = 1.0e-4f;  // in light depth units ([0,1] over the fitted depth range)
  float slope_bias = 1.0f;        // rasterizer slope-scaled bias
  // A sun with a size (PCSS): skip the blocker search and the filter where the map's 8x8-texel blocks
  // show every tap of a pixel would agree (its surface lies on a plane the blocks fit and nothing
  // nearer the light lies within its search radius, or it lies wholly behind the map's surface
  // there). The same term bit for bit; false runs every pixel's taps (Stats::expensive_path_fraction:
  // the share of the pixels that ran them). Spot and point lights' maps are not masked (their search
  // spans more blocks than a pixel reads).
  bool masking = true;
  // A point light's six face maps (on a CPU device, a spot light's map too; the cascades' filtered
  // maps of local lights alike): one pass lists the 8x8 pixel tiles each face's cone reaches, and each
  // face resolves its tiles alone instead of the whole frame. The same term bit for bit; false resolves
  // every face over the whole frame.
  bool local_light_tiles = true;
};

struct CascadeSettings {
  uint32_t count = 4;                 // 1..4
  uint32_t map_size = 1024;           // per cascade, square
  float lambda = 0.75f;               // split blend: 0 uniform, 1 logarithmic
  float max_distance = 60.0f;         // world units from the camera; the last cascade fades out here
  float blend_band = 0.1f;            // fraction of a cascade's depth range blended into the next
  float constant_bias = 0.5f;         // in texels of depth (scaled with each cascade's texel size)
  float slope_bias = 1.5f;            // rasterizer slope-scaled bias
  float normal_offset = 1.0f;         // in texels, along the geometric normal
  bool cull_front_faces = false;      // render back faces into the maps (closed meshes only)
  // PCF disk radius in world units (same across cascades). For a sun with a size
  // (Light::angular_diameter_degrees) the narrowest filter: pixels whose PCSS penumbra is wider take
  // PCSS's radius instead (continuous across cascades), the rest keep this kernel.
  float kernel_radius = 0.08f;
  Masking masking = Masking::Auto;    // where the filter (12 taps, or PCSS's) may be skipped
  bool blur = true;                   // 5x5 blur on pixels whose taps disagreed
};

struct IzbSettings {
  // Light-space grid, square, texels a side; each of a point light's six faces takes three quarters
  // of it (rounded up to whole 16-texel tiles): a face holds about a sixth of the light's points.
  uint32_t resolution = 1024;
  uint32_t samples_per_pixel = 1;     // 1 (ray per pixel) or 32 (frustum per pixel footprint)
  float max_distance = 0.0f;          // 0: every visible point; else only points nearer the camera
  bool csm = false;                   // conservative shadow map z-prepass culls certainly shadowed points
  // Known-lit culling, the CSM's dual (the sun's IZB; a local light's runs without): a compute pass
  // keeps per grid texel the nearest light depth of every caster touching it (alpha-tested ones
  // included) and per texel corner the nearest of their planes there (a caster covering a whole
  // tile of 16x16 texels: the same per tile and tile corner); a point no farther from the light than
  // its texel's bound or the blend of its corners' planes, and likewise for its tile (at 32 spp:
  // every sample, each in its own texel) is lit for certain and enters no list. Exact: the answer is
  // the same with it off. It proves most open ground lit (a floor's own plane passes through its
  // points), but the map visits every texel the casters touch short of whole tiles: it pays where
  // much of the view is lit ground under few casters and costs where many casters overlap
  // (tests/bench/BENCHMARKS.md, "Known-lit culling"). Auto (the default) times the IZB's passes with
  // it off and on (two to four frames each, until each way's last two frames agree), once the trace's
  // and the CSM's own choices are made, and keeps the faster per configuration (Stats::lit_choice).
  LitCulling lit_culling = LitCulling::Auto;
  // With csm: where every caster in the CSM was chosen automatically (CsmChoice::Auto), also time the
  // IZB's passes with the prepass and without it (two to four frames each, once the trace's and the CSM's
  // backends are chosen, before the lit culling's probe) and skip it where it costs more than the
  // trace work it saves, per configuration (Stats::csm_run_choice). Exact either way. A caster put
  // in the CSM by CsmChoice::On keeps it running.
  bool csm_timed = false;
  // Times each step of the light frustum ("light_frustum_fit", which also fits the grid and culls
  // the caster draws, on a CPU device in a step of its own, "light_frustum_cull";
  // "light_frustum_triangles", absent where the compute trace's first step sets up a scene's few
  // caster triangles itself) and of the compute trace, CSM and lit map
  // ("<work>_records", "_tiles", "_texels", "trace_pairs"), and the build's pass over every pixel
  // ("build_classify"; on a CPU device its node insertion too, "build_insert"), inside their pass's
  // region. Each region's timestamps wait for the work before them, a few µs per step on a GPU, so it
  // is off where the frame's time matters.
  bool step_timings = false;
  StepOneShape step_one_shape = StepOneShape::Auto;
  CsmTest csm_test = CsmTest::Barycentric;
  ConservativeRaster raster = ConservativeRaster::Auto;  // for the raster trace
  PassBackend trace = PassBackend::Auto;     // frustum trace: conservative raster or compute binning
  PassBackend csm_backend = PassBackend::Auto;  // CSM (hertel/bary only; the hardware tests are raster)
  ListLayout lists = ListLayout::Linked;
  bool depth_cull = true;             // cull trace fragments behind the farthest node of their texel
  // 32 spp with the compute trace: a pixel's node goes only into the lowest texel of each 2x2 block of
  // texels its samples lie in (one node for most pixels, not one per texel), and the trace pairs a
  // caster with a texel where it touches that texel's 2x2 block. Exact either way (every node test
  // covers all of a pixel's samples); shorter lists for a few more pairs (Sponza v1 4K on an H200:
  // the trace's pair walks 0.27 -> 0.21 ms, the whole IZB 1.25 -> 1.16, tests/bench/BENCHMARKS.md).
  // Ignored at 1 spp and by the raster trace.
  bool anchored_nodes = true;
  // Skip nodes whose pixel is already fully shadowed. At 32 spp also when false, except where the
  // hybrid keeps occluder heights for its penumbrae (with a light size): true there leaves a pixel the
  // nearest occluder among those tested before it was covered, which depends on the trace's order.
  bool progressive_removal = false;
  float node_pool_factor = 1.25f;     // pool size = factor * pixels * (1 or expected texels per μQuad)
  uint32_t node_pool_override = 0;    // nonzero: fixed pool size in nodes (tests of overflow)
  // Validation path: no lists at all; every candidate is tested against every caster triangle by the
  // same exact test (the overflow fallback). Slow; for checking the trace.
  bool brute_force = false;
};

struct Settings {
  Technique technique = Technique::Hybrid;
  ShadowMapSettings shadow_map;
  CascadeSettings cascades;
  IzbSettings izb;
  DebugView debug = DebugView::None;
  // Hybrid: hard at contact, soft away from it, as the light's size makes them (the sun's
  // Light::angular_diameter_degrees). The IZB's exact term, then around its shadow edges a penumbra as
  // wide as the sun's disc seen past the occluder: each pixel near an edge averages the occluder
  // heights the IZB found for the shadowed pixels whose penumbra reaches it, and filters the exact
  // term over a disc of that radius across the light, on its own surface, in world units (so the
  // width depends neither on the world's units nor on the distance from the camera). Where the
  // penumbra is narrower than a pixel the term is the IZB's, exact; a sun of size 0 gives the IZB's
  // term everywhere. Penumbrae wider than gpu_shared::kPenumbraMaxRadius (48) pixels in radius are
  // filtered at that radius (a 4K screen's under the real sun pass 24 on Sponza). A spot or
  // point light takes the IZB's hard term.
  // hybrid_izb_distance: 0, the IZB covers every visible point; > 0, only points up to that distance
  // from the camera, fading over its last tenth into the cascades (which cover the rest up to
  // cascades.max_distance, filtered by the light's size too), for views whose far points are many and
  // far (a large outdoor world).
  float hybrid_izb_distance = 0.0f;
  // rt: shadow rays per pixel over the light (Light::angular_diameter_degrees, radius): 0 traces one
  // ray toward the light's centre, the hard shadow whatever its size; 1..64 that many rays spread
  // evenly over the sun's disc or the sphere's disc as the point sees it, turned per pixel, the term
  // their lit fraction (no denoiser: few rays are noisy). Ignored at 32 spp (IzbSettings) and for a
  // light of size 0.
  uint32_t rt_light_samples = 0;
  // How many of the host's world units make a metre (1: metres, 100: centimetres, 0.01: hectometres).
  // The distances above stated in world units are taken in metres and scaled by it: cascades.max_distance
  // and kernel_radius, izb.max_distance and hybrid_izb_distance (each finite and >= 0: record refuses
  // another in one line naming it). Nothing else in
  // the module depends on the world's units or on how far the scene is from the world's origin (see
  // FrameDesc::origin). Finite and > 0.
  float units_per_metre = 1.0f;
};

// `settings` with its distances in metres (Settings::units_per_metre) turned into world units.
Settings in_world_units(const Settings& settings);

// Why the automatic CSM choice took or left an entity.
struct CsmDecision {
  uint64_t instance_id = 0;  // Instance::id of the host (the engine adapter: entity index << 32 | generation)
  std::string name;
  bool in_csm = false;
  bool automatic = false;
  double large_triangle_area_share = 0.0;  // share of light-space area in triangles >= kLargeTexels
  std::string reason;
};

struct Stats {
  // IZB
  uint64_t shading_points = 0;        // covered pixels
  uint64_t lit_candidates = 0;        // covered, receiving, facing the light, inside the IZB range
  uint64_t nodes_inserted = 0;        // for the candidates neither culling settled
  uint64_t csm_culled = 0;            // candidates the CSM proved shadowed
  double culling_rate = 0.0;          // csm_culled / lit_candidates
  uint64_t lit_culled = 0;            // candidates the lit map proved lit (IzbSettings::lit_culling)
  uint64_t csm_texels_covered = 0;
  uint64_t node_pool_size = 0;
  uint64_t node_overflow = 0;         // insertions that found the pool full
  uint64_t overflow_pixels = 0;       // pixels resolved by the exact fallback because of that
  uint64_t list_length_max = 0;
  double list_length_average = 0.0;   // over non-empty texels
  uint64_t nonempty_texels = 0;
  uint64_t trace_fragments_before_cull = 0;
  uint64_t trace_fragments_after_cull = 0;
  uint64_t triangle_tests = 0;        // ray/frustum-triangle tests
  double triangle_tests_per_pixel = 0.0;
  bool hardware_conservative = false;
  // Raster or compute, per pass: what ran, why ("forced", "only one available", "probing",
  // "auto: ..."), and the probe's GPU times in ms (0 where not measured).
  struct BackendChoice {
    std::string backend;
    std::string reason;
    double raster_ms = 0.0;
    double compute_ms = 0.0;
  };
  BackendChoice trace_choice;
  BackendChoice csm_choice;
  BackendChoice lit_choice;  // known-lit culling: backend "off" or "on", and why
  BackendChoice csm_run_choice;  // IzbSettings::csm_timed: backend "run" or "skip", and why
  // On a GPU, the shape of the compute trace's and CSM's first step, timed: "wide" (many triangles per
  // workgroup, only the smallest worked texel by texel there) or "narrow" (fewer, and more of them).
  BackendChoice tile_work_choice;
  // IZB casters: every caster triangle, and those its passes walked this frame (in a caster whose
  // world bounds reach the light frustum fitted to the view's points, and reaching it themselves).
  uint64_t caster_triangles = 0;
  uint64_t caster_triangles_listed = 0;
  // Compute trace work: tile-row records, (triangle, tile) pairs kept, (triangle, texel) pairs kept.
  uint64_t trace_records = 0;
  uint64_t trace_tile_pairs = 0;
  uint64_t trace_pairs = 0;
  // Ray traced: rays (candidates x samples), those that hit a caster, top-level instances, and the
  // triangles in the bottom levels (each mesh once, however many instances use it).
  uint64_t rays_traced = 0;
  uint64_t rays_occluded = 0;
  uint64_t rt_instances = 0;
  uint64_t rt_triangles = 0;
  // GPU memory the technique holds, by resource (debug name -> bytes), and its sum. Resources shared
  // with the renderer (G-buffer, scene geometry) are not counted.
  std::map<std::string, uint64_t> memory_bytes;
  uint64_t memory_total_bytes = 0;
  // Cascades, and `sm` with a light size (its resolve's pixels whose PCSS taps ran, of those it
  // resolved with the light's size; ShadowMapSettings::masking)
  double expensive_path_fraction = 0.0;
  uint64_t expensive_path_pixels = 0;
  uint64_t blurred_pixels = 0;
  std::vector<float> cascade_splits;
  // Of those cascades, how many were drawn: the hybrid with a limited range draws none that ends
  // before the nearest pixel it hands the cascades (hybrid_izb_distance).
  uint32_t cascades_drawn = 0;
  // CSM caster choice, and whether the prepass ran this frame ("ran", "off", or "skipped: why")
  std::vector<CsmDecision> csm_decisions;
  std::string csm_status = "off";
  // One entry per light of the frame, in FrameDesc::lights order (the fields above describe the last
  // IZB or ray-traced pass of the frame). A point light's IZB figures sum its six faces, each of which
  // takes only its own points (a point counts once).
  struct LightStats {
    std::string kind;                // "directional", "spot" or "point"
    uint64_t lit_candidates = 0;     // IZB or rt: points the light reaches and that face it
    uint64_t nodes_inserted = 0;     // IZB
    uint64_t csm_culled = 0;         // IZB with the CSM prepass
    uint64_t node_overflow = 0;      // IZB
    uint64_t list_length_max = 0;    // IZB
    uint64_t rays_traced = 0;        // rt
    uint64_t rays_occluded = 0;      // rt
    double gpu_ms = 0.0;             // the light's passes: its "light i" region, or "shadows" for one light
    // A point light under sm, cascades, izb or hybrid: how many of its six cube-face cones were
    // recorded (a cone in which no point of the view can lie within the light's range is skipped;
    // with none left, one still runs to write the term of the points out of the light's reach).
    // 0 for other lights and techniques.
    uint32_t faces_recorded = 0;
    // False for a spot or point light whose cone (a point light's ball) within its range meets no
    // point of the camera's frustum: no technique pass ran for it; its term is 0 on every covered
    // pixel and 1 on the background, what the passes would have written (one pass over the frame).
    bool reaches_view = true;
    // IZB: the trace's and the CSM prepass's backends for this light (a spot or point light's
    // perspective grid always takes the compute passes, and says so); empty for other techniques.
    BackendChoice trace_choice;
    BackendChoice csm_choice;
  };
  std::vector<LightStats> lights;
};

// Parsing/printing helpers for command lines and JSON ("sm", "cascades", "izb", "izb+csm", "hybrid",
// "hybrid+csm", "rt").
SHADOWS_API std::optional<Settings> parse_mode(const std::string& mode, Settings base);
SHADOWS_API std::string mode_name(const Settings& settings);
SHADOWS_API std::optional<CsmTest> parse_csm_test(const std::string& name);
SHADOWS_API std::string csm_test_name(CsmTest test);
SHADOWS_API std::optional<Masking> parse_masking(const std::string& name);
SHADOWS_API std::string masking_name(Masking masking);
SHADOWS_API std::optional<DebugView> parse_debug_view(const std::string& name);
SHADOWS_API std::optional<PassBackend> parse_backend(const std::string& name);  // "auto", "raster", "compute"
SHADOWS_API std::string backend_name(PassBackend backend);
SHADOWS_API std::optional<ListLayout> parse_list_layout(const std::string& name);  // "linked", "sorted"
SHADOWS_API std::string list_layout_name(ListLayout layout);
SHADOWS_API std::optional<LitCulling> parse_lit_culling(const std::string& name);  // "off", "on", "auto"
SHADOWS_API std::string lit_culling_name(LitCulling mode);

}  // namespace shadows
