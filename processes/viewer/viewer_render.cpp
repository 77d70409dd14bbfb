#include "viewer_render.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "snapnav/plot/map_view.hpp"
#include "snapnav/plot/plot.hpp"

namespace snapnav::viewer {

const cv::Scalar kHomingColour(200, 0, 200);
const cv::Scalar kMapColour(70, 70, 70);
const cv::Scalar kGridOccupiedColour(150, 140, 125);
const cv::Scalar kScanColour(215, 195, 90);
const cv::Scalar kPlaceCellColour(44, 160, 44);  // plot::SeriesColour(2), as POSE_PLACE_CELLS

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kPanelWidthPx = 430;
constexpr int kTitleHeightPx = 34;
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kGreyText(100, 100, 100);
const cv::Scalar kBackground(255, 255, 255);
const cv::Scalar kPanoramaHoming(255, 0, 255);
const cv::Scalar kMemoryCellColour(149, 207, 149);  // the place-cell green, lighter

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string Format(const char* fmt, double a) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), fmt, a);
  return buf;
}

double Deg(double rad) { return rad * 180 / kPi; }

double Seconds(const ViewerScene& scene, int64_t utime) {
  return scene.first_utime ? (utime - scene.first_utime) * 1e-6 : 0.0;
}

// Column of `bearing` in a panorama of `width` px whose column 0 looks at `col0` (fractional, in [0, width)).
double BearingColumn(double bearing_rad, double col0_rad, int width) {
  double c = (col0_rad - bearing_rad) / (2 * kPi) * width;
  c = std::fmod(c, static_cast<double>(width));
  if (c < 0) c += width;
  return c;
}

// The 2-sigma position error of a covariance: the ellipse's semi-major axis [m] (0 when unknown).
double PositionError(const Eigen::Matrix3d& cov, double sigma) {
  if (!cov.allFinite() || (cov(0, 0) <= 0 && cov(1, 1) <= 0)) return 0;
  return plot::CovarianceEllipse(cov(0, 0), cov(0, 1), cov(1, 1), sigma).major;
}

void DrawTrack(cv::Mat& img, const plot::MapView& view, const Track& track, bool truth, const cv::Scalar& colour,
               const RenderOptions& options) {
  std::vector<const PoseSample*> samples;
  samples.reserve(track.poses.size() + 1);
  for (const auto& p : track.poses) samples.push_back(&p);
  if (track.poses.empty() || track.poses.back().utime != track.latest.utime) samples.push_back(&track.latest);
  // One polyline per stretch between announced jumps; a ring where each jump landed.
  std::vector<cv::Point2d> pts;
  size_t next_jump = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const PoseSample& p = *samples[i];
    bool jumped = false;
    while (i > 0 && next_jump < track.jumps.size() && track.jumps[next_jump] <= p.utime) {
      jumped = jumped || track.jumps[next_jump] > samples[i - 1]->utime;
      ++next_jump;
    }
    if (jumped) {
      view.DrawPolyline(img, pts, colour, truth ? 3 : 2);
      pts.clear();
      const cv::Point2d at = view.ToPixel(p.pose.x_m, p.pose.y_m);
      cv::circle(img, cv::Point(static_cast<int>(std::lround(at.x)), static_cast<int>(std::lround(at.y))), 6, colour, 2,
                 cv::LINE_8);
    }
    pts.emplace_back(p.pose.x_m, p.pose.y_m);
  }
  view.DrawPolyline(img, pts, colour, truth ? 3 : 2);
  if (truth) return;  // the ground truth has no covariance
  int64_t last = 0;
  const int64_t step = static_cast<int64_t>(options.ellipse_interval_s * 1e6);
  for (const auto& p : track.poses) {
    if (last != 0 && p.utime - last < step) continue;
    last = p.utime;
    view.DrawCovarianceEllipse(img, p.pose.x_m, p.pose.y_m, p.covariance(0, 0), p.covariance(0, 1),
                               p.covariance(1, 1), options.ellipse_sigma, colour, 1);
  }
  const auto& c = track.latest.covariance;
  view.DrawCovarianceEllipse(img, track.latest.pose.x_m, track.latest.pose.y_m, c(0, 0), c(0, 1), c(1, 1),
                             options.ellipse_sigma, colour, 2);
}

