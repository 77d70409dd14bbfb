#include "icp_slam.hpp"

#include <fcntl.h>
#include <mrpt/core/Clock.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "import_util.hpp"
#include "importers.hpp"
#include "mrpt_time.hpp"
#include "snapnav/laser_scan_t.hpp"

namespace snapnav::eval {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

using importers::MrptTimeToUtime;
using importers::UtimeToMrptTime;

std::string FirstLine(const std::string& text) {
  // MRPT exception texts: keep the innermost "Message:" line if there is one.
  std::istringstream in(text);
  std::string line, message;
  while (std::getline(in, line)) {
    const auto pos = line.find("Message:");
    if (pos != std::string::npos) {
      message = line.substr(pos + 8);
      message.erase(0, message.find_first_not_of(" \t"));
    }
  }
  return message.empty() ? text.substr(0, text.find('\n')) : message;
}

std::string Quote(const std::string& s) { return s.find_first_of(" \t'\"") == std::string::npos ? s : "'" + s + "'"; }

// The last `n` lines of a file, indented, for error messages.
std::string LastLines(const std::string& path, size_t n) {
  std::ifstream in(path);
  std::deque<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    std::replace(line.begin(), line.end(), '\r', '\n');
    if (const auto cut = line.rfind('\n'); cut != std::string::npos) line = line.substr(cut + 1);
    if (line.empty()) continue;
    lines.push_back(line);
    if (lines.size() > n) lines.pop_front();
  }
  std::string out;
  for (const auto& l : lines) out += "\n    " + l;
  return out.empty() ? "\n    (no output)" : out;
}

// `name` as run: a path if it has a slash, else the first executable of that name on PATH.
std::string FindProgram(const std::string& name, const std::string& package) {
  auto executable = [](const std::string& p) {
    struct stat st {};
    return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(p.c_str(), X_OK) == 0;
  };
  if (name.find('/') != std::string::npos) {
    if (executable(name)) return name;
    throw std::runtime_error(name + ": no such executable (install Debian's " + package + ")");
  }
  const char* path_env = std::getenv("PATH");
  std::istringstream dirs(path_env ? path_env : "/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    const std::string candidate = (dir.empty() ? "." : dir) + "/" + name;
    if (executable(candidate)) return candidate;
  }
  throw std::runtime_error(name + " not found on PATH (install Debian's " + package + ")");
}

struct ProgramResult {
  int status = 0;  // waitpid status
  double wall_seconds = 0;
};

// Runs argv[0] with stdin from /dev/null (icp-slam waits for a key after an error otherwise)
// and stdout and stderr into `log_path`; kills it after timeout_s.
ProgramResult RunProgram(const std::vector<std::string>& argv, const std::string& log_path, double timeout_s) {
  const int log_fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd < 0) throw std::runtime_error("cannot write " + log_path + ": " + std::strerror(errno));
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const auto t0 = Clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(log_fd);
    throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  }
  if (pid == 0) {
    const int null_fd = ::open("/dev/null", O_RDONLY);
    if (null_fd >= 0) ::dup2(null_fd, 0);
    ::dup2(log_fd, 1);
    ::dup2(log_fd, 2);
    ::execv(args[0], args.data());
    const std::string msg = std::string("exec ") + args[0] + ": " + std::strerror(errno) + "\n";
    (void)!::write(2, msg.data(), msg.size());
    ::_exit(127);
  }
  ::close(log_fd);
  ProgramResult result;
  for (;;) {
    const pid_t r = ::waitpid(pid, &result.status, WNOHANG);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) throw std::runtime_error(std::string("waitpid failed: ") + std::strerror(errno));
    if (std::chrono::duration<double>(Clock::now() - t0).count() > timeout_s) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &result.status, 0);
      throw std::runtime_error(argv[0] + " did not finish within " + std::to_string(static_cast<int>(timeout_s)) +
                               " s and was killed; its output is in " + log_path + LastLines(log_path, 10));
    }
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  result.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return result;
}

std::string CommandLine(const std::vector<std::string>& argv) {
  std::string s;
  for (const auto& a : argv) s += (s.empty() ? "" : " ") + Quote(a);
  return s;
}

void CheckExit(const ProgramResult& r, const std::vector<std::string>& argv, const std::string& log_path) {
  if (WIFEXITED(r.status) && WEXITSTATUS(r.status) == 0) return;
  const std::string how = WIFEXITED(r.status) ? "exited with code " + std::to_string(WEXITSTATUS(r.status))
                                              : "was killed by signal " + std::to_string(WTERMSIG(r.status));
  throw std::runtime_error("`" + CommandLine(argv) + "` " + how + "; its output is in " + log_path +
                           ", last lines:" + LastLines(log_path, 12));
}

