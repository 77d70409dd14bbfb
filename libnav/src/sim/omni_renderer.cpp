#include "snapnav/nav/sim/omni_renderer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace snapnav::nav::sim {
namespace {

// A texture level's column pair around x (wrapped around) and the weight of the second.
struct TexelColumns {
  int x0, x1;
  double fx;
};
inline TexelColumns Columns(const cv::Mat& img, double x) {
  const int w = img.cols;
  x -= std::floor(x / w) * w;
  const int x0 = std::min(static_cast<int>(x), w - 1);
  return {x0, x0 + 1 < w ? x0 + 1 : 0, x - x0};
}

// Bilinear sample of a texture level at columns `cols` and row y (wrapped around), scaled by `shade`.
inline cv::Vec3b Sample(const cv::Mat& img, const TexelColumns& cols, double y, double shade) {
  const int h = img.rows;
  y -= std::floor(y / h) * h;
  const int y0 = std::min(static_cast<int>(y), h - 1);
  const int y1 = y0 + 1 < h ? y0 + 1 : 0;
  const double fx = cols.fx, fy = y - y0;
  const cv::Vec3b& a = img.at<cv::Vec3b>(y0, cols.x0);
  const cv::Vec3b& b = img.at<cv::Vec3b>(y0, cols.x1);
  const cv::Vec3b& c = img.at<cv::Vec3b>(y1, cols.x0);
  const cv::Vec3b& d = img.at<cv::Vec3b>(y1, cols.x1);
  cv::Vec3b out;
  for (int k = 0; k < 3; ++k) {
    const double top = a[k] + fx * (b[k] - a[k]);
    const double bottom = c[k] + fx * (d[k] - c[k]);
    out[k] = cv::saturate_cast<uint8_t>((top + fy * (bottom - top)) * shade);
  }
  return out;
}

// Mip level whose texel matches a footprint of `meters_per_pixel`.
inline const cv::Mat& Level(const Texture& t, double meters_per_pixel, double* scale) {
  const double texels = meters_per_pixel * t.levels[0].cols / t.width_m;
  int level = texels > 1 ? static_cast<int>(std::log2(texels)) : 0;
  level = std::min(level, static_cast<int>(t.levels.size()) - 1);
  *scale = std::ldexp(1.0, -level);
  return t.levels[level];
}

}  // namespace

void CameraOptics::Validate() const {
  if (!enabled) return;
  auto grey = [](double v) { return v >= 0 && v <= 255; };
  if (!grey(housing_grey) || !grey(lens_grey)) throw std::invalid_argument("optics: grey levels must be in 0..255");
  if (!(lens_radius_frac >= 0 && lens_radius_frac < 0.95)) throw std::invalid_argument("optics: lens_radius_frac must be in [0, 0.95)");
  if (!(vignetting >= 0 && vignetting < 1)) throw std::invalid_argument("optics: vignetting must be in [0, 1)");
  for (double g : {colour_gain_b, colour_gain_g, colour_gain_r}) {
    if (!(g > 0 && g <= 4)) throw std::invalid_argument("optics: colour gains must be in (0, 4]");
  }
  if (!(shot_noise >= 0) || !(read_noise_grey >= 0)) throw std::invalid_argument("optics: noise must be >= 0");
  if (!(rim_softness_px >= 0 && rim_softness_px <= 20)) throw std::invalid_argument("optics: rim_softness_px must be in [0, 20]");
  for (const auto& p : parts) {
    if (!(p.radius0_frac >= 0 && p.radius1_frac >= 0 && p.radius0_frac <= 2 && p.radius1_frac <= 2) ||
        !(p.width_frac > 0 && p.width_frac <= 0.5) || !grey(p.grey) || !std::isfinite(p.bearing0_rad) ||
        !std::isfinite(p.bearing1_rad)) {
      throw std::invalid_argument("optics: a robot part needs radii in [0, 2], width_frac in (0, 0.5], grey in 0..255");
    }
  }
  if (!(window_width_rad >= 0 && window_width_rad < 2 * M_PI) || !(window_gain >= 0 && window_gain <= 10) ||
      !(window_elevation_top_rad >= window_elevation_bottom_rad) || !std::isfinite(window_bearing_rad)) {
    throw std::invalid_argument("optics: the window needs width in [0, 360) deg, gain in [0, 10], top >= bottom");
  }
  for (double e : {calibration_error_x_px, calibration_error_y_px, calibration_error_radius_px}) {
    if (!std::isfinite(e) || std::abs(e) > 50) throw std::invalid_argument("optics: calibration errors must be within 50 px");
  }
  if (!(exposure_target_grey > 0 && exposure_target_grey < 255)) {
    throw std::invalid_argument("optics: exposure_target_grey must be in (0, 255)");
  }
  if (!(exposure_rate > 0 && exposure_rate <= 1)) throw std::invalid_argument("optics: exposure_rate must be in (0, 1]");
  if (!(exposure_min > 0 && exposure_min <= 1 && exposure_max >= 1 && exposure_max <= 16)) {
    throw std::invalid_argument("optics: the exposure range needs 0 < exposure_min <= 1 <= exposure_max <= 16");
  }
  if (jpeg_quality < 0 || jpeg_quality > 100) throw std::invalid_argument("optics: jpeg_quality must be in 0..100 (0: none)");
  if (!(exposure_time_s >= 0 && exposure_time_s <= 0.5)) throw std::invalid_argument("optics: exposure_time_s must be in [0, 0.5]");
}