// The occupancy grid, pixel by pixel of the plot area: free cells light grey, occupied ones dark,
// unknown ones left as the background.
void DrawGrid(cv::Mat& img, const plot::MapView& view, const GridView& g) {
  if (g.width <= 0 || g.height <= 0 || g.resolution_m <= 0) return;
  const cv::Rect area = view.area() & cv::Rect(0, 0, img.cols, img.rows);
  const cv::Point2d p0 = view.ToPixel(0, 0);
  const double s = view.pixels_per_m();
  const double c = std::cos(g.origin_theta_rad), sn = std::sin(g.origin_theta_rad), inv = 1.0 / g.resolution_m;
  for (int py = area.y; py < area.y + area.height; ++py) {
    cv::Vec3b* row = img.ptr<cv::Vec3b>(py);
    const double wy = (p0.y - (py + 0.5)) / s - g.origin_y_m;
    for (int px = area.x; px < area.x + area.width; ++px) {
      const double wx = ((px + 0.5) - p0.x) / s - g.origin_x_m;
      const double gx = (c * wx + sn * wy) * inv, gy = (-sn * wx + c * wy) * inv;
      if (gx < 0 || gy < 0 || gx >= g.width || gy >= g.height) continue;
      const int8_t v = g.cells[static_cast<size_t>(gy) * static_cast<size_t>(g.width) + static_cast<size_t>(gx)];
      if (v < 0) continue;
      if (v >= 65) {
        row[px] = cv::Vec3b(static_cast<uint8_t>(kGridOccupiedColour[0]), static_cast<uint8_t>(kGridOccupiedColour[1]),
                            static_cast<uint8_t>(kGridOccupiedColour[2]));
      } else {
        const auto grey = static_cast<uint8_t>(std::lround(232 - 1.4 * v));
        row[px] = cv::Vec3b(grey, grey, grey);
      }
    }
  }
}

void DrawMapPart(cv::Mat& img, const Layout& layout, const ViewerScene& scene, const RenderOptions& options) {
  plot::WorldBounds bounds;
  if (scene.grid && scene.grid->any_known) {
    bounds.Extend(scene.grid->known_x0, scene.grid->known_y0);
    bounds.Extend(scene.grid->known_x1, scene.grid->known_y1);
  }
  for (const auto& [_, t] : scene.tracks) {
    for (const auto& p : t.poses) bounds.Extend(p.pose.x_m, p.pose.y_m);
    if (t.received > 0) bounds.Extend(t.latest.pose.x_m, t.latest.pose.y_m);
  }
  for (const auto& p : scene.map_points) bounds.Extend(p.x, p.y);
  for (const auto& p : scene.memory_cells) bounds.Extend(p.x, p.y);
  for (const auto& m : scene.matches) bounds.Extend(m.x_m, m.y_m);
  // The scan of the moment, in the world at the robot pose (it widens the view to what the robot sees).
  const auto robot = RobotPose(scene, options);
  std::vector<cv::Point2f> scan_world;
  if (scene.scan && robot && std::llabs(robot->second.utime - scene.scan->utime) <= options.scan_max_age_s * 1e6) {
    const nav::Pose2 sensor = robot->second.pose.Compose(scene.scan->mount);
    scan_world.reserve(scene.scan->points.size());
    for (const auto& p : scene.scan->points) {
      const Eigen::Vector2d w = sensor.Transform({p.x, p.y});
      scan_world.emplace_back(static_cast<float>(w.x()), static_cast<float>(w.y()));
      bounds.Extend(w.x(), w.y());
    }
  }
  const plot::MapView view(layout.map, bounds, options.min_span_m, 0.04);
  view.DrawAxes(img);
  if (scene.grid) DrawGrid(img, view, *scene.grid);  // under everything

  view.DrawPoints(img, scan_world, kScanColour, 3);  // under the map, so both show where they agree
  view.DrawPoints(img, scene.map_points, kMapColour, 2);
  for (const auto& c : scene.memory_cells) {
    view.DrawCircle(img, c.x, c.y, 4, kMemoryCellColour, 1);
  }

  // Ground truth first, so the estimates are drawn over it.
  const auto truth = scene.tracks.find(scene.truth_channel);
  if (truth != scene.tracks.end()) DrawTrack(img, view, truth->second, true, ChannelColour(truth->first), options);
  for (const auto& [ch, t] : scene.tracks) {
    if (ch != scene.truth_channel) DrawTrack(img, view, t, false, ChannelColour(ch), options);
  }

  for (const auto& m : scene.matches) view.DrawCircle(img, m.x_m, m.y_m, 3, kPlaceCellColour, cv::FILLED);
  if (!scene.matches.empty()) {
    const auto& m = scene.matches.back();
    view.DrawCircle(img, m.x_m, m.y_m, 8, kPlaceCellColour, 2);
  }

  for (const auto& [ch, t] : scene.tracks) {
    if (t.received > 0) view.DrawPose(img, t.latest.pose.x_m, t.latest.pose.y_m, t.latest.pose.theta_rad, 9, ChannelColour(ch));
  }
  if (scene.homing && scene.homing->valid && robot) {
    const auto& r = robot->second.pose;
    view.DrawArrow(img, r.x_m, r.y_m, r.theta_rad + scene.homing->direction_rad, options.homing_arrow_px,
                   kHomingColour, 3);
  }
  view.DrawScaleBar(img);
  if (scene.tracks.empty() && scene.map_points.empty() && !scene.grid) {
    plot::DrawText(img, "waiting for poses and maps ...", {layout.map.x + 20, layout.map.y + 25}, 0.55, kGreyText);
  }
}

