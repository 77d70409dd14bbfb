#include "homing_eval.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "calibrated_mask.hpp"
#include "snapnav/glue/image_msg.hpp"

#include "snapnav/nav/sim/world.hpp"
#include "snapnav/nav/landmarks/view_fusion.hpp"

namespace snapnav::eval {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
using Clock = std::chrono::steady_clock;

// People of the scene (if any) walking between images: one world steps them around the robot,
// which stands where the camera is (they walk around it, never through it).
class Crowd {
 public:
  Crowd(const nav::sim::Scene& scene, uint64_t seed) : world_(scene, {}, {}, seed) {}
  // People after dt_s of walking (0.1 s steps) with the robot standing at `robot`.
  const std::vector<nav::sim::Cylinder>& Advance(double dt_s, const nav::Pose2& robot) {
    world_.SetTruePose(robot);
    const int steps = std::max(1, static_cast<int>(std::lround(dt_s / 0.1)));
    for (int i = 0; i < steps; ++i) world_.Step(0, 0, 0.1);
    return world_.people();
  }

 private:
  nav::sim::World world_;
};

}  // namespace

ViewRenderer::ViewRenderer(const nav::sim::Scene& scene, const nav::sim::OmniCameraOptions& camera, uint64_t seed)
    : scene_(&scene),
      camera_(camera),
      renderer_(scene, camera),
      unwrapper_(camera.ReportedMirror(), camera.panorama, cv::Size(camera.omni_width_px, camera.omni_height_px)),
      rng_(seed) {}

cv::Mat ViewRenderer::Sensor(const nav::Pose2& pose, CameraPipeline::Input input,
                             const std::vector<nav::sim::Cylinder>& people) {
  cv::Mat image;
  if (input == CameraPipeline::Input::kRaw) renderer_.RenderOmni(pose, people, &image);
  else renderer_.RenderPanorama(pose, people, &image);
  return image;
}

cv::Mat ViewRenderer::ToPanorama(const cv::Mat& sensor, const CameraPipeline& pipeline) {
  cv::Mat image = sensor.clone();
  nav::sim::ApplyImageEffects(pipeline.effects, rng_, &image);
  if (pipeline.low_resolution_scale < 1.0) {
    cv::Mat small;
    cv::resize(image, small, cv::Size(), pipeline.low_resolution_scale, pipeline.low_resolution_scale, cv::INTER_NEAREST);
    cv::resize(small, image, sensor.size(), 0, 0, cv::INTER_NEAREST);
  }
  if (pipeline.input == CameraPipeline::Input::kPanorama) return image;
  cv::Mat pano;
  unwrapper_.Unwrap(image, &pano);
  return pano;
}

void HomingMethod::SetMask(const cv::Mat& panorama_mask) {
  if (!panorama_mask.empty()) throw std::logic_error(name() + " does not take a mask");
}

cv::Mat RawMask(const std::string& source, const ViewRenderer& renderer, cv::Size raw_size, uint64_t seed) {
  if (source == "none" || source.empty()) return {};
  if (source == "calibrated") return CalibratedMask(renderer.scene(), renderer.camera(), seed);
  if (source == "truth") return TruthMask(renderer.PartsMask());
  return glue::LoadMask(source, raw_size);  // no such file, not an image, another size: an error naming it
}

cv::Mat UseRawMask(const cv::Mat& raw_mask, ViewRenderer& renderer) {
  renderer.SetMask(raw_mask);
  return raw_mask.empty() ? cv::Mat() : renderer.panorama_mask();
}

cv::Mat UseMask(const std::string& source, ViewRenderer& renderer, cv::Size raw_size, uint64_t seed) {
  return UseRawMask(RawMask(source, renderer, raw_size, seed), renderer);
}

