// log-import: converts recorded data into an LCM log.
//   log-import rawlog INPUT --out LOG                    MRPT rawlog (plain or gzip)
//   log-import carmen INPUT --out LOG                    CARMEN text log (plain or gzip)
//   log-import images FOLDER [--positions CSV] --out LOG  images + positions CSV

#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <iomanip>
#include <iostream>
#include <string>

#include "importers.hpp"
#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/time.hpp"

namespace snapnav::importers {
namespace {

// Prints progress to stderr at most once a second, so short imports stay quiet.
class ProgressPrinter {
 public:
  explicit ProgressPrinter(bool enabled) : enabled_(enabled), last_(glue::MonotonicUtime()) {}

  void operator()(const Progress& p) {
    if (!enabled_) return;
    const int64_t now = glue::MonotonicUtime();
    if (now - last_ < 1'000'000) return;
    last_ = now;
    std::cerr << "log-import: ";
    if (p.total > 0) {
      std::cerr << std::min<int64_t>(100, p.done * 100 / p.total) << "% (";
    }
    if (p.unit == "bytes") {
      std::cerr << std::fixed << std::setprecision(1) << p.done / 1e6;
      if (p.total > 0) std::cerr << " of " << p.total / 1e6;
      std::cerr << " MB";
    } else {
      std::cerr << p.done;
      if (p.total > 0) std::cerr << " of " << p.total;
      std::cerr << " " << p.unit;
    }
    std::cerr << (p.total > 0 ? ")" : "") << "\n";
    std::cerr.unsetf(std::ios::floatfield);
  }