CameraOptics CameraOpticsPreset(const std::string& name) {
  CameraOptics o;
  if (name == "clean") return o;
  if (name != "realistic") throw std::invalid_argument("camera preset '" + name + "': expected clean or realistic");
  o.enabled = true;
  constexpr double d = M_PI / 180;
  // Three struts holding the mirror and a cable running up one side, as on a real robot.
  o.parts = {{60 * d, 0.38, 60 * d, 1.08, 0.035, 38},
             {180 * d, 0.38, 180 * d, 1.08, 0.035, 38},
             {300 * d, 0.38, 300 * d, 1.08, 0.035, 38},
             {100 * d, 0.42, 125 * d, 1.08, 0.016, 12}};
  return o;
}

MirrorModel OmniCameraOptions::ReportedMirror() const {
  if (!optics.enabled) return mirror;
  const MirrorProfile profile = MirrorProfile::FromMirror(mirror);
  const double outer = mirror.outer_radius_px + optics.calibration_error_radius_px;
  const double inner = std::max(mirror.inner_radius_px, optics.lens_radius_frac * mirror.outer_radius_px + 2.0) +
                       optics.calibration_error_radius_px;
  return MirrorWithRadii(mirror.center_x_px + optics.calibration_error_x_px,
                         mirror.center_y_px + optics.calibration_error_y_px, inner, outer, profile);
}

void OmniCameraOptions::Validate() const {
  if (!(height_m > 0)) throw std::invalid_argument("camera: height_m must be positive");
  if (omni_width_px < 16 || omni_height_px < 16) {
    throw std::invalid_argument("camera: the raw image's omni_width_px and omni_height_px must be at least 16");
  }
  mirror.Validate();
  panorama.Validate();
  optics.Validate();
  // The rim may run past the image's border, as a real camera's often does (a 16:9 frame); the
  // centre must lie inside.
  if (!(mirror.center_x_px >= 0 && mirror.center_x_px < omni_width_px && mirror.center_y_px >= 0 &&
        mirror.center_y_px < omni_height_px)) {
    throw std::invalid_argument("camera: the mirror centre (" + std::to_string(mirror.center_x_px) + ", " +
                                std::to_string(mirror.center_y_px) + ") lies outside the " +
                                std::to_string(omni_width_px) + "x" + std::to_string(omni_height_px) + " raw image");
  }
}

void ImageEffectsOptions::Validate() const {
  if (!(blur_sigma_px >= 0) || !std::isfinite(blur_sigma_px))
    throw std::invalid_argument("image effects: blur_sigma_px must be >= 0");
  if (!(noise_sigma >= 0) || !std::isfinite(noise_sigma))
    throw std::invalid_argument("image effects: noise_sigma must be >= 0");
  if (!(salt_pepper_fraction >= 0 && salt_pepper_fraction <= 1)) {
    throw std::invalid_argument("image effects: salt_pepper_fraction must be in [0, 1]");
  }
  if (!(gain >= 0) || !std::isfinite(gain)) throw std::invalid_argument("image effects: gain must be >= 0");
  if (!std::isfinite(offset)) throw std::invalid_argument("image effects: offset must be finite");
}