void DrawPanel(cv::Mat& img, const Layout& layout, const ViewerScene& scene, const RenderOptions& options) {
  const int x = layout.panel.x;
  int y = layout.panel.y;
  auto line = [&](const std::string& text, double scale = 0.45, const cv::Scalar& colour = kBlack) {
    plot::DrawText(img, text, {x, y + 9}, scale, colour);
    y += 19;
  };
  auto heading = [&](const std::string& text) {
    y += 6;
    plot::DrawText(img, text, {x, y + 9}, 0.5, kBlack, 1);
    cv::line(img, {x, y + 19}, {layout.panel.x + layout.panel.width - 10, y + 19}, cv::Scalar(200, 200, 200), 1);
    y += 25;
  };

  heading(Format("Trajectories (ellipses: %.0f sigma)", options.ellipse_sigma));
  std::vector<std::string> order;
  if (scene.tracks.count(scene.truth_channel)) order.push_back(scene.truth_channel);
  for (const auto& [ch, _] : scene.tracks)
    if (ch != scene.truth_channel) order.push_back(ch);
  if (order.empty()) line("no pose_t channel yet", 0.45, kGreyText);
  for (const auto& ch : order) {
    const Track& t = scene.tracks.at(ch);
    plot::DrawLegend(img, {x, y}, {{ch + "  (" + std::to_string(t.received) + ")", ChannelColour(ch),
                                     plot::LegendMark::kLine}},
                     0.45);
    y += 20;
    const auto& p = t.latest.pose;
    std::string detail = Format("x %.2f m", p.x_m) + Format("  y %.2f m", p.y_m) + Format("  th %.0f deg", Deg(p.theta_rad));
    const double err = PositionError(t.latest.covariance, options.ellipse_sigma);
    if (err > 0) detail += Format("  +-%.3f m", err);
    plot::DrawText(img, detail, {x + 30, y + 7}, 0.4, kGreyText);
    y += 19;
  }

  heading("Map, place cells, homing");
  std::vector<plot::LegendEntry> entries;
  if (scene.grid) {
    const GridView& g = *scene.grid;
    entries.push_back({"occupancy grid: " + std::to_string(g.width) + " x " + std::to_string(g.height) + Format(" cells of %.2f m", g.resolution_m) +
                           " (" + g.source + ")",
                       kGridOccupiedColour, plot::LegendMark::kDot});
  }
  if (!scene.map_points.empty()) {
    entries.push_back({"point map: " + std::to_string(scene.map_points.size()) + " points (" + scene.map_estimator + ")",
                       kMapColour, plot::LegendMark::kDot});
  }
  if (scene.scan) {
    const auto robot = RobotPose(scene, options);
    entries.push_back({"laser scan: " + std::to_string(scene.scan->points.size()) + " returns" +
                           (robot ? " at " + robot->first : std::string(" (no robot pose)")),
                       kScanColour, plot::LegendMark::kDot});
  }
  if (!scene.memory_cells.empty()) {
    entries.push_back({"memory: " + std::to_string(scene.memory_cells.size()) + " place cells",
                       kMemoryCellColour, plot::LegendMark::kCircle});
  }
  if (!scene.matches.empty()) {
    const auto& m = scene.matches.back();
    entries.push_back({"matched cell " + std::to_string(m.cell_id) + Format(" at (%.2f", m.x_m) + Format(", %.2f)", m.y_m) +
                           Format(" d=%.3f", m.distance),
                       kPlaceCellColour, plot::LegendMark::kDot});
  }
  if (scene.homing) {
    const auto& h = *scene.homing;
    const bool variant = !h.alv_variant.empty() && h.alv_variant != h.method;
    entries.push_back({"homing vector (" + h.method + (variant ? ", " + h.alv_variant : "") + ")" +
                           (h.valid ? "" : ": no estimate"),
                       kHomingColour, plot::LegendMark::kArrow});
  }
  if (entries.empty()) line("nothing yet", 0.45, kGreyText);
  y = plot::DrawLegend(img, {x, y}, entries, 0.42).br().y;
  if (scene.homing && scene.homing->valid) {
    const auto& h = *scene.homing;
    plot::DrawText(img,
                   Format("  direction %.1f deg", Deg(h.direction_rad)) + Format(", compass %.1f deg", Deg(h.compass_rotation_rad)),
                   {x + 30, y + 8}, 0.4, kGreyText);
    y += 19;
    plot::DrawText(img, Format("  magnitude %.3f", h.magnitude) + ", " + std::to_string(h.landmarks_used) + " landmarks",
                   {x + 30, y + 8}, 0.4, kGreyText);
    y += 19;
  }

  heading("Messages");
  int shown = 0;
  for (const auto& [ch, n] : scene.channel_counts) {
    if (y > layout.panel.y + layout.panel.height - 40) {
      line("... " + std::to_string(scene.channel_counts.size() - shown) + " more channels", 0.4, kGreyText);
      break;
    }
    plot::DrawText(img, ch, {x, y + 8}, 0.4, kBlack);
    plot::DrawText(img, std::to_string(n), {x + 250, y + 8}, 0.4, kBlack);
    y += 17;
    ++shown;
  }
  if (scene.rejected > 0) line(std::to_string(scene.rejected) + " messages rejected (see stderr)", 0.42, cv::Scalar(0, 0, 200));
}