std::ifstream OpenText(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + what + " " + path);
  return in;
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

bool IsRawlogPath(const std::string& path) { return EndsWith(path, ".rawlog") || EndsWith(path, ".rawlog.gz"); }

std::string MakeIcpSlamConfig(const std::string& base_ini, const std::string& rawlog, const std::string& output_dir,
                              const std::string& base_name, const std::vector<IcpSlamKey>& set) {
  const std::string app = "MappingApplication";
  std::vector<IcpSlamKey> keys = {{app, "rawlog_file", rawlog},         {app, "rawlog_offset", "0"},
                                  {app, "logOutput_dir", output_dir},    {app, "LOG_FREQUENCY", "0"},
                                  {app, "SAVE_3D_SCENE", "0"},           {app, "SAVE_POSE_LOG", "0"},
                                  {app, "SHOW_PROGRESS_3D_REAL_TIME", "0"}, {app, "verbosity", "LVL_WARN"}};
  const size_t own = keys.size();  // these are added where missing; the others must be there
  keys.insert(keys.end(), set.begin(), set.end());
  std::vector<bool> done(keys.size(), false);
  std::istringstream in(base_ini);
  std::vector<std::string> lines;
  std::string line, section;
  int header = -1;
  auto trim = [](std::string s) {
    s.erase(0, s.find_first_not_of(" \t\r"));
    s.erase(s.find_last_not_of(" \t\r") + 1);
    return s;
  };
  while (std::getline(in, line)) {
    const std::string t = trim(line);
    if (!t.empty() && t.front() == '[') {
      section = t.substr(1, t.find(']') == std::string::npos ? std::string::npos : t.find(']') - 1);
      if (section == app && header < 0) header = static_cast<int>(lines.size());
    } else if (!t.empty() && t[0] != '#' && t[0] != ';') {
      const auto eq = t.find('=');
      const std::string key = eq == std::string::npos ? "" : trim(t.substr(0, eq));
      for (size_t k = 0; k < keys.size(); ++k) {
        if (section == keys[k].section && key == keys[k].key) {
          std::string was = trim(t.substr(eq + 1));
          was = trim(was.substr(0, was.find("//")));
          lines.push_back("# snapnav: was " + keys[k].key + " = " + was);
          line = keys[k].key + " = " + keys[k].value;
          done[k] = true;
        }
      }
    }
    lines.push_back(line);
  }
  if (header < 0) throw std::invalid_argument("the icp-slam config has no [MappingApplication] section");
  std::vector<std::string> added;
  for (size_t k = 0; k < keys.size(); ++k) {
    if (done[k]) continue;
    if (k >= own) {
      throw std::invalid_argument("the icp-slam config has no key " + keys[k].key + " in [" + keys[k].section + "]");
    }
    added.push_back("# snapnav: added");
    added.push_back(keys[k].key + " = " + keys[k].value);
  }
  lines.insert(lines.begin() + header + 1, added.begin(), added.end());
  std::string out = "# icp-slam config generated by snapnav (tools/eval/icp_slam.cpp)" +
                    (base_name.empty() ? std::string() : " from " + base_name) +
                    ".\n# Each key it sets follows a '# snapnav:' line (MRPT's ini reader takes '//' comments after a "
                    "value,\n# not '#').\n";
  for (const auto& l : lines) out += l + "\n";
  return out;
}

std::vector<nav::Pose2> ParseIcpSlamPath(const std::string& path) {
  std::ifstream in = OpenText(path, "icp-slam path");
  std::vector<nav::Pose2> poses;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream s(line);
    long step = -1;
    nav::Pose2 p;
    std::string extra;
    if (!(s >> step >> p.x_m >> p.y_m >> p.theta_rad) || (s >> extra)) {
      throw std::runtime_error(path + ":" + std::to_string(n) + ": expected 'step x y yaw', got '" + line + "'");
    }
    if (step != static_cast<long>(poses.size())) {
      throw std::runtime_error(path + ":" + std::to_string(n) + ": step " + std::to_string(step) + ", expected " +
                               std::to_string(poses.size()));
    }
    if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.theta_rad)) {
      throw std::runtime_error(path + ":" + std::to_string(n) + ": pose is not finite");
    }
    poses.push_back(p);
  }
  return poses;
}