void ApplyImageEffects(const ImageEffectsOptions& o, std::mt19937_64& rng, cv::Mat* image) {
  if (o.blur_sigma_px > 0) cv::GaussianBlur(*image, *image, cv::Size(), o.blur_sigma_px);
  if (o.gain != 1.0 || o.offset != 0.0) image->convertTo(*image, -1, o.gain, o.offset);
  if (o.noise_sigma > 0) {
    std::normal_distribution<double> n(0.0, o.noise_sigma);
    const int channels = image->channels();
    for (int y = 0; y < image->rows; ++y) {
      uint8_t* row = image->ptr<uint8_t>(y);
      for (int x = 0; x < image->cols * channels; ++x) row[x] = cv::saturate_cast<uint8_t>(row[x] + n(rng));
    }
  }
  if (o.salt_pepper_fraction > 0) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int y = 0; y < image->rows; ++y) {
      for (int x = 0; x < image->cols; ++x) {
        const double r = u(rng);
        if (r < o.salt_pepper_fraction) {
          const uint8_t v = r < o.salt_pepper_fraction / 2 ? 0 : 255;
          uint8_t* px = image->ptr<uint8_t>(y) + x * image->channels();
          for (int k = 0; k < image->channels(); ++k) px[k] = v;
        }
      }
    }
  }
}

OmniRenderer::OmniRenderer(const Scene& scene, const OmniCameraOptions& options) : scene_(scene), options_(options) {
  scene_.Validate();
  options_.Validate();
  const MirrorModel& m = options_.mirror;
  // The fine panorama has about one column per pixel of the outer mirror circle
  // and one row per pixel of radius, so remapping loses nothing.
  fine_.width_px = static_cast<int>(std::ceil(2 * M_PI * m.outer_radius_px));
  fine_.height_px = static_cast<int>(std::ceil(m.outer_radius_px - m.inner_radius_px)) + 1;
  fine_.bearing_col0_rad = M_PI;
  fine_.elevation_top_rad = std::max(m.elevation_inner_rad, m.elevation_outer_rad);
  fine_.elevation_bottom_rad = std::min(m.elevation_inner_rad, m.elevation_outer_rad);
  // Raw pixel -> fine panorama pixel (float), kept in cv::remap's fixed-point form below.
  cv::Mat map_x(options_.omni_height_px, options_.omni_width_px, CV_32FC1);
  cv::Mat map_y(options_.omni_height_px, options_.omni_width_px, CV_32FC1);
  // With optics the rim is blended over a few pixels: the content continues just outside it.
  const double beyond = options_.optics.enabled ? options_.optics.rim_softness_px + 1.5 : 0.0;
  for (int v = 0; v < options_.omni_height_px; ++v) {
    for (int u = 0; u < options_.omni_width_px; ++u) {
      auto dir = MirrorDirection(m, u, v);
      if (!dir && beyond > 0) {
        const double du = u - m.center_x_px, dv = v - m.center_y_px, r = std::hypot(du, dv);
        if (r > m.outer_radius_px && r <= m.outer_radius_px + beyond) {
          const double k = (m.outer_radius_px - 1e-6) / r;
          dir = MirrorDirection(m, m.center_x_px + du * k, m.center_y_px + dv * k);
        }
      }
      if (!dir) {
        map_x.at<float>(v, u) = -1;  // outside the ring: border colour
        map_y.at<float>(v, u) = -1;
        continue;
      }
      map_x.at<float>(v, u) = static_cast<float>(fine_.ColumnOfBearing((*dir)[0]));
      map_y.at<float>(v, u) = static_cast<float>(fine_.RowOfElevation((*dir)[1]));
    }
  }
  if (options_.optics.enabled) BuildOptics(map_y);
  // The maps in OpenCV's fixed-point form once (remap converts float maps to it on every call).
  cv::convertMaps(map_x, map_y, remap_xy_, remap_frac_, CV_16SC2);
}

