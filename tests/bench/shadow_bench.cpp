// shadow_bench: renders a scene view with each requested shadow mode, measures every GPU pass with
// timestamp queries (medians over frames after warm-up), optionally compares the visibility with the
// Embree reference, and writes one JSON object per run.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "engine/assets/scene.hpp"
#include "engine/core/animation.hpp"
#include "engine/core/skinning.hpp"
#include "engine/core/command_line.hpp"
#include "engine/render/renderer.hpp"
#include "frame_capture.hpp"
#include "shadows_engine/shadows_engine.hpp"

namespace {

using nlohmann::json;

struct Options {
  std::string scene = "contact";
  size_t view = 0;
  std::string light = "sun";  // sun, spot or point: the scene's first light of that kind
  uint32_t width = 512, height = 512;
  uint32_t izb = 1024;
  uint32_t cascade_size = 0;  // 0: the module's default
  std::vector<std::string> modes = {"sm"};
  uint32_t spp = 1;
  std::vector<std::string> csm_tests = {"bary"};
  std::string masking;  // empty: the default
  std::string csm_choice;  // empty: per entity; "on", "off", "auto" to force all
  engine::Detail detail = engine::Detail::Full;  // of scene files' generated content
  int frames = 10;
  int warmup = 3;
  bool reference = false;
  double max_mismatch = -1.0;      // --max-mismatch: a run over it fails the benchmark (negative: no bound)
  double max_coverage_mae = -1.0;  // --max-coverage-mae, likewise
  bool faceted_terminator = false;  // the smooth-terminator offset off, to show what it removes
  std::string device;
  std::string json_path;
  std::string diff_dir;
  std::string screenshot_dir;
  std::string dump_dir;  // raw float32 visibility per run, for comparing runs offline
  uint32_t node_pool = 0;
  std::string raster;  // auto|hardware|software
  std::vector<std::string> traces = {"auto"};        // frustum trace backends to run
  std::vector<std::string> csm_backends = {"auto"};  // CSM backends to run
  std::string lists;  // empty: the default list layout
  std::string anchored_nodes;  // on|off; empty: the default (IzbSettings::anchored_nodes)
  std::vector<std::string> lit_culling;  // on/off per run, in order (repeats alternate); empty: the default
  bool csm_timed = false;   // IzbSettings::csm_timed
  bool step_times = false;  // IzbSettings::step_timings
  std::vector<uint32_t> instances = {1};  // copies of the scene on a grid (a list in the suite)
  std::string suite;   // "paper": the paper's tables, every technique, every view, two sizes
  bool quick = false;  // suite at small sizes (lavapipe, the tests)
  std::string out_dir; // suite: where suite.json and suite.md go
  std::vector<uint32_t> spps = {1};  // suite: samples per pixel to run
  std::vector<size_t> views;         // suite: views to run (empty: every view)
  bool large_world = false;          // --large-world: the offset goes into Scene::origin
  bool sun = false;                  // --sun: a glTF lit by its own lights gets the default sun too
  double scale = 1.0;                // --scale: the scene scaled about the origin (engine::transform_scene)
  glm::dvec3 offset{0.0};            // --offset: then moved by this (world units)
  std::optional<double> time;        // --time: the scene's animations posed at this time (seconds)
  bool rigid = false;                // --rigid: skinned and morphing meshes drawn rigid in their rest pose
  std::optional<double> light_size;  // --light-size: the sun's angular diameter, degrees
  std::optional<double> light_radius;  // --light-radius: every spot and point light's radius, world units
  double hybrid_izb_distance = 0.0;   // --hybrid-izb-distance: Settings::hybrid_izb_distance, metres
  uint32_t rt_rays = 0;              // --rt-rays: Settings::rt_light_samples
  uint32_t reference_rays = 256;     // --reference-rays: the area-light reference's rays a pixel
};

const char* kUsage =
    "usage: shadow_bench [--scene NAME|FILE.gltf] [--view N] [--size WxH] [--izb N] [--cascade-size N] [--mode LIST]\n"
    "                    [--spp 1|32] [--csm-test LIST] [--masking off|edge|depth-extent|planes|auto]\n"
    "                    [--csm-choice on|off|auto] [--raster auto|hardware|software] [--node-pool N]\n"
    "                    [--trace LIST] [--csm-backend LIST] [--lists linked|sorted] [--lit-culling LIST]\n"
    "                    [--anchored-nodes on|off] [--csm-timed] [--step-times] [--frames N] [--warmup N] [--reference] [--faceted-terminator] [--device gpu|lavapipe|INDEX]\n"
    "                    [--max-mismatch R] [--max-coverage-mae E]\n"
    "                    [--json FILE] [--diff DIR] [--screenshot DIR] [--dump DIR] [--instances N] [--detail full|low]\n"
    "                    [--light sun|spot|point] [--scale S] [--offset X,Y,Z] [--large-world] [--sun]\n"
    "                    [--time SECONDS] [--rigid] [--light-size DEGREES] [--light-radius R] [--rt-rays N]\n"
    "                    [--reference-rays N] [--hybrid-izb-distance M]\n"
    "       shadow_bench --suite paper [--quick] [--out DIR] [--scene LIST] [--views LIST] [--instances LIST]\n"
    "                    [--spp LIST] [--sizes WxH:IZB,...] [--frames N] [--warmup N] [--device ...]\n"
    "  LIST is comma-separated; modes: off, sm, cascades, izb, izb+csm, hybrid, hybrid+csm, rt;\n"
    "  csm tests: hertel, bary, bary-hw, inner-hw; trace and CSM backends: auto, raster, compute\n"
    "  (auto times both on the first frames and keeps the faster; its probe frames come before the warm-up);\n"
    "  lit culling: on, off, auto (timed both ways, the faster kept; repeat to alternate: on,off,on,off).\n"
    "  --csm-timed: an automatic CSM runs only where the IZB measures faster with it (IzbSettings::csm_timed).\n"
    "  --anchored-nodes: 32 spp, compute trace: a node per 2x2 block of texels (IzbSettings::anchored_nodes).\n"
    "  --step-times: each step of the light frustum, compute trace, CSM, lit map and build timed apart (their\n"
    "  timestamps cost waits; IzbSettings::step_timings).\n"
    "  --scale S --offset X,Y,Z: the scene (procedural, glTF or level) scaled about the origin, then moved, with\n"
    "  its views, light ranges and camera planes (100: a centimetre world; 1e4,0,1e4: far from the origin).\n"
    "  --large-world: the offset goes into engine::Scene::origin (double) and the entities stay near 0, as a\n"
    "  host of a world far from its origin keeps them; the renderer and the module then work relative to it.\n"
    "  --reference and --dump cover every light the frame shadows (the sun while it shines, and up to three\n"
    "  spot and point lights), one JSON reference entry per light; --light spot|point shadows that light alone.\n"
    "  --sun: a glTF lit by its own spot and point lights and no directional light is lit by them alone\n"
    "  unless --sun brings the default sun.\n"
    "  --time SECONDS: the scene's animations (procedural ones, glTF clips, skinned and morphing meshes)\n"
    "  posed at that time, so an animated frame is reproducible; without it the scene stays as loaded.\n"
    "  --rigid: skinned and morphing meshes become rigid meshes in their rest pose (nothing is deformed):\n"
    "  the static frame an animated one is compared with.\n"
    "  --light-size DEGREES: the sun's angular diameter (default: the scene's, 0.53 unless it says; 0 hard,\n"
    "  at most 10); --light-radius R: every spot and point light's radius (world units, after --scale).\n"
    "  --rt-rays N: rt traces N rays per pixel over the light (Settings::rt_light_samples, 0..64; 0: the\n"
    "  light's centre alone, hard). With a light size, --reference also reports soft_mae (mean |term -\n"
    "  reference| over covered pixels) and penumbra_mae (the same where the reference is within 0.02..0.98)\n"
    "  against an area-light reference of --reference-rays N stratified rays a pixel (default 256; figures\n"
    "  worth quoting use 256 or more), computed once per view and size; the hard metrics stay against the\n"
    "  hard reference. The sun's default size (0.53) counts: --light-size 0 skips the area reference.\n"
    "  --hybrid-izb-distance M: the hybrid's IZB covers the points within M metres of the camera and the\n"
    "  cascades the rest, as the walkthrough on a CPU device (Settings::hybrid_izb_distance; 0, the\n"
    "  default: every point).\n"
    "  --instances N places N copies of the scene on a grid (shared meshes). The paper suite runs the IIEEJ\n"
    "  paper's Table 2 (izb vs izb+csm per pass) and Table 3 (CSM time and culling per coverage test) for\n"
    "  every view at 1920x1080/IZB 1024 and 3840x2160/IZB 2048 (--quick: 160x90/128 and 320x180/256),\n"
    "  with sm, cascades, hybrid+csm and rt in the same run; writes DIR/suite.json and DIR/suite.md.\n";

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) if (!item.empty()) out.push_back(item);
  return out;
}