void DrawPanoramaPart(cv::Mat& img, const Layout& layout, const ViewerScene& scene) {
  const cv::Rect r = layout.panorama;
  const int label_y = r.y - 13;
  if (!scene.panorama || scene.panorama->image.empty()) {
    img(r).setTo(cv::Scalar(235, 235, 235));
    plot::DrawText(img, "panorama: waiting for OMNI_PANORAMA or OMNI_FRAME ...", {r.x + 20, r.y + r.height / 2}, 0.55,
                   kGreyText);
    return;
  }
  const PanoramaView& pano = *scene.panorama;
  cv::Mat bgr;
  if (pano.image.channels() == 1) {
    cv::cvtColor(pano.image, bgr, cv::COLOR_GRAY2BGR);
  } else {
    bgr = pano.image;
  }
  cv::resize(bgr, img(r), r.size(), 0, 0, cv::INTER_LINEAR);
  cv::rectangle(img, r, cv::Scalar(120, 120, 120), 1);
  const int w = pano.image.cols;
  const double sx = static_cast<double>(r.width) / w;
  plot::DrawText(img, "panorama " + pano.source + Format("  t = %.2f s", Seconds(scene, pano.utime)), {r.x, label_y},
                 0.45);

  // Bearing ticks under the image, every 45 degrees from column 0.
  for (int k = 0; k <= 8; ++k) {
    const double c = k * w / 8.0;
    double deg = std::round(Deg(pano.bearing_col0_rad - c * 2 * kPi / w));
    deg = std::fmod(deg + 540.0, 360.0) - 180.0;  // (-180, 180]
    if (deg == -180 && k == 0) deg = 180;
    const int px = r.x + cvRound(c * sx);
    cv::line(img, {px, r.y + r.height}, {px, r.y + r.height + 5}, kBlack, 1);
    const std::string label = Format("%.0f", deg);
    int baseline = 0;
    const int tw = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, 0.38, 1, &baseline).width;
    cv::putText(img, label, {px - tw / 2, r.y + r.height + 18}, cv::FONT_HERSHEY_SIMPLEX, 0.38, kBlack, 1, cv::LINE_AA);
  }
  plot::DrawText(img, "bearing [deg], robot frame (0 = forward, + = left)", {r.x + r.width - 330, r.y + r.height + 32},
                 0.4, kGreyText);

  // Landmarks: a tick at the top edge and a ring at the landmark's row.
  std::vector<plot::LegendEntry> legend;
  for (const auto& [ch, set] : scene.landmarks) {
    const cv::Scalar colour = LandmarkColour(set.method);
    const double sy = set.panorama_height_px > 0 ? static_cast<double>(r.height) / set.panorama_height_px : 0;
    for (size_t i = 0; i < set.bearings_rad.size(); ++i) {
      const double c = BearingColumn(set.bearings_rad[i], pano.bearing_col0_rad, w);
      const int px = r.x + cvRound(c * sx);
      cv::line(img, {px, r.y + 1}, {px, r.y + 9}, colour, 2);
      if (sy > 0 && i < set.rows_px.size() && std::isfinite(set.rows_px[i])) {
        const int py = r.y + std::clamp(cvRound(set.rows_px[i] * sy), 0, r.height - 1);
        cv::circle(img, {px, py}, 5, kBlack, 1, cv::LINE_AA);
        cv::circle(img, {px, py}, 4, colour, 1, cv::LINE_AA);
      }
    }
    legend.push_back({ch + ": " + std::to_string(set.bearings_rad.size()) + " landmarks" +
                          Format(", t = %.2f s", Seconds(scene, set.utime)),
                      colour, plot::LegendMark::kCircle});
  }
  if (scene.homing && scene.homing->valid) {
    const double c = BearingColumn(scene.homing->direction_rad, pano.bearing_col0_rad, w);
    const int px = r.x + cvRound(c * sx);
    cv::line(img, {px, r.y}, {px, r.y + r.height - 1}, kBlack, 3);
    cv::line(img, {px, r.y}, {px, r.y + r.height - 1}, kPanoramaHoming, 1);
    plot::DrawText(img, "home", {px + 5, r.y + 20}, 0.5, kBlack, 4);
    plot::DrawText(img, "home", {px + 5, r.y + 20}, 0.5, kPanoramaHoming, 1);
    legend.push_back({"homing direction", kPanoramaHoming, plot::LegendMark::kLine});
  }
  // Legend to the right of the title line.
  int lx = r.x + 480;
  for (const auto& e : legend) {
    const cv::Rect used = plot::DrawLegend(img, {lx, label_y - 10}, {e}, 0.4);
    lx += used.width + 25;
  }
}

}  // namespace