void OmniRenderer::BuildOptics(const cv::Mat& map_y) {
  const CameraOptics& o = options_.optics;
  const MirrorModel& m = options_.mirror;
  const int W = options_.omni_width_px, H = options_.omni_height_px;
  const double R = m.outer_radius_px, Rl = o.lens_radius_frac * R;
  // The parts' coverage (anti-aliased bars) and grey.
  parts_alpha_ = cv::Mat(H, W, CV_32F, cv::Scalar(0));
  cv::Mat parts_grey(H, W, CV_32F, cv::Scalar(0));
  for (const RobotPart& p : o.parts) {
    const Eigen::Vector2d a(m.center_x_px - p.radius0_frac * R * std::sin(p.bearing0_rad),
                            m.center_y_px - p.radius0_frac * R * std::cos(p.bearing0_rad));
    const Eigen::Vector2d b(m.center_x_px - p.radius1_frac * R * std::sin(p.bearing1_rad),
                            m.center_y_px - p.radius1_frac * R * std::cos(p.bearing1_rad));
    const double hw = 0.5 * p.width_frac * R;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min(a.x(), b.x()) - hw - 2)));
    const int x1 = std::min(W - 1, static_cast<int>(std::ceil(std::max(a.x(), b.x()) + hw + 2)));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min(a.y(), b.y()) - hw - 2)));
    const int y1 = std::min(H - 1, static_cast<int>(std::ceil(std::max(a.y(), b.y()) + hw + 2)));
    const Eigen::Vector2d ab = b - a;
    const double len2 = std::max(1e-9, ab.squaredNorm());
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2d q(x, y);
        const double t = std::clamp((q - a).dot(ab) / len2, 0.0, 1.0);
        const double d = (q - (a + t * ab)).norm();
        const float alpha = static_cast<float>(std::clamp(hw - d + 0.5, 0.0, 1.0));
        if (alpha > parts_alpha_.at<float>(y, x)) {
          parts_alpha_.at<float>(y, x) = alpha;
          parts_grey.at<float>(y, x) = static_cast<float>(p.grey);
        }
      }
    }
  }
  const double gains[3] = {o.colour_gain_b, o.colour_gain_g, o.colour_gain_r};
  optics_gain_.assign(static_cast<size_t>(W) * H * 3, 0);
  optics_offset_.assign(static_cast<size_t>(W) * H * 3, 0);
  const double soft = std::max(1e-3, o.rim_softness_px);
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      const double r = std::hypot(x - m.center_x_px, y - m.center_y_px);
      const double a_m = std::clamp((R - r) / soft + 0.5, 0.0, 1.0);           // the mirror (soft rim)
      const double a_l = std::clamp(Rl - r + 0.5, 0.0, 1.0);                    // the camera's reflection
      const double ring = std::clamp(r - 0.8 * Rl + 0.5, 0.0, 1.0);            // its lighter barrel
      const double lens = o.lens_grey + 40.0 * ring;
      const double a_p = parts_alpha_.at<float>(y, x);
      const double vig = std::max(0.2, 1.0 - o.vignetting * (r / R) * (r / R));
      const double content = a_m * (1 - a_l) * (1 - a_p);
      const double fixed = ((lens * a_l) * a_m + o.housing_grey * (1 - a_m)) * (1 - a_p) + parts_grey.at<float>(y, x) * a_p;
      for (int k = 0; k < 3; ++k) {
        const double g = gains[k] * vig;
        const size_t i = (static_cast<size_t>(y) * W + x) * 3 + k;
        optics_gain_[i] = static_cast<uint16_t>(std::lround(std::min(1023.0, g * content * 256)));
        optics_offset_[i] = static_cast<uint16_t>(std::lround(std::min(65535.0, g * fixed * 128)));
      }
    }
  }
  // The fine panorama's rows that reach a pixel the camera shows (not under its own reflection),
  // with two rows to spare for the bilinear remap: the rest is not rendered.
  float lowest_row = 0;
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      const double r = std::hypot(x - m.center_x_px, y - m.center_y_px);
      if (std::clamp(Rl - r + 0.5, 0.0, 1.0) < 1.0) lowest_row = std::max(lowest_row, map_y.at<float>(y, x));
    }
  }
  render_rows_ = std::min(fine_.height_px, static_cast<int>(std::ceil(lowest_row)) + 3);
  // Sensor noise: a table of standard normal samples indexed by a fast generator, scaled per grey level.
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<float> normal(0.f, 1.f);
  noise_table_.resize(1 << 16);
  for (float& v : noise_table_) v = normal(rng);
  for (int v = 0; v < 256; ++v) {
    noise_sigma_[v] = static_cast<float>(std::sqrt(o.read_noise_grey * o.read_noise_grey + o.shot_noise * v));
  }
  noise_state_ = o.seed * 0x9e3779b97f4a7c15ULL + 0x632be59bd9b4e019ULL;
  if (noise_state_ == 0) noise_state_ = 1;
}

