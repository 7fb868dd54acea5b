#include "shadows/settings.hpp"

namespace shadows {

std::optional<Settings> parse_mode(const std::string& mode, Settings base) {
  if (mode == "off") {
    base.technique = Technique::Off;
  } else if (mode == "sm") {
    base.technique = Technique::ShadowMap;
  } else if (mode == "cascades") {
    base.technique = Technique::Cascades;
  } else if (mode == "izb") {
    base.technique = Technique::Izb;
    base.izb.csm = false;
  } else if (mode == "izb+csm") {
    base.technique = Technique::Izb;
    base.izb.csm = true;
  } else if (mode == "hybrid") {
    base.technique = Technique::Hybrid;
  } else if (mode == "hybrid+csm") {
    base.technique = Technique::Hybrid;
    base.izb.csm = true;
  } else if (mode == "rt") {
    base.technique = Technique::RayTraced;
  } else {
    return std::nullopt;
  }
  return base;
}

std::string mode_name(const Settings& s) {
  switch (s.technique) {
    case Technique::Off: return "off";
    case Technique::ShadowMap: return "sm";
    case Technique::Cascades: return "cascades";
    case Technique::Izb: return s.izb.csm ? "izb+csm" : "izb";
    case Technique::Hybrid: return s.izb.csm ? "hybrid+csm" : "hybrid";
    case Technique::RayTraced: return "rt";
  }
  return "?";
}

std::optional<CsmTest> parse_csm_test(const std::string& name) {
  if (name == "hertel") return CsmTest::Hertel;
  if (name == "bary") return CsmTest::Barycentric;
  if (name == "bary-hw") return CsmTest::BarycentricHw;
  if (name == "inner-hw") return CsmTest::InnerHw;
  return std::nullopt;
}

std::string csm_test_name(CsmTest test) {
  switch (test) {
    case CsmTest::Hertel: return "hertel";
    case CsmTest::Barycentric: return "bary";
    case CsmTest::BarycentricHw: return "bary-hw";
    case CsmTest::InnerHw: return "inner-hw";
  }
  return "?";
}

std::optional<Masking> parse_masking(const std::string& name) {
  if (name == "off") return Masking::Off;
  if (name == "edge") return Masking::Edge;
  if (name == "depth-extent") return Masking::DepthExtent;
  if (name == "auto") return Masking::Auto;
  if (name == "planes") return Masking::Planes;
  return std::nullopt;
}

std::string masking_name(Masking masking) {
  switch (masking) {
    case Masking::Off: return "off";
    case Masking::Edge: return "edge";
    case Masking::DepthExtent: return "depth-extent";
    case Masking::Auto: return "auto";
    case Masking::Planes: return "planes";
  }
  return "?";
}

std::optional<DebugView> parse_debug_view(const std::string& name) {
  if (name == "none") return DebugView::None;
  if (name == "visibility") return DebugView::VisibilityMask;
  if (name == "list-length") return DebugView::ListLength;
  if (name == "cascades") return DebugView::Cascades;
  if (name == "csm") return DebugView::CsmCoverage;
  if (name == "expensive") return DebugView::ExpensivePath;
  return std::nullopt;
}

std::optional<PassBackend> parse_backend(const std::string& name) {
  if (name == "auto") return PassBackend::Auto;
  if (name == "raster") return PassBackend::Raster;
  if (name == "compute") return PassBackend::Compute;
  return std::nullopt;
}

std::string backend_name(PassBackend backend) {
  switch (backend) {
    case PassBackend::Auto: return "auto";
    case PassBackend::Raster: return "raster";
    case PassBackend::Compute: return "compute";
  }
  return "?";
}

std::optional<ListLayout> parse_list_layout(const std::string& name) {
  if (name == "linked") return ListLayout::Linked;
  if (name == "sorted") return ListLayout::Sorted;
  return std::nullopt;
}

std::string list_layout_name(ListLayout layout) { return layout == ListLayout::Sorted ? "sorted" : "linked"; }

std::optional<LitCulling> parse_lit_culling(const std::string& name) {
  if (name == "off") return LitCulling::Off;
  if (name == "on") return LitCulling::On;
  if (name == "auto") return LitCulling::Auto;
  return std::nullopt;
}

std::string lit_culling_name(LitCulling mode) {
  switch (mode) {
    case LitCulling::Off: return "off";
    case LitCulling::On: return "on";
    case LitCulling::Auto: return "auto";
  }
  return "?";
}

Settings in_world_units(const Settings& settings) {
  Settings s = settings;
  const float u = settings.units_per_metre;
  s.cascades.max_distance *= u;
  s.cascades.kernel_radius *= u;
  s.izb.max_distance *= u;
  s.hybrid_izb_distance *= u;
  return s;
}

}  // namespace shadows
