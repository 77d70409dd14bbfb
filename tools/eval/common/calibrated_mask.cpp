#include "calibrated_mask.hpp"

#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "calibrate_mirror.hpp"
#include "snapnav/nav/homing/image_mask.hpp"
#include "snapnav/nav/homing/mirror_calibration.hpp"

namespace snapnav::eval {

cv::Mat CalibratedMask(const nav::sim::Scene& scene, const nav::sim::OmniCameraOptions& camera, uint64_t seed,
                       int frames, std::string* note) {
  const int cells = scene.grid.nx * scene.grid.ny;
  if (cells < 3) throw std::runtime_error("scene '" + scene.name + "': no grid to take calibration frames at");
  const int n = std::min(frames, cells);
  nav::sim::OmniRenderer renderer(scene, camera);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> heading(-M_PI, M_PI);
  std::vector<cv::Mat> views;
  for (int k = 0; k < n; ++k) {
    const int cell = static_cast<int>(static_cast<int64_t>(k) * cells / n);
    const Eigen::Vector2d p = scene.grid.Position(cell % scene.grid.nx, cell / scene.grid.nx);
    cv::Mat image;
    renderer.RenderOmni({p.x(), p.y(), heading(rng)}, {}, &image);
    views.push_back(image);
  }
  std::string why;
  const auto cal = nav::CalibrateMirror(calibrate::MeanImage(views),
                                        nav::MirrorProfile::FromMirror(camera.ReportedMirror()), {}, &why);
  if (!cal) throw std::runtime_error("--mask calibrated: no mirror rim found on the rendered frames: " + why);
  nav::OcclusionStats stats;
  cv::Mat mask = nav::SelfOcclusionMask(views, cal->mirror, nav::OcclusionOptions(), &stats);
  if (note) {
    std::ostringstream s;
    s.precision(1);
    s << std::fixed << 100 * stats.masked_fraction << " % of the ring from " << stats.frames << " frames";
    *note = s.str();
  }
  return mask;
}

cv::Mat TruthMask(const cv::Mat& parts_mask) {
  return nav::GrowMasked(parts_mask, nav::OcclusionOptions().grow_px, false);
}

std::string MaskOrDefault(const std::string& flag, const nav::sim::OmniCameraOptions& camera) {
  if (!flag.empty()) return flag;
  return camera.optics.enabled ? "calibrated" : "none";
}

}  // namespace snapnav::eval