void OmniRenderer::ApplyWindow(const Pose2& robot, cv::Mat* fine) const {
  const CameraOptics& o = options_.optics;
  if (o.window_gain == 1.0 || o.window_width_rad <= 0) return;
  constexpr double kSoft = 0.03;  // soft edges [rad]
  auto weight = [](double distance_outside) { return std::clamp(0.5 - distance_outside / kSoft, 0.0, 1.0); };
  std::vector<double> row_weight(static_cast<size_t>(fine->rows));
  for (int r = 0; r < fine->rows; ++r) {
    const double e = fine_.ElevationOfRow(r);
    row_weight[r] = weight(std::max(o.window_elevation_bottom_rad - e, e - o.window_elevation_top_rad));
  }
  for (int c = 0; c < fine->cols; ++c) {
    const double off = std::abs(WrapAngle(robot.theta_rad + fine_.BearingOfColumn(c) - o.window_bearing_rad));
    const double wc = weight(off - 0.5 * o.window_width_rad);
    if (wc <= 0) continue;
    for (int r = 0; r < fine->rows; ++r) {
      const double f = 1.0 + (o.window_gain - 1.0) * wc * row_weight[r];
      if (f == 1.0) continue;
      cv::Vec3b& px = fine->at<cv::Vec3b>(r, c);
      for (int k = 0; k < 3; ++k) px[k] = cv::saturate_cast<uint8_t>(px[k] * f);
    }
  }
}

void OmniRenderer::MeterExposure(const cv::Mat& fine) {
  const CameraOptics& o = options_.optics;
  if (!o.auto_exposure) {
    exposure_ = 1.0;
    return;
  }
  // Mean grey of the visible rows, every 4th pixel of every 4th row, weighted by the cast.
  const int rows = render_rows_ > 0 ? render_rows_ : fine.rows;
  uint64_t sum[3] = {0, 0, 0};
  uint64_t n = 0;
  for (int r = 0; r < rows; r += 4) {
    const uint8_t* p = fine.ptr<uint8_t>(r);
    for (int c = 0; c < fine.cols; c += 4) {
      sum[0] += p[3 * c];
      sum[1] += p[3 * c + 1];
      sum[2] += p[3 * c + 2];
      ++n;
    }
  }
  const double mean = n == 0 ? o.exposure_target_grey
                             : (o.colour_gain_b * sum[0] + o.colour_gain_g * sum[1] + o.colour_gain_r * sum[2]) /
                                   (3.0 * static_cast<double>(n)) * (1.0 - 0.5 * o.vignetting);
  const double ideal = std::clamp(o.exposure_target_grey / std::max(1.0, mean), o.exposure_min, o.exposure_max);
  exposure_ = exposure_settled_ ? std::exp(std::log(exposure_) + o.exposure_rate * (std::log(ideal) - std::log(exposure_)))
                                : ideal;
  exposure_ = std::clamp(exposure_, o.exposure_min, o.exposure_max);
  exposure_settled_ = true;
}

