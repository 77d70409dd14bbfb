#pragma once
// Conversions between omni_frame_t messages and OpenCV images
// (library snapnav_glue_image, so only image processes link OpenCV's codecs).

#include <ostream>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "snapnav/glue/ini.hpp"
#include "snapnav/nav/homing/omni_geometry.hpp"
#include "snapnav/omni_frame_t.hpp"

namespace snapnav::glue {

// "gray8" | "rgb8" | "jpeg" | "png" -> omni_frame_t::GRAY8 ...; throws std::invalid_argument.
int8_t ParseFrameEncoding(const std::string& name);
// omni_frame_t::GRAY8 ... -> "gray8" ...; "?" for an unknown value.
std::string FrameEncodingName(int8_t encoding);

// A frame holding `image` (8-bit: CV_8UC1 grey, CV_8UC3 BGR or CV_8UC4 BGRA, whose alpha is
// dropped; a padded ROI is fine) in `encoding` (omni_frame_t::GRAY8, RGB8 in R,G,B order, JPEG
// or PNG). Geometry fields are zero, kind RAW_OMNI, utime 0: set them after.
// Throws std::invalid_argument on an empty or unsupported image or an unknown encoding,
// std::runtime_error when the encoder fails.
omni_frame_t ImageToFrame(const cv::Mat& image, int8_t encoding, int jpeg_quality = 90);

// Frames larger than this are refused before anything is allocated for them [pixels].
inline constexpr int64_t kMaxFramePixels = int64_t{1} << 26;  // 64 Mpx, e.g. 8192 x 8192

// The size a PNG or JPEG file says it has (from its header, nothing decoded); nullopt when the
// bytes are not a PNG (JPEG) file or the header is cut short.
std::optional<cv::Size> CompressedImageSize(const std::vector<uint8_t>& bytes, int8_t encoding);

// The frame's pixels as CV_8UC3 BGR (RGB8, colour JPEG/PNG) or CV_8UC1 (GRAY8, grey JPEG/PNG).
// Throws std::invalid_argument when sizes, stride or encoding do not add up, or decoding fails.
// A frame over kMaxFramePixels, or a compressed one whose header gives another size than the
// frame's (a decompression bomb), is refused before decoding.
cv::Mat FrameToImage(const omni_frame_t& frame);

void SetMirror(const nav::MirrorModel& mirror, omni_frame_t* frame);
void SetPanorama(const nav::PanoramaModel& panorama, omni_frame_t* frame);
nav::MirrorModel MirrorOf(const omni_frame_t& frame);
nav::PanoramaModel PanoramaOf(const omni_frame_t& frame);

// The mirror calibration of a config section (keys center_x_px, center_y_px, inner_radius_px,
// outer_radius_px, elevation_inner_deg, elevation_outer_deg), and the panorama geometry
// (width_px, height_px, elevation_top_deg, elevation_bottom_deg). Missing keys and bad values
// are glue::ConfigError naming file and line; the models are not validated here.
nav::MirrorModel ReadMirrorConfig(const IniFile& ini, const std::string& section = "mirror");
nav::PanoramaModel ReadPanoramaConfig(const IniFile& ini, const std::string& section = "panorama");
// The self-occlusion mask a config names ([mirror] mask = FILE, relative paths from the config's
// folder; empty: none): the path, or "" for none. Marks the key read.
std::string ReadMirrorMaskPath(const IniFile& ini, const std::string& section = "mirror");
// A mask image (image_mask.hpp: any 8-bit image, non-zero = usable, 0 = masked) as CV_8UC1; with
// `expected` (non-empty), of that size. Throws std::runtime_error naming the file when it cannot
// be read, is not an image or has another size.
cv::Mat LoadMask(const std::string& path, cv::Size expected = cv::Size());
// The mask a config names, loaded (LoadMask): empty when none; a file that cannot be read, is no
// image or has another size than `expected` (non-empty) is a ConfigError naming the config's file,
// line and key ("sim.ini:12: [mirror] mask = 'm.png': mask /x/m.png: no such file").
struct MirrorMask {
  std::string path;  // "" for none
  cv::Mat mask;      // CV_8UC1, empty for none
};
MirrorMask ReadMirrorMask(const IniFile& ini, cv::Size expected = cv::Size(), const std::string& section = "mirror");
// A process's `--mask FILE` (kMaskFlagHelp): sets the config's [mirror] mask to FILE made absolute
// (FILE is relative to the working folder, the key's value to the config's); "" leaves the config as
// it is. A missing file, or a config without the key, is a ConfigError naming the flag.
inline constexpr const char* kMaskFlagHelp =
    "the robot's own parts in the raw frames (PNG, black = masked; calibrate-mirror writes one); overrides "
    "[mirror] mask";
void ApplyMaskFlag(const std::string& mask_file, IniFile* ini, const std::string& section = "mirror");

// The sections the two readers above read back (header line included).
void PrintMirrorConfig(std::ostream& out, const nav::MirrorModel& mirror, const std::string& section = "mirror");
// The same with the mask key (after the mirror's keys; "" for none).
void PrintMirrorConfig(std::ostream& out, const nav::MirrorModel& mirror, const std::string& mask_path,
                       const std::string& section);
void PrintPanoramaConfig(std::ostream& out, const nav::PanoramaModel& panorama, const std::string& section = "panorama");

}  // namespace snapnav::glue