void RenderOptions::Validate() const {
  if (size.width < 900 || size.height < 700)
    throw std::invalid_argument("viewer: width_px and height_px must be at least 900 and 700");
  if (!(ellipse_sigma > 0)) throw std::invalid_argument("viewer: ellipse_sigma must be positive");
  if (!(ellipse_interval_s > 0)) throw std::invalid_argument("viewer: ellipse_interval_s must be positive");
  if (!(min_span_m > 0)) throw std::invalid_argument("viewer: min_span_m must be positive");
  if (!(scan_max_age_s >= 0)) throw std::invalid_argument("viewer: scan_max_age_s must not be negative");
  if (homing_arrow_px < 5) throw std::invalid_argument("viewer: homing_arrow_px must be at least 5");
}

Layout ComputeLayout(cv::Size size) {
  Layout l;
  const int pano_w = size.width - 100;
  const int pano_h = std::min(pano_w * 120 / 720, size.height / 4);
  const int pano_block = pano_h + 75;  // title line above, bearing labels below
  const int top = size.height - pano_block;
  l.map = cv::Rect(70, kTitleHeightPx + 6, size.width - kPanelWidthPx - 70 - 25, top - kTitleHeightPx - 6 - 55);
  l.panel = cv::Rect(size.width - kPanelWidthPx + 10, kTitleHeightPx + 6, kPanelWidthPx - 20, top - kTitleHeightPx - 6);
  l.panorama = cv::Rect(50, top + 30, pano_w, pano_h);
  return l;
}