void OmniRenderer::ApplyMotionBlur(const CameraMotion& motion, cv::Mat* fine) {
  const CameraOptics& o = options_.optics;
  const double shutter_s = o.exposure_time_s * exposure_;
  if (shutter_s <= 0 || (motion.linear_mps == 0 && motion.angular_radps == 0)) return;
  const int W = fine_.width_px, rows = render_rows_ > 0 ? render_rows_ : fine->rows;
  const double cols_per_rad = W / (2 * M_PI);
  // Half-widths of the box per column (above the horizon) and per row (the floor, nearer).
  std::vector<int> k(static_cast<size_t>(W));
  std::vector<double> sin_b(static_cast<size_t>(W));
  for (int c = 0; c < W; ++c) sin_b[c] = std::sin(fine_.BearingOfColumn(c));
  auto half_width = [&](int c, double depth_m) {
    const double rate = motion.linear_mps * sin_b[c] / std::max(0.05, depth_m) - motion.angular_radps;
    return static_cast<int>(0.5 * std::abs(rate) * shutter_s * cols_per_rad + 0.5);
  };
  int max_k = 0;
  for (int c = 0; c < W; ++c) max_k = std::max(max_k, half_width(c, 0.05 + options_.height_m));
  max_k = std::min(max_k, W / 2 - 1);
  if (max_k == 0) return;
  const int ext = W + 2 * max_k;
  prefix_.resize(static_cast<size_t>(ext + 1) * 3);
  std::vector<int> k_wall(static_cast<size_t>(W));
  for (int c = 0; c < W; ++c) k_wall[c] = std::min(max_k, half_width(c, column_depth_[c]));
  std::vector<uint8_t> row_copy(static_cast<size_t>(ext) * 3);
  for (int r = 0; r < rows; ++r) {
    const double te = std::tan(fine_.ElevationOfRow(r));
    const double floor_d = te < 0 ? options_.height_m / -te : INFINITY;
    bool any = false;
    for (int c = 0; c < W; ++c) {
      k[c] = floor_d < column_depth_[c] ? std::min(max_k, half_width(c, floor_d)) : k_wall[c];
      any = any || k[c] > 0;
    }
    if (!any) continue;
    uint8_t* p = fine->ptr<uint8_t>(r);
    // The row extended by max_k columns at each side (bearings wrap around), and its running sums.
    std::copy(p + 3 * (W - max_k), p + 3 * W, row_copy.begin());
    std::copy(p, p + 3 * W, row_copy.begin() + 3 * max_k);
    std::copy(p, p + 3 * max_k, row_copy.begin() + 3 * (max_k + W));
    int32_t* s = prefix_.data();
    s[0] = s[1] = s[2] = 0;
    for (int i = 0; i < 3 * ext; ++i) s[i + 3] = s[i] + row_copy[i];
    for (int c = 0; c < W; ++c) {
      if (k[c] == 0) continue;
      const int a = c + max_k - k[c], b = c + max_k + k[c] + 1;  // [a, b) in the extended row
      const int n = b - a;
      for (int ch = 0; ch < 3; ++ch) p[3 * c + ch] = static_cast<uint8_t>((s[3 * b + ch] - s[3 * a + ch] + n / 2) / n);
    }
  }
}

void OmniRenderer::ApplyOptics(cv::Mat* image) {
  const int W = image->cols, H = image->rows;
  const uint32_t e = static_cast<uint32_t>(std::lround(exposure_ * 256));  // Q8
  const uint16_t* gain = optics_gain_.data();
  const uint16_t* offset = optics_offset_.data();
  const float* table = noise_table_.data();
  uint64_t state = noise_state_;
  uint64_t bits = 0;
  int left = 0;
  for (int y = 0; y < H; ++y) {
    uint8_t* p = image->ptr<uint8_t>(y);
    const size_t base = static_cast<size_t>(y) * W * 3;
    for (int i = 0; i < W * 3; ++i) {
      const int v = std::min<int>(
          255, static_cast<int>(((static_cast<uint32_t>(p[i]) * gain[base + i] + 2u * offset[base + i]) * e + 32768u) >> 16));
      if (left == 0) {
        // xorshift64*: four 16-bit table indices per draw.
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        bits = state * 0x2545F4914F6CDD1DULL;
        left = 4;
      }
      const float n = table[bits & 0xffff];
      bits >>= 16;
      --left;
      const float out = static_cast<float>(v) + noise_sigma_[v] * n + 0.5f;
      p[i] = static_cast<uint8_t>(out <= 0.f ? 0 : (out >= 255.f ? 255 : static_cast<int>(out)));
    }
  }
  noise_state_ = state;
}

cv::Mat OmniRenderer::PartsMask() const {
  if (!options_.optics.enabled || parts_alpha_.empty()) {
    return cv::Mat(options_.omni_height_px, options_.omni_width_px, CV_8UC1, cv::Scalar(255));
  }
  return parts_alpha_ <= 0.02f;
}