std::vector<double> ParseIcpSlamTimes(const std::string& path) {
  std::ifstream in = OpenText(path, "icp-slam timing");
  std::vector<double> ms;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream s(line);
    double t = 0;
    long map_size = 0;
    if (!(s >> t >> map_size) || !std::isfinite(t) || t < 0) {
      throw std::runtime_error(path + ":" + std::to_string(n) + ": expected 'milliseconds map_size', got '" + line +
                               "'");
    }
    ms.push_back(t);
  }
  return ms;
}

std::vector<RawlogStep> ReadRawlogSteps(const std::string& rawlog) {
  mrpt::io::CFileGZInputStream file;
  std::string error;
  if (!file.open(rawlog, error)) throw std::runtime_error("cannot open rawlog " + rawlog + ": " + error);
  auto archive = mrpt::serialization::archiveFrom(file);
  std::vector<RawlogStep> steps;
  size_t entry = 0;
  for (;;) {
    mrpt::obs::CActionCollection::Ptr action;
    mrpt::obs::CSensoryFrame::Ptr frame;
    mrpt::obs::CObservation::Ptr observation;
    try {
      if (!mrpt::obs::CRawlog::getActionObservationPairOrObservation(archive, action, frame, observation, entry)) {
        // It returns false at the end, and also (printing MRPT's exception) on data it cannot read.
        if (!file.checkEOF()) {
          throw std::runtime_error(rawlog + ": rawlog entry " + std::to_string(entry) +
                                   " cannot be read (MRPT's message is above); icp-slam stops there too");
        }
        break;
      }
    } catch (const std::exception& e) {
      throw std::runtime_error(rawlog + ": rawlog entry " + std::to_string(entry) +
                               " cannot be read: " + FirstLine(e.what()));
    }
    RawlogStep step;
    std::optional<int64_t> first, scan;
    auto look = [&](const mrpt::obs::CObservation::Ptr& o) {
      if (!o) return;
      const auto u = MrptTimeToUtime(o->timestamp);
      if (!first) first = u;
      if (dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(o.get()) && !step.scan) {
        step.scan = true;
        scan = u;
      }
    };
    if (observation) {
      look(observation);
    } else if (frame) {
      for (const auto& o : *frame) look(o);
    }
    step.utime = scan.value_or(first.value_or(0));
    steps.push_back(step);
  }
  return steps;
}

std::vector<nav::StampedPose> PosesAtScans(const std::vector<RawlogStep>& steps, const std::vector<nav::Pose2>& poses) {
  if (poses.size() != steps.size()) {
    throw std::runtime_error("icp-slam wrote " + std::to_string(poses.size()) + " poses for the " +
                             std::to_string(steps.size()) + " entries of the rawlog");
  }
  std::vector<nav::StampedPose> out;
  for (size_t i = 0; i < steps.size(); ++i) {
    if (steps[i].scan) out.push_back({steps[i].utime, poses[i]});
  }
  return out;
}

