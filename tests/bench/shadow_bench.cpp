// shadow_bench: renders a scene view with each requested shadow mode, measures every GPU pass with
// timestamp queries (medians over frames after warm-up), optionally compares the visibility with the
// Embree reference, and writes one JSON object per run.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "engine/assets/scene.hpp"
#include "engine/core/command_line.hpp"
#include "engine/render/renderer.hpp"
#include "frame_capture.hpp"
#include "shadows/shadows.hpp"

namespace {

using nlohmann::json;

struct Options {
  std::string scene = "contact";
  size_t view = 0;
  uint32_t width = 512, height = 512;
  uint32_t izb = 1024;
  std::vector<std::string> modes = {"sm"};
  uint32_t spp = 1;
  std::vector<std::string> csm_tests = {"bary"};
  std::string masking;  // empty: the default
  std::string csm_choice;  // empty: per entity; "on", "off", "auto" to force all
  int frames = 10;
  int warmup = 3;
  bool reference = false;
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
};

const char* kUsage =
    "usage: shadow_bench [--scene NAME|FILE.gltf] [--view N] [--size WxH] [--izb N] [--mode LIST]\n"
    "                    [--spp 1|32] [--csm-test LIST] [--masking off|edge|depth-extent]\n"
    "                    [--csm-choice on|off|auto] [--raster auto|hardware|software] [--node-pool N]\n"
    "                    [--trace LIST] [--csm-backend LIST] [--lists linked|sorted]\n"
    "                    [--frames N] [--warmup N] [--reference] [--faceted-terminator] [--device gpu|lavapipe|INDEX]\n"
    "                    [--json FILE] [--diff DIR] [--screenshot DIR] [--dump DIR]\n"
    "  LIST is comma-separated; modes: off, sm, cascades, izb, izb+csm, hybrid, hybrid+csm;\n"
    "  csm tests: hertel, bary, bary-hw, inner-hw; trace and CSM backends: auto, raster, compute\n"
    "  (auto times both on the first frames and keeps the faster; its probe frames come before the warm-up).\n";

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) if (!item.empty()) out.push_back(item);
  return out;
}

Options parse(int argc, char** argv) {
  Options o;
  engine::CommandLine args(argc, argv);
  while (args.next()) {
    const std::string& a = args.flag();
    if (a == "--scene") o.scene = args.value();
    else if (a == "--view") o.view = args.uint_value();
    else if (a == "--size") args.size_value(o.width, o.height);
    else if (a == "--izb") o.izb = args.uint_value();
    else if (a == "--mode") o.modes = split(args.value());
    else if (a == "--spp") o.spp = args.uint_value();
    else if (a == "--csm-test") o.csm_tests = split(args.value());
    else if (a == "--masking") o.masking = args.value();
    else if (a == "--csm-choice") o.csm_choice = args.value();
    else if (a == "--raster") o.raster = args.value();
    else if (a == "--trace") o.traces = split(args.value());
    else if (a == "--csm-backend") o.csm_backends = split(args.value());
    else if (a == "--lists") o.lists = args.value();
    else if (a == "--node-pool") o.node_pool = args.uint_value();
    else if (a == "--frames") o.frames = int(args.uint_value());
    else if (a == "--warmup") o.warmup = int(args.uint_value());
    else if (a == "--reference") o.reference = true;
    else if (a == "--faceted-terminator") o.faceted_terminator = true;
    else if (a == "--device") o.device = args.value();
    else if (a == "--json") o.json_path = args.value();
    else if (a == "--diff") o.diff_dir = args.value();
    else if (a == "--screenshot") o.screenshot_dir = args.value();
    else if (a == "--dump") o.dump_dir = args.value();
    else if (a == "--help" || a == "-h") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else throw std::runtime_error("unknown option " + a + " (see --help)");
  }
  if (o.spp != 1 && o.spp != 32) throw std::runtime_error("--spp must be 1 or 32");
  if (o.frames < 1) throw std::runtime_error("--frames must be at least 1");
  return o;
}