void OmniRenderer::RenderPanorama(const Pose2& robot, const std::vector<Cylinder>& people, cv::Mat* out) const {
  Render(options_.panorama, robot, people, out);
}

void OmniRenderer::RenderOmni(const Pose2& robot, const std::vector<Cylinder>& people, cv::Mat* out,
                              const CameraMotion& motion, std::vector<uint8_t>* jpeg) {
  if (jpeg) jpeg->clear();
  // The fine panorama has one extra column, a copy of column 0, so bilinear sampling
  // is seamless at the bearing seam; the buffer is reused from frame to frame.
  fine_image_.create(fine_.height_px, fine_.width_px + 1, CV_8UC3);
  cv::Mat body = fine_image_.colRange(0, fine_.width_px);
  const CameraOptics& o = options_.optics;
  if (!o.enabled) {
    Render(fine_, robot, people, &body);
  } else {
    // Rows under the camera's own reflection are never seen: not rendered.
    Render(fine_, robot, people, &body, render_rows_, &column_depth_);
    if (render_rows_ < fine_.height_px) body.rowRange(render_rows_, fine_.height_px).setTo(cv::Scalar::all(0));
    ApplyWindow(robot, &body);
    MeterExposure(body);
    ApplyMotionBlur(motion, &body);
  }
  fine_image_.col(0).copyTo(fine_image_.col(fine_.width_px));
  cv::remap(fine_image_, *out, remap_xy_, remap_frac_, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(16, 16, 16));
  if (!o.enabled) return;
  ApplyOptics(out);
  if (o.jpeg_quality > 0) {
    std::vector<uint8_t>& bytes = jpeg ? *jpeg : jpeg_;
    if (!cv::imencode(".jpg", *out, bytes, {cv::IMWRITE_JPEG_QUALITY, o.jpeg_quality}) || bytes.empty()) {
      throw std::runtime_error("the simulated camera could not JPEG-encode its frame");
    }
    if (!jpeg) cv::imdecode(bytes, cv::IMREAD_COLOR, out);
  }
}