cv::Scalar ChannelColour(const std::string& channel) {
  struct Known {
    const char* suffix;
    cv::Scalar colour;
  };
  static const Known kKnown[] = {
      {"POSE_GROUND_TRUTH", cv::Scalar(0, 0, 0)},      {"POSE_DEAD_RECKONING", plot::SeriesColour(1)},
      {"POSE_LASER_SLAM", plot::SeriesColour(0)},      {"POSE_EKF", plot::SeriesColour(3)},
      {"POSE_RATSLAM", plot::SeriesColour(4)},         {"POSE_PLACE_CELLS", plot::SeriesColour(2)},
  };
  for (const auto& k : kKnown) {
    if (EndsWith(channel, k.suffix)) return k.colour;
  }
  // Other channels: brown, pink, olive, cyan, by a stable hash of the name (FNV-1a).
  static const int kOthers[] = {5, 6, 8, 9};
  uint32_t h = 2166136261u;
  for (unsigned char c : channel) h = (h ^ c) * 16777619u;
  return plot::SeriesColour(kOthers[h % 4]);
}

cv::Scalar LandmarkColour(const std::string& method) {
  if (method == "vline") return {0, 255, 255};  // yellow
  if (method == "sift") return {255, 255, 0};   // cyan
  if (method == "surf") return {0, 255, 0};     // lime
  return {255, 255, 255};
}

std::optional<std::pair<std::string, PoseSample>> RobotPose(const ViewerScene& scene, const RenderOptions& options) {
  for (const auto& wanted : options.robot_pose_channels) {
    for (const auto& [ch, t] : scene.tracks) {
      if (t.received > 0 && (ch == wanted || EndsWith(ch, wanted))) return std::make_pair(ch, t.latest);
    }
  }
  return std::nullopt;
}

cv::Mat RenderScene(const ViewerScene& scene, const RenderOptions& options) {
  options.Validate();
  cv::Mat img(options.size, CV_8UC3, kBackground);
  const Layout layout = ComputeLayout(options.size);
  std::string title = options.title;
  if (scene.latest_utime) {
    title += Format("   t = %.2f s", Seconds(scene, scene.latest_utime)) +
             Format(" (utime %.6f s)", scene.latest_utime * 1e-6);
  } else {
    title += "   (no message yet)";
  }
  plot::DrawText(img, title, {20, kTitleHeightPx / 2 + 2}, 0.6, kBlack, 1);
  if (!scene.source.empty()) {
    int baseline = 0;
    const int tw = cv::getTextSize(scene.source, cv::FONT_HERSHEY_SIMPLEX, 0.4, 1, &baseline).width;
    plot::DrawText(img, scene.source, {options.size.width - tw - 15, kTitleHeightPx / 2 + 2}, 0.4, kGreyText);
  }
  DrawMapPart(img, layout, scene, options);
  DrawPanel(img, layout, scene, options);
  DrawPanoramaPart(img, layout, scene);
  return img;
}

cv::Mat TileViews(const std::vector<cv::Mat>& views, const std::vector<std::string>& titles, int max_width_px) {
  if (views.empty() || views.size() != titles.size()) throw std::invalid_argument("TileViews: one title per view, at least one view");
  if (max_width_px < 100) throw std::invalid_argument("TileViews: max_width_px must be at least 100");
  const int n = static_cast<int>(views.size());
  const int cols = n <= 3 ? n : static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
  const int rows = (n + cols - 1) / cols;
  const int cell_w = max_width_px / cols, title_h = 30;
  int cell_h = 0;
  for (const auto& v : views) {
    if (v.empty() || v.type() != CV_8UC3) throw std::invalid_argument("TileViews: views must be non-empty BGR images");
    cell_h = std::max(cell_h, static_cast<int>(std::lround(v.rows * static_cast<double>(cell_w) / v.cols)));
  }
  cv::Mat out(rows * (cell_h + title_h), cols * cell_w, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int i = 0; i < n; ++i) {
    const cv::Rect cell((i % cols) * cell_w, (i / cols) * (cell_h + title_h), cell_w, cell_h + title_h);
    const int h = static_cast<int>(std::lround(views[i].rows * static_cast<double>(cell_w) / views[i].cols));
    cv::resize(views[i], out(cv::Rect(cell.x, cell.y + title_h, cell_w, h)), cv::Size(cell_w, h), 0, 0, cv::INTER_AREA);
    cv::rectangle(out, cv::Rect(cell.x, cell.y, cell_w, title_h), cv::Scalar(60, 60, 60), cv::FILLED);
    cv::putText(out, titles[i], {cell.x + 8, cell.y + 21}, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(255, 255, 255), 1,
                cv::LINE_AA);
    cv::rectangle(out, cell, cv::Scalar(60, 60, 60), 1);
  }
  return out;
}

}  // namespace snapnav::viewer