struct RunConfig {
  std::string mode;
  std::string csm_test;
  std::string trace = "none";
  std::string csm_backend = "none";
  shadows::Settings settings;
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
    base.izb.samples_per_pixel = o.spp;
    base.izb.node_pool_override = o.node_pool;
    if (!o.lists.empty()) {
      auto layout = shadows::parse_list_layout(o.lists);
      if (!layout) throw std::runtime_error("--lists '" + o.lists + "': expected linked or sorted");
      base.izb.lists = *layout;
    }
    if (!o.raster.empty()) {
      if (o.raster == "auto") base.izb.raster = shadows::ConservativeRaster::Auto;
      else if (o.raster == "hardware") base.izb.raster = shadows::ConservativeRaster::Hardware;
      else if (o.raster == "software") base.izb.raster = shadows::ConservativeRaster::Software;
      else throw std::runtime_error("--raster '" + o.raster + "': expected auto, hardware or software");
    }
    if (!o.masking.empty()) {
      auto m = shadows::parse_masking(o.masking);
      if (!m) throw std::runtime_error("--masking '" + o.masking + "': expected off, edge or depth-extent");
      base.cascades.masking = *m;
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
  return runs;
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
  c["expensive_path_fraction"] = s.expensive_path_fraction;
  c["expensive_path_pixels"] = s.expensive_path_pixels;
  c["blurred_pixels"] = s.blurred_pixels;
  c["trace_pairs"] = s.trace_pairs;
  c["trace_records"] = s.trace_records;
  c["trace_tile_pairs"] = s.trace_tile_pairs;
  return c;
}

json choice_json(const shadows::Stats::BackendChoice& c) {
  return {{"backend", c.backend}, {"reason", c.reason}, {"raster_ms", c.raster_ms}, {"compute_ms", c.compute_ms}};
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Options o = parse(argc, argv);
    const auto runs = expand_runs(o);
    auto scene = engine::load_scene(o.scene);
    apply_csm_choice(*scene, o.csm_choice);
    scene->apply_view(o.view);

    engine::gpu::Context ctx({.device = o.device});
    engine::Renderer renderer(ctx, {o.width, o.height});
    renderer.set_scene(*scene);
    renderer.set_smooth_terminator(!o.faceted_terminator);
    auto module = shadows::install(renderer, runs.front().settings);

    std::unique_ptr<reference::EmbreeTracer> tracer;
    std::vector<float> reference_vis;
    if (o.reference) tracer = std::make_unique<reference::EmbreeTracer>(scene->registry);

    json results = json::array();
    std::printf("%-12s %-9s %-8s %-8s %4s %10s %10s %12s %12s %10s\n", "mode", "csm_test", "trace", "csm_pass",
                "spp", "total_ms", "frame_ms", "mismatch", "false_shad", "cov_mae");
    for (const auto& run : runs) {
      module->settings() = run.settings;
      json entry;
      entry["device"] = ctx.device_name();
      entry["driver"] = ctx.driver_description();
      entry["scene"] = scene->name;
      entry["view"] = o.view;
      entry["triangles"] = scene->triangle_count();
      entry["size"] = {o.width, o.height};
      entry["izb"] = o.izb;
      entry["mode"] = run.mode;
      entry["spp"] = o.spp;
      entry["csm_test"] = run.csm_test;
      std::string why;
      if (run.csm_test != "none" && !module->supported(run.settings.izb.csm_test, &why)) {
        entry["status"] = "unavailable";
        entry["reason"] = why;
        std::printf("%-12s %-9s unavailable: %s\n", run.mode.c_str(), run.csm_test.c_str(), why.c_str());
        results.push_back(entry);
        continue;
      }
      // Automatic backends first time both (a few frames), then keep the faster. Timed frames run
      // without the statistics passes; one more frame after them collects the statistics.
      module->set_collect_stats(true);
      for (int f = 0; f < 16 && (module->stats().trace_choice.reason == "probing" ||
                                 module->stats().csm_choice.reason == "probing" || f == 0);
           ++f)
        renderer.render_frame(0.0f);
      module->set_collect_stats(false);
      for (int f = 0; f < o.warmup; ++f) renderer.render_frame(0.0f);
      renderer.profiler().clear_history();
      for (int f = 0; f < o.frames; ++f) renderer.render_frame(0.0f);

      json gpu_ms;
      for (const auto& name : renderer.profiler().region_names()) {
        const double ms = renderer.profiler().median_ms(name);
        if (ms > 0.0 || name == "shadows") gpu_ms[name] = ms;
      }
      // total: per frame, the sum of the technique's passes (statistics passes excluded); then the median.
      {
        std::vector<double> totals(size_t(o.frames), 0.0);
        for (const auto& pass : module->pass_names()) {
          const auto h = renderer.profiler().history(pass);
          for (size_t f = 0; f < h.size() && f < totals.size(); ++f) totals[f] += h[f];
        }
        std::sort(totals.begin(), totals.end());
        const size_t n = totals.size();
        gpu_ms["total"] = n % 2 ? totals[n / 2] : 0.5 * (totals[n / 2 - 1] + totals[n / 2]);
      }
      entry["gpu_ms"] = gpu_ms;
      const double frame_ms = renderer.profiler().median_ms("frame");
      module->set_collect_stats(true);
      renderer.render_frame(0.0f);
      entry["frames"] = o.frames;
      entry["warmup"] = o.warmup;
      entry["counts"] = stats_json(module->stats());
      entry["culling_rate"] = module->stats().culling_rate;
      entry["hardware_conservative"] = module->stats().hardware_conservative;
      entry["csm_status"] = module->stats().csm_status;
      entry["trace"] = run.trace;
      entry["lists"] = shadows::list_layout_name(run.settings.izb.lists);
      entry["csm_backend"] = run.csm_backend;
      if (!module->stats().trace_choice.backend.empty()) entry["trace_choice"] = choice_json(module->stats().trace_choice);
      if (!module->stats().csm_choice.backend.empty()) entry["csm_choice"] = choice_json(module->stats().csm_choice);
      if (!module->stats().cascade_splits.empty()) entry["cascade_splits"] = module->stats().cascade_splits;
      json decisions = json::array();
      for (const auto& d : module->stats().csm_decisions)
        decisions.push_back({{"name", d.name}, {"in_csm", d.in_csm}, {"automatic", d.automatic},
                             {"large_triangle_area_share", d.large_triangle_area_share}, {"reason", d.reason}});
      if (!decisions.empty()) entry["csm_decisions"] = decisions;

      double mismatch = -1, mae = -1;
      uint64_t false_shadowed = 0;
      if (tracer) {
        if (reference_vis.empty()) reference_vis = support::reference_visibility(renderer, *tracer, o.spp);
        const auto vis = module->read_visibility();
        const auto cmp = reference::compare_visibility(vis, reference_vis);
        entry["reference"] = {{"pixels", cmp.pixels},
                              {"mismatched", cmp.mismatched},
                              {"false_shadowed", cmp.false_shadowed},
                              {"false_lit", cmp.false_lit},
                              {"mismatch_rate", cmp.mismatch_rate},
                              {"coverage_mae", cmp.coverage_mae},
                              {"coverage_max_error", cmp.coverage_max_error}};
        mismatch = cmp.mismatch_rate;
        mae = cmp.coverage_mae;
        false_shadowed = cmp.false_shadowed;
        if (!o.diff_dir.empty()) {
          const std::string file = o.diff_dir + "/diff_" + scene->name + "_v" + std::to_string(o.view) + "_" +
                                   run.mode + "_" + run.csm_test + "_spp" + std::to_string(o.spp) + ".png";
          std::filesystem::create_directories(o.diff_dir);
          reference::write_diff_png(file, o.width, o.height, vis, reference_vis);
        }
      }
      if (!o.dump_dir.empty()) {
        std::filesystem::create_directories(o.dump_dir);
        const auto vis = module->read_visibility();
        const std::string file = o.dump_dir + "/vis_" + scene->name + "_v" + std::to_string(o.view) + "_" + run.mode +
                                 "_" + run.csm_test + "_spp" + std::to_string(o.spp) + "_" +
                                 (o.raster.empty() ? "auto" : o.raster) + "_" + run.trace + "_" + run.csm_backend +
                                 ".f32";
        std::ofstream out(file, std::ios::binary);
        out.write(reinterpret_cast<const char*>(vis.data()), std::streamsize(vis.size() * sizeof(float)));
      }
      if (!o.screenshot_dir.empty()) {
        std::filesystem::create_directories(o.screenshot_dir);
        renderer.write_png(o.screenshot_dir + "/" + scene->name + "_v" + std::to_string(o.view) + "_" + run.mode +
                           ".png");
      }
      entry["validation_messages"] = ctx.validation_message_count();
      results.push_back(entry);
      const auto ran = [](const shadows::Stats::BackendChoice& c, const std::string& asked) {
        return asked == "none" || c.backend.empty() ? asked : c.backend;
      };
      std::printf("%-12s %-9s %-8s %-8s %4u %10.3f %10.3f %12.6f %12llu %10.5f\n", run.mode.c_str(),
                  run.csm_test.c_str(), ran(module->stats().trace_choice, run.trace).c_str(),
                  ran(module->stats().csm_choice, run.csm_backend).c_str(), o.spp,
                  gpu_ms["total"].get<double>(), frame_ms, mismatch,
                  (unsigned long long)false_shadowed, mae);
      for (const auto& [name, value] : gpu_ms.items())
        if (name != "total") std::printf("    %-26s %10.3f ms\n", name.c_str(), value.get<double>());
    }
    if (tracer && !o.screenshot_dir.empty() && !reference_vis.empty()) {
      // The lighting path fed by the reference instead of a technique: what the image should be.
      renderer.set_external_shadow_term(reference_vis);
      renderer.render_frame(0.0f);
      renderer.write_png(o.screenshot_dir + "/" + scene->name + "_v" + std::to_string(o.view) + "_reference.png");
      renderer.set_external_shadow_term({});
    }
    if (!o.json_path.empty()) {
      const std::filesystem::path p(o.json_path);
      if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
      std::ofstream out(o.json_path);
      if (!out) throw std::runtime_error("cannot write " + o.json_path);
      out << results.dump(2) << "\n";
      std::printf("wrote %s\n", o.json_path.c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "shadow_bench: %s\n", e.what());
    return 1;
  }
}