std::vector<uint32_t> split_uints(const std::string& flag, const std::string& s) {
  std::vector<uint32_t> out;
  for (const auto& item : split(s)) {
    char* end = nullptr;
    const unsigned long v = std::strtoul(item.c_str(), &end, 10);
    if (!end || *end || item[0] == '-' || v > 0xffffffffUL)
      throw std::runtime_error(flag + " '" + s + "': expected a comma-separated list of counts");
    out.push_back(uint32_t(v));
  }
  if (out.empty()) throw std::runtime_error(flag + " needs a value");
  return out;
}

// A finite number, or a one-line error naming the option.
double parse_number(const std::string& flag, const std::string& v) {
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (v.empty() || !end || *end || !std::isfinite(x)) throw std::runtime_error(flag + " '" + v + "': expected a finite number");
  return x;
}

struct SizeConfig {
  uint32_t width, height, izb;
  std::string label;
};
std::vector<SizeConfig> g_suite_sizes;  // --sizes override for the suite

Options parse(int argc, char** argv) {
  Options o;
  engine::CommandLine args(argc, argv);
  while (args.next()) {
    const std::string& a = args.flag();
    if (a == "--scene") o.scene = args.value();
    else if (a == "--view") o.view = args.uint_value();
    else if (a == "--size") args.size_value(o.width, o.height);
    else if (a == "--izb") o.izb = args.uint_value();
    else if (a == "--cascade-size") o.cascade_size = args.uint_value();
    else if (a == "--mode") o.modes = split(args.value());
    else if (a == "--spp") {
      o.spps = split_uints("--spp", args.value());
      o.spp = o.spps.front();
    }
    else if (a == "--instances") o.instances = split_uints("--instances", args.value());
    else if (a == "--detail") {
      const std::string v = args.value();
      if (v != "full" && v != "low") throw std::runtime_error("--detail '" + v + "': expected full or low");
      o.detail = v == "low" ? engine::Detail::Low : engine::Detail::Full;
    }
    else if (a == "--suite") o.suite = args.value();
    else if (a == "--quick") o.quick = true;
    else if (a == "--out") o.out_dir = args.value();
    else if (a == "--views") for (uint32_t v : split_uints("--views", args.value())) o.views.push_back(v);
    else if (a == "--sizes") {
      for (const auto& item : split(args.value())) {
        SizeConfig c{};
        if (std::sscanf(item.c_str(), "%ux%u:%u", &c.width, &c.height, &c.izb) != 3 || !c.width || !c.height || !c.izb)
          throw std::runtime_error("--sizes '" + item + "': expected WxH:IZB");
        c.label = std::to_string(c.width) + "x" + std::to_string(c.height);
        g_suite_sizes.push_back(c);
      }
    }
    else if (a == "--csm-test") o.csm_tests = split(args.value());
    else if (a == "--masking") o.masking = args.value();
    else if (a == "--csm-choice") o.csm_choice = args.value();
    else if (a == "--raster") o.raster = args.value();
    else if (a == "--trace") o.traces = split(args.value());
    else if (a == "--csm-backend") o.csm_backends = split(args.value());
    else if (a == "--lists") o.lists = args.value();
    else if (a == "--anchored-nodes") o.anchored_nodes = args.value();
    else if (a == "--node-pool") o.node_pool = args.uint_value();
    else if (a == "--lit-culling") o.lit_culling = split(args.value());
    else if (a == "--frames") o.frames = int(args.uint_value());
    else if (a == "--warmup") o.warmup = int(args.uint_value());
    else if (a == "--reference") o.reference = true;
    else if (a == "--csm-timed") o.csm_timed = true;
    else if (a == "--step-times") o.step_times = true;
    else if (a == "--max-mismatch" || a == "--max-coverage-mae") {
      const std::string v = args.value();
      char* end = nullptr;
      const double bound = std::strtod(v.c_str(), &end);
      if (v.empty() || !end || *end || !(bound >= 0.0))
        throw std::runtime_error(a + " '" + v + "': expected a non-negative number");
      (a == "--max-mismatch" ? o.max_mismatch : o.max_coverage_mae) = bound;
    }
    else if (a == "--sun") o.sun = true;
    else if (a == "--large-world") o.large_world = true;
    else if (a == "--scale") o.scale = parse_number(a, args.value());
    else if (a == "--time") o.time = parse_number(a, args.value());
    else if (a == "--rigid") o.rigid = true;
    else if (a == "--light-size") o.light_size = parse_number(a, args.value());
    else if (a == "--light-radius") o.light_radius = parse_number(a, args.value());
    else if (a == "--hybrid-izb-distance") o.hybrid_izb_distance = parse_number(a, args.value());
    else if (a == "--rt-rays") o.rt_rays = split_uints(a, args.value()).at(0);
    else if (a == "--reference-rays") o.reference_rays = split_uints(a, args.value()).at(0);
    else if (a == "--offset") {
      const std::string v = args.value();
      const auto items = split(v);
      if (items.size() != 3) throw std::runtime_error("--offset '" + v + "': expected X,Y,Z");
      for (int i = 0; i < 3; ++i) o.offset[i] = parse_number(a, items[size_t(i)]);
    }
    else if (a == "--faceted-terminator") o.faceted_terminator = true;
    else if (a == "--device") o.device = args.value();
    else if (a == "--json") o.json_path = args.value();
    else if (a == "--diff") o.diff_dir = args.value();
    else if (a == "--light") o.light = args.value();
    else if (a == "--screenshot") o.screenshot_dir = args.value();
    else if (a == "--dump") o.dump_dir = args.value();
    else if (a == "--help" || a == "-h") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else throw std::runtime_error("unknown option " + a + " (see --help)");
  }
  for (uint32_t spp : o.spps)
    if (spp != 1 && spp != 32) throw std::runtime_error("--spp must be 1 or 32");
  if (!(o.scale > 0.0)) throw std::runtime_error("--scale must be positive");
  if (o.reference_rays < 1) throw std::runtime_error("--reference-rays must be at least 1");
  if (o.frames < 1) throw std::runtime_error("--frames must be at least 1");
  if ((o.max_mismatch >= 0.0 || o.max_coverage_mae >= 0.0) && (!o.reference || !o.suite.empty()))
    throw std::runtime_error("--max-mismatch and --max-coverage-mae need --reference (and no --suite)");
  if (!o.suite.empty() && o.suite != "paper") throw std::runtime_error("--suite '" + o.suite + "': expected paper");
  if (o.suite.empty() && (o.instances.size() > 1 || o.spps.size() > 1))
    throw std::runtime_error("lists for --instances and --spp need --suite");
  for (uint32_t n : o.instances)
    if (n == 0) throw std::runtime_error("--instances must be at least 1");
  if (o.light != "sun" && o.light != "spot" && o.light != "point")
    throw std::runtime_error("--light '" + o.light + "': expected sun, spot or point");
  if (o.light != "sun" && !o.suite.empty()) throw std::runtime_error("--light spot|point is for single runs, not --suite");
  return o;
}

