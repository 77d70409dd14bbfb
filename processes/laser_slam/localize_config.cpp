#include "localize_config.hpp"

#include <ostream>
#include <stdexcept>

#include "snapnav/glue/options.hpp"

namespace snapnav::processes {

namespace {

// The [localize] keys, declared once: read, printed and described from here.
const glue::OptionTable<nav::MapLocalizerOptions>& LocalizeTable() {
  using O = nav::MapLocalizerOptions;
  static const auto table = glue::OptionTable<O>()
      .Number("global_resolution_m", "m", [](auto& o) -> auto& { return o.global.resolution_m; })
      .Degrees("global_heading_step_deg", [](auto& o) -> auto& { return o.global.heading_step_rad; })
      .Number("global_sigma_m", "m", [](auto& o) -> auto& { return o.global.sigma_m; })
      .Number("global_depth", "", [](auto& o) -> auto& { return o.global.depth; })
      .Number("global_max_range_m", "m", [](auto& o) -> auto& { return o.global.max_range_m; })
      .Number("global_max_points", "", [](auto& o) -> auto& { return o.global.max_points; })
      .Number("distinct_m", "m", [](auto& o) -> auto& { return o.global.distinct_m; })
      .Degrees("distinct_deg", [](auto& o) -> auto& { return o.global.distinct_rad; })
      .Number("min_global_score", "", &O::min_global_score)
      .Number("max_global_ambiguity", "", &O::max_global_ambiguity)
      .Flag("accumulate_evidence", &O::accumulate_evidence)
      .Number("accept_fit", "", &O::accept_fit)
      .Number("window_scans", "", &O::window_scans)
      .Number("window_m", "m", &O::window_m)
      .Number("lost_fit", "", &O::lost_fit)
      .Number("lost_after_scans", "", &O::lost_after_scans)
      .Number("reset_sigma_xy_m", "m", &O::reset_sigma_xy_m)
      .Degrees("reset_sigma_deg", &O::reset_sigma_theta_rad)
      .Number("occupied_threshold", "", [](auto& o) -> auto& { return o.global.occupied_threshold; })
      .Number("free_threshold", "", [](auto& o) -> auto& { return o.global.free_threshold; });
  return table;
}

}  // namespace

LocalizeConfig LocalizeConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  LocalizeConfig c;
  c.status_channel = channel_prefix + ini.GetString("channels", "localization_status");
  const char* s = "localize";
  nav::MapLocalizerOptions& o = c.options;
  LocalizeTable().ReadKeys(ini, s, &o);
  try {
    o.global.Validate();
    nav::MapLocalizerOptions check = o;
    check.tracking = nav::LaserSlamOptions{};
    check.Validate();
  } catch (const std::invalid_argument& e) {
    // The library's messages name its fields; name the [localize] key that sets each.
    const std::string what = e.what();
    if (what.find("heading_step") != std::string::npos) ini.FailKey(s, "global_heading_step_deg", what);
    if (what.find("global search: resolution_m") != std::string::npos) ini.FailKey(s, "global_resolution_m", what);
    if (what.find("global search: max_range_m") != std::string::npos) ini.FailKey(s, "global_max_range_m", what);
    if (what.find("reset_sigma") != std::string::npos && !(o.reset_sigma_xy_m > 0)) ini.FailKey(s, "reset_sigma_xy_m", what);
    if (what.find("reset_sigma") != std::string::npos) ini.FailKey(s, "reset_sigma_deg", what);
    throw ini.ValidationError(what);
  }
  return c;
}

void LocalizeConfig::Print(std::ostream& out) const {
  LocalizeTable().Print(out, options);
}

}  // namespace snapnav::processes
