// RatSLAM facade: OpenRatSLAM's local view, pose cell and experience map nodes, wired in-process.
#include <cmath>
#include <stdexcept>
#include <string>

#include "snapnav/nav/ratslam/ratslam.hpp"

namespace snapnav::nav {

void RatSlamOptions::Validate() const {
  local_view.Validate();
  pose_cells.Validate();
  experience_map.Validate();
}

RatSlam::RatSlam(const RatSlamOptions& options, const Pose2& start)
    : options_(options),
      view_(options.local_view),
      cells_(options.pose_cells),
      map_(options.experience_map, start) {}

std::optional<Pose2> RatSlam::experience_pose() const {
  if (map_.current() < 0) return std::nullopt;
  return map_.experiences()[static_cast<size_t>(map_.current())].pose;
}

void RatSlam::OnOdometry(const Pose2& delta, double dt_s) {
  if (!std::isfinite(delta.x_m) || !std::isfinite(delta.y_m) || !std::isfinite(delta.theta_rad)) {
    throw std::invalid_argument("ratslam: the odometry increment must be finite");
  }
  if (!std::isfinite(dt_s) || dt_s < 0) throw std::invalid_argument("ratslam: dt_s must be finite and >= 0");
  ++odometry_steps_;
  map_.OnOdometry(delta, dt_s);
  pc_pending_ = pc_pending_.Compose(delta);
  pc_pending_s_ += dt_s;
  if (pc_pending_s_ + 1e-9 < options_.pose_cells.pc_update_interval_s) return;  // (rounding of summed dt)
  // Pose cells: the chord of the increments, from each layer's heading.
  const double translation_m = std::hypot(pc_pending_.x_m, pc_pending_.y_m);
  const double direction_rad = translation_m > 0 ? std::atan2(pc_pending_.y_m, pc_pending_.x_m) : 0.0;
  cells_.OnOdometry(translation_m, direction_rad, pc_pending_.theta_rad);
  pc_pending_ = {};
  pc_pending_s_ = 0;
  // As OpenRatSLAM's experience map node handles the pose cells' TopologicalAction.
  const PoseCellAction action = cells_.GetAction();
  switch (action.kind) {
    case PoseCellAction::kNone:
      return;
    case PoseCellAction::kCreateExperience: {
      const int id = map_.CreateExperience(view_.current(), action.relative_rad);
      if (id != action.experience) {
        throw std::logic_error("ratslam: experience map and pose cells disagree on experience ids (" +
                               std::to_string(id) + " vs " + std::to_string(action.experience) + ")");
      }
      break;
    }
    case PoseCellAction::kLinkExperience:
      if (map_.LinkTo(action.experience, action.relative_rad, /*loop_closure=*/true)) {
        ++loop_closures_;
      } else {
        ++switches_;
      }
      map_.SetExperience(action.experience, action.relative_rad);
      break;
  }
  map_.Relax();
}

RatSlamViewResult RatSlam::OnImage(const cv::Mat& panorama_gray, const cv::Mat& mask) {
  const ViewMatch m = view_.OnImage(panorama_gray, mask);
  cells_.OnViewTemplate(m.template_id, m.relative_rad);
  ++images_;
  RatSlamViewResult r;
  r.template_id = m.template_id;
  r.new_template = m.new_template;
  r.match_difference = m.difference;
  r.relative_rad = m.relative_rad;
  return r;
}

}  // namespace snapnav::nav