struct RunConfig {
  std::string mode;
  std::string csm_test;
  std::string trace = "none";
  std::string csm_backend = "none";
  shadows::Settings settings;
  bool csm_everything = false;  // every caster in the CSM for this run (the paper's Table 3)
};

shadows::PassBackend backend_option(const std::string& flag, const std::string& name) {
  auto b = shadows::parse_backend(name);
  if (!b) throw std::runtime_error(flag + " '" + name + "': expected auto, raster or compute");
  return *b;
}

std::vector<RunConfig> expand_runs(const Options& o) {
  std::vector<RunConfig> runs;
  for (const auto& mode : o.modes) {
    shadows::Settings base;
    base.izb.resolution = o.izb;
    if (o.cascade_size) base.cascades.map_size = o.cascade_size;
    base.izb.samples_per_pixel = o.spp;
    base.izb.node_pool_override = o.node_pool;
    base.izb.csm_timed = o.csm_timed;
    base.izb.step_timings = o.step_times;
    base.hybrid_izb_distance = float(o.hybrid_izb_distance);
    if (!o.lists.empty()) {
      auto layout = shadows::parse_list_layout(o.lists);
      if (!layout) throw std::runtime_error("--lists '" + o.lists + "': expected linked or sorted");
      base.izb.lists = *layout;
    }
    if (!o.anchored_nodes.empty()) {
      if (o.anchored_nodes != "on" && o.anchored_nodes != "off")
        throw std::runtime_error("--anchored-nodes '" + o.anchored_nodes + "': expected on or off");
      base.izb.anchored_nodes = o.anchored_nodes == "on";
    }
    if (!o.raster.empty()) {
      if (o.raster == "auto") base.izb.raster = shadows::ConservativeRaster::Auto;
      else if (o.raster == "hardware") base.izb.raster = shadows::ConservativeRaster::Hardware;
      else if (o.raster == "software") base.izb.raster = shadows::ConservativeRaster::Software;
      else throw std::runtime_error("--raster '" + o.raster + "': expected auto, hardware or software");
    }
    if (!o.masking.empty()) {
      auto m = shadows::parse_masking(o.masking);
      if (!m) throw std::runtime_error("--masking '" + o.masking + "': expected off, edge, depth-extent, planes or auto");
      base.cascades.masking = *m;
      base.shadow_map.masking = *m != shadows::Masking::Off;  // sm has one kind of masking: on or off
    }
    auto settings = shadows::parse_mode(mode, base);
    if (!settings) throw std::runtime_error("--mode '" + mode + "' is not a shadow mode (see --help)");
    const bool uses_izb =
        settings->technique == shadows::Technique::Izb || settings->technique == shadows::Technique::Hybrid;
    const bool uses_csm = settings->izb.csm && uses_izb;
    if (!uses_izb) {
      runs.push_back({mode, "none", "none", "none", *settings});
      continue;
    }
    for (const auto& trace : o.traces) {
      RunConfig traced{mode, "none", trace, "none", *settings};
      traced.settings.izb.trace = backend_option("--trace", trace);
      if (!uses_csm) {
        runs.push_back(traced);
        continue;
      }
      for (const auto& test_name : o.csm_tests) {
        auto test = shadows::parse_csm_test(test_name);
        if (!test) throw std::runtime_error("--csm-test '" + test_name + "': expected hertel, bary, bary-hw or inner-hw");
        for (const auto& backend : o.csm_backends) {
          // The hardware coverage tests exist only as raster passes.
          const bool hardware_test = *test == shadows::CsmTest::BarycentricHw || *test == shadows::CsmTest::InnerHw;
          if (hardware_test && backend == "compute") continue;
          RunConfig run = traced;
          run.csm_test = test_name;
          run.csm_backend = backend;
          run.settings.izb.csm_test = *test;
          run.settings.izb.csm_backend = backend_option("--csm-backend", backend);
          runs.push_back(run);
        }
      }
    }
  }
  if (o.lit_culling.empty()) return runs;
  // Each IZB run once per --lit-culling value, in the order given.
  std::vector<RunConfig> lit_runs;
  for (const auto& run : runs) {
    const bool uses_izb =
        run.settings.technique == shadows::Technique::Izb || run.settings.technique == shadows::Technique::Hybrid;
    if (!uses_izb) {
      lit_runs.push_back(run);
      continue;
    }
    for (const auto& value : o.lit_culling) {
      const auto mode = shadows::parse_lit_culling(value);
      if (!mode) throw std::runtime_error("--lit-culling '" + value + "': expected on, off or auto");
      RunConfig r = run;
      r.settings.izb.lit_culling = *mode;
      lit_runs.push_back(r);
    }
  }
  return lit_runs;
}

void apply_csm_choice(engine::Scene& scene, const std::string& choice) {
  if (choice.empty()) return;
  engine::CsmChoice c;
  if (choice == "on") c = engine::CsmChoice::On;
  else if (choice == "off") c = engine::CsmChoice::Off;
  else if (choice == "auto") c = engine::CsmChoice::Auto;
  else throw std::runtime_error("--csm-choice '" + choice + "': expected on, off or auto");
  scene.registry.each<engine::ShadowCaster>([&](engine::Entity, engine::ShadowCaster& s) { s.csm = c; });
}

json stats_json(const shadows::Stats& s) {
  json c;
  c["shading_points"] = s.shading_points;
  c["lit_candidates"] = s.lit_candidates;
  c["nodes_inserted"] = s.nodes_inserted;
  c["csm_culled"] = s.csm_culled;
  c["lit_culled"] = s.lit_culled;
  c["caster_triangles"] = s.caster_triangles;
  c["caster_triangles_listed"] = s.caster_triangles_listed;
  c["csm_texels_covered"] = s.csm_texels_covered;
  c["node_pool_size"] = s.node_pool_size;
  c["node_overflow"] = s.node_overflow;
  c["overflow_pixels"] = s.overflow_pixels;
  c["list_length_max"] = s.list_length_max;
  c["list_length_average"] = s.list_length_average;
  c["nonempty_texels"] = s.nonempty_texels;
  c["trace_fragments_before_cull"] = s.trace_fragments_before_cull;
  c["trace_fragments_after_cull"] = s.trace_fragments_after_cull;
  c["triangle_tests"] = s.triangle_tests;
  c["triangle_tests_per_pixel"] = s.triangle_tests_per_pixel;
  // Per light-space fragment: per (triangle, texel) pair the trace kept (raster fragments after the
  // depth cull, or the compute trace's pairs).
  const uint64_t fragments = s.trace_pairs ? s.trace_pairs : s.trace_fragments_after_cull;
  c["triangle_tests_per_fragment"] = fragments ? double(s.triangle_tests) / double(fragments) : 0.0;
  c["expensive_path_fraction"] = s.expensive_path_fraction;
  c["expensive_path_pixels"] = s.expensive_path_pixels;
  c["blurred_pixels"] = s.blurred_pixels;
  c["trace_pairs"] = s.trace_pairs;
  c["trace_records"] = s.trace_records;
  c["trace_tile_pairs"] = s.trace_tile_pairs;
  c["rays_traced"] = s.rays_traced;
  c["rays_occluded"] = s.rays_occluded;
  c["rays_per_pixel"] = s.lit_candidates ? double(s.rays_traced) / double(s.lit_candidates) : 0.0;
  c["rt_instances"] = s.rt_instances;
  c["rt_triangles"] = s.rt_triangles;
  return c;
}

