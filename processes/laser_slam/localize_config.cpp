#include "localize_config.hpp"

#include <ostream>
#include <stdexcept>

namespace snapnav::processes {

namespace {
constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
}

LocalizeConfig LocalizeConfig::FromIni(const glue::IniFile& ini, const std::string& channel_prefix) {
  LocalizeConfig c;
  c.status_channel = channel_prefix + ini.GetString("channels", "localization_status");
  const char* s = "localize";
  nav::MapLocalizerOptions& o = c.options;
  o.global.resolution_m = ini.GetDouble(s, "global_resolution_m");
  o.global.heading_step_rad = ini.GetDouble(s, "global_heading_step_deg") / kDegPerRad;
  o.global.sigma_m = ini.GetDouble(s, "global_sigma_m");
  o.global.depth = ini.GetInt(s, "global_depth");
  o.global.max_range_m = ini.GetDouble(s, "global_max_range_m");
  o.global.max_points = ini.GetInt(s, "global_max_points");
  o.global.distinct_m = ini.GetDouble(s, "distinct_m");
  o.global.distinct_rad = ini.GetDouble(s, "distinct_deg") / kDegPerRad;
  o.global.occupied_threshold = ini.GetDouble(s, "occupied_threshold");
  o.global.free_threshold = ini.GetDouble(s, "free_threshold");
  o.min_global_score = ini.GetDouble(s, "min_global_score");
  o.max_global_ambiguity = ini.GetDouble(s, "max_global_ambiguity");
  o.accept_fit = ini.GetDouble(s, "accept_fit");
  o.window_scans = ini.GetInt(s, "window_scans");
  o.window_m = ini.GetDouble(s, "window_m");
  o.lost_fit = ini.GetDouble(s, "lost_fit");
  o.lost_after_scans = ini.GetInt(s, "lost_after_scans");
  o.reset_sigma_xy_m = ini.GetDouble(s, "reset_sigma_xy_m");
  o.reset_sigma_theta_rad = ini.GetDouble(s, "reset_sigma_deg") / kDegPerRad;
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
  const nav::MapLocalizerOptions& o = options;
  out << "global_resolution_m = " << o.global.resolution_m << "\nglobal_heading_step_deg = " << o.global.heading_step_rad * kDegPerRad
      << "\nglobal_sigma_m = " << o.global.sigma_m << "\nglobal_depth = " << o.global.depth
      << "\nglobal_max_range_m = " << o.global.max_range_m << "\nglobal_max_points = " << o.global.max_points
      << "\ndistinct_m = " << o.global.distinct_m << "\ndistinct_deg = " << o.global.distinct_rad * kDegPerRad
      << "\nmin_global_score = " << o.min_global_score << "\nmax_global_ambiguity = " << o.max_global_ambiguity
      << "\naccept_fit = " << o.accept_fit << "\nwindow_scans = " << o.window_scans << "\nwindow_m = " << o.window_m
      << "\nlost_fit = " << o.lost_fit << "\nlost_after_scans = " << o.lost_after_scans
      << "\nreset_sigma_xy_m = " << o.reset_sigma_xy_m << "\nreset_sigma_deg = " << o.reset_sigma_theta_rad * kDegPerRad
      << "\noccupied_threshold = " << o.global.occupied_threshold << "\nfree_threshold = " << o.global.free_threshold << "\n";
}

}  // namespace snapnav::processes
