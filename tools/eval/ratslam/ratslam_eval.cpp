#include "ratslam_eval.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <optional>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "json_values.hpp"
#include "results.hpp"
#include "scene_file.hpp"
#include "stats.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/nav/trajectory.hpp"
#include "snapnav/nav/homing/unwrap.hpp"
#include "snapnav/odometry_t.hpp"
#include "snapnav/plot/plot.hpp"

namespace snapnav::eval {
namespace {

using Clock = std::chrono::steady_clock;

TrajectoryErrors ErrorsOf(const std::vector<nav::Pose2>& estimate, const std::vector<nav::Pose2>& truth,
                          double rpe_delta_m) {
  std::vector<std::pair<nav::Pose2, nav::Pose2>> pairs;
  for (size_t i = 0; i < truth.size(); ++i) pairs.push_back({estimate[i], truth[i]});
  TrajectoryErrors t;
  t.ate = nav::ComputeAte(pairs);
  t.ate_aligned = nav::ComputeAte(pairs, nav::AlignSE2(pairs));
  t.rpe = nav::ComputeRpe(pairs, rpe_delta_m);
  return t;
}

// RatSLAM and dead reckoning on the readings, timing each call.
class RatSlamSink : public SimSensorSink {
 public:
  RatSlamSink(const nav::RatSlamOptions& options, RatSlamEvaluation* out) : slam_(options, {}), out_(out) {}

  void OnOdometry(int64_t, const nav::Pose2& delta, double dt_s, const nav::Pose2& truth) override {
    if (have_truth_) travelled_m_ += std::hypot(truth.x_m - last_truth_.x_m, truth.y_m - last_truth_.y_m);
    last_truth_ = truth;
    have_truth_ = true;
    dead_reckoning_ = dead_reckoning_.Compose(delta);
    const int before = slam_.loop_closures();
    const auto t0 = Clock::now();
    slam_.OnOdometry(delta, dt_s);
    odometry_ms_.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    // Experiences are created where the robot is now.
    while (out_->experience_truth.size() < slam_.experience_map().experiences().size()) {
      out_->experience_truth.push_back(truth);
    }
    if (slam_.loop_closures() > before) {
      out_->loop_closure_travel_m.push_back(travelled_m_);
      const nav::ExperienceLink& l = slam_.experience_map().links().back();
      const nav::Pose2& a = out_->experience_truth[static_cast<size_t>(l.from)];
      const nav::Pose2& b = out_->experience_truth[static_cast<size_t>(l.to)];
      out_->loop_closure_true_distance_m.push_back(std::hypot(a.x_m - b.x_m, a.y_m - b.y_m));
    }
  }

  void OnPanoramaMask(const cv::Mat& mask) override { mask_ = mask.clone(); }
  void OnPanorama(int64_t utime, const cv::Mat& gray, const nav::Pose2& truth) override {
    const auto t0 = Clock::now();
    const nav::RatSlamViewResult v = slam_.OnImage(gray, mask_);
    image_ms_.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    RatSlamEvaluation::FrameTrace f;
    f.template_id = v.template_id;
    f.new_template = v.new_template;
    f.difference = v.match_difference.value_or(-1);
    f.relative_rad = v.relative_rad;
    f.experience = slam_.experience_map().current();
    f.pc_x = slam_.pose_cells().best_x();
    f.pc_y = slam_.pose_cells().best_y();
    f.pc_th = slam_.pose_cells().best_th();
    out_->trace.push_back(f);
    out_->utime.push_back(utime);
    out_->truth.push_back(truth);
    out_->ratslam.push_back(slam_.pose());
    const auto e = slam_.experience_pose();
    out_->experience.push_back(e ? *e : (out_->experience.empty() ? nav::Pose2{} : out_->experience.back()));
    out_->dead_reckoning.push_back(dead_reckoning_);
  }

  void Finish() {
    out_->experiences = slam_.experience_map().experiences();
    out_->links = slam_.experience_map().links();
    out_->loop_closures = slam_.loop_closures();
    out_->switches = slam_.experience_switches();
    out_->templates = slam_.templates();
    out_->injections = slam_.pose_cells().injections();
    out_->odometry_ms_median = Median(odometry_ms_);
    out_->odometry_ms_mean = Mean(odometry_ms_);
    out_->image_ms_median = Median(image_ms_);
    out_->image_ms_mean = Mean(image_ms_);
  }

