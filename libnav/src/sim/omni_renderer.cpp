#include "snapnav/nav/sim/omni_renderer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace snapnav::nav::sim {
namespace {

// Bilinear sample of a texture level with wrap-around, scaled by `shade`.
inline cv::Vec3b Sample(const cv::Mat& img, double x, double y, double shade) {
  const int w = img.cols, h = img.rows;
  x -= std::floor(x / w) * w;
  y -= std::floor(y / h) * h;
  const int x0 = std::min(static_cast<int>(x), w - 1), y0 = std::min(static_cast<int>(y), h - 1);
  const int x1 = x0 + 1 < w ? x0 + 1 : 0, y1 = y0 + 1 < h ? y0 + 1 : 0;
  const double fx = x - x0, fy = y - y0;
  const cv::Vec3b& a = img.at<cv::Vec3b>(y0, x0);
  const cv::Vec3b& b = img.at<cv::Vec3b>(y0, x1);
  const cv::Vec3b& c = img.at<cv::Vec3b>(y1, x0);
  const cv::Vec3b& d = img.at<cv::Vec3b>(y1, x1);
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

// z_m is measured from the bottom of the surface; the texture's top row is at height_m.
inline cv::Vec3b SampleSurface(const Texture& t, double u_m, double z_m, double meters_per_pixel, double shade) {
  double scale;
  const cv::Mat& img = Level(t, meters_per_pixel, &scale);
  const double x = u_m / t.width_m * t.levels[0].cols * scale;
  const double y = (1.0 - z_m / t.height_m) * t.levels[0].rows * scale;
  return Sample(img, x, y, shade);
}

inline cv::Vec3b SamplePlane(const Scene& scene, int texture, const cv::Vec3b& plain, const Eigen::Vector2d& p,
                             double meters_per_pixel, double shade) {
  if (texture < 0) {
    return cv::Vec3b(cv::saturate_cast<uint8_t>(plain[0] * shade), cv::saturate_cast<uint8_t>(plain[1] * shade),
                     cv::saturate_cast<uint8_t>(plain[2] * shade));
  }
  const Texture& t = scene.textures[texture];
  double scale;
  const cv::Mat& img = Level(t, meters_per_pixel, &scale);
  return Sample(img, p.x() / t.width_m * t.levels[0].cols * scale, p.y() / t.height_m * t.levels[0].rows * scale,
                shade);
}

}  // namespace

void OmniCameraOptions::Validate() const {
  if (!(height_m > 0)) throw std::invalid_argument("camera: height_m must be positive");
  if (omni_width_px < 16 || omni_height_px < 16) {
    throw std::invalid_argument("camera: the raw image's omni_width_px and omni_height_px must be at least 16");
  }
  mirror.Validate();
  panorama.Validate();
  if (mirror.center_x_px - mirror.outer_radius_px < -0.5 || mirror.center_x_px + mirror.outer_radius_px > omni_width_px - 0.5 ||
      mirror.center_y_px - mirror.outer_radius_px < -0.5 || mirror.center_y_px + mirror.outer_radius_px > omni_height_px - 0.5) {
    throw std::invalid_argument("camera: the mirror circle does not fit in the raw image");
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
  map_x_.create(options_.omni_height_px, options_.omni_width_px, CV_32FC1);
  map_y_.create(options_.omni_height_px, options_.omni_width_px, CV_32FC1);
  for (int v = 0; v < options_.omni_height_px; ++v) {
    for (int u = 0; u < options_.omni_width_px; ++u) {
      const auto dir = MirrorDirection(m, u, v);
      if (!dir) {
        map_x_.at<float>(v, u) = -1;  // outside the ring: border colour
        map_y_.at<float>(v, u) = -1;
        continue;
      }
      map_x_.at<float>(v, u) = static_cast<float>(fine_.ColumnOfBearing((*dir)[0]));
      map_y_.at<float>(v, u) = static_cast<float>(fine_.RowOfElevation((*dir)[1]));
    }
  }
}

void OmniRenderer::RenderPanorama(const Pose2& robot, const std::vector<Cylinder>& people, cv::Mat* out) const {
  Render(options_.panorama, robot, people, out);
}

void OmniRenderer::RenderOmni(const Pose2& robot, const std::vector<Cylinder>& people, cv::Mat* out) {
  // The fine panorama has one extra column, a copy of column 0, so bilinear sampling
  // is seamless at the bearing seam; the buffer is reused from frame to frame.
  fine_image_.create(fine_.height_px, fine_.width_px + 1, CV_8UC3);
  cv::Mat body = fine_image_.colRange(0, fine_.width_px);
  Render(fine_, robot, people, &body);
  fine_image_.col(0).copyTo(fine_image_.col(fine_.width_px));
  cv::remap(fine_image_, *out, map_x_, map_y_, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(16, 16, 16));
}

void OmniRenderer::Render(const PanoramaModel& model, const Pose2& robot, const std::vector<Cylinder>& people,
                          cv::Mat* out) const {
  out->create(model.height_px, model.width_px, CV_8UC3);
  const Eigen::Vector2d eye = robot.Transform({options_.offset_x_m, 0.0});
  const double cam_z = options_.height_m;
  const double ceiling = scene_.ceiling_height_m;
  const double col_angle = 2 * M_PI / model.width_px;
  const double row_angle = std::abs(model.elevation_top_rad - model.elevation_bottom_rad) / (model.height_px - 1);
  std::vector<double> tan_e(model.height_px);
  for (int r = 0; r < model.height_px; ++r) tan_e[r] = std::tan(model.ElevationOfRow(r));
  std::vector<RayHit> hits;
  for (int c = 0; c < model.width_px; ++c) {
    const double world_bearing = robot.theta_rad + model.BearingOfColumn(c);
    const Eigen::Vector2d dir(std::cos(world_bearing), std::sin(world_bearing));
    CastRay(scene_, people, eye, dir, -1.0, &hits);
    for (int r = 0; r < model.height_px; ++r) {
      const double te = tan_e[r];
      const double floor_d = te < 0 ? cam_z / -te : INFINITY;
      const double ceil_d = (te > 0 && ceiling > 0) ? (ceiling - cam_z) / te : INFINITY;
      cv::Vec3b px;
      bool done = false;
      for (const RayHit& h : hits) {
        if (h.distance_m >= floor_d || h.distance_m >= ceil_d) break;
        const double z = cam_z + h.distance_m * te;
        if (z >= h.bottom_m && z <= h.height_m) {
          px = SampleSurface(scene_.textures[h.texture], h.u_m, z - h.bottom_m, h.distance_m * col_angle, h.shade);
          done = true;
          break;
        }
      }
      if (!done) {
        if (floor_d < ceil_d && std::isfinite(floor_d)) {
          const Eigen::Vector2d p = eye + floor_d * dir;
          const double footprint = floor_d * row_angle / std::max(0.05, -te / std::sqrt(1 + te * te));
          px = SamplePlane(scene_, scene_.floor_texture, scene_.floor_bgr, p, footprint, 0.9);
        } else if (std::isfinite(ceil_d)) {
          const Eigen::Vector2d p = eye + ceil_d * dir;
          px = SamplePlane(scene_, scene_.ceiling_texture, scene_.ceiling_bgr, p, ceil_d * row_angle * 4, 1.0);
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
