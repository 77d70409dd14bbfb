#pragma once
// MRPT's icp-slam beside our laser SLAM: runs the icp-slam app (Debian's mrpt-apps) as a
// subprocess on a rawlog, or on a CARMEN log converted with carmen2rawlog first, and reads
// back its trajectory and its time per scan.
//
// How its output is read (MRPT 2.5):
//  - icp-slam writes one line "step x y yaw" per rawlog entry it processes to
//    <logOutput_dir>/log_estimated_path.txt (the robot pose after that entry), and the time of
//    its per-entry processing (CMetricMapBuilderICP::processActionObservation or
//    processObservation, measured inside the app) as "ms map_size" to log_times.txt.
//    Neither file holds times, so the rawlog is read again here with the same MRPT function
//    icp-slam uses (CRawlog::getActionObservationPairOrObservation): entry k gets the time of
//    its laser scan, converted to microseconds since the Unix epoch as log-import does, so the
//    poses pair with the scans of the log-import'ed LCM log by time. An action/sensory-frame
//    rawlog whose first sensory frame has no action before it (the Malaga loop) starts at its
//    second frame, as icp-slam does.
//  - carmen2rawlog (MRPT 2.5.8) gives every observation the same timestamp (the time of the
//    conversion), which icp-slam's odometry extrapolation rejects: it then never moves. So the
//    converted rawlog is re-stamped: scan k gets the time log-import gives the k-th scan of the
//    same CARMEN file (ImportCarmenFile with default options) and each odometry observation the
//    time of the scan of its line.
//  - The per-scan time is the sum of log_times.txt (all entries, odometry-only ones included)
//    divided by the scans processed: icp-slam's own timing of its SLAM step, without process
//    start, reading the rawlog or writing files. The wall time of the whole process is kept
//    beside it.
//
// The config is generated from a shipped icp-slam ini file (default: the classic point-map ICP
// demo) with the GUI, 3D-scene and pose-log outputs off, INFO logging off (icp-slam logs inside
// the timed step), and the output folder in the work folder; it is written to
// <work_dir>/icp-slam.ini.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "snapnav/nav/pose2.hpp"
#include "snapnav/nav/trajectory.hpp"

namespace snapnav::eval {

inline constexpr char kIcpSlamClassicConfig[] = "/usr/share/mrpt/config_files/icp-slam/icp-slam_demo_classic.ini";
inline constexpr char kMalagaLoopRawlog[] =
    "/usr/share/mrpt/datasets/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";

// One key of an icp-slam ini file to set: `key = value` in [section].
struct IcpSlamKey {
  std::string section, key, value;
};

struct IcpSlamOptions {
  std::string icp_slam = "icp-slam";            // program: a name looked up on PATH, or a path
  std::string carmen2rawlog = "carmen2rawlog";  // for CARMEN input
  std::string base_config = kIcpSlamClassicConfig;
  std::vector<IcpSlamKey> set;  // keys of base_config set to other values (each must be in it)
  double timeout_s = 900;  // icp-slam is killed after this long [s]
  bool progress = true;    // what is run, on stderr
};

// One entry of a rawlog as icp-slam steps through it.
struct RawlogStep {
  int64_t utime = 0;  // time of its laser scan, else of its first observation [us since the Unix epoch]; 0: none
  bool scan = false;  // holds a CObservation2DRangeScan
};

struct IcpSlamRun {
  std::vector<nav::StampedPose> poses;  // icp-slam's pose after each scan, at the scan's time
  int64_t steps = 0;                    // rawlog entries icp-slam processed
  double slam_seconds = 0;              // sum of log_times.txt: icp-slam's own timing of its SLAM steps
  double wall_seconds = 0;              // the icp-slam process, start to exit
  std::string rawlog;                   // the rawlog icp-slam read
  std::string config;                   // the generated config (<work_dir>/icp-slam.ini)
  std::string command;                  // the command run
  std::string output;                   // its stdout and stderr (<work_dir>/icp-slam.log)