 private:
  bool enabled_;
  int64_t last_;
};

bool SameFile(const std::string& a, const std::string& b) {
  struct stat sa {
  }, sb{};
  return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

int Main(int argc, char** argv) {
  std::string out;
  std::string channel_prefix;
  std::string positions;
  std::string time_source = "auto";
  double rate_hz = 10.0;
  bool quiet = false;
  CarmenOptions carmen;
  ImageOptions images;
  RawlogOptions rawlog;
  glue::Flags flags(
      "log-import",
      "Converts recorded data into an LCM log (event time = message utime). FORMAT is one of:\n"
      "  rawlog INPUT   MRPT rawlog, plain or gzip: action/sensory-frame pairs or observations only.\n"
      "                 CObservation2DRangeScan -> " +
          std::string(channels::kLaserScan) + ", odometry increments or CObservationOdometry -> " +
          channels::kOdometry +
          ".\n"
          "  carmen INPUT   CARMEN text log, plain or gzip: FLASER and ROBOTLASER1 -> " +
          channels::kLaserScan + " and " + kPoseCarmen + " (the log's robot pose, estimator \"" + kCarmenEstimator +
          "\"); ODOM lines, or the scans' odometry poses if there are none -> " + channels::kOdometry +
          ". Other messages are skipped and counted.\n"
          "  images FOLDER  PNG/JPEG files (bytes kept as they are) listed in a CSV with the columns\n"
          "                 file,x_m,y_m,heading_rad[,utime] -> " +
          channels::kOmniFrame + " and " + channels::kPoseGroundTruth +
          " (estimator \"ground_truth\").\n"
          "Prints a summary (messages per channel, time span). Bad lines or a truncated input are reported as\n"
          "FILE:LINE or FILE: byte offset; everything valid is still written; the exit status is then 1.");
  flags.AddString("out", &out, "the LCM log to write (replaced if it exists)");
  flags.AddString("channel-prefix", &channel_prefix, "prefix prepended to every channel name");
  flags.AddDouble("rate-hz", &rate_hz,
                  "rate of synthesized times where the input has none: per rawlog entry, CARMEN message line, "
                  "or image row [Hz]");
  flags.AddBool("quiet", &quiet, "no progress reports");
  flags.AddString("time", &time_source,
                  "carmen: message times from the log's timestamps: auto (use them if positive and strictly "
                  "increasing per stream, else synthesize), log, or synthesize");
  flags.AddDouble("flaser-fov-deg", &carmen.flaser_fov_deg, "carmen: FLASER field of view, centred ahead [deg]");
  flags.AddDouble("flaser-max-range-m", &carmen.flaser_max_range_m,
                  "carmen: FLASER range_max_m; readings at or above it (or >= 81.9, SICK's no-return value) are "
                  "written as range_max_m [m]");
  flags.AddString("positions", &positions, "images: the positions CSV (default: FOLDER/positions.csv)");
  flags.AddBool("panorama", &images.panorama, "images: the images are unwrapped panoramas (default: raw omni images)");
  flags.AddDouble("mirror-center-x-px", &images.mirror_center_x_px, "images: mirror centre column [px]");
  flags.AddDouble("mirror-center-y-px", &images.mirror_center_y_px, "images: mirror centre row [px]");
  flags.AddDouble("mirror-inner-radius-px", &images.mirror_inner_radius_px, "images: inner radius of the ring [px]");
  flags.AddDouble("mirror-outer-radius-px", &images.mirror_outer_radius_px, "images: outer radius of the ring [px]");
  flags.AddDouble("mirror-elevation-inner-rad", &images.mirror_elevation_inner_rad,
                  "images: elevation seen at the inner radius [rad]");
  flags.AddDouble("mirror-elevation-outer-rad", &images.mirror_elevation_outer_rad,
                  "images: elevation seen at the outer radius [rad]");
  flags.AddDouble("bearing-col0-rad", &images.bearing_col0_rad, "images, --panorama: bearing of column 0 [rad]");
  flags.AddDouble("elevation-top-rad", &images.elevation_top_rad, "images, --panorama: elevation of row 0 [rad]");
  flags.AddDouble("elevation-bottom-rad", &images.elevation_bottom_rad,
                  "images, --panorama: elevation of the last row [rad]");
  flags.AddString("sensor-name", &images.sensor_name, "images: sensor_name of the frames");
  flags.AllowPositional("FORMAT INPUT", "rawlog|carmen|images, then the file or folder to import");
  if (!flags.Parse(argc, argv)) return 0;

  if (flags.positional().size() != 2) throw glue::FlagError("expected FORMAT and INPUT (see --help)");
  const std::string format = flags.positional()[0];
  const std::string input = flags.positional()[1];
  if (format != "rawlog" && format != "carmen" && format != "images") {
    throw glue::FlagError("unknown FORMAT '" + format + "' (rawlog, carmen or images)");
  }
  if (out.empty()) throw glue::FlagError("--out LOG is required");
  // Flags of another format are mistakes, not silently ignored.
  const CarmenOptions carmen_defaults;
  const ImageOptions image_defaults;
  if (format != "carmen" && (time_source != "auto" || carmen.flaser_fov_deg != carmen_defaults.flaser_fov_deg ||
                             carmen.flaser_max_range_m != carmen_defaults.flaser_max_range_m)) {
    throw glue::FlagError("--time, --flaser-fov-deg and --flaser-max-range-m apply to FORMAT carmen only");
  }
  const bool image_flags = !positions.empty() || images.panorama || images.sensor_name != image_defaults.sensor_name ||
                           images.mirror_center_x_px != 0 || images.mirror_center_y_px != 0 ||
                           images.mirror_inner_radius_px != 0 || images.mirror_outer_radius_px != 0 ||
                           images.mirror_elevation_inner_rad != 0 || images.mirror_elevation_outer_rad != 0 ||
                           images.bearing_col0_rad != 0 || images.elevation_top_rad != 0 ||
                           images.elevation_bottom_rad != 0;
  if (format != "images" && image_flags) {
    throw glue::FlagError(
        "--positions, --panorama, --mirror-*, --bearing-col0-rad, --elevation-* and --sensor-name apply to "
        "FORMAT images only");
  }
  if (SameFile(input, out)) throw glue::FlagError("--out must not be the input file");

  const ChannelNames names = ChannelNames::WithPrefix(channel_prefix);
  ProgressPrinter printer(!quiet);
  try {
    carmen.time_source = ParseTimeSource(time_source);
  } catch (const std::invalid_argument& e) {
    throw glue::FlagError(std::string("--time: ") + e.what());
  }
  carmen.channels = images.channels = rawlog.channels = names;
  carmen.rate_hz = images.rate_hz = rawlog.rate_hz = rate_hz;
  carmen.progress = images.progress = rawlog.progress = [&printer](const Progress& p) { printer(p); };
  try {
    if (format == "carmen") carmen.Validate();
    if (format == "images") images.Validate();
    if (format == "rawlog") rawlog.Validate();
  } catch (const std::invalid_argument& e) {
    throw glue::FlagError(e.what());
  }
  if (format == "images" && positions.empty()) positions = input + "/positions.csv";

  // Effective parameters.
  const std::string output_channels = format == "images" ? names.omni_frame + "," + names.pose_ground_truth
                                                         : names.laser_scan + "," + names.odometry +
                                                               (format == "carmen" ? "," + names.pose_carmen : "");
  std::cerr << "log-import " << format << ": input=" << input << " out=" << out << " channels=" << output_channels
            << " rate_hz=" << rate_hz;
  if (format == "carmen") {
    std::cerr << " time=" << ToString(carmen.time_source) << " flaser_fov_deg=" << carmen.flaser_fov_deg
              << " flaser_max_range_m=" << carmen.flaser_max_range_m;
  }
  if (format == "images") {
    std::cerr << " positions=" << positions << " kind=" << (images.panorama ? "panorama" : "raw_omni")
              << " mirror_center_px=(" << images.mirror_center_x_px << "," << images.mirror_center_y_px
              << ") mirror_radii_px=(" << images.mirror_inner_radius_px << "," << images.mirror_outer_radius_px
              << ") mirror_elevations_rad=(" << images.mirror_elevation_inner_rad << ","
              << images.mirror_elevation_outer_rad << ") bearing_col0_rad=" << images.bearing_col0_rad
              << " elevations_rad=(" << images.elevation_top_rad << "," << images.elevation_bottom_rad << ")";
  }
  std::cerr << "\n";

  const int64_t start = glue::MonotonicUtime();
  LcmLogSink sink(out);
  ImportReport report;
  if (format == "rawlog") report = ImportRawlog(input, sink, rawlog);
  if (format == "carmen") report = ImportCarmenFile(input, sink, carmen);
  if (format == "images") report = ImportImages(input, positions, sink, images);
  sink.Close();
  const double seconds = static_cast<double>(glue::MonotonicUtime() - start) * 1e-6;

  PrintSummary(report, std::cout);
  std::cout << "import time: " << std::fixed << std::setprecision(2) << seconds << " s\n";
  if (report.TotalMessages() == 0) {
    std::remove(out.c_str());
    std::cout << "no message imported: " << out << " not written\n";
    if (report.ok()) {
      std::cerr << "log-import: nothing in " << input << " converts to snapnav messages (see skipped above)\n";
      return 1;
    }
  } else {
    std::cout << "wrote " << out << "\n";
  }
  if (!report.ok()) {
    std::cerr << "log-import: " << report.error_count << (report.error_count == 1 ? " error" : " errors")
              << " (listed above); " << report.TotalMessages() << " valid messages written\n";
    return 1;
  }
  return 0;
}

}  // namespace
}  // namespace snapnav::importers

int main(int argc, char** argv) { return snapnav::glue::RunMain(argc, argv, snapnav::importers::Main); }
