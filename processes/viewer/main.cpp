// viewer: the live picture of a run in an OpenCV window, or PNG snapshots without a display.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>

#include <opencv2/highgui.hpp>

#include "snapnav/glue/app.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/place_cells.hpp"
#include "snapnav/glue/shutdown.hpp"
#include "snapnav/glue/time.hpp"
#include "snapnav/plot/plot.hpp"
#include "viewer_node.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;

constexpr char kWindow[] = "snapnav viewer";

bool HaveDisplay() {
  for (const char* v : {"DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM"}) {
    const char* s = std::getenv(v);
    if (s && *s) return true;
  }
  return false;
}

std::string SnapshotName(double t_s) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "viewer-t%07.1fs.png", t_s);
  return buf;
}

int Main(int argc, char** argv) {
  glue::CommonFlags common;
  common.config = SNAPNAV_CONFIG_DIR "/viewer.ini";
  std::string png_dir, memory, prefixes_text;
  double png_interval_s = -1;
  bool no_window = false, close_at_end = false;
  glue::Flags flags("viewer",
                    "The live picture of a run: the laser map, every pose channel's trajectory with 2-sigma covariance\n"
                    "ellipses, the ground truth, place cells, the laser scan and the homing vector at the robot, and\n"
                    "the current panorama with its landmarks. It only subscribes, so it shows a live bus or a log\n"
                    "(--lcm-url 'file://LOG?speed=0'). An OpenCV window (q or Esc closes it) refreshed at\n"
                    "[viewer] refresh_hz; --png DIR writes snapshots every png_interval_s of message time and at\n"
                    "exit, and needs no display.");
  flags.AddCommon(&common);
  std::string mask;
  flags.AddString("mask", &mask, glue::kMaskFlagHelp);
  flags.AddString("png", &png_dir, "write PNG snapshots into this folder (created); no window unless a display is set");
  flags.AddDouble("png-interval-s", &png_interval_s,
                  "a snapshot every this much message time [s] (overrides [viewer] png_interval_s; 0: at exit only)");
  flags.AddString("memory", &memory, "draw the place cells of this memory file (placecells --memory)");
  flags.AddBool("no-window", &no_window, "no window even when a display is set (with --png)");
  flags.AddBool("close-at-end", &close_at_end, "at the end of a file:// log close the window instead of keeping it");
  flags.AddString("prefixes", &prefixes_text,
                  "several robots on one bus: one view per channel prefix (comma-separated, e.g. R1_,R2_,R3_), side by "
                  "side in one picture (instead of --channel-prefix)");
  if (!flags.Parse(argc, argv)) return 0;

  std::vector<std::string> prefixes = glue::SplitList(prefixes_text);
  if (!prefixes.empty() && !common.channel_prefix.empty()) throw glue::FlagError("give --prefixes or --channel-prefix, not both");
  if (prefixes.empty()) prefixes.push_back(common.channel_prefix);
  auto ini = glue::IniFile::Load(common.config);
  glue::ApplyMaskFlag(mask, &ini);
  auto config = processes::ViewerConfig::FromIni(ini, prefixes.front());
  if (png_interval_s >= 0) config.png_interval_s = png_interval_s;
  const bool window = HaveDisplay() && !no_window;
  if (png_dir.empty() && !HaveDisplay()) {
    throw glue::FlagError(
        "no display: DISPLAY and WAYLAND_DISPLAY are not set. Use --png DIR to write snapshots without a display, "
        "or run on a desktop session or over ssh -X");
  }
  if (png_dir.empty() && no_window) throw glue::FlagError("--no-window needs --png DIR (nothing would be shown)");
  if (!png_dir.empty()) fs::create_directories(png_dir);
  std::cerr << "viewer: config " << common.config << "\n";
  config.Print(std::cerr);

  glue::InstallShutdownHandlers();
  glue::Bus bus(common.lcm_url);
  // One node per robot (channel prefix), all on the one bus.
  std::vector<std::unique_ptr<processes::ViewerNode>> nodes;
  for (const auto& prefix : prefixes) {
    auto c = processes::ViewerConfig::FromIni(ini, prefix);
    c.png_interval_s = config.png_interval_s;
    nodes.push_back(std::make_unique<processes::ViewerNode>(bus, c));
  }
  if (!memory.empty()) {
    const nav::PlaceCellMemory mem = glue::LoadPlaceMemory(memory);
    std::vector<cv::Point2f> cells;
    for (const auto& c : mem.cells()) cells.emplace_back(static_cast<float>(c.pose.x_m), static_cast<float>(c.pose.y_m));
    std::cerr << "viewer: " << cells.size() << " place cells from " << memory << "\n";
    for (auto& node : nodes) node->SetMemoryCells(cells);
  }
  std::cerr << "viewer: poses " << config.pose_channels << ", map " << config.point_map_channel << ", panorama "
            << config.panorama_channel << " or " << config.omni_channel << ", landmarks " << config.landmark_channels
            << (nodes.size() > 1 ? ", one view per prefix " + prefixes_text : std::string()) << " (" << bus.url()
            << ")" << (window ? ", window" : "") << (png_dir.empty() ? "" : ", snapshots in " + png_dir) << "\n";
  // Message time over every view: the first seen and the latest [us]; 0 before the first message.
  const auto first_utime = [&] {
    int64_t t = 0;
    for (const auto& n : nodes) {
      if (n->first_utime() != 0 && (t == 0 || n->first_utime() < t)) t = n->first_utime();
    }
    return t;
  };
  const auto latest_utime = [&] {
    int64_t t = 0;
    for (const auto& n : nodes) t = std::max(t, n->latest_utime());
    return t;
  };
  const auto render = [&]() -> cv::Mat {
    if (nodes.size() == 1) return nodes.front()->Render();
    std::vector<cv::Mat> views;
    std::vector<std::string> titles;
    for (size_t i = 0; i < nodes.size(); ++i) {
      views.push_back(nodes[i]->Render());
      titles.push_back("robot " + prefixes[i]);
    }
    return viewer::TileViews(views, titles, std::max(config.render.size.width, 2400));
  };

  int written = 0;
  auto write_png = [&](const std::string& name) {
    const std::string path = (fs::path(png_dir) / name).string();
    plot::SavePng(render(), path);
    ++written;
    std::cerr << "viewer: t " << std::fixed << std::setprecision(1) << (latest_utime() - first_utime()) * 1e-6
              << " s: " << path << "\n";
  };
  bool quit = false;
  auto show = [&](int wait_ms) {
    cv::imshow(kWindow, render());
    const int key = cv::waitKey(wait_ms);
    if (key == 'q' || key == 27 || cv::getWindowProperty(kWindow, cv::WND_PROP_VISIBLE) < 1) quit = true;
  };
  if (window) cv::namedWindow(kWindow, cv::WINDOW_AUTOSIZE);

  const int64_t refresh_us = static_cast<int64_t>(1e6 / config.refresh_hz);
  const int64_t png_us = static_cast<int64_t>(config.png_interval_s * 1e6);
  int64_t next_refresh = glue::MonotonicUtime();
  int64_t next_png = 0;  // message time of the next snapshot; 0: after the first message
  while (!quit && !glue::ShutdownRequested() && !bus.end_of_log()) {
    bus.HandleOnce(window ? 10 : 100);
    if (!png_dir.empty() && png_us > 0 && first_utime() != 0) {
      if (next_png == 0) next_png = first_utime() + png_us;
      if (latest_utime() >= next_png) {
        write_png(SnapshotName((next_png - first_utime()) * 1e-6));
        while (next_png <= latest_utime()) next_png += png_us;
      }
    }
    if (window && glue::MonotonicUtime() >= next_refresh) {
      show(1);
      next_refresh = glue::MonotonicUtime() + refresh_us;
    }
  }
  if (window && bus.end_of_log() && !close_at_end && !quit) {
    std::cerr << "viewer: end of the log; q or Esc closes the window\n";
    while (!quit && !glue::ShutdownRequested()) show(static_cast<int>(refresh_us / 1000));
  }
  if (!png_dir.empty()) write_png("viewer-final.png");
  if (window) cv::destroyAllWindows();
  std::cerr << "viewer: " << written << " snapshots written\n";
  for (const auto& node : nodes) node->Report(std::cerr);
  bus.ReportStats(std::cerr);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return glue::RunMain(argc, argv, Main); }