void OmniRenderer::Render(const PanoramaModel& model, const Pose2& robot, const std::vector<Cylinder>& people,
                          cv::Mat* out, int rows, std::vector<float>* depth) const {
  out->create(model.height_px, model.width_px, CV_8UC3);
  const int row_end = rows < 0 ? model.height_px : std::min(rows, model.height_px);
  if (depth) depth->assign(static_cast<size_t>(model.width_px), 1e3f);
  const Eigen::Vector2d eye = robot.Transform({options_.offset_x_m, 0.0});
  const double cam_z = options_.height_m;
  const double ceiling = scene_.ceiling_height_m;
  const double col_angle = 2 * M_PI / model.width_px;
  const double row_angle = std::abs(model.elevation_top_rad - model.elevation_bottom_rad) / (model.height_px - 1);
  // What does not depend on the column, once per row: the elevation's tangent, the distances to the
  // floor and the ceiling, and the mip level their footprint picks (the same arithmetic as per pixel,
  // so the image is the same to the bit; choosing levels per pixel took about a third of a frame).
  struct RowPlan {
    double te, floor_d, ceil_d;
    const cv::Mat* floor_level = nullptr;
    double floor_scale = 1;
    const cv::Mat* ceil_level = nullptr;
    double ceil_scale = 1;
  };
  std::vector<RowPlan> plan(static_cast<size_t>(row_end));
  for (int r = 0; r < row_end; ++r) {
    RowPlan& rp = plan[static_cast<size_t>(r)];
    const double te = std::tan(model.ElevationOfRow(r));
    rp.te = te;
    rp.floor_d = te < 0 ? cam_z / -te : INFINITY;
    rp.ceil_d = (te > 0 && ceiling > 0) ? (ceiling - cam_z) / te : INFINITY;
    if (rp.floor_d < rp.ceil_d && std::isfinite(rp.floor_d)) {
      if (scene_.floor_texture >= 0) {
        const double footprint = rp.floor_d * row_angle / std::max(0.05, -te / std::sqrt(1 + te * te));
        rp.floor_level = &Level(scene_.textures[scene_.floor_texture], footprint, &rp.floor_scale);
      }
    } else if (std::isfinite(rp.ceil_d) && scene_.ceiling_texture >= 0) {
      rp.ceil_level = &Level(scene_.textures[scene_.ceiling_texture], rp.ceil_d * row_angle * 4, &rp.ceil_scale);
    }
  }
  // A plane's texel at world point p, at the level chosen for its row.
  auto plane = [](const Texture& t, const cv::Mat& level, double scale, const Eigen::Vector2d& p, double shade) {
    return Sample(level, Columns(level, p.x() / t.width_m * t.levels[0].cols * scale),
                  p.y() / t.height_m * t.levels[0].rows * scale, shade);
  };
  auto plain = [](const cv::Vec3b& bgr, double shade) {
    return cv::Vec3b(cv::saturate_cast<uint8_t>(bgr[0] * shade), cv::saturate_cast<uint8_t>(bgr[1] * shade),
                     cv::saturate_cast<uint8_t>(bgr[2] * shade));
  };
  // Per surface a column's ray crosses: its texture level (the footprint is the same on every row)
  // and its horizontal texture coordinate; z is measured from the surface's bottom, the texture's top
  // row at its height.
  struct HitPlan {
    const Texture* texture;
    const cv::Mat* level;
    double scale;
    TexelColumns columns;
  };
  std::vector<RayHit> hits;
  std::vector<HitPlan> hit_plans;
  for (int c = 0; c < model.width_px; ++c) {
    const double world_bearing = robot.theta_rad + model.BearingOfColumn(c);
    const Eigen::Vector2d dir(std::cos(world_bearing), std::sin(world_bearing));
    CastRay(scene_, people, eye, dir, -1.0, &hits);
    if (depth && !hits.empty()) (*depth)[c] = static_cast<float>(hits.front().distance_m);
    hit_plans.clear();
    for (const RayHit& h : hits) {
      HitPlan hp;
      hp.texture = &scene_.textures[h.texture];
      hp.level = &Level(*hp.texture, h.distance_m * col_angle, &hp.scale);
      hp.columns = Columns(*hp.level, h.u_m / hp.texture->width_m * hp.texture->levels[0].cols * hp.scale);
      hit_plans.push_back(hp);
    }
    for (int r = 0; r < row_end; ++r) {
      const RowPlan& rp = plan[static_cast<size_t>(r)];
      const double te = rp.te, floor_d = rp.floor_d, ceil_d = rp.ceil_d;
      cv::Vec3b px;
      bool done = false;
      for (size_t i = 0; i < hits.size(); ++i) {
        const RayHit& h = hits[i];
        if (h.distance_m >= floor_d || h.distance_m >= ceil_d) break;
        const double z = cam_z + h.distance_m * te;
        if (z >= h.bottom_m && z <= h.height_m) {
          const HitPlan& hp = hit_plans[i];
          const double y = (1.0 - (z - h.bottom_m) / hp.texture->height_m) * hp.texture->levels[0].rows * hp.scale;
          px = Sample(*hp.level, hp.columns, y, h.shade);
          done = true;
          break;
        }
      }
      if (!done) {
        if (floor_d < ceil_d && std::isfinite(floor_d)) {
          const Eigen::Vector2d p = eye + floor_d * dir;
          px = rp.floor_level ? plane(scene_.textures[scene_.floor_texture], *rp.floor_level, rp.floor_scale, p, 0.9)
                              : plain(scene_.floor_bgr, 0.9);
        } else if (std::isfinite(ceil_d)) {
          const Eigen::Vector2d p = eye + ceil_d * dir;
          px = rp.ceil_level ? plane(scene_.textures[scene_.ceiling_texture], *rp.ceil_level, rp.ceil_scale, p, 1.0)
                             : plain(scene_.ceiling_bgr, 1.0);
        } else {
          // Open sky: brighter towards the zenith.
          const double f = std::clamp(0.8 + 0.4 * te, 0.0, 1.2);
          px = cv::Vec3b(cv::saturate_cast<uint8_t>(scene_.sky_bgr[0] * f),
                         cv::saturate_cast<uint8_t>(scene_.sky_bgr[1] * f),
                         cv::saturate_cast<uint8_t>(scene_.sky_bgr[2] * f));
        }
      }
      out->at<cv::Vec3b>(r, c) = px;
    }
  }
}

}  // namespace snapnav::nav::sim
