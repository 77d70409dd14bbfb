#include "compare_config.hpp"

#include <ostream>
#include <string>

#include "fused_slam_node.hpp"
#include "laser_slam_node.hpp"
#include "ratslam_node.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/place_cells.hpp"

namespace snapnav::eval {

processes::SimConfig LoadCompareConfigs(const CompareConfigPaths& paths, CompareOptions* o) {
  const auto sim = processes::SimConfig::FromIni(glue::IniFile::Load(paths.sim), "");
  o->camera = sim.camera;
  o->effects = sim.effects;
  const auto places = glue::IniFile::Load(paths.placecells);
  o->view = glue::ReadPlaceViewOptions(places);
  o->localizer = glue::ReadLocalizerOptions(places);
  o->vocabulary = glue::ReadVocabularyOptions(places);
  o->laser = processes::LaserSlamConfig::FromIni(glue::IniFile::Load(paths.laser), "").options;
  o->fused = processes::FusedSlamConfig::FromIni(glue::IniFile::Load(paths.fused), "").options;
  o->ratslam = processes::RatSlamConfig::FromIni(glue::IniFile::Load(paths.ratslam), "").options;
  return sim;
}

void PrintCompareOptions(std::ostream& out, const CompareConfigPaths& paths, const CompareOptions& o) {
  const nav::FusedSlamOptions& f = o.fused;
  out << "sim config " << paths.sim << " (camera " << (o.camera.optics.enabled ? "realistic" : "clean") << ", mask "
      << o.mask << "), fused config " << paths.fused << ", laser config " << paths.laser
      << ", place-cell config " << paths.placecells << ", RatSLAM config " << paths.ratslam << "\n"
      << "visual fixes " << o.visual_rate_hz << " Hz (" << (o.visual_prediction ? "fused pose as prediction" : "global")
      << "), RatSLAM frames " << o.ratslam_rate_hz << " Hz ("
      << (o.run_ratslam ? "on" : "off")
      << "), cells every " << o.cell_spacing_m << " m at the " << ExplorePoseName(o.explore_pose)
      << " pose (explore seed " << o.explore_seed << "), RPE per " << o.rpe_delta_m
      << " m, recovery under " << o.recovery_error_m << " m for " << o.recovery_hold_s << " s\n"
      << "[fused_slam] gate_chi2 " << f.gate_chi2 << ", agree_chi2 " << f.agree_chi2 << ", relocalize_after "
      << f.relocalize_after << " within " << f.relocalize_window_s << " s (max fit loss " << f.relocalize_max_fit_loss
      << (f.relocalize_net_of_accepted ? ", net of accepted" : "") << "), relocalize sigma " << f.relocalize_sigma_xy_m << " m / " << f.relocalize_sigma_theta_rad
      << " rad, fix sigma floor " << f.min_fix_sigma_xy_m << " m / " << f.min_fix_sigma_theta_rad << " rad, start sigma "
      << f.start_sigma_xy_m << " m / " << f.start_sigma_theta_rad << " rad, map offset cells " << f.map_cell_m
      << " m (drift " << f.map_drift_xy_m << " m / " << f.map_drift_theta_rad << " rad per sqrt m)"
      << ", suspect_after " << f.suspect_after << ", map_min_fit " << f.map_min_fit << ", dynamic points "
      << (f.dynamic_explain_m > 0 ? "left out" : "kept") << " (explain " << f.dynamic_explain_m << " m, behind "
      << f.dynamic_max_behind_m << " m, map age " << f.dynamic_map_age_s << " s, max fraction " << f.dynamic_max_fraction
      << ")"
      << ", occlusion fix inflation " << f.occlusion_fix_inflation << ", map drift "
      << (f.map_drift_accumulates ? "accumulated since new cells" : "per scan") << ", laser min constraint "
      << f.laser_min_constraint << (f.map_inherits_laser_drift ? " (cells inherit its drift)" : "")
      << ", fix correlation " << f.fix_correlation_m << " m\n";
}

}  // namespace snapnav::eval
