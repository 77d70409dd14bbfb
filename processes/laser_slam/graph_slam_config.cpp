#include "graph_slam_config.hpp"

#include <ostream>
#include <stdexcept>

namespace snapnav::processes {
namespace {

constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;

}  // namespace

const char* SlamBackendName(SlamBackend b) {
  switch (b) {
    case SlamBackend::kEkf: return "ekf";
    case SlamBackend::kGraph: return "graph";
  }
  return "?";
}

std::optional<SlamBackend> ParseSlamBackend(const std::string& name) {
  if (name == "ekf") return SlamBackend::kEkf;
  if (name == "graph") return SlamBackend::kGraph;
  return std::nullopt;
}

nav::GraphSlamOptions ReadGraphSlamOptions(const glue::IniFile& ini, const std::string& section) {
  const char* s = section.c_str();
  nav::GraphSlamOptions o;
  const auto deg = [&](const char* key) { return ini.GetDouble(s, key) / kDegPerRad; };
  o.keyframe_distance_m = ini.GetDouble(s, "graph_keyframe_distance_m");
  o.keyframe_angle_rad = deg("graph_keyframe_angle_deg");
  o.keyframe_reuse_m = ini.GetDouble(s, "graph_keyframe_reuse_m");
  o.keyframe_reuse_rad = deg("graph_keyframe_reuse_deg");
  o.edge_sigma_xy_m = ini.GetDouble(s, "graph_edge_sigma_xy_m");
  o.edge_sigma_xy_per_m = ini.GetDouble(s, "graph_edge_sigma_xy_per_m");
  o.edge_sigma_theta_rad = deg("graph_edge_sigma_theta_deg");
  o.edge_sigma_theta_per_m = deg("graph_edge_sigma_theta_deg_per_m");
  o.local_map_m = ini.GetDouble(s, "graph_local_map_m");
  o.frontend_reset_m = ini.GetDouble(s, "graph_frontend_reset_m");
  o.frontend_reset_rad = deg("graph_frontend_reset_deg");
  o.loop_min_travel_m = ini.GetDouble(s, "graph_loop_min_travel_m");
  o.loop_distance_m = ini.GetDouble(s, "graph_loop_distance_m");
  o.loop_search_sigmas = ini.GetDouble(s, "graph_loop_search_sigmas");
  o.loop_window_min_m = ini.GetDouble(s, "graph_loop_window_min_m");
  o.loop_window_max_m = ini.GetDouble(s, "graph_loop_window_max_m");
  o.loop_window_min_rad = deg("graph_loop_window_min_deg");
  o.loop_window_max_rad = deg("graph_loop_window_max_deg");
  o.loop_submap_m = ini.GetDouble(s, "graph_loop_submap_m");
  o.loop_submap_sigma_m = ini.GetDouble(s, "graph_loop_submap_sigma_m");
  o.loop_max_range_m = ini.GetDouble(s, "graph_loop_max_range_m");
  o.loop_candidates = ini.GetInt(s, "graph_loop_candidates");
  o.loop_search.cell_m = ini.GetDouble(s, "graph_loop_cell_m");
  o.loop_search.sigma_m = ini.GetDouble(s, "graph_loop_sigma_m");
  o.loop_search.levels = ini.GetInt(s, "graph_loop_levels");
  o.loop_search.step_rad = deg("graph_loop_step_deg");
  o.loop_search.exclusion_m = ini.GetDouble(s, "graph_loop_exclusion_m");
  o.loop_search.exclusion_rad = deg("graph_loop_exclusion_deg");
  o.loop_search.ambiguity_floor = ini.GetDouble(s, "graph_loop_ambiguity_floor");
  o.loop_scan_cell_m = ini.GetDouble(s, "graph_loop_scan_cell_m");
  o.loop_query_m = ini.GetDouble(s, "graph_loop_query_m");
  o.loop_max_turn_rate_rad_s = deg("graph_loop_max_turn_rate_deg_s");
  o.loop_min_score = ini.GetDouble(s, "graph_loop_min_score");
  o.loop_min_fit = ini.GetDouble(s, "graph_loop_min_fit");
  o.loop_max_ambiguity = ini.GetDouble(s, "graph_loop_max_ambiguity");
  o.loop_gate_mahalanobis2 = ini.GetDouble(s, "graph_loop_gate_mahalanobis2");
  o.loop_confident_sigma_m = ini.GetDouble(s, "graph_loop_confident_sigma_m");
  o.loop_pending_keyframes = ini.GetInt(s, "graph_loop_pending_keyframes");
  o.loop_alone_min_score = ini.GetDouble(s, "graph_loop_alone_min_score");
  o.loop_sigma_xy_m = ini.GetDouble(s, "graph_loop_sigma_xy_m");
  o.loop_sigma_theta_rad = deg("graph_loop_sigma_theta_deg");
  o.optimizer_iterations = ini.GetInt(s, "graph_optimizer_iterations");
  o.closure_chi2_max = ini.GetDouble(s, "graph_closure_chi2_max");
  o.optimize_min_m = ini.GetDouble(s, "graph_optimize_min_m");
  o.optimize_min_rad = deg("graph_optimize_min_deg");
  o.optimize_every = ini.GetInt(s, "graph_optimize_every");
  o.loop_async = ini.GetBool(s, "graph_loop_async");
  o.loop_async_scans = ini.GetInt(s, "graph_loop_async_scans");
  ini.Check([&o] { o.Validate(); });
  return o;
}

void PrintGraphSlamOptions(std::ostream& out, const nav::GraphSlamOptions& o) {
  out << "graph_keyframe_distance_m = " << o.keyframe_distance_m
      << "\ngraph_keyframe_angle_deg = " << o.keyframe_angle_rad * kDegPerRad
      << "\ngraph_keyframe_reuse_m = " << o.keyframe_reuse_m
      << "\ngraph_keyframe_reuse_deg = " << o.keyframe_reuse_rad * kDegPerRad
      << "\ngraph_edge_sigma_xy_m = " << o.edge_sigma_xy_m << "\ngraph_edge_sigma_xy_per_m = " << o.edge_sigma_xy_per_m
      << "\ngraph_edge_sigma_theta_deg = " << o.edge_sigma_theta_rad * kDegPerRad
      << "\ngraph_edge_sigma_theta_deg_per_m = " << o.edge_sigma_theta_per_m * kDegPerRad
      << "\ngraph_local_map_m = " << o.local_map_m << "\ngraph_frontend_reset_m = " << o.frontend_reset_m
      << "\ngraph_frontend_reset_deg = " << o.frontend_reset_rad * kDegPerRad
      << "\ngraph_loop_min_travel_m = " << o.loop_min_travel_m << "\ngraph_loop_distance_m = " << o.loop_distance_m
      << "\ngraph_loop_search_sigmas = " << o.loop_search_sigmas
      << "\ngraph_loop_window_min_m = " << o.loop_window_min_m << "\ngraph_loop_window_max_m = " << o.loop_window_max_m
      << "\ngraph_loop_window_min_deg = " << o.loop_window_min_rad * kDegPerRad
      << "\ngraph_loop_window_max_deg = " << o.loop_window_max_rad * kDegPerRad
      << "\ngraph_loop_submap_m = " << o.loop_submap_m << "\ngraph_loop_submap_sigma_m = " << o.loop_submap_sigma_m << "\ngraph_loop_max_range_m = " << o.loop_max_range_m
      << "\ngraph_loop_candidates = " << o.loop_candidates << "\ngraph_loop_cell_m = " << o.loop_search.cell_m
      << "\ngraph_loop_sigma_m = " << o.loop_search.sigma_m << "\ngraph_loop_levels = " << o.loop_search.levels
      << "\ngraph_loop_step_deg = " << o.loop_search.step_rad * kDegPerRad
      << "\ngraph_loop_exclusion_m = " << o.loop_search.exclusion_m
      << "\ngraph_loop_exclusion_deg = " << o.loop_search.exclusion_rad * kDegPerRad
      << "\ngraph_loop_ambiguity_floor = " << o.loop_search.ambiguity_floor
      << "\ngraph_loop_scan_cell_m = " << o.loop_scan_cell_m << "\ngraph_loop_query_m = " << o.loop_query_m
      << "\ngraph_loop_max_turn_rate_deg_s = " << o.loop_max_turn_rate_rad_s * kDegPerRad << "\ngraph_loop_min_score = " << o.loop_min_score
      << "\ngraph_loop_min_fit = " << o.loop_min_fit << "\ngraph_loop_max_ambiguity = " << o.loop_max_ambiguity
      << "\ngraph_loop_gate_mahalanobis2 = " << o.loop_gate_mahalanobis2
      << "\ngraph_loop_confident_sigma_m = " << o.loop_confident_sigma_m
      << "\ngraph_loop_pending_keyframes = " << o.loop_pending_keyframes
      << "\ngraph_loop_alone_min_score = " << o.loop_alone_min_score
      << "\ngraph_loop_sigma_xy_m = " << o.loop_sigma_xy_m
      << "\ngraph_loop_sigma_theta_deg = " << o.loop_sigma_theta_rad * kDegPerRad
      << "\ngraph_optimizer_iterations = " << o.optimizer_iterations
      << "\ngraph_closure_chi2_max = " << o.closure_chi2_max << "\ngraph_optimize_min_m = " << o.optimize_min_m
      << "\ngraph_optimize_min_deg = " << o.optimize_min_rad * kDegPerRad << "\ngraph_optimize_every = " << o.optimize_every
      << "\ngraph_loop_async = " << (o.loop_async ? "true" : "false")
      << "\ngraph_loop_async_scans = " << o.loop_async_scans << "\n";
}

}  // namespace snapnav::processes