GridDatabase RenderGrid(const nav::sim::Scene& scene, ViewRenderer& renderer, const GridOptions& options,
                        const std::function<void(int, int)>& progress) {
  if (scene.grid.nx < 1 || scene.grid.ny < 1) throw std::runtime_error("scene '" + scene.name + "' defines no grid");
  GridDatabase db;
  db.nx = scene.grid.nx;
  db.ny = scene.grid.ny;
  const Eigen::Vector2d home = options.home.value_or(scene.grid.Position(db.nx / 2, db.ny / 2));
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> heading(-M_PI, M_PI);
  double best = std::numeric_limits<double>::infinity();
  for (int iy = 0; iy < db.ny; ++iy) {
    for (int ix = 0; ix < db.nx; ++ix) {
      const Eigen::Vector2d p = scene.grid.Position(ix, iy);
      db.poses.push_back({p.x(), p.y(), options.random_headings ? heading(rng) : 0.0});
      const double d = (p - home).norm();
      if (d < best) {
        best = d;
        db.home_index = static_cast<int>(db.poses.size()) - 1;
      }
    }
  }
  if (best > 1e-6) {
    throw std::runtime_error("home (" + std::to_string(home.x()) + ", " + std::to_string(home.y()) +
                             ") is not a grid position of scene '" + scene.name + "'");
  }
  db.poses[db.home_index].theta_rad = 0;
  db.home = db.poses[db.home_index];
  options.frames.Validate();
  const bool people = scene.people.count > 0;
  Crowd crowd(scene, options.seed);
  for (size_t i = 0; i < db.poses.size(); ++i) {
    db.people.push_back(people ? crowd.Advance(2.0, db.poses[i]) : std::vector<nav::sim::Cylinder>{});
    db.sensor.push_back(renderer.Sensor(db.poses[i], options.input, db.people.back()));
    const bool at_home = static_cast<int>(i) == db.home_index;
    const int frames = at_home ? options.frames.home_frames : options.frames.current_frames;
    const double interval = at_home ? options.frames.home_interval_s : options.frames.current_interval_s;
    db.more_sensor.emplace_back();
    db.more_people.emplace_back();
    Crowd still = crowd;  // the robot stays; the main crowd goes on as without these frames
    for (int k = 1; k < frames; ++k) {
      db.more_people.back().push_back(people ? still.Advance(interval, db.poses[i]) : db.people.back());
      db.more_sensor.back().push_back(renderer.Sensor(db.poses[i], options.input, db.more_people.back().back()));
    }
    if (progress) progress(static_cast<int>(i) + 1, static_cast<int>(db.poses.size()));
  }
  return db;
}

void FrameProtocol::Validate() const {
  if (home_frames < 1 || current_frames < 1 || !(home_interval_s > 0) || !(current_interval_s > 0)) {
    throw std::invalid_argument("frames: home_frames and current_frames must be >= 1, the intervals > 0");
  }
}

void HogMethod::SetHomeFrames(const std::vector<cv::Mat>& frames) {
  SetHome(median_frames_ && frames.size() > 1 ? nav::MedianImage(frames) : frames.front());
}

std::optional<nav::HomingEstimate> HogMethod::HomeFrames(const std::vector<cv::Mat>& frames) {
  return Home(median_frames_ && frames.size() > 1 ? nav::MedianImage(frames) : frames.front());
}

GridResult EvaluatePanoramas(const GridDatabase& db, const std::vector<cv::Mat>& panoramas, HomingMethod& method) {
  std::vector<std::vector<cv::Mat>> frames;
  frames.reserve(panoramas.size());
  for (const auto& p : panoramas) frames.push_back({p});
  return EvaluateFrames(db, frames, method);
}

GridResult EvaluateFrames(const GridDatabase& db, const std::vector<std::vector<cv::Mat>>& frames, HomingMethod& method) {
  if (frames.size() != db.poses.size()) throw std::invalid_argument("homing evaluation: one frame list per grid position");
  for (const auto& f : frames) {
    if (f.empty()) throw std::invalid_argument("homing evaluation: a grid position without frames");
  }
  GridResult r;
  method.SetHomeFrames(frames[db.home_index]);
  const Eigen::Vector2d home(db.home.x_m, db.home.y_m);
  std::vector<double> errors, compass;
  for (size_t i = 0; i < db.poses.size(); ++i) {
    const nav::Pose2& pose = db.poses[i];
    if (static_cast<int>(i) == db.home_index) {
      r.error_rad.push_back(kNaN);
      r.direction_world_rad.push_back(kNaN);
      r.compass_error_rad.push_back(kNaN);
      continue;
    }
    const auto t0 = Clock::now();
    const auto e = method.HomeFrames(frames[i]);
    r.seconds_in_method += std::chrono::duration<double>(Clock::now() - t0).count();
    ++r.method_calls;
    const double truth = std::atan2(home.y() - pose.y_m, home.x() - pose.x_m);
    double error = M_PI, world = kNaN, compass_error = kNaN;
    if (e) {
      world = nav::WrapAngle(e->direction_rad + pose.theta_rad);
      error = std::abs(nav::WrapAngle(world - truth));
      // The compass reports the heading of the current view relative to home (heading 0 in a
      // rendered grid; a lab's grid folder has its own).
      compass_error = std::abs(nav::WrapAngle(e->compass_rotation_rad - (pose.theta_rad - db.home.theta_rad)));
      compass.push_back(compass_error);
    } else {
      ++r.failures;
    }
    r.error_rad.push_back(error);
    r.direction_world_rad.push_back(world);
    r.compass_error_rad.push_back(compass_error);
    errors.push_back(error);
  }
  r.positions = static_cast<int>(errors.size());
  if (!errors.empty()) {
    double sum = 0;
    for (double e : errors) sum += e;
    r.aae_deg = sum / errors.size() * 180 / M_PI;
    std::sort(errors.begin(), errors.end());
    r.median_deg = errors[errors.size() / 2] * 180 / M_PI;
    r.max_deg = errors.back() * 180 / M_PI;
  }
  if (!compass.empty()) {
    double sum = 0;
    for (double c : compass) sum += c;
    r.compass_mean_deg = sum / compass.size() * 180 / M_PI;
  }
  return r;
}