json choice_json(const shadows::Stats::BackendChoice& c) {
  return {{"backend", c.backend}, {"reason", c.reason}, {"raster_ms", c.raster_ms}, {"compute_ms", c.compute_ms}};
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// One scene (with its copies) on one device and renderer; runs configurations and returns their JSON.
struct Bench {
  const Options& o;
  engine::gpu::Context& ctx;
  engine::Scene& scene;
  engine::Renderer& renderer;
  std::shared_ptr<shadows::ShadowModule> module;
  std::unique_ptr<reference::EmbreeTracer> tracer;
  std::vector<float> reference_vis;  // for the current view, size and spp
  size_t view = 0;
  uint32_t instances = 1;
  std::optional<reference::LocalLight> local_light = std::nullopt;  // --light spot|point
  float local_radius = 0.0f;                                         // its radius
  // The area-light references of the current view and size (area_key), one per light that has a size.
  std::string area_key;
  std::vector<std::vector<float>> area_vis;
  double off_frame_ms = -1.0;  // the frame's GPU time in this invocation's `off` run, if any
  std::string off_frame_key;   // its scene, view and size

  // Light `l`'s area reference (its size > 0), computed once per view, size and light.
  const std::vector<float>& area_reference(size_t l, const support::FrameLightCheck& c) {
    const VkExtent2D e = renderer.extent();
    const std::string key = std::to_string(view) + "/" + std::to_string(e.width) + "x" + std::to_string(e.height);
    if (key != area_key) {
      area_vis.clear();
      area_key = key;
    }
    if (area_vis.size() <= l) area_vis.resize(l + 1);
    if (area_vis[l].empty())
      area_vis[l] = local_light
                        ? support::area_reference_visibility(renderer, *tracer, o.reference_rays, *local_light, c.size)
                        : support::area_reference_visibility(renderer, *tracer, o.reference_rays, c);
    return area_vis[l];
  }

  // The soft metrics of light `l` against its area reference, into its JSON reference entry; the line
  // to print.
  std::string soft_metrics(size_t l, const support::FrameLightCheck& c, json& r) {
    const auto soft = reference::compare_soft(c.visibility, area_reference(l, c));
    r["light_size"] = c.size;
    r["reference_rays"] = o.reference_rays;
    r["soft_pixels"] = soft.pixels;
    r["soft_mae"] = soft.soft_mae;
    r["penumbra_pixels"] = soft.penumbra_pixels;
    r["penumbra_mae"] = soft.penumbra_mae;
    char line[256];
    std::snprintf(line, sizeof line,
                  "    light %zu (%s, size %g): soft_mae %.5f (%llu px), penumbra_mae %.5f (%llu px), %u rays\n", l,
                  c.kind.c_str(), double(c.size), soft.soft_mae, (unsigned long long)soft.pixels, soft.penumbra_mae,
                  (unsigned long long)soft.penumbra_pixels, o.reference_rays);
    return line;
  }

  json measure(const RunConfig& run, bool print) {
    module->settings() = run.settings;
    module->settings().units_per_metre = float(scene.units_per_metre);
    module->settings().rt_light_samples = o.rt_rays;
    const uint32_t spp = run.settings.izb.samples_per_pixel;
    const VkExtent2D extent = renderer.extent();
    json entry;
    entry["device"] = ctx.device_name();
    entry["driver"] = ctx.driver_description();
    entry["scene"] = scene.name;
    entry["light"] = o.light;
    entry["view"] = view;
    entry["instances"] = instances;
    entry["triangles"] = scene.triangle_count();
    entry["size"] = {extent.width, extent.height};
    entry["izb"] = run.settings.izb.resolution;
    entry["mode"] = run.mode;
    entry["spp"] = spp;
    entry["csm_test"] = run.csm_test;
    entry["trace"] = run.trace;
    entry["csm_backend"] = run.csm_backend;
    entry["csm_everything"] = run.csm_everything;
    entry["lit_culling"] = shadows::lit_culling_name(run.settings.izb.lit_culling);
    entry["csm_timed"] = run.settings.izb.csm_timed;
    std::string why;
    if (!module->supported(run.settings.technique, &why) ||
        (run.csm_test != "none" && !module->supported(run.settings.izb.csm_test, &why))) {
      entry["status"] = "unavailable";
      entry["reason"] = why;
      if (print) std::printf("%-12s %-9s unavailable: %s\n", run.mode.c_str(), run.csm_test.c_str(), why.c_str());
      return entry;
    }
    entry["status"] = "ran";
    // Every caster in the CSM for this run only; the scene's own choices come back afterwards.
    std::vector<std::pair<engine::Entity, engine::CsmChoice>> saved_choices;
    if (run.csm_everything)
      scene.registry.each<engine::ShadowCaster>([&](engine::Entity e, engine::ShadowCaster& c) {
        saved_choices.emplace_back(e, c.csm);
        c.csm = engine::CsmChoice::On;
      });
    struct Restore {
      engine::Registry& registry;
      std::vector<std::pair<engine::Entity, engine::CsmChoice>>& saved;
      ~Restore() {
        for (auto& [e, c] : saved) registry.get<engine::ShadowCaster>(e).csm = c;
      }
    } restore{scene.registry, saved_choices};
    // Automatic backends first time both (a few frames), then keep the faster. The probing and timed
    // frames run without the statistics (as an application's frames do: their counting would weigh
    // on the probe's timings); one more frame after them collects the statistics.
    module->set_collect_stats(false);
    const auto lit_undecided = [&] {
      const auto& lit = module->stats().lit_choice;
      return run.settings.izb.lit_culling == shadows::LitCulling::Auto && (lit.reason == "probing" || lit.reason.empty());
    };
    // The timed CSM's probe starts once the backends are chosen, where the CSM runs at all.
    const auto csm_run_undecided = [&] {
      const auto& st = module->stats();
      return run.settings.izb.csm_timed && run.settings.izb.csm &&
             (st.csm_run_choice.reason == "probing" || (st.csm_run_choice.reason.empty() && st.csm_status == "ran"));
    };
    // A GPU times step 1's shape once the backends are chosen, where the compute trace or CSM runs.
    const bool gpu_device = ctx.properties().deviceType != VK_PHYSICAL_DEVICE_TYPE_CPU;
    const auto shape_undecided = [&] {
      const auto& st = module->stats();
      const bool tile_work = st.trace_choice.backend == "compute" || st.csm_choice.backend == "compute";
      return st.tile_work_choice.reason == "probing" || (gpu_device && tile_work && st.tile_work_choice.reason.empty());
    };
    for (int f = 0; f < 48 && (module->stats().trace_choice.reason == "probing" ||
                               module->stats().csm_choice.reason == "probing" || lit_undecided() ||
                               csm_run_undecided() || shape_undecided() || f == 0);
         ++f)
      renderer.render_frame(0.0f);
    for (int f = 0; f < o.warmup; ++f) renderer.render_frame(0.0f);
    renderer.profiler().clear_history();
    for (int f = 0; f < o.frames; ++f) renderer.render_frame(0.0f);

    // The module's region is 0 where it records nothing (`off` in the engine: FrameContext::written).
    json gpu_ms{{"shadows", 0.0}};
    for (const auto& name : renderer.profiler().region_names()) {
      const double ms = renderer.profiler().median_ms(name);
      if (ms > 0.0) gpu_ms[name] = ms;
    }
    // total: per frame, the sum of the technique's passes (statistics passes excluded); then the median.
    {
      std::vector<double> totals(size_t(o.frames), 0.0);
      for (const auto& pass : module->pass_names()) {
        const auto h = renderer.profiler().history(pass);
        for (size_t f = 0; f < h.size() && f < totals.size(); ++f) totals[f] += h[f];
      }
      gpu_ms["total"] = median(totals);
    }
    // named: per frame, the sum of the regions directly inside the module's region; what it leaves
    // unnamed is the region's time no region accounts for (work outside them, waits between them).
    {
      std::vector<double> named(size_t(o.frames), 0.0);
      for (const auto& child : renderer.profiler().children("shadows")) {
        const auto h = renderer.profiler().history(child);
        for (size_t f = 0; f < h.size() && f < named.size(); ++f) named[f] += h[f];
      }
      gpu_ms["named"] = median(named);
    }
    entry["gpu_ms"] = gpu_ms;
    entry["passes"] = module->pass_names();
    const double frame_ms = renderer.profiler().median_ms("frame");
    // What the frame pays: its GPU time over that of an `off` run earlier in this invocation (same
    // scene, view and size).
    const std::string off_key = scene.name + "/" + std::to_string(view) + "/" + std::to_string(renderer.extent().width) +
                                "x" + std::to_string(renderer.extent().height);
    if (off_key != off_frame_key) off_frame_ms = -1.0;
    if (run.settings.technique == shadows::Technique::Off) {
      off_frame_ms = frame_ms;
      off_frame_key = off_key;
    }
    entry["frame_ms"] = frame_ms;
    if (off_frame_ms >= 0.0) entry["frame_over_off_ms"] = frame_ms - off_frame_ms;
    module->set_collect_stats(true);
    renderer.render_frame(0.0f);
    const shadows::Stats& st = module->stats();
    entry["frames"] = o.frames;
    entry["warmup"] = o.warmup;
    entry["counts"] = stats_json(st);
    entry["culling_rate"] = st.culling_rate;
    entry["hardware_conservative"] = st.hardware_conservative;
    entry["csm_status"] = st.csm_status;
    json lights = json::array();
    for (const auto& l : st.lights)
      lights.push_back({{"kind", l.kind}, {"lit_candidates", l.lit_candidates}, {"nodes_inserted", l.nodes_inserted},
                        {"csm_culled", l.csm_culled}, {"node_overflow", l.node_overflow},
                        {"list_length_max", l.list_length_max}, {"rays_traced", l.rays_traced},
                        {"rays_occluded", l.rays_occluded}, {"gpu_ms", l.gpu_ms}, {"faces_recorded", l.faces_recorded}, {"reaches_view", l.reaches_view}});
    entry["lights"] = lights;
    entry["lists"] = shadows::list_layout_name(run.settings.izb.lists);
    entry["anchored_nodes"] = run.settings.izb.anchored_nodes;
    entry["memory_bytes"] = st.memory_bytes;
    entry["memory_total_bytes"] = st.memory_total_bytes;
    if (!st.trace_choice.backend.empty()) entry["trace_choice"] = choice_json(st.trace_choice);
    if (!st.csm_choice.backend.empty()) entry["csm_choice"] = choice_json(st.csm_choice);
    if (!st.lit_choice.backend.empty()) entry["lit_choice"] = choice_json(st.lit_choice);
    if (!st.csm_run_choice.backend.empty()) entry["csm_run_choice"] = choice_json(st.csm_run_choice);
    if (!st.tile_work_choice.backend.empty()) entry["tile_work_choice"] = choice_json(st.tile_work_choice);
    if (!st.cascade_splits.empty()) {
      entry["cascade_splits"] = st.cascade_splits;
      entry["cascades_drawn"] = st.cascades_drawn;
    }
    json decisions = json::array();
    for (const auto& d : st.csm_decisions)
      decisions.push_back({{"name", d.name}, {"in_csm", d.in_csm}, {"automatic", d.automatic},
                           {"large_triangle_area_share", d.large_triangle_area_share}, {"reason", d.reason}});
    if (!decisions.empty()) entry["csm_decisions"] = decisions;

    double mismatch = -1, mae = -1;
    uint64_t false_shadowed = 0;
    const std::string tag = scene.name + "_v" + std::to_string(view) + "_" + run.mode + "_" + run.csm_test + "_spp" +
                            std::to_string(spp);
    // Every light the frame shadows (the sun and the local lights the adapter records), or the one
    // --light spot|point asked for: its term and, with --reference, Embree's.
    std::vector<support::FrameLightCheck> checks;
    if (o.reference) {
      // The reference traces the frame's triangles relative to the frame's origin (the renderer rebases
      // a camera far from the world's origin).
      if (!tracer || tracer->shift() != support::frame_shift(renderer)) {
        tracer = std::make_unique<reference::EmbreeTracer>(scene.registry, support::frame_shift(renderer));
        reference_vis.clear();
        area_vis.clear();
      }
      if (local_light) {
        if (reference_vis.empty()) reference_vis = support::reference_visibility(renderer, *tracer, spp, *local_light);
        checks.push_back({o.light, module->read_visibility(), reference_vis, local_radius, *local_light});
      } else {
        checks = support::check_every_light(renderer, *tracer, spp);
        reference_vis = checks.front().reference;
      }
    } else if (!o.dump_dir.empty()) {
      checks.push_back({local_light ? o.light : "sun", module->read_visibility(), {}});
      if (!local_light)
        for (uint32_t i = 0; i < renderer.frame_view().local_lights.size(); ++i) {
          auto term = renderer.read_local_shadow_term(i);
          for (size_t p = 0; p < term.size(); ++p)
            if (checks.front().visibility[p] < 0.0f) term[p] = -1.0f;
          checks.push_back({renderer.frame_view().local_lights[i].kind == engine::LocalLightKind::Spot ? "spot" : "point",
                            std::move(term), {}});
        }
    }
    json references = json::array();
    std::string soft_line;  // the first light's soft metrics, printed after its line
    for (size_t l = 0; l < checks.size(); ++l) {
      const auto& c = checks[l];
      const std::string light_tag = tag + (checks.size() > 1 ? "_light" + std::to_string(l) + "_" + c.kind : "");
      if (!c.reference.empty()) {
        const auto cmp = reference::compare_visibility(c.visibility, c.reference);
        json r = {{"light", l},
                  {"kind", c.kind},
                  {"pixels", cmp.pixels},
                  {"mismatched", cmp.mismatched},
                  {"false_shadowed", cmp.false_shadowed},
                  {"false_lit", cmp.false_lit},
                  {"mismatch_rate", cmp.mismatch_rate},
                  {"coverage_mae", cmp.coverage_mae},
                  {"coverage_max_error", cmp.coverage_max_error}};
        const std::string soft = c.size > 0.0f ? soft_metrics(l, c, r) : "";
        references.push_back(r);
        if (l == 0) {
          entry["reference"] = r;  // the first light's, as before
          mismatch = cmp.mismatch_rate;
          mae = cmp.coverage_mae;
          false_shadowed = cmp.false_shadowed;
          soft_line = soft;
        } else if (print) {
          std::printf("    light %zu (%s): mismatch %.6f, false shadowed %llu, false lit %llu, MAE %.5f\n", l, c.kind.c_str(),
                      cmp.mismatch_rate, (unsigned long long)cmp.false_shadowed, (unsigned long long)cmp.false_lit,
                      cmp.coverage_mae);
          std::fputs(soft.c_str(), stdout);
        }
        if (!o.diff_dir.empty()) {
          std::filesystem::create_directories(o.diff_dir);
          reference::write_diff_png(o.diff_dir + "/diff_" + light_tag + ".png", extent.width, extent.height,
                                    c.visibility, c.reference);
        }
      }
      if (!o.dump_dir.empty()) {
        std::filesystem::create_directories(o.dump_dir);
        const std::string file = o.dump_dir + "/vis_" + light_tag + "_" + (o.raster.empty() ? "auto" : o.raster) + "_" +
                                 run.trace + "_" + run.csm_backend + ".f32";
        std::ofstream out(file, std::ios::binary);
        out.write(reinterpret_cast<const char*>(c.visibility.data()), std::streamsize(c.visibility.size() * sizeof(float)));
      }
    }
    if (!references.empty()) entry["references"] = references;
    if (!o.screenshot_dir.empty()) {
      std::filesystem::create_directories(o.screenshot_dir);
      renderer.write_png(o.screenshot_dir + "/" + scene.name + "_v" + std::to_string(view) + "_" + run.mode + ".png");
    }
    entry["validation_messages"] = ctx.validation_message_count();
    if (print) {
      const auto ran = [](const shadows::Stats::BackendChoice& c, const std::string& asked) {
        return asked == "none" || c.backend.empty() ? asked : c.backend;
      };
      // Asked for, or chosen by its probe (the default Auto): which way ran and why.
      if (!o.lit_culling.empty() || !st.lit_choice.backend.empty())
        std::printf("lit culling %s%s: %llu of %llu candidates culled, %llu nodes\n",
                    shadows::lit_culling_name(run.settings.izb.lit_culling).c_str(),
                    run.settings.izb.lit_culling == shadows::LitCulling::Auto
                        ? (" (" + st.lit_choice.backend + ", " + st.lit_choice.reason + ")").c_str()
                        : "",
                    (unsigned long long)st.lit_culled, (unsigned long long)st.lit_candidates,
                    (unsigned long long)st.nodes_inserted);
      if (!st.tile_work_choice.backend.empty())
        std::printf("tile work: %s (%s)\n", st.tile_work_choice.backend.c_str(), st.tile_work_choice.reason.c_str());
      if (run.settings.izb.csm_timed && run.settings.izb.csm)
        std::printf("csm: %s (timed: %s, %s)\n", st.csm_status.c_str(), st.csm_run_choice.backend.c_str(),
                    st.csm_run_choice.reason.c_str());
      if (st.caster_triangles > 0)
        std::printf("light frustum: %llu of %llu caster triangles listed\n",
                    (unsigned long long)st.caster_triangles_listed, (unsigned long long)st.caster_triangles);
      for (size_t i = 0; i < st.lights.size(); ++i)
        if (!st.lights[i].reaches_view)
          std::printf("light %zu (%s): reaches no point of the view; its term written in one pass, no technique pass ran\n",
                      i, st.lights[i].kind.c_str());
      for (size_t i = 0; i < st.lights.size(); ++i)
        if (st.lights[i].faces_recorded > 0)
          std::printf("light %zu (point): %u of its 6 cube-face cones recorded (the others reach no point of the view)\n",
                      i, st.lights[i].faces_recorded);
      std::printf("%-12s %-9s %-8s %-8s %4u %10.3f %10.3f %12.6f %12llu %10.5f %9.1f\n", run.mode.c_str(),
                  run.csm_test.c_str(), ran(st.trace_choice, run.trace).c_str(),
                  ran(st.csm_choice, run.csm_backend).c_str(), spp, gpu_ms["total"].get<double>(), frame_ms,
                  mismatch, (unsigned long long)false_shadowed, mae, double(st.memory_total_bytes) / (1 << 20));
      std::fputs(soft_line.c_str(), stdout);
      const double region = gpu_ms["shadows"], named = gpu_ms["named"];
      std::printf("    cost: region %.3f ms, named %.3f ms (%.1f%% of the region unnamed)", region, named,
                  region > 0.0 ? 100.0 * (region - named) / region : 0.0);
      if (off_frame_ms >= 0.0) std::printf(", frame - frame(off) %.3f ms", frame_ms - off_frame_ms);
      std::printf("\n");
      for (const auto& [name, value] : gpu_ms.items())
        if (name != "total" && name != "named") std::printf("    %-26s %10.3f ms\n", name.c_str(), value.get<double>());
    }
    return entry;
  }
};

void print_header() {
  std::printf("%-12s %-9s %-8s %-8s %4s %10s %10s %12s %12s %10s %9s\n", "mode", "csm_test", "trace", "csm_pass",
              "spp", "total_ms", "frame_ms", "mismatch", "false_shad", "cov_mae", "mem_MiB");
}

// Every deformable mesh as a rigid one in its rest pose (copies sharing one MeshData stay shared).
void make_rigid(engine::Scene& scene) {
  std::map<const engine::MeshData*, std::shared_ptr<const engine::MeshData>> rigid;
  scene.registry.each<engine::Mesh>([&](engine::Entity, engine::Mesh& mesh) {
    if (!mesh.data || !mesh.data->deform) return;
    auto& copy = rigid[mesh.data.get()];
    if (!copy) {
      auto data = std::make_shared<engine::MeshData>(*mesh.data);
      data->deform.reset();
      copy = std::move(data);
    }
    mesh.data = copy;
  });
}

std::unique_ptr<engine::Scene> load(const std::string& name, uint32_t instances, const Options& o) {
  auto scene = engine::load_scene(name, o.detail);
  if (o.sun) engine::enable_default_sun(*scene);
  if (o.large_world) {
    engine::transform_scene(*scene, o.scale, glm::dvec3(0.0), "--scale");
    scene->origin = o.offset;
  } else if (o.scale != 1.0 || o.offset != glm::dvec3(0.0)) {
    engine::transform_scene(*scene, o.scale, o.offset, "--scale/--offset");
  }
  engine::replicate_scene(*scene, instances);
  apply_csm_choice(*scene, o.csm_choice);
  if (o.rigid) make_rigid(*scene);
  if (o.light_size)
    scene->registry.each<engine::DirectionalLight>(
        [&](engine::Entity, engine::DirectionalLight& l) { l.angular_diameter_degrees = float(*o.light_size); });
  if (o.light_radius) {
    scene->registry.each<engine::SpotLight>([&](engine::Entity, engine::SpotLight& l) { l.radius = float(*o.light_radius); });
    scene->registry.each<engine::PointLight>([&](engine::Entity, engine::PointLight& l) { l.radius = float(*o.light_radius); });
  }
  if (o.time) {
    engine::update_animations(scene->registry, float(*o.time));
    engine::update_clip_animations(scene->registry, float(*o.time));
  }
  return scene;
}

void write_json(const std::string& path, const json& results) {
  const std::filesystem::path p(path);
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << results.dump(2) << "\n";
  std::printf("wrote %s\n", path.c_str());
}

int run_single(const Options& o) {
  const auto runs = expand_runs(o);
  auto scene = load(o.scene, o.instances.front(), o);
  scene->apply_view(o.view);

  engine::gpu::Context ctx({.device = o.device});
  engine::Renderer renderer(ctx, {o.width, o.height});
  renderer.set_scene(*scene);
  renderer.set_smooth_terminator(!o.faceted_terminator);
  Bench bench{o, ctx, *scene, renderer, shadows::install(renderer, runs.front().settings), nullptr, {}, o.view,
              o.instances.front()};
  if (o.light != "sun") {
    const auto light = support::scene_local_light(
        scene->registry, o.light == "spot" ? shadows::LightType::Spot : shadows::LightType::Point);
    bench.module->set_light(light.module);
    bench.local_light = light.reference;
    bench.local_radius = light.module.radius;
  }
  // A technique the device cannot run at all is an error here (one line naming what it lacks).
  for (const auto& run : runs)
    if (std::string why; !bench.module->supported(run.settings.technique, &why))
      throw std::runtime_error("--mode " + run.mode + ": " + why);

  json results = json::array();
  print_header();
  for (const auto& run : runs) results.push_back(bench.measure(run, true));
  if (bench.tracer && !o.screenshot_dir.empty() && !bench.reference_vis.empty()) {
    // The lighting path fed by the reference instead of a technique: what the image should be (the
    // area light's where the light has a size, "_area_reference.png", beside the hard one).
    renderer.set_external_shadow_term(bench.reference_vis);
    renderer.render_frame(0.0f);
    renderer.write_png(o.screenshot_dir + "/" + scene->name + "_v" + std::to_string(o.view) + "_reference.png");
    if (!bench.area_vis.empty() && !bench.area_vis[0].empty()) {
      renderer.set_external_shadow_term(bench.area_vis[0]);
      renderer.render_frame(0.0f);
      renderer.write_png(o.screenshot_dir + "/" + scene->name + "_v" + std::to_string(o.view) + "_area_reference.png");
    }
    renderer.set_external_shadow_term({});
  }
  if (!o.dump_dir.empty() && !bench.area_vis.empty() && !bench.area_vis[0].empty()) {
    // The first light's area reference beside the techniques' terms (--dump), in the same layout.
    std::ofstream out(o.dump_dir + "/area_reference_" + scene->name + "_v" + std::to_string(o.view) + ".f32",
                      std::ios::binary);
    out.write(reinterpret_cast<const char*>(bench.area_vis[0].data()),
              std::streamsize(bench.area_vis[0].size() * sizeof(float)));
  }
  if (!o.json_path.empty()) write_json(o.json_path, results);
  // The bounds make a benchmark run a check: each run over one fails it, named with its figure.
  int failed = 0;
  for (const auto& r : results) {
    if (!r.contains("reference")) continue;
    const std::string what = r["mode"].get<std::string>() + " (" + r["scene"].get<std::string>() + " view " +
                             std::to_string(r["view"].get<size_t>()) + ", " + std::to_string(r["spp"].get<uint32_t>()) +
                             " spp)";
    for (const auto& ref : r["references"]) {
      const std::string light = r["references"].size() == 1 ? what
                                                             : what + " light " + std::to_string(ref["light"].get<size_t>()) +
                                                                   " (" + ref["kind"].get<std::string>() + ")";
      const double mismatch = ref["mismatch_rate"], mae = ref["coverage_mae"];
      if (o.max_mismatch >= 0.0 && mismatch > o.max_mismatch) {
        std::fprintf(stderr, "shadow_bench: %s: mismatch rate %.6f over --max-mismatch %g\n", light.c_str(), mismatch,
                     o.max_mismatch);
        ++failed;
      }
      if (o.max_coverage_mae >= 0.0 && mae > o.max_coverage_mae) {
        std::fprintf(stderr, "shadow_bench: %s: coverage MAE %.6f over --max-coverage-mae %g\n", light.c_str(), mae,
                     o.max_coverage_mae);
        ++failed;
      }
    }
  }
  return failed ? 2 : 0;
}

// ---- The paper suite ----

// The configurations of one (view, size, spp): Table 2's izb and izb+csm (bary), Table 3's other
// coverage tests, and the other techniques.
// The trace and CSM backends are the first of --trace / --csm-backend (default auto).
std::vector<RunConfig> suite_runs(const Options& o, uint32_t izb, uint32_t spp) {
  std::vector<RunConfig> runs;
  shadows::Settings base;
  base.izb.resolution = izb;
  base.izb.samples_per_pixel = spp;
  const std::string trace = o.traces.front(), csm_backend = o.csm_backends.front();
  base.izb.trace = backend_option("--trace", trace);
  base.izb.csm_backend = backend_option("--csm-backend", csm_backend);
  for (const char* mode : {"izb", "izb+csm", "sm", "cascades", "hybrid+csm", "rt"}) {
    const shadows::Settings s = *shadows::parse_mode(mode, base);
    const bool izb_mode = s.technique == shadows::Technique::Izb || s.technique == shadows::Technique::Hybrid;
    runs.push_back({mode, s.izb.csm ? "bary" : "none", izb_mode ? trace : "none", s.izb.csm ? csm_backend : "none", s});
  }
  if (spp == 1) {
    for (auto test : {shadows::CsmTest::Hertel, shadows::CsmTest::Barycentric, shadows::CsmTest::BarycentricHw,
                      shadows::CsmTest::InnerHw}) {
      const bool hardware_test = test == shadows::CsmTest::BarycentricHw || test == shadows::CsmTest::InnerHw;
      RunConfig r{"izb+csm", shadows::csm_test_name(test), trace, hardware_test ? "raster" : csm_backend,
                  *shadows::parse_mode("izb+csm", base)};
      r.settings.izb.csm_test = test;
      // The hardware coverage tests exist only as raster passes.
      if (hardware_test) r.settings.izb.csm_backend = shadows::PassBackend::Raster;
      r.csm_everything = true;
      runs.push_back(r);
    }
  }
  return runs;
}

const json* find_run(const json& results, const std::string& scene, size_t view, const std::string& size,
                     uint32_t spp, const std::string& mode, const std::string& csm_test,
                     bool csm_everything = false) {
  for (const auto& r : results) {
    const std::string s = std::to_string(r["size"][0].get<uint32_t>()) + "x" + std::to_string(r["size"][1].get<uint32_t>());
    if (r["scene"] == scene && r["view"] == view && s == size && r["spp"] == spp && r["mode"] == mode &&
        r["csm_test"] == csm_test && r.value("csm_everything", false) == csm_everything)
      return &r;
  }
  return nullptr;
}

std::string ms_cell(const json* r, const std::string& pass) {
  if (!r) return "—";
  if (r->value("status", "") != "ran") return "n/a";
  const auto& g = (*r)["gpu_ms"];
  if (!g.contains(pass)) return "-";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3f", g[pass].get<double>());
  return buf;
}

std::string fmt(const char* format, double v) {
  char buf[48];
  std::snprintf(buf, sizeof(buf), format, v);
  return buf;
}

// The suite's tables as Markdown: Table 2 per size (views side by side), techniques per view with
// memory, Table 3, the 32/1 spp ratio and the scaling table.
std::string suite_markdown(const json& results, const std::vector<SizeConfig>& sizes, const Options& o) {
  std::ostringstream md;
  if (results.empty()) return "";
  md << "Device: " << results[0]["device"].get<std::string>() << ", driver " << results[0]["driver"].get<std::string>()
     << "; medians of " << o.frames << " frames after " << o.warmup << " warm-up; GPU ms.\n\n";
  std::vector<std::pair<std::string, size_t>> scene_views;  // in run order, instances = 1 first
  std::vector<std::string> scenes;
  for (const auto& r : results) {
    const std::pair<std::string, size_t> sv{r["scene"], r["view"]};
    if (std::find(scene_views.begin(), scene_views.end(), sv) == scene_views.end()) scene_views.push_back(sv);
    if (std::find(scenes.begin(), scenes.end(), sv.first) == scenes.end()) scenes.push_back(sv.first);
  }
  const std::vector<std::pair<std::string, std::string>> passes = {
      {"light frustum", "light_frustum"}, {"CSM generation", "csm"},     {"IZB build", "izb_build"},
      {"frustum trace", "frustum_trace"}, {"fallback", "izb_fallback"}, {"resolve", "izb_resolve"},
      {"**total**", "total"}};
  for (uint32_t spp : o.spps) {
    for (const auto& size : sizes) {
      md << "### Table 2 layout: " << size.label << ", IZB " << size.izb << "², " << spp << " spp\n\n| pass |";
      for (const auto& [scene, view] : scene_views) md << " " << scene << " v" << view << " izb | izb+csm |";
      md << "\n|---|";
      for (size_t i = 0; i < scene_views.size(); ++i) md << "---|---|";
      md << "\n";
      for (const auto& [label, pass] : passes) {
        md << "| " << label << " |";
        for (const auto& [scene, view] : scene_views)
          md << " " << ms_cell(find_run(results, scene, view, size.label, spp, "izb", "none"), pass) << " | "
             << ms_cell(find_run(results, scene, view, size.label, spp, "izb+csm", "bary"), pass) << " |";
        md << "\n";
      }
      md << "| izb / izb+csm |";
      for (const auto& [scene, view] : scene_views) {
        const json* a = find_run(results, scene, view, size.label, spp, "izb", "none");
        const json* b = find_run(results, scene, view, size.label, spp, "izb+csm", "bary");
        const bool ok = a && b && (*a)["status"] == "ran" && (*b)["status"] == "ran" &&
                        (*b)["gpu_ms"]["total"].get<double>() > 0.0;
        md << " | " << (ok ? fmt("%.2f×", (*a)["gpu_ms"]["total"].get<double>() / (*b)["gpu_ms"]["total"].get<double>()) : "—")
           << " |";
      }
      md << "\n\n";

      md << "### Every technique: " << size.label << ", " << spp << " spp (total ms; GPU memory MiB; work)\n\n"
         << "| scene, view | triangles | sm | cascades | izb | izb+csm | hybrid+csm | rt | rt vs izb+csm | memory MiB: sm / cascades / izb / izb+csm / hybrid+csm / rt | izb+csm tests per pixel / per fragment, list avg | rt rays per pixel |\n"
         << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
      const std::vector<std::pair<std::string, std::string>> techniques = {
          {"sm", "none"}, {"cascades", "none"}, {"izb", "none"}, {"izb+csm", "bary"}, {"hybrid+csm", "bary"}, {"rt", "none"}};
      for (const auto& [scene, view] : scene_views) {
        const json* any = find_run(results, scene, view, size.label, spp, "sm", "none");
        md << "| " << scene << " v" << view << " | " << (any ? std::to_string((*any)["triangles"].get<uint64_t>()) : "—")
           << " |";
        for (const auto& [mode, test] : techniques)
          md << " " << ms_cell(find_run(results, scene, view, size.label, spp, mode, test), "total") << " |";
        const json* rt = find_run(results, scene, view, size.label, spp, "rt", "none");
        const json* csm = find_run(results, scene, view, size.label, spp, "izb+csm", "bary");
        if (rt && csm && (*rt)["status"] == "ran" && (*csm)["status"] == "ran") {
          const double a = (*rt)["gpu_ms"]["total"], b = (*csm)["gpu_ms"]["total"];
          md << " " << (a < b ? "rt " + fmt("%.2f×", b / a) : "izb+csm " + fmt("%.2f×", a / b)) << " faster |";
        } else {
          md << " " << (rt && rt->contains("reason") ? "rt n/a" : "—") << " |";
        }
        md << " ";
        for (size_t i = 0; i < techniques.size(); ++i) {
          const json* r = find_run(results, scene, view, size.label, spp, techniques[i].first, techniques[i].second);
          md << (i ? " / " : "")
             << (r && (*r)["status"] == "ran" ? fmt("%.1f", (*r)["memory_total_bytes"].get<double>() / 1048576.0) : "—");
        }
        md << " |";
        if (csm && (*csm)["status"] == "ran") {
          const auto& c = (*csm)["counts"];
          md << " " << fmt("%.1f", c["triangle_tests_per_pixel"].get<double>()) << " / "
             << fmt("%.2f", c["triangle_tests_per_fragment"].get<double>()) << ", "
             << fmt("%.1f", c["list_length_average"].get<double>()) << " |";
        } else {
          md << " — |";
        }
        md << " " << (rt && (*rt)["status"] == "ran" ? fmt("%.1f", (*rt)["counts"]["rays_per_pixel"].get<double>()) : "—")
           << " |\n";
      }
      md << "\n";
      if (spp != 1) continue;
      md << "### Table 3 layout: " << size.label << ", IZB " << size.izb
         << "²: CSM time and culling rate per coverage test (every caster in the CSM)\n\n"
         << "| scene, view | hertel | bary | bary-hw | inner-hw |\n|---|---|---|---|---|\n";
      for (const auto& [scene, view] : scene_views) {
        md << "| " << scene << " v" << view << " |";
        for (const char* test : {"hertel", "bary", "bary-hw", "inner-hw"}) {
          const json* r = find_run(results, scene, view, size.label, 1, "izb+csm", test, true);
          if (!r || (*r)["status"] != "ran") {
            md << " " << (r ? "n/a" : "—") << " |";
            continue;
          }
          md << " " << ms_cell(r, "csm") << " ms, " << fmt("%.1f%%", (*r)["culling_rate"].get<double>() * 100.0);
          if ((*r)["csm_status"] != "ran") md << " (" << (*r)["csm_status"].get<std::string>() << ")";
          md << " |";
        }
        md << "\n";
      }
      md << "\n";
    }
  }
  // 32 spp / 1 spp per technique, when both ran.
  if (std::find(o.spps.begin(), o.spps.end(), 1u) != o.spps.end() &&
      std::find(o.spps.begin(), o.spps.end(), 32u) != o.spps.end()) {
    md << "### 32 spp / 1 spp (total ms ratio)\n\n| size | scene, view | izb | izb+csm | hybrid+csm | rt |\n|---|---|---|---|---|---|\n";
    for (const auto& size : sizes)
      for (const auto& [scene, view] : scene_views) {
        md << "| " << size.label << " | " << scene << " v" << view << " |";
        for (const auto& [mode, test] : std::vector<std::pair<std::string, std::string>>{
                 {"izb", "none"}, {"izb+csm", "bary"}, {"hybrid+csm", "bary"}, {"rt", "none"}}) {
          const json* a = find_run(results, scene, view, size.label, 32, mode, test);
          const json* b = find_run(results, scene, view, size.label, 1, mode, test);
          const bool ok = a && b && (*a)["status"] == "ran" && (*b)["status"] == "ran" &&
                          (*b)["gpu_ms"]["total"].get<double>() > 0.0;
          md << " " << (ok ? fmt("%.2f", (*a)["gpu_ms"]["total"].get<double>() / (*b)["gpu_ms"]["total"].get<double>()) : "—")
             << " |";
        }
        md << "\n";
      }
    md << "\n";
  }
  return md.str();
}

int run_suite(const Options& o) {
  std::vector<SizeConfig> sizes = g_suite_sizes;
  if (sizes.empty())
    sizes = o.quick ? std::vector<SizeConfig>{{160, 90, 128, "160x90"}, {320, 180, 256, "320x180"}}
                    : std::vector<SizeConfig>{{1920, 1080, 1024, "1920x1080"}, {3840, 2160, 2048, "3840x2160"}};
  const std::string out_dir = o.out_dir.empty() ? "suite_out" : o.out_dir;
  engine::gpu::Context ctx({.device = o.device});
  json results = json::array();
  print_header();
  for (const auto& scene_name : split(o.scene)) {
    for (uint32_t instances : o.instances) {
      auto scene = load(scene_name, instances, o);
      std::vector<size_t> views = o.views;
      if (views.empty())
        for (size_t v = 0; v < scene->views.size(); ++v) views.push_back(v);
      engine::Renderer renderer(ctx, {sizes.front().width, sizes.front().height});
      renderer.set_scene(*scene);
      Bench bench{o, ctx, *scene, renderer, shadows::install(renderer, {}), nullptr, {}, 0, instances};
      for (size_t view : views) {
        scene->apply_view(view);
        bench.view = view;
        for (const auto& size : sizes) {
          if (renderer.extent().width != size.width || renderer.extent().height != size.height)
            renderer.resize({size.width, size.height});
          for (uint32_t spp : o.spps) {
            std::printf("-- %s v%zu, %u triangles, %s, IZB %u, %u spp\n", scene->name.c_str(), view,
                        unsigned(scene->triangle_count()), size.label.c_str(), size.izb, spp);
            for (const auto& run : suite_runs(o, size.izb, spp)) results.push_back(bench.measure(run, true));
          }
        }
      }
    }
  }
  write_json(out_dir + "/suite.json", results);
  const std::string md_path = out_dir + "/suite.md";
  std::ofstream md(md_path);
  if (!md) throw std::runtime_error("cannot write " + md_path);
  md << suite_markdown(results, sizes, o);
  std::printf("wrote %s\n", md_path.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Options o = parse(argc, argv);
    return o.suite.empty() ? run_single(o) : run_suite(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "shadow_bench: %s\n", e.what());
    return 1;
  }
}