int64_t RestampCarmenRawlog(const std::string& converted_rawlog, const std::string& carmen_log,
                            const std::string& out_rawlog) {
  // The scan times log-import gives the CARMEN log (default options).
  class ScanTimes : public importers::Sink {
   public:
    void Write(const std::string& channel, int64_t utime, const std::string& payload) override {
      if (channel != channels::kLaserScan) return;
      laser_scan_t s;
      if (s.decode(payload.data(), 0, static_cast<int>(payload.size())) <= 0) return;
      utimes.push_back(utime);
      beams.push_back(static_cast<int>(s.ranges_m.size()));
    }
    std::vector<int64_t> utimes;
    std::vector<int> beams;
  } times;
  importers::ImportCarmenFile(carmen_log, times, importers::CarmenOptions{});
  if (times.utimes.empty()) throw std::runtime_error(carmen_log + ": no laser scans (log-import reads none)");

  mrpt::io::CFileGZInputStream in;
  std::string error;
  if (!in.open(converted_rawlog, error))
    throw std::runtime_error("cannot open rawlog " + converted_rawlog + ": " + error);
  auto archive = mrpt::serialization::archiveFrom(in);
  std::vector<mrpt::serialization::CSerializable::Ptr> objects;
  for (;;) {
    mrpt::serialization::CSerializable::Ptr o;
    try {
      archive >> o;
    } catch (const mrpt::serialization::CExceptionEOF&) {
      break;
    } catch (const std::exception& e) {
      throw std::runtime_error(converted_rawlog + ": object " + std::to_string(objects.size()) +
                               " cannot be read: " + FirstLine(e.what()));
    }
    objects.push_back(o);
  }
  // Scan k <- the k-th scan's time; other observations <- the time of the next scan (carmen2rawlog
  // writes a line's odometry before its scan), or of the last one at the end.
  std::vector<size_t> scan_index(objects.size(), 0);
  size_t scans = 0;
  for (size_t i = 0; i < objects.size(); ++i) {
    if (auto* s = dynamic_cast<mrpt::obs::CObservation2DRangeScan*>(objects[i].get())) {
      if (scans < times.utimes.size() && static_cast<int>(s->getScanSize()) != times.beams[scans]) {
        throw std::runtime_error(converted_rawlog + ": scan " + std::to_string(scans) + " has " +
                                 std::to_string(s->getScanSize()) + " beams but log-import reads " +
                                 std::to_string(times.beams[scans]) + " from " + carmen_log);
      }
      ++scans;
    }
  }
  if (scans != times.utimes.size()) {
    throw std::runtime_error(converted_rawlog + " holds " + std::to_string(scans) + " scans but log-import reads " +
                             std::to_string(times.utimes.size()) + " from " + carmen_log +
                             ": their times cannot be matched");
  }
  size_t next_scan = 0;
  for (size_t i = 0; i < objects.size(); ++i) {
    auto* o = dynamic_cast<mrpt::obs::CObservation*>(objects[i].get());
    if (!o) continue;
    const bool is_scan = dynamic_cast<mrpt::obs::CObservation2DRangeScan*>(o) != nullptr;
    const size_t k = std::min(next_scan, times.utimes.size() - 1);
    o->timestamp = UtimeToMrptTime(times.utimes[k]);
    if (is_scan) ++next_scan;
  }
  mrpt::io::CFileGZOutputStream out;
  if (!out.open(out_rawlog, 0, error)) throw std::runtime_error("cannot write rawlog " + out_rawlog + ": " + error);
  auto out_archive = mrpt::serialization::archiveFrom(out);
  for (const auto& o : objects) out_archive << *o;
  out.close();
  return static_cast<int64_t>(scans);
}

std::vector<std::optional<nav::Pose2>> PosesAtTimes(const std::vector<int64_t>& utimes,
                                                    const std::vector<nav::StampedPose>& poses, int64_t max_dt_us) {
  std::vector<std::optional<nav::Pose2>> out(utimes.size());
  for (size_t i = 0; i < utimes.size(); ++i) {
    if (const auto k = nav::NearestInTime(poses, utimes[i], max_dt_us)) out[i] = poses[*k].pose;
  }
  return out;
}

IcpSlamComparison CompareWithIcpSlam(const std::vector<int64_t>& scan_utimes, const std::vector<nav::Pose2>& slam,
                                     const std::vector<nav::StampedPose>& icp, int64_t max_dt_us) {
  if (scan_utimes.size() != slam.size()) throw std::invalid_argument("CompareWithIcpSlam: one pose per scan time");
  IcpSlamComparison c;
  c.icp_at_scans = PosesAtTimes(scan_utimes, icp, max_dt_us);
  std::vector<std::pair<nav::Pose2, nav::Pose2>> pairs;
  for (size_t i = 0; i < slam.size(); ++i) {
    if (c.icp_at_scans[i]) pairs.push_back({slam[i], *c.icp_at_scans[i]});
  }
  c.paired = static_cast<int64_t>(pairs.size());
  if (pairs.size() < 2) {
    throw std::runtime_error("only " + std::to_string(pairs.size()) + " of the log's " +
                             std::to_string(scan_utimes.size()) + " scans pair with icp-slam's " +
                             std::to_string(icp.size()) + " poses by time (within " + std::to_string(max_dt_us) +
                             " us): was the LCM log imported (log-import) from the file icp-slam ran on?");
  }
  c.slam_to_icp = nav::AlignSE2(pairs);
  c.difference = nav::ComputeAte(pairs, c.slam_to_icp);
  return c;
}