ReturnResult EvaluateReturn(const GridDatabase& db, HomingMethod& method, ViewRenderer& renderer,
                            const CameraPipeline& pipeline, const ReturnOptions& options,
                            const std::function<void(int, int)>& progress,
                            const std::vector<std::vector<cv::Mat>>* panorama_frames) {
  options.frames.Validate();
  if (options.start_stride < 1) throw std::invalid_argument("return runs: start_stride must be >= 1");
  ReturnResult result;
  const nav::sim::Scene& scene = renderer.scene();
  const bool people = scene.people.count > 0;
  // The home view as the grid evaluation has it: its first home_frames frames.
  auto db_frames = [&](size_t i, int n) {
    if (panorama_frames) {
      const auto& all = (*panorama_frames)[i];
      return std::vector<cv::Mat>(all.begin(), all.begin() + std::clamp<int>(n, 1, static_cast<int>(all.size())));
    }
    std::vector<cv::Mat> f{renderer.ToPanorama(db.sensor[i], pipeline)};
    for (int k = 1; k < n && i < db.more_sensor.size() && k - 1 < static_cast<int>(db.more_sensor[i].size()); ++k) {
      f.push_back(renderer.ToPanorama(db.more_sensor[i][k - 1], pipeline));
    }
    return f;
  };
  method.SetHomeFrames(db_frames(db.home_index, options.frames.home_frames));
  const Eigen::Vector2d home(db.home.x_m, db.home.y_m);
  double path_ratio_sum = 0;
  std::vector<size_t> starts;
  int eligible = 0;
  for (size_t i = 0; i < db.poses.size(); ++i) {
    if ((Eigen::Vector2d(db.poses[i].x_m, db.poses[i].y_m) - home).norm() > options.success_radius_m + 1e-9) {
      if (eligible++ % options.start_stride == 0) starts.push_back(i);
    }
  }
  for (size_t k = 0; k < starts.size(); ++k) {
    nav::Pose2 pose = db.poses[starts[k]];
    ReturnRun run;
    const double straight = (Eigen::Vector2d(pose.x_m, pose.y_m) - home).norm();
    run.path.push_back({pose.x_m, pose.y_m});
    // The crowd of this run walks around the robot; the first view is the database's.
    std::optional<Crowd> crowd;
    if (people) {
      crowd.emplace(scene, options.seed * 1000003 + starts[k]);
      crowd->Advance(options.people_warm_up_s, pose);
    }
    std::vector<cv::Mat> frames = db_frames(starts[k], options.frames.current_frames);
    while (run.path_length_m + options.step_m <= options.max_path_factor * straight + 1e-9) {
      const auto e = method.HomeFrames(frames);
      if (!e) break;
      pose.theta_rad = nav::WrapAngle(pose.theta_rad + e->direction_rad);  // turn towards home, then step
      pose.x_m += options.step_m * std::cos(pose.theta_rad);
      pose.y_m += options.step_m * std::sin(pose.theta_rad);
      run.path_length_m += options.step_m;
      run.path.push_back({pose.x_m, pose.y_m});
      if ((Eigen::Vector2d(pose.x_m, pose.y_m) - home).norm() <= options.success_radius_m) {
        run.success = true;
        break;
      }
      frames.clear();
      std::vector<nav::sim::Cylinder> walkers;
      if (crowd) walkers = crowd->Advance(options.people_dt_s, pose);
      frames.push_back(renderer.ToPanorama(renderer.Sensor(pose, pipeline.input, walkers), pipeline));
      for (int f = 1; f < options.frames.current_frames; ++f) {
        if (crowd) walkers = crowd->Advance(options.frames.current_interval_s, pose);
        frames.push_back(renderer.ToPanorama(renderer.Sensor(pose, pipeline.input, walkers), pipeline));
      }
    }
    if (run.success) {
      ++result.successes;
      path_ratio_sum += run.path_length_m / std::max(1e-9, straight - options.success_radius_m);
    }
    result.runs.push_back(std::move(run));
    if (progress) progress(static_cast<int>(k) + 1, static_cast<int>(starts.size()));
  }
  result.starts = static_cast<int>(starts.size());
  result.ratio = result.starts ? static_cast<double>(result.successes) / result.starts : 0.0;
  result.mean_path_ratio = result.successes ? path_ratio_sum / result.successes : 0.0;
  return result;
}

