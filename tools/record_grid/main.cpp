// record-grid: a lab's own image grid from the bus (issue 21). Omni frames (OMNI_FRAME) and a
// pose channel (e.g. laser SLAM's POSE_LASER_SLAM) in; one image per grid node out, taken when
// the robot is within --tolerance-m of a node that has no image yet, as a folder in the format
// gridgen writes (images/, positions.csv, camera.ini with the frames' [mirror]) that
// `eval homing --grid` and `eval localization --grid` read.
#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>

#include <opencv2/imgcodecs.hpp>

#include "snapnav/glue/app.hpp"
#include "snapnav/glue/bus.hpp"
#include "snapnav/glue/channels.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/pose_corrections.hpp"
#include "snapnav/glue/shutdown.hpp"
#include "snapnav/glue/time.hpp"
#include "snapnav/omni_frame_t.hpp"
#include "snapnav/pose_correction_t.hpp"
#include "snapnav/pose_t.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;

struct Recorded {
  std::string file;
  int ix = 0, iy = 0;  // signed, relative to the origin node; shifted to 0.. when written
  nav::Pose2 pose;       // as received on --pose
  int64_t pose_utime = 0;  // ... published then
  int64_t utime = 0;       // the frame's
};

int Main(int argc, char** argv) {
  glue::CommonFlags common;
  std::string frames_channel = channels::kOmniFrame, pose_channel = channels::kPoseLaserSlam, out_dir, origin_text;
  std::string ready_file, correction_channel = channels::kLaserSlamCorrection;
  double spacing_m = 0.2, tolerance_m = 0.03, max_pose_age_s = 0.15, duration_s = 0;
  int max_images = 0;
  glue::Flags flags("record-grid",
                    "Records a lab's own image grid from the bus: the frames of --frames (raw omni images or\n"
                    "panoramas) with the pose of --pose (laser SLAM's by default; the pose whose utime is nearest the\n"
                    "frame's, within --max-pose-age-s). A frame is kept when the robot stands within --tolerance-m\n"
                    "of a node of a --spacing-m grid (node 0,0 at --origin, default the first pose) that has no image\n"
                    "yet. Writes OUT/images/NNNNN.png, OUT/positions.csv (file,ix,iy,x_m,y_m,heading_rad,utime;\n"
                    "indices from 0) and, for raw frames, OUT/camera.ini with the frames' [mirror] and [panorama]:\n"
                    "the format gridgen writes, read by eval homing --grid and eval localization --grid. Runs until\n"
                    "--max-images, --duration-s, SIGINT or the end of a log (--lcm-url file://LOG?speed=0).\n"
                    "The poses are corrected by the newest table of --correction for --pose (laser SLAM's graph\n"
                    "back end moves its past poses when it closes a loop): a node is chosen at the corrected pose,\n"
                    "and positions.csv holds the images' poses as the last table puts them.\n"
                    "The channels get --channel-prefix.");
  flags.AddCommon(&common);
  flags.AddString("frames", &frames_channel, "omni frame channel (omni_frame_t)");
  flags.AddString("pose", &pose_channel, "pose channel (pose_t): POSE_LASER_SLAM, POSE_EKF, POSE_GROUND_TRUTH ...");
  flags.AddString("correction", &correction_channel,
                  "pose_correction_t channel of the --pose's corrections (laser-slam's graph back end; empty: none)");
  flags.AddString("out", &out_dir, "output folder (required; must not hold a positions.csv yet)");
  flags.AddDouble("spacing-m", &spacing_m, "grid spacing [m]");
  flags.AddDouble("tolerance-m", &tolerance_m, "largest distance from a node at which its image is taken [m]");
  flags.AddString("origin", &origin_text, "node 0,0 of the grid, X,Y [m] (default: the first pose)");
  flags.AddDouble("max-pose-age-s", &max_pose_age_s, "largest |pose utime - frame utime| [s]");
  flags.AddInt("max-images", &max_images, "stop after this many images; 0: no limit");
  flags.AddDouble("duration-s", &duration_s, "stop after this long [s, wall clock]; 0: until SIGINT");
  flags.AddString("ready-file", &ready_file, "create this file once subscribed");
  if (!flags.Parse(argc, argv)) return 0;
  if (out_dir.empty()) throw glue::FlagError("--out DIR is required");
  if (!common.config.empty()) throw glue::FlagError("record-grid has no config file; use its flags");
  if (!(spacing_m > 0)) throw glue::FlagError("--spacing-m must be > 0");
  if (!(tolerance_m > 0) || tolerance_m >= spacing_m / 2) throw glue::FlagError("--tolerance-m must be in (0, spacing / 2)");
  if (!(max_pose_age_s > 0)) throw glue::FlagError("--max-pose-age-s must be > 0");
  if (max_images < 0) throw glue::FlagError("--max-images must be >= 0");
  std::optional<Eigen::Vector2d> origin;
  if (!origin_text.empty()) {
    const auto parts = glue::SplitList(origin_text);
    try {
      if (parts.size() != 2) throw std::invalid_argument(origin_text);
      origin = Eigen::Vector2d(std::stod(parts[0]), std::stod(parts[1]));
    } catch (const std::exception&) {
      throw glue::FlagError("--origin must be X,Y in metres, not '" + origin_text + "'");
    }
  }
  const fs::path out(out_dir);
  if (fs::exists(out / "positions.csv")) throw glue::FlagError("--out " + out_dir + " already holds a positions.csv");
  fs::create_directories(out / "images");
  frames_channel = common.channel_prefix + frames_channel;
  pose_channel = common.channel_prefix + pose_channel;
  if (!correction_channel.empty()) correction_channel = common.channel_prefix + correction_channel;

  glue::InstallShutdownHandlers();
  glue::Bus bus(common.lcm_url);
  std::deque<std::pair<int64_t, nav::Pose2>> poses;  // recent poses by utime
  std::map<std::pair<int, int>, Recorded> recorded;
  std::vector<std::pair<int, int>> order;
  int64_t frames = 0, without_pose = 0, off_node = 0, taken_nodes = 0, undecodable = 0;
  bool raw = false, camera_written = false;
  glue::PoseCorrections corrections(pose_channel);
  int64_t bad_corrections = 0;
  if (!correction_channel.empty()) {
    bus.Subscribe<pose_correction_t>(correction_channel, [&](const pose_correction_t& m) {
      std::string problem;
      if (corrections.Take(m, &problem) == glue::PoseCorrections::Taken::kInvalid) {
        ++bad_corrections;
        std::cerr << "record-grid: a pose correction on " << correction_channel << " refused: " << problem << "\n";
      }
    });
  }
  bus.Subscribe<pose_t>(pose_channel, [&](const pose_t& m) {
    poses.emplace_back(m.utime, glue::FromPoseMsg(m));
    while (poses.size() > 200) poses.pop_front();
  }, glue::Bus::kOdometryQueueCapacity);
  bus.Subscribe<omni_frame_t>(frames_channel, [&](const omni_frame_t& f) {
    ++frames;
    const std::pair<int64_t, nav::Pose2>* best = nullptr;
    for (const auto& p : poses) {
      if (!best || std::llabs(p.first - f.utime) < std::llabs(best->first - f.utime)) best = &p;
    }
    if (!best || std::llabs(best->first - f.utime) > static_cast<int64_t>(max_pose_age_s * 1e6)) {
      ++without_pose;
      return;
    }
    const nav::Pose2 pose = corrections.Correct(best->first, best->second);
    if (!origin) origin = Eigen::Vector2d(pose.x_m, pose.y_m);
    const int ix = static_cast<int>(std::lround((pose.x_m - origin->x()) / spacing_m));
    const int iy = static_cast<int>(std::lround((pose.y_m - origin->y()) / spacing_m));
    const Eigen::Vector2d node = *origin + spacing_m * Eigen::Vector2d(ix, iy);
    if ((Eigen::Vector2d(pose.x_m, pose.y_m) - node).norm() > tolerance_m) {
      ++off_node;
      return;
    }
    if (recorded.count({ix, iy})) {
      ++taken_nodes;
      return;
    }
    cv::Mat image;
    try {
      image = glue::FrameToImage(f);
    } catch (const std::exception& e) {
      ++undecodable;
      std::cerr << "record-grid: frame " << f.utime << " not decoded: " << e.what() << "\n";
      return;
    }
    const bool is_raw = f.kind == omni_frame_t::RAW_OMNI;
    if (!camera_written) {
      raw = is_raw;
      if (raw) {
        std::ofstream camera(out / "camera.ini");
        camera << "; the calibration the frames of " << frames_channel << " carried (record-grid)\n";
        glue::PrintMirrorConfig(camera, glue::MirrorOf(f));
        camera << "\n";
        glue::PrintPanoramaConfig(camera, glue::PanoramaOf(f));
      }
      camera_written = true;
    } else if (is_raw != raw) {
      ++undecodable;
      return;  // one kind per folder
    }
    char name[32];
    std::snprintf(name, sizeof name, "images/%05d.png", static_cast<int>(recorded.size()));
    if (!cv::imwrite((out / name).string(), image)) throw std::runtime_error("cannot write " + (out / name).string());
    recorded[{ix, iy}] = Recorded{name, ix, iy, best->second, best->first, f.utime};
    order.push_back({ix, iy});
    std::cerr << "record-grid: " << recorded.size() << " images, the last at node (" << ix << ", " << iy << "), ("
              << std::fixed << std::setprecision(3) << pose.x_m << ", " << pose.y_m << ")\r" << std::flush;
  });
  std::cerr << "record-grid: frames " << frames_channel << ", poses " << pose_channel << ", spacing " << spacing_m
            << " m, tolerance " << tolerance_m << " m, into " << out_dir << " (" << bus.url() << ")\n";
  if (!ready_file.empty()) std::ofstream(ready_file) << "ready\n";
  const int64_t end = duration_s > 0 ? glue::MonotonicUtime() + static_cast<int64_t>(duration_s * 1e6) : 0;
  bus.Run([&] {
    return (end == 0 || glue::MonotonicUtime() < end) && (max_images == 0 || static_cast<int>(recorded.size()) < max_images);
  });

  int min_ix = 0, min_iy = 0;
  for (const auto& [key, r] : recorded) {
    min_ix = std::min(min_ix, r.ix);
    min_iy = std::min(min_iy, r.iy);
  }
  std::ofstream csv(out / "positions.csv");
  csv << "file,ix,iy,x_m,y_m,heading_rad,utime\n" << std::setprecision(9);
  for (const auto& key : order) {
    const auto& r = recorded.at(key);
    const nav::Pose2 p = corrections.Correct(r.pose_utime, r.pose);  // as the last correction puts it
    csv << r.file << "," << r.ix - min_ix << "," << r.iy - min_iy << "," << p.x_m << "," << p.y_m << ","
        << p.theta_rad << "," << r.utime << "\n";
  }
  std::cerr << "\nrecord-grid: " << recorded.size() << " images written to " << out_dir << " (" << frames
            << " frames: " << without_pose << " without a pose within " << max_pose_age_s << " s, " << off_node
            << " off a node, " << taken_nodes << " at a node already taken, " << undecodable << " not decoded)\n";
  if (corrections.tables() > 0 || bad_corrections > 0) {
    std::cerr << "record-grid: " << corrections.tables() << " correction tables of " << pose_channel
              << " taken (the last of correction " << corrections.corrections() << ", " << corrections.ranges()
              << " ranges), " << bad_corrections << " refused\n";
  }
  bus.ReportStats(std::cerr);
  return recorded.empty() ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