IcpSlamRun RunIcpSlam(const std::string& input, const std::string& work_dir, const IcpSlamOptions& options) {
  if (!fs::is_regular_file(input)) throw std::runtime_error("icp-slam input " + input + ": no such file");
  if (!fs::is_regular_file(options.base_config)) {
    throw std::runtime_error("icp-slam config " + options.base_config + ": no such file (install Debian's mrpt-apps)");
  }
  const std::string icp_slam = FindProgram(options.icp_slam, "mrpt-apps");
  fs::create_directories(work_dir);
  const fs::path work = fs::absolute(work_dir);
  auto say = [&](const std::string& s) {
    if (options.progress) std::cerr << "icp-slam: " << s << "\n";
  };

  IcpSlamRun run;
  run.rawlog = fs::absolute(input).string();
  if (!IsRawlogPath(input)) {
    const std::string carmen2rawlog = FindProgram(options.carmen2rawlog, "mrpt-apps");
    // carmen2rawlog reads plain text only.
    std::string text = input;
    {
      importers::internal::ZlibInputFile in(input);
      if (!in.is_open()) throw std::runtime_error("cannot open CARMEN log " + input);
      if (in.compressed()) {
        text = (work / "carmen.log").string();
        std::ofstream out(text, std::ios::binary);
        out << in.rdbuf();
        if (!in.error().empty()) throw std::runtime_error(input + ": " + in.error());
        if (!out) throw std::runtime_error("cannot write " + text);
      }
    }
    const std::string converted = (work / "carmen2rawlog.rawlog").string();
    const std::vector<std::string> argv = {carmen2rawlog, "-q", "-w", "-z", "0", "-i", text, "-o", converted};
    say("converting: " + CommandLine(argv));
    const std::string log = (work / "carmen2rawlog.log").string();
    CheckExit(RunProgram(argv, log, options.timeout_s), argv, log);
    run.rawlog = (work / "restamped.rawlog").string();
    const int64_t scans = RestampCarmenRawlog(converted, input, run.rawlog);
    say("re-stamped " + std::to_string(scans) +
        " scans with log-import's times (carmen2rawlog gives every "
        "observation the same time): " +
        run.rawlog);
  }

  std::string base;
  {
    std::ifstream in = OpenText(options.base_config, "icp-slam config");
    std::ostringstream s;
    s << in.rdbuf();
    base = s.str();
  }
  const fs::path out_dir = work / "icp-slam-out";
  run.config = (work / "icp-slam.ini").string();
  {
    std::ofstream cfg(run.config);
    cfg << MakeIcpSlamConfig(base, run.rawlog, out_dir.string(), options.base_config, options.set);
    if (!cfg) throw std::runtime_error("cannot write " + run.config);
  }
  fs::remove(out_dir / "log_estimated_path.txt");
  fs::remove(out_dir / "log_times.txt");
  const std::vector<std::string> argv = {icp_slam, run.config, run.rawlog};
  run.command = CommandLine(argv);
  run.output = (work / "icp-slam.log").string();
  say("running: " + run.command);
  const ProgramResult r = RunProgram(argv, run.output, options.timeout_s);
  CheckExit(r, argv, run.output);
  run.wall_seconds = r.wall_seconds;

  const std::string path_file = (out_dir / "log_estimated_path.txt").string();
  if (!fs::exists(path_file)) {
    throw std::runtime_error("`" + run.command + "` wrote no " + path_file + "; last lines of its output (" +
                             run.output + "):" + LastLines(run.output, 12));
  }
  const std::vector<nav::Pose2> poses = ParseIcpSlamPath(path_file);
  const std::vector<double> ms = ParseIcpSlamTimes((out_dir / "log_times.txt").string());
  const std::vector<RawlogStep> steps = ReadRawlogSteps(run.rawlog);
  if (poses.size() != steps.size()) {
    throw std::runtime_error("`" + run.command + "` wrote " + std::to_string(poses.size()) + " poses to " + path_file +
                             " for the " + std::to_string(steps.size()) + " entries of " + run.rawlog +
                             "; last lines of its output (" + run.output + "):" + LastLines(run.output, 12));
  }
  if (ms.size() != poses.size()) {
    throw std::runtime_error((out_dir / "log_times.txt").string() + " has " + std::to_string(ms.size()) +
                             " lines for " + std::to_string(poses.size()) + " poses");
  }
  run.poses = PosesAtScans(steps, poses);
  run.steps = static_cast<int64_t>(steps.size());
  for (double t : ms) run.slam_seconds += t / 1000.0;
  if (run.poses.empty()) throw std::runtime_error(run.rawlog + " has no laser scans icp-slam processed");
  std::sort(run.poses.begin(), run.poses.end(), [](const auto& a, const auto& b) { return a.utime < b.utime; });
  say(std::to_string(run.poses.size()) + " scans in " + std::to_string(run.steps) + " rawlog entries; " +
      std::to_string(run.ms_per_scan()) + " ms/scan (its own timing), " + std::to_string(run.wall_ms_per_scan()) +
      " ms/scan wall");
  return run;
}

}  // namespace snapnav::eval