  double ms_per_scan() const { return poses.empty() ? 0 : 1000 * slam_seconds / static_cast<double>(poses.size()); }
  double wall_ms_per_scan() const {
    return poses.empty() ? 0 : 1000 * wall_seconds / static_cast<double>(poses.size());
  }
};

// Whether `path` names an MRPT rawlog (".rawlog" or ".rawlog.gz"); anything else is taken as a
// CARMEN log (plain or gzip).
bool IsRawlogPath(const std::string& path);

// Runs icp-slam on `input` (a rawlog, or a CARMEN log) with the work files in `work_dir`
// (created; icp-slam empties <work_dir>/icp-slam-out). Throws std::runtime_error naming the
// program, command, exit status and the last lines of its output when a program is missing or
// fails, or naming the file when an input or output cannot be read.
IcpSlamRun RunIcpSlam(const std::string& input, const std::string& work_dir, const IcpSlamOptions& options = {});

// Our trajectory (the pose after each scan of a run) beside icp-slam's, paired by scan time.
struct IcpSlamComparison {
  std::vector<std::optional<nav::Pose2>> icp_at_scans;  // icp-slam's pose at each of our scans, if it has one
  int64_t paired = 0;                                   // scans with both poses
  nav::Pose2 slam_to_icp;                               // the SE(2) alignment of our frame onto icp-slam's
  nav::AteResult difference;                            // position differences after it [m]
};
// Pairs within max_dt_us. Throws std::runtime_error if fewer than 2 scans pair (the LCM log was
// not imported from icp-slam's input).
IcpSlamComparison CompareWithIcpSlam(const std::vector<int64_t>& scan_utimes, const std::vector<nav::Pose2>& slam,
                                     const std::vector<nav::StampedPose>& icp, int64_t max_dt_us = 1000);

// ---- the pieces, for tests

// The icp-slam config: `base_ini` (the text of an icp-slam ini file) with these keys of
// [MappingApplication] set (replaced where present, added after the section header otherwise):
// rawlog_file, rawlog_offset = 0, logOutput_dir, LOG_FREQUENCY = 0, SAVE_3D_SCENE = 0,
// SAVE_POSE_LOG = 0, SHOW_PROGRESS_3D_REAL_TIME = 0, verbosity = LVL_WARN; and each of `set`
// replaced in its section. Throws std::invalid_argument if there is no [MappingApplication]
// section, or a key of `set` is not in its section.
std::string MakeIcpSlamConfig(const std::string& base_ini, const std::string& rawlog, const std::string& output_dir,
                              const std::string& base_name = "", const std::vector<IcpSlamKey>& set = {});

// log_estimated_path.txt: one "step x y yaw" line per entry, steps 0, 1, 2, ... Throws
// std::runtime_error naming the file and line on anything else.
std::vector<nav::Pose2> ParseIcpSlamPath(const std::string& path);
// log_times.txt: one "milliseconds map_size" line per entry; returns the milliseconds.
std::vector<double> ParseIcpSlamTimes(const std::string& path);

// The entries of a rawlog, as icp-slam steps through it. Throws std::runtime_error naming the
// file if it cannot be read.
std::vector<RawlogStep> ReadRawlogSteps(const std::string& rawlog);

// icp-slam's per-entry poses at the times of the entries that hold scans. Throws
// std::runtime_error unless there is one pose per entry.
std::vector<nav::StampedPose> PosesAtScans(const std::vector<RawlogStep>& steps, const std::vector<nav::Pose2>& poses);

// Re-stamps a rawlog written by carmen2rawlog from `carmen_log` (see above) into `out_rawlog`.
// Returns the number of scans. Throws std::runtime_error if its scans do not correspond
// one-to-one to the scans log-import reads from the CARMEN log.
int64_t RestampCarmenRawlog(const std::string& converted_rawlog, const std::string& carmen_log,
                            const std::string& out_rawlog);

// For each of `utimes`, the pose of `poses` (sorted by utime) nearest in time within max_dt_us,
// if any.
std::vector<std::optional<nav::Pose2>> PosesAtTimes(const std::vector<int64_t>& utimes,
                                                    const std::vector<nav::StampedPose>& poses, int64_t max_dt_us);

}  // namespace snapnav::eval