 private:
  nav::RatSlam slam_;
  cv::Mat mask_;  // the panoramas' self-occlusion mask (empty: none)
  RatSlamEvaluation* out_;
  nav::Pose2 dead_reckoning_, last_truth_;
  bool have_truth_ = false;
  double travelled_m_ = 0;
  std::vector<double> odometry_ms_, image_ms_;
};

}  // namespace

int RatSlamEvaluation::false_loop_closures(double max_distance_m) const {
  int n = 0;
  for (double d : loop_closure_true_distance_m) n += d > max_distance_m ? 1 : 0;
  return n;
}

int RatSlamEvaluation::inconsistent_links(double tolerance_m) const {
  int n = 0;
  for (const nav::ExperienceLink& l : links) {
    if (static_cast<size_t>(std::max(l.from, l.to)) >= experience_truth.size()) continue;
    const nav::Pose2& a = experience_truth[static_cast<size_t>(l.from)];
    const nav::Pose2& b = experience_truth[static_cast<size_t>(l.to)];
    if (std::abs(std::hypot(a.x_m - b.x_m, a.y_m - b.y_m) - l.d_m) > tolerance_m) {
      ++n;
      if (std::getenv("RATSLAM_DEBUG")) {
        std::fprintf(stderr, "bad link %d -> %d (loop %d): d %.2f m, true %.2f m; from truth %.2f,%.2f to truth %.2f,%.2f\n",
                     l.from, l.to, l.loop_closure ? 1 : 0, l.d_m, std::hypot(a.x_m - b.x_m, a.y_m - b.y_m), a.x_m, a.y_m,
                     b.x_m, b.y_m);
      }
    }
  }
  return n;
}

void SimCameraOptions::Validate() const {
  sim.Validate();
  EveryNSteps(sim.physics_rate_hz, camera_rate_hz, "camera");
  camera.Validate();
  effects.Validate();
  if (camera.optics.enabled && !raw_frames) {
    throw std::invalid_argument(
        "the realistic camera's optics act on the raw image: a run with it renders raw frames and unwraps them "
        "(raw_frames)");
  }
}

SimCameraOptions SimCameraOptions::FromSimConfig(const processes::SimConfig& config) {
  SimCameraOptions o;
  o.sim = SimSlamOptions::FromSimConfig(config);
  o.camera_rate_hz = config.camera_rate_hz;
  o.camera = config.camera;
  o.effects = config.effects;
  o.raw_frames = config.camera.optics.enabled;  // the realistic camera exists only in raw frames
  return o;
}

namespace {

// The harness's readings for a SimSensorSink: odometry from the second reading on (the first only
// fixes the start, as in the processes), truth in the start frame, every frame.
class SensorSinkAdapter : public SimDriveSink {
 public:
  explicit SensorSinkAdapter(SimSensorSink& sink) : sink_(sink) {}
  void OnStart(const nav::sim::Scene&, const nav::Pose2& start) override { to_start_frame_ = start.Inverse(); }
  void OnOdometry(const odometry_t& o, const nav::Pose2& truth) override {
    if (started_) sink_.OnOdometry(o.utime, glue::OdometryDelta(o), o.delta_t_s, to_start_frame_.Compose(truth));
    started_ = true;
  }
  void OnScan(const laser_scan_t& scan) override { sink_.OnScan(scan.utime, scan); }
  bool WantsFrames() const override { return true; }
  void OnFrame(int64_t utime, const cv::Mat& gray, const nav::Pose2& truth) override {
    sink_.OnPanorama(utime, gray, to_start_frame_.Compose(truth));
  }
  void OnPanoramaMask(const cv::Mat& mask) override { sink_.OnPanoramaMask(mask); }

 private:
  SimSensorSink& sink_;
  nav::Pose2 to_start_frame_;
  bool started_ = false;
};

}  // namespace

SimCameraRun RunSimulatedSensors(const SimCameraOptions& options, SimSensorSink& sink,
                                 const std::function<void(double, int)>& progress) {
  options.Validate();
  SimFrameOptions frames;
  frames.rate_hz = options.camera_rate_hz;
  frames.camera = options.camera;
  frames.effects = options.effects;
  frames.raw_frames = options.raw_frames;
  frames.people = options.people;
  frames.raw_mask = options.raw_mask;
  frames.truth_mask = options.truth_mask;
  SensorSinkAdapter adapter(sink);
  return DriveSimulation(options.sim, &frames, adapter, "sim camera run", progress);
}

namespace {

// Forwards every reading to several sinks.
class FanOut : public SimSensorSink {
 public:
  explicit FanOut(std::vector<std::unique_ptr<RatSlamSink>>* sinks) : sinks_(sinks) {}
  void OnOdometry(int64_t utime, const nav::Pose2& delta, double dt_s, const nav::Pose2& truth) override {
    for (auto& s : *sinks_) s->OnOdometry(utime, delta, dt_s, truth);
  }
  void OnPanorama(int64_t utime, const cv::Mat& gray, const nav::Pose2& truth) override {
    for (auto& s : *sinks_) s->OnPanorama(utime, gray, truth);
  }
  void OnPanoramaMask(const cv::Mat& mask) override {
    for (auto& s : *sinks_) s->OnPanoramaMask(mask);
  }

