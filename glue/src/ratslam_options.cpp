#include "snapnav/glue/ratslam_options.hpp"

namespace snapnav::glue {

const OptionTable<nav::RatSlamOptions>& RatSlamOptionTable() {
  using O = nav::RatSlamOptions;
  static const auto table = OptionTable<O>()
      .Number("image_crop_x_min_px", "px", [](auto& o) -> auto& { return o.local_view.image_crop_x_min_px; })
      .Number("image_crop_x_max_px", "px", [](auto& o) -> auto& { return o.local_view.image_crop_x_max_px; })
      .Number("image_crop_y_min_px", "px", [](auto& o) -> auto& { return o.local_view.image_crop_y_min_px; })
      .Number("image_crop_y_max_px", "px", [](auto& o) -> auto& { return o.local_view.image_crop_y_max_px; })
      .Number("template_x_size", "", [](auto& o) -> auto& { return o.local_view.template_x_size; })
      .Number("template_y_size", "", [](auto& o) -> auto& { return o.local_view.template_y_size; })
      .Flag("vt_panoramic", [](auto& o) -> auto& { return o.local_view.vt_panoramic; })
      .Number("vt_shift_match", "", [](auto& o) -> auto& { return o.local_view.vt_shift_match; })
      .Number("vt_step_match", "", [](auto& o) -> auto& { return o.local_view.vt_step_match; })
      .Flag("vt_shift_subcolumn", [](auto& o) -> auto& { return o.local_view.vt_shift_subcolumn; })
      .Number("vt_match_threshold", "", [](auto& o) -> auto& { return o.local_view.vt_match_threshold; })
      .Number("vt_normalisation", "", [](auto& o) -> auto& { return o.local_view.vt_normalisation; })
      .Number("vt_patch_normalise", "", [](auto& o) -> auto& { return o.local_view.vt_patch_normalise; })
      .Number("vt_min_patch_normalisation_std", "", [](auto& o) -> auto& { return o.local_view.vt_min_patch_normalisation_std; })
      .Number("pc_dim_xy", "", [](auto& o) -> auto& { return o.pose_cells.pc_dim_xy; })
      .Number("pc_dim_th", "", [](auto& o) -> auto& { return o.pose_cells.pc_dim_th; })
      .Number("pc_w_e_dim", "", [](auto& o) -> auto& { return o.pose_cells.pc_w_e_dim; })
      .Number("pc_w_e_var", "", [](auto& o) -> auto& { return o.pose_cells.pc_w_e_var; })
      .Number("pc_w_i_dim", "", [](auto& o) -> auto& { return o.pose_cells.pc_w_i_dim; })
      .Number("pc_w_i_var", "", [](auto& o) -> auto& { return o.pose_cells.pc_w_i_var; })
      .Number("pc_global_inhib", "", [](auto& o) -> auto& { return o.pose_cells.pc_global_inhib; })
      .Number("pc_cell_x_size_m", "m", [](auto& o) -> auto& { return o.pose_cells.pc_cell_x_size_m; })
      .Number("pc_cells_to_avg", "", [](auto& o) -> auto& { return o.pose_cells.pc_cells_to_avg; })
      .Number("pc_vt_inject_energy", "", [](auto& o) -> auto& { return o.pose_cells.pc_vt_inject_energy; })
      .Number("vt_active_decay", "", [](auto& o) -> auto& { return o.pose_cells.vt_active_decay; })
      .Number("pc_vt_restore", "", [](auto& o) -> auto& { return o.pose_cells.pc_vt_restore; })
      .Number("pc_vt_skip_recent", "", [](auto& o) -> auto& { return o.pose_cells.pc_vt_skip_recent; })
      .Number("exp_delta_pc_threshold", "", [](auto& o) -> auto& { return o.pose_cells.exp_delta_pc_threshold; })
      .Number("pc_update_interval_s", "s", [](auto& o) -> auto& { return o.pose_cells.pc_update_interval_s; })
      .Number("exp_loops", "", [](auto& o) -> auto& { return o.experience_map.exp_loops; })
      .Number("exp_correction", "", [](auto& o) -> auto& { return o.experience_map.exp_correction; });
  return table;
}

nav::RatSlamOptions ReadRatSlamOptions(const IniFile& ini, const std::string& section) {
  return RatSlamOptionTable().Read(ini, section);
}

void PrintRatSlamOptions(std::ostream& out, const nav::RatSlamOptions& options, const std::string& section) {
  out << "[" << section << "]\n";
  RatSlamOptionTable().Print(out, options);
}

}  // namespace snapnav::glue