cv::Mat DrawVectorMap(const GridDatabase& db, const GridResult& result, const std::string& title,
                      const ReturnResult* paths) {
  double xmin = 1e9, xmax = -1e9, ymin = 1e9, ymax = -1e9;
  for (const auto& p : db.poses) {
    xmin = std::min(xmin, p.x_m); xmax = std::max(xmax, p.x_m);
    ymin = std::min(ymin, p.y_m); ymax = std::max(ymax, p.y_m);
  }
  if (paths) {
    for (const auto& run : paths->runs) {
      for (const auto& p : run.path) {
        xmin = std::min(xmin, p.x()); xmax = std::max(xmax, p.x());
        ymin = std::min(ymin, p.y()); ymax = std::max(ymax, p.y());
      }
    }
  }
  const double spacing = db.nx > 1 ? (db.poses[1].x_m - db.poses[0].x_m) : 0.2;
  const double margin = spacing * 1.0;
  xmin -= margin; xmax += margin; ymin -= margin; ymax += margin;
  const int size = 720, top = 50;
  const double scale = (size - 40) / std::max(xmax - xmin, ymax - ymin);
  cv::Mat img(size + top, size, CV_8UC3, cv::Scalar(255, 255, 255));
  auto px = [&](double x, double y) {
    return cv::Point(static_cast<int>(20 + (x - xmin) * scale), static_cast<int>(top + size - 20 - (y - ymin) * scale));
  };
  // The title at 0.6, smaller when it would not fit.
  int baseline = 0;
  const double title_width = cv::getTextSize(title, cv::FONT_HERSHEY_SIMPLEX, 0.6, 1, &baseline).width;
  const double title_scale = std::min(0.6, 0.6 * (size - 24) / std::max(1.0, title_width));
  cv::putText(img, title, {12, 30}, cv::FONT_HERSHEY_SIMPLEX, title_scale, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  if (paths) {
    for (const auto& run : paths->runs) {
      const cv::Scalar c = run.success ? cv::Scalar(200, 200, 200) : cv::Scalar(160, 160, 255);
      for (size_t i = 1; i < run.path.size(); ++i) {
        cv::line(img, px(run.path[i - 1].x(), run.path[i - 1].y()), px(run.path[i].x(), run.path[i].y()), c, 1, cv::LINE_AA);
      }
    }
  }
  const double arrow = spacing * 0.8 * scale;
  for (size_t i = 0; i < db.poses.size(); ++i) {
    const auto& p = db.poses[i];
    const cv::Point a = px(p.x_m, p.y_m);
    if (static_cast<int>(i) == db.home_index) {
      cv::drawMarker(img, a, cv::Scalar(0, 0, 0), cv::MARKER_STAR, 18, 2, cv::LINE_AA);
      continue;
    }
    const double dir = result.direction_world_rad[i];
    if (std::isnan(dir)) {
      cv::drawMarker(img, a, cv::Scalar(0, 0, 255), cv::MARKER_TILTED_CROSS, 8, 1, cv::LINE_AA);
      continue;
    }
    const double err = result.error_rad[i] * 180 / M_PI;
    const cv::Scalar colour = err < 15 ? cv::Scalar(40, 150, 40) : err < 45 ? cv::Scalar(0, 150, 230) : cv::Scalar(30, 30, 220);
    const cv::Point b(a.x + static_cast<int>(arrow * std::cos(dir)), a.y - static_cast<int>(arrow * std::sin(dir)));
    cv::arrowedLine(img, a, b, colour, 2, cv::LINE_AA, 0, 0.3);
  }
  // Legend and scale bar.
  const int ly = top + size - 8;
  cv::putText(img, "error < 15 deg", {20, ly}, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(40, 150, 40), 1, cv::LINE_AA);
  cv::putText(img, "< 45 deg", {150, ly}, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 150, 230), 1, cv::LINE_AA);
  cv::putText(img, ">= 45 deg", {240, ly}, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(30, 30, 220), 1, cv::LINE_AA);
  const int bar = static_cast<int>(0.5 * scale);
  cv::line(img, {size - 30 - bar, ly - 4}, {size - 30, ly - 4}, cv::Scalar(0, 0, 0), 2);
  cv::putText(img, "0.5 m", {size - 30 - bar, ly - 10}, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return img;
}

}  // namespace snapnav::eval
