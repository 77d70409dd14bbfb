#include "snapnav/glue/slam_options.hpp"

namespace snapnav::glue {

const OptionTable<nav::LaserSlamOptions>& LaserSlamOptionTable() {
  using O = nav::LaserSlamOptions;
  static const auto table = OptionTable<O>()
      .Number("translation_noise_m_per_m", "m/m", [](auto& o) -> auto& { return o.motion.translation_noise_m_per_m; })
      .Number("rotation_noise_rad_per_rad", "rad/rad", [](auto& o) -> auto& { return o.motion.rotation_noise_rad_per_rad; })
      .Number("rotation_noise_rad_per_m", "rad/m", [](auto& o) -> auto& { return o.motion.rotation_noise_rad_per_m; })
      .Number("initial_sigma_xy_m", "m", &O::initial_sigma_xy_m)
      .Degrees("initial_sigma_theta_deg", &O::initial_sigma_theta_rad)
      .Choice("metric", &O::metric, {nav::IcpMetric::kPointToPoint, nav::IcpMetric::kPointToLine}, nav::IcpMetricName)
      .Number("match_distance_m", "m", &O::match_distance_m)
      .Number("match_distance_start_m", "m", &O::match_distance_start_m)
      .Number("robust_scale_m", "m", &O::robust_scale_m)
      .Number("max_range_m", "m", &O::max_range_m)
      .Number("search_sigmas", "", &O::search_sigmas)
      .Degrees("search_window_max_deg", &O::search_window_max_rad)
      .Degrees("search_step_deg", &O::search_step_rad)
      .Choice("matcher", &O::matcher, {nav::ScanMatcher::kHeading, nav::ScanMatcher::kCorrelative}, nav::ScanMatcherName)
      .Number("search_window_xy_m", "m", &O::search_window_xy_m)
      .Number("search_sigma_m", "m", &O::search_sigma_m)
      .Number("search_prior_weight", "", &O::search_prior_weight)
      .Number("refine_starts", "", &O::refine_starts)
      .Number("refine_prune_iterations", "", &O::refine_prune_iterations)
      .Number("refine_prune_fraction", "", &O::refine_prune_fraction)
      .Number("scan_latency_s", "s", &O::scan_latency_s)
      .Number("recovery_fit", "", &O::recovery_fit)
      .Number("turn_noise_rad_per_rad", "rad/rad", &O::turn_noise_rad_per_rad)
      .Number("interval_sigma_xy_m", "m", &O::interval_sigma_xy_m)
      .Degrees("interval_sigma_theta_deg", &O::interval_sigma_theta_rad)
      .Number("interval_full_m", "m", &O::interval_full_m)
      .Degrees("interval_full_deg", &O::interval_full_rad)
      .Flag("motion_noise_per_scan", &O::motion_noise_per_scan)
      .Flag("stale_odometry", &O::stale_odometry)
      .Number("stale_fraction", "", &O::stale_fraction)
      .Number("hypothesis_odds", "", &O::hypothesis_odds)
      .Number("match_sigma_xy_m", "m", &O::match_sigma_xy_m)
      .Degrees("match_sigma_theta_deg", &O::match_sigma_theta_rad)
      .Number("gate_mahalanobis2", "", &O::gate_mahalanobis2)
      .Number("gate_full_fit", "", &O::gate_full_fit)
      .Number("max_ambiguity", "", &O::max_ambiguity)
      .Flag("ambiguous_update", &O::ambiguous_update)
      .Flag("wall_orientation", &O::wall_orientation)
      .Degrees("wall_window_deg", &O::wall_window_rad)
      .Degrees("wall_kernel_deg", &O::wall_kernel_rad)
      .Degrees("wall_sigma_deg", &O::wall_sigma_rad)
      .Number("wall_min_contrast", "", &O::wall_min_contrast)
      .Number("wall_min_map_points", "", &O::wall_min_map_points)
      .Number("wall_gate_mahalanobis2", "", &O::wall_gate_mahalanobis2)
      .Number("min_fit", "", &O::min_fit)
      .Flag("adaptive_motion_noise", &O::adaptive_motion_noise)
      .Number("adaptive_window_scans", "", &O::adaptive_window_scans)
      .Number("adaptive_scale_min", "", &O::adaptive_scale_min)
      .Number("adaptive_scale_max", "", &O::adaptive_scale_max)
      .Flag("odometry_calibration", [](auto& o) -> auto& { return o.odometry_calibration.apply; })
      .Number("odometry_calibration_memory_m", "m", [](auto& o) -> auto& { return o.odometry_calibration.memory_m; })
      .Degrees("odometry_calibration_prior_drift_deg_per_m",
               [](auto& o) -> auto& { return o.odometry_calibration.prior_drift_rad_per_m; }, "deg/m")
      .Number("odometry_calibration_prior_turn_scale", "", [](auto& o) -> auto& { return o.odometry_calibration.prior_turn_scale; })
      .Number("odometry_calibration_prior_distance_scale", "",
              [](auto& o) -> auto& { return o.odometry_calibration.prior_distance_scale; })
      .Number("odometry_calibration_stretch_m", "m", [](auto& o) -> auto& { return o.odometry_calibration.segment_m; })
      .Degrees("odometry_calibration_stretch_deg", [](auto& o) -> auto& { return o.odometry_calibration.segment_rad; })
      .Flag("odometry_calibration_noise", [](auto& o) -> auto& { return o.odometry_calibration.noise; })
      .Number("odometry_calibration_noise_min", "", [](auto& o) -> auto& { return o.odometry_calibration.noise_scale_min; })
      .Number("outlier_scale", "", &O::outlier_scale)
      .Number("outlier_min_fit", "", &O::outlier_min_fit)
      .Number("update_score_margin", "", &O::update_score_margin)
      .Number("icp_iterations", "", &O::icp_iterations)
      .Number("icp_convergence_m", "m", &O::icp_convergence_m)
      .Number("point_sigma_m", "m", &O::point_sigma_m)
      .Degrees("point_sigma_deg", &O::point_sigma_rad)
      .Number("min_matches", "", &O::min_matches)
      .Number("map_resolution_m", "m", &O::map_resolution_m)
      .Number("add_distance_m", "m", &O::add_distance_m)
      .Number("scan_step", "", &O::scan_step)
      .Number("lookup_cell_m", "m", &O::lookup_cell_m);
  return table;
}

const OptionTable<nav::GraphSlamOptions>& GraphSlamOptionTable() {
  using G = nav::GraphSlamOptions;
  static const auto table = OptionTable<G>()
      .Number("graph_keyframe_distance_m", "m", &G::keyframe_distance_m)
      .Degrees("graph_keyframe_angle_deg", &G::keyframe_angle_rad)
      .Number("graph_keyframe_reuse_m", "m", &G::keyframe_reuse_m)
      .Degrees("graph_keyframe_reuse_deg", &G::keyframe_reuse_rad)
      .Number("graph_keyframes_per_place", "", &G::keyframes_per_place)
      .Number("graph_edge_sigma_xy_m", "m", &G::edge_sigma_xy_m)
      .Number("graph_edge_sigma_xy_per_m", "1/m", &G::edge_sigma_xy_per_m)
      .Degrees("graph_edge_sigma_theta_deg", &G::edge_sigma_theta_rad)
      .Degrees("graph_edge_sigma_theta_deg_per_m", &G::edge_sigma_theta_per_m, "deg/m")
      .Number("graph_local_map_m", "m", &G::local_map_m)
      .Number("graph_frontend_reset_m", "m", &G::frontend_reset_m)
      .Degrees("graph_frontend_reset_deg", &G::frontend_reset_rad)
      .Number("graph_loop_min_travel_m", "m", &G::loop_min_travel_m)
      .Number("graph_loop_distance_m", "m", &G::loop_distance_m)
      .Number("graph_loop_search_sigmas", "", &G::loop_search_sigmas)
      .Number("graph_loop_window_min_m", "m", &G::loop_window_min_m)
      .Number("graph_loop_window_max_m", "m", &G::loop_window_max_m)
      .Degrees("graph_loop_window_min_deg", &G::loop_window_min_rad)
      .Degrees("graph_loop_window_max_deg", &G::loop_window_max_rad)
      .Number("graph_loop_submap_m", "m", &G::loop_submap_m)
      .Number("graph_loop_submap_sigma_m", "m", &G::loop_submap_sigma_m)
      .Number("graph_loop_max_range_m", "m", &G::loop_max_range_m)
      .Number("graph_loop_candidates", "", &G::loop_candidates)
      .Number("graph_loop_cell_m", "m", [](auto& o) -> auto& { return o.loop_search.cell_m; })
      .Number("graph_loop_sigma_m", "m", [](auto& o) -> auto& { return o.loop_search.sigma_m; })
      .Number("graph_loop_levels", "", [](auto& o) -> auto& { return o.loop_search.levels; })
      .Degrees("graph_loop_step_deg", [](auto& o) -> auto& { return o.loop_search.step_rad; })
      .Number("graph_loop_exclusion_m", "m", [](auto& o) -> auto& { return o.loop_search.exclusion_m; })
      .Degrees("graph_loop_exclusion_deg", [](auto& o) -> auto& { return o.loop_search.exclusion_rad; })
      .Number("graph_loop_ambiguity_floor", "", [](auto& o) -> auto& { return o.loop_search.ambiguity_floor; })
      .Number("graph_loop_scan_cell_m", "m", &G::loop_scan_cell_m)
      .Number("graph_loop_query_m", "m", &G::loop_query_m)
      .Degrees("graph_loop_max_turn_rate_deg_s", &G::loop_max_turn_rate_rad_s, "deg/s")
      .Number("graph_loop_min_score", "", &G::loop_min_score)
      .Number("graph_loop_min_fit", "", &G::loop_min_fit)
      .Number("graph_loop_max_ambiguity", "", &G::loop_max_ambiguity)
      .Number("graph_loop_gate_mahalanobis2", "", &G::loop_gate_mahalanobis2)
      .Number("graph_loop_confident_sigma_m", "m", &G::loop_confident_sigma_m)
      .Number("graph_loop_pending_keyframes", "", &G::loop_pending_keyframes)
      .Number("graph_loop_alone_min_score", "", &G::loop_alone_min_score)
      .Number("graph_loop_sigma_xy_m", "m", &G::loop_sigma_xy_m)
      .Degrees("graph_loop_sigma_theta_deg", &G::loop_sigma_theta_rad)
      .Number("graph_optimizer_iterations", "", &G::optimizer_iterations)
      .Number("graph_closure_chi2_max", "", &G::closure_chi2_max)
      .Number("graph_optimize_min_m", "m", &G::optimize_min_m)
      .Degrees("graph_optimize_min_deg", &G::optimize_min_rad)
      .Number("graph_optimize_every", "", &G::optimize_every)
      .Flag("graph_loop_async", &G::loop_async)
      .Number("graph_loop_async_scans", "", &G::loop_async_scans);
  return table;
}

nav::LaserSlamOptions ReadLaserSlamOptions(const IniFile& ini, const std::string& section) {
  return LaserSlamOptionTable().Read(ini, section);
}

void PrintLaserSlamOptions(std::ostream& out, const nav::LaserSlamOptions& options) {
  LaserSlamOptionTable().Print(out, options);
}

nav::GraphSlamOptions ReadGraphSlamOptions(const IniFile& ini, const std::string& section) {
  return GraphSlamOptionTable().Read(ini, section);
}

void PrintGraphSlamOptions(std::ostream& out, const nav::GraphSlamOptions& options) {
  GraphSlamOptionTable().Print(out, options);
}

}  // namespace snapnav::glue
