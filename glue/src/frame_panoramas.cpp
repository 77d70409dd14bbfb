#include "snapnav/glue/frame_panoramas.hpp"

#include <cmath>

#include "snapnav/glue/image_msg.hpp"
#include "snapnav/nav/homing/image_mask.hpp"
#include "snapnav/nav/pose2.hpp"

namespace snapnav::glue {
namespace {

constexpr double kDeg = M_PI / 180.0;
// Panorama geometry of a frame and of the config may differ by float rounding [rad].
constexpr double kGeometryTolerance_rad = 1e-4;

bool SameMirror(const nav::MirrorModel& a, const nav::MirrorModel& b) {
  return a.center_x_px == b.center_x_px && a.center_y_px == b.center_y_px && a.inner_radius_px == b.inner_radius_px &&
         a.outer_radius_px == b.outer_radius_px && a.elevation_inner_rad == b.elevation_inner_rad &&
         a.elevation_outer_rad == b.elevation_outer_rad;
}

bool IsZeroMirror(const omni_frame_t& f) {
  return f.mirror_center_x_px == 0 && f.mirror_center_y_px == 0 && f.mirror_inner_radius_px == 0 &&
         f.mirror_outer_radius_px == 0 && f.mirror_elevation_inner_rad == 0 && f.mirror_elevation_outer_rad == 0;
}

std::string SizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

}  // namespace

void FramePanoramas::SetMask(const cv::Mat& raw_mask) {
  if (!raw_mask.empty() && raw_mask.type() != CV_8UC1) throw std::invalid_argument("frames: the mask must be 8-bit grey");
  raw_mask_ = raw_mask;
  unwrapper_.reset();  // rebuilt with the mask
  mask_.release();
  mask_clearance_.release();
}

std::optional<cv::Mat> FramePanoramas::Convert(const omni_frame_t& f) {
  reason_.clear();
  detail_.clear();
  mask_.release();
  mask_clearance_.release();
  if (f.kind != omni_frame_t::RAW_OMNI && f.kind != omni_frame_t::PANORAMA) {
    Fail("unknown kind", "kind " + std::to_string(f.kind) + " (RAW_OMNI 0 or PANORAMA 1)");
    return std::nullopt;
  }
  if (f.encoding < omni_frame_t::GRAY8 || f.encoding > omni_frame_t::PNG) {
    Fail("unknown encoding", "encoding " + std::to_string(f.encoding) + " (GRAY8 0, RGB8 1, JPEG 2, PNG 3)");
    return std::nullopt;
  }
  if (f.width <= 0 || f.height <= 0 || f.data.empty()) {
    Fail("empty image", SizeText(f.width, f.height) + " with " + std::to_string(f.data.size()) + " bytes");
    return std::nullopt;
  }
  const bool raw = f.kind == omni_frame_t::RAW_OMNI;
  const nav::PanoramaModel& p = panorama_;
  if (!raw) {
    if (f.width != p.width_px || f.height != p.height_px) {
      Fail("wrong size",
             "panorama is " + SizeText(f.width, f.height) + ", [panorama] is " + SizeText(p.width_px, p.height_px));
      return std::nullopt;
    }
    if (std::abs(nav::WrapAngle(f.bearing_col0_rad - p.bearing_col0_rad)) > kGeometryTolerance_rad ||
        std::abs(f.elevation_top_rad - p.elevation_top_rad) > kGeometryTolerance_rad ||
        std::abs(f.elevation_bottom_rad - p.elevation_bottom_rad) > kGeometryTolerance_rad) {
      Fail("wrong geometry", "panorama bearing_col0 " + std::to_string(f.bearing_col0_rad / kDeg) +
                                   " deg, elevations " + std::to_string(f.elevation_top_rad / kDeg) + ".." +
                                   std::to_string(f.elevation_bottom_rad / kDeg) + " deg differ from [panorama] (" +
                                   std::to_string(p.bearing_col0_rad / kDeg) + " deg, " +
                                   std::to_string(p.elevation_top_rad / kDeg) + ".." +
                                   std::to_string(p.elevation_bottom_rad / kDeg) + " deg)");
      return std::nullopt;
    }
  }
  cv::Mat image;
  try {
    image = FrameToImage(f);
  } catch (const std::exception& e) {
    Fail("undecodable image", e.what());
    return std::nullopt;
  }
  if (image.empty()) {
    Fail("empty image", "decoded to no pixels");
    return std::nullopt;
  }
  if (!raw) return image;

  // Raw: unwrap with the frame's calibration (the config's when the frame has none). The map is
  // rebuilt only when the calibration or the image size changes.
  const nav::MirrorModel mirror = IsZeroMirror(f) ? default_mirror_ : MirrorOf(f);
  const cv::Size size = image.size();
  if (!raw_mask_.empty() && raw_mask_.size() != size) {
    Fail("wrong mask size", "frame is " + SizeText(size.width, size.height) + ", the mask " +
                                SizeText(raw_mask_.cols, raw_mask_.rows));
    return std::nullopt;
  }
  if (!unwrapper_ || !SameMirror(unwrapper_->mirror(), mirror) || unwrapper_size_ != size) {
    if (refused_calibration_ && SameMirror(refused_calibration_->first, mirror) &&
        refused_calibration_->second == size) {
      Fail("bad mirror calibration", refused_reason_);
      return std::nullopt;
    }
    try {
      unwrapper_ = nav::Unwrapper(mirror, p, size);
      if (!raw_mask_.empty()) unwrapper_->SetMask(raw_mask_);
      unwrapper_clearance_ = nav::MaskClearance(unwrapper_->panorama_mask());
      unwrapper_size_ = size;
      ++unwrapper_builds_;
    } catch (const std::exception& e) {
      refused_calibration_ = std::make_pair(mirror, size);
      refused_reason_ = std::string(e.what()) + " (" + SizeText(size.width, size.height) + " image)";
      Fail("bad mirror calibration", refused_reason_);
      return std::nullopt;
    }
  }
  cv::Mat panorama;
  unwrapper_->Unwrap(image, &panorama);  // masked pixels filled
  mask_ = unwrapper_->panorama_mask();
  mask_clearance_ = unwrapper_clearance_;
  return panorama;
}

}  // namespace snapnav::glue