 private:
  std::vector<std::unique_ptr<RatSlamSink>>* sinks_;
};

}  // namespace

std::vector<RatSlamEvaluation> EvaluateRatSlamVariants(const RatSlamEvalOptions& options,
                                                       const std::vector<nav::RatSlamOptions>& variants,
                                                       const std::function<void(double, int)>& progress) {
  if (variants.empty()) throw std::invalid_argument("ratslam eval: no RatSLAM configuration");
  if (!(options.rpe_delta_m > 0)) throw std::invalid_argument("ratslam eval: rpe_delta_m must be positive");
  for (const auto& v : variants) v.Validate();
  std::vector<RatSlamEvaluation> out(variants.size());
  std::vector<std::unique_ptr<RatSlamSink>> sinks;
  for (size_t i = 0; i < variants.size(); ++i) sinks.push_back(std::make_unique<RatSlamSink>(variants[i], &out[i]));
  FanOut fan(&sinks);
  const SimCameraRun run = RunSimulatedSensors(options.run, fan, progress);
  const nav::sim::Scene scene = processes::LoadSceneFile(processes::SceneFilePath(options.run.sim.scene));
  for (size_t i = 0; i < out.size(); ++i) {
    RatSlamEvaluation& e = out[i];
    sinks[i]->Finish();
    e.run = run;
    e.scene = scene;
    if (e.truth.size() < 2) throw std::runtime_error("ratslam eval: fewer than 2 frames");
    e.odometry_rate_hz = options.run.sim.odometry_rate_hz;
    e.camera_rate_hz = options.run.camera_rate_hz;
    e.ratslam_errors = ErrorsOf(e.ratslam, e.truth, options.rpe_delta_m);
    e.experience_errors = ErrorsOf(e.experience, e.truth, options.rpe_delta_m);
    e.dead_reckoning_errors = ErrorsOf(e.dead_reckoning, e.truth, options.rpe_delta_m);
  }
  return out;
}

RatSlamEvaluation EvaluateRatSlam(const RatSlamEvalOptions& options, const std::function<void(double, int)>& progress) {
  return std::move(EvaluateRatSlamVariants(options, {options.ratslam}, progress).front());
}

cv::Mat DrawExperienceMap(const RatSlamEvaluation& e, const std::string& title) {
  // Everything in the scene frame: poses of the start frame composed with the true start.
  const nav::Pose2& s = e.run.start;
  auto scene_xy = [&](const nav::Pose2& p) {
    const nav::Pose2 q = s.Compose(p);
    return Eigen::Vector2d(q.x_m, q.y_m);
  };
  std::vector<Eigen::Vector2d> truth, dr, nodes;
  for (const auto& p : e.truth) truth.push_back(scene_xy(p));
  for (const auto& p : e.dead_reckoning) dr.push_back(scene_xy(p));
  for (const auto& x : e.experiences) nodes.push_back(scene_xy(x.pose));
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  auto extend = [&](const Eigen::Vector2d& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  };
  for (const auto& w : e.scene.walls) {
    extend(w.a);
    extend(w.b);
  }
  for (const auto* v : {&truth, &nodes}) {
    for (const auto& p : *v) extend(p);
  }
  lo -= Eigen::Vector2d(0.5, 0.5);
  hi += Eigen::Vector2d(0.5, 0.5);
  const int size = 900, top = 40, margin = 20;
  const double scale = (size - 2 * margin) / std::max(hi.x() - lo.x(), hi.y() - lo.y());
  const int width = static_cast<int>(std::ceil((hi.x() - lo.x()) * scale)) + 2 * margin;
  const int height = static_cast<int>(std::ceil((hi.y() - lo.y()) * scale)) + 2 * margin + top;
  cv::Mat img(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  auto px = [&](const Eigen::Vector2d& p) {
    return cv::Point(static_cast<int>(std::lround(margin + (p.x() - lo.x()) * scale)),
                     static_cast<int>(std::lround(height - margin - (p.y() - lo.y()) * scale)));
  };
  for (const auto& w : e.scene.walls) cv::line(img, px(w.a), px(w.b), cv::Scalar(170, 170, 170), 2, cv::LINE_AA);
  auto polyline = [&](const std::vector<Eigen::Vector2d>& pts, const cv::Scalar& colour, int thickness) {
    for (size_t i = 1; i < pts.size(); ++i) cv::line(img, px(pts[i - 1]), px(pts[i]), colour, thickness, cv::LINE_AA);
  };
  const cv::Scalar green(60, 170, 60), grey(150, 150, 150), blue(200, 110, 30), red(40, 40, 220);
  polyline(dr, grey, 1);
  polyline(truth, green, 2);
  for (const auto& l : e.links) {
    if (!l.loop_closure) {
      cv::line(img, px(nodes[static_cast<size_t>(l.from)]), px(nodes[static_cast<size_t>(l.to)]), blue, 1, cv::LINE_AA);
    }
  }
  for (const auto& l : e.links) {
    if (l.loop_closure) {
      cv::line(img, px(nodes[static_cast<size_t>(l.from)]), px(nodes[static_cast<size_t>(l.to)]), red, 2, cv::LINE_AA);
    }
  }
  for (const auto& n : nodes) cv::circle(img, px(n), 2, blue, cv::FILLED, cv::LINE_AA);
  // Loop closures join experiences made on different passes at the same place: the links are short,
  // so their ends are ringed.
  for (const auto& l : e.links) {
    if (!l.loop_closure) continue;
    for (const int end : {l.from, l.to}) cv::circle(img, px(nodes[static_cast<size_t>(end)]), 5, red, 1, cv::LINE_AA);
  }
  // Legend, scale bar and title.
  int y = top + 18;
  for (const auto& [name, colour] : std::vector<std::pair<std::string, cv::Scalar>>{
           {"ground truth", green}, {"dead reckoning", grey}, {"experiences + links", blue}, {"loop closures (ringed)", red}}) {
    cv::line(img, cv::Point(width - 200, y - 4), cv::Point(width - 175, y - 4), colour, 2, cv::LINE_AA);
    cv::putText(img, name, cv::Point(width - 168, y), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(40, 40, 40), 1,
                cv::LINE_AA);
    y += 18;
  }
  const double bar_m = (hi.x() - lo.x()) > 12 ? 5.0 : 1.0;
  const cv::Point b0(margin + 10, height - margin - 8);
  cv::line(img, b0, b0 + cv::Point(static_cast<int>(bar_m * scale), 0), cv::Scalar(0, 0, 0), 2);
  cv::putText(img, (bar_m >= 5 ? "5 m" : "1 m"), b0 + cv::Point(0, -6), cv::FONT_HERSHEY_SIMPLEX, 0.45,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(img, title, cv::Point(10, 26), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return img;
}

namespace {

void JsonErrors(results::Json& j, const std::string& key, const TrajectoryErrors& e) {
  j[key + "_ate_rmse_m"] = R4(e.ate_aligned.rmse_m);
  j[key + "_ate_max_m"] = R4(e.ate_aligned.max_m);
  j[key + "_ate_unaligned_rmse_m"] = R4(e.ate.rmse_m);
  j[key + "_ate_unaligned_final_m"] = R4(e.ate.final_m);
  j[key + "_rpe_translation_rmse_m"] = R4(e.rpe.translation_rmse_m);
  j[key + "_rpe_rotation_rmse_deg"] = R4(e.rpe.rotation_rmse_deg);
}

cv::Mat DrawErrors(const RatSlamEvaluation& e) {
  plot::Series rs{"ratslam (aligned)", {}, {}}, dr{"dead reckoning (aligned)", {}, {}};
  std::vector<std::pair<nav::Pose2, nav::Pose2>> rp, dp;
  for (size_t i = 0; i < e.truth.size(); ++i) {
    rp.push_back({e.ratslam[i], e.truth[i]});
    dp.push_back({e.dead_reckoning[i], e.truth[i]});
  }
  const nav::Pose2 ra = nav::AlignSE2(rp), da = nav::AlignSE2(dp);
  double travelled = 0;
  const size_t every = std::max<size_t>(1, e.truth.size() / 400);
  for (size_t i = 0; i < e.truth.size(); ++i) {
    if (i > 0) travelled += std::hypot(e.truth[i].x_m - e.truth[i - 1].x_m, e.truth[i].y_m - e.truth[i - 1].y_m);
    if (i % every != 0 && i + 1 != e.truth.size()) continue;
    for (auto [series, est, align] : {std::tuple{&rs, &e.ratslam, &ra}, std::tuple{&dr, &e.dead_reckoning, &da}}) {
      const nav::Pose2 p = align->Compose((*est)[i]);
      series->x.push_back(travelled);
      series->y.push_back(std::hypot(p.x_m - e.truth[i].x_m, p.y_m - e.truth[i].y_m));
    }
  }
  plot::Axes axes;
  axes.title = e.run.scene_name + ": position error against the ground truth (after SE(2) alignment)";
  axes.x_label = "distance travelled [m]";
  axes.y_label = "error [m]";
  axes.y_from_zero = true;
  return plot::LineChart(axes, {rs, dr}, {900, 500});
}

}  // namespace

void PrintRatSlamEvaluation(std::ostream& out, const RatSlamEvaluation& e) {
  auto line = [&](const char* name, const TrajectoryErrors& t) {
    out << std::fixed << std::setprecision(3) << "  " << std::left << std::setw(15) << name << std::right
        << " ATE RMSE " << t.ate_aligned.rmse_m << " m aligned (max " << t.ate_aligned.max_m << "), unaligned "
        << t.ate.rmse_m << " m (final " << t.ate.final_m << "); RPE per " << t.rpe.delta_m << " m: "
        << t.rpe.translation_rmse_m << " m, " << t.rpe.rotation_rmse_deg << " deg\n";
  };
  out << std::fixed << std::setprecision(1) << "ratslam eval: " << e.run.scene_name << ", " << e.run.laps << " laps, "
      << e.run.distance_m << " m in " << e.run.duration_s << " s, " << e.run.frames << " frames, " << e.run.odometry
      << " odometry; " << e.templates << " templates, " << e.experiences.size() << " experiences, " << e.links.size()
      << " links, " << e.loop_closures << " loop closures (" << e.false_loop_closures()
      << " between places > 1 m apart), " << e.inconsistent_links()
      << " inconsistent links, " << e.injections << " view injections\n";
  line("ratslam", e.ratslam_errors);
  line("experience", e.experience_errors);
  line("dead reckoning", e.dead_reckoning_errors);
  out << std::setprecision(3) << "  time: " << e.odometry_ms_median << " ms per odometry (mean " << e.odometry_ms_mean
      << "), " << e.image_ms_median << " ms per image (mean " << e.image_ms_mean << "); "
      << std::setprecision(1) << 100 * e.core_load() << " % of a core at " << e.odometry_rate_hz << " Hz odometry and "
      << e.camera_rate_hz << " Hz frames\n";
}

void WriteRatSlamEvaluation(const RatSlamEvaluation& e, const RatSlamEvalOptions& options, const std::string& dir) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  const fs::path out(dir);
  const nav::PoseCellOptions& pc = options.ratslam.pose_cells;
  const nav::LocalViewOptions& lv = options.ratslam.local_view;
  results::Json json;
  json["scene"] = e.run.scene_name;
  json["seed"] = options.run.sim.seed;
  json["laps"] = R4(e.run.laps);
  json["duration_s"] = R4(e.run.duration_s);
  json["distance_m"] = R4(e.run.distance_m);
  json["frames"] = R4(e.run.frames);
  json["odometry"] = R4(e.run.odometry);
  json["raw_frames"] = options.run.raw_frames;
  json["camera"] = options.run.camera.optics.enabled ? "realistic" : "clean";
  json["mask"] = options.mask;  // none | calibrated | truth | the file's path, as eval homing writes it
  json["heading_drift_deg_per_m"] = R4(options.run.sim.drive.heading_drift_deg_per_m);
  json["ratslam_templates"] = R4(e.templates);
  json["ratslam_experiences"] = e.experiences.size();
  json["ratslam_links"] = e.links.size();
  json["ratslam_loop_closures"] = R4(e.loop_closures);
  json["ratslam_false_loop_closures"] = R4(e.false_loop_closures());
  json["ratslam_inconsistent_links"] = R4(e.inconsistent_links());
  json["ratslam_experience_switches"] = R4(e.switches);
  json["ratslam_view_injections"] = R4(e.injections);
  json["ratslam_first_loop_closure_travel_m"] =
      R4(e.loop_closure_travel_m.empty() ? -1.0 : e.loop_closure_travel_m.front());
  json["ratslam_ms_per_odometry"] = R4(e.odometry_ms_median);
  json["ratslam_ms_per_odometry_mean"] = R4(e.odometry_ms_mean);
  json["ratslam_ms_per_image"] = R4(e.image_ms_median);
  json["ratslam_ms_per_image_mean"] = R4(e.image_ms_mean);
  json["ratslam_core_load"] = R4(e.core_load());
  json["render_s"] = R4(e.run.render_s);
  json["pc_dim_xy"] = R4(pc.pc_dim_xy);
  json["pc_dim_th"] = R4(pc.pc_dim_th);
  json["pc_cell_x_size_m"] = R4(pc.pc_cell_x_size_m);
  json["template_x_size"] = R4(lv.template_x_size);
  json["template_y_size"] = R4(lv.template_y_size);
  json["vt_match_threshold"] = R4(lv.vt_match_threshold);
  json["rpe_delta_m"] = R4(options.rpe_delta_m);
  JsonErrors(json, "ratslam", e.ratslam_errors);
  JsonErrors(json, "ratslam_experience", e.experience_errors);
  JsonErrors(json, "dead_reckoning", e.dead_reckoning_errors);
  results::WriteJsonFile((out / "summary.json").string(), json);
  auto write = [&](const fs::path& path, const std::string& text) {
    std::ofstream f(path);
    f << text;
    if (!f) throw std::runtime_error("cannot write " + path.string());
  };
  std::ostringstream title;
  title << std::fixed << std::setprecision(2) << e.run.scene_name << ", " << e.run.laps << " laps, "
        << std::setprecision(0) << e.run.distance_m << " m: " << e.experiences.size() << " experiences, "
        << e.loop_closures << " loop closures; ATE ratslam " << std::setprecision(2)
        << e.ratslam_errors.ate_aligned.rmse_m << " m, dead reckoning " << e.dead_reckoning_errors.ate_aligned.rmse_m
        << " m";
  plot::SavePng(DrawExperienceMap(e, title.str()), (out / "experience_map.png").string());
  plot::SavePng(DrawErrors(e), (out / "errors.png").string());
  std::ostringstream csv;
  csv << "utime,truth_x_m,truth_y_m,truth_theta_rad,ratslam_x_m,ratslam_y_m,ratslam_theta_rad,experience_x_m,"
         "experience_y_m,experience_theta_rad,dr_x_m,dr_y_m,dr_theta_rad,template,new_template,difference,"
         "relative_rad,experience,pc_x,pc_y,pc_th\n"
      << std::setprecision(9);
  for (size_t i = 0; i < e.truth.size(); ++i) {
    csv << e.utime[i];
    for (const nav::Pose2* p : {&e.truth[i], &e.ratslam[i], &e.experience[i], &e.dead_reckoning[i]}) {
      csv << "," << p->x_m << "," << p->y_m << "," << p->theta_rad;
    }
    const auto& f = e.trace[i];
    csv << "," << f.template_id << "," << (f.new_template ? 1 : 0) << "," << f.difference << "," << f.relative_rad
        << "," << f.experience << "," << f.pc_x << "," << f.pc_y << "," << f.pc_th << "\n";
  }
  write(out / "trajectories.csv", csv.str());
  std::ostringstream ex;
  ex << "experience,x_m,y_m,theta_rad,view_template,truth_x_m,truth_y_m,truth_theta_rad\n" << std::setprecision(9);
  for (size_t i = 0; i < e.experiences.size(); ++i) {
    const nav::Pose2& p = e.experiences[i].pose;
    const nav::Pose2 t = i < e.experience_truth.size() ? e.experience_truth[i] : nav::Pose2{};
    ex << i << "," << p.x_m << "," << p.y_m << "," << p.theta_rad << "," << e.experiences[i].view_template << ","
       << t.x_m << "," << t.y_m << "," << t.theta_rad << "\n";
  }
  std::ostringstream li;
  li << "from,to,d_m,heading_rad,facing_rad,dt_s,loop_closure\n" << std::setprecision(9);
  for (const nav::ExperienceLink& l : e.links) {
    li << l.from << "," << l.to << "," << l.d_m << "," << l.heading_rad << "," << l.facing_rad << "," << l.dt_s << ","
       << (l.loop_closure ? 1 : 0) << "\n";
  }
  write(out / "experiences.csv", ex.str());
  write(out / "links.csv", li.str());
}

}  // namespace snapnav::eval
