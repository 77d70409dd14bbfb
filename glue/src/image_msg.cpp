#include "snapnav/glue/image_msg.hpp"

#include <cmath>

#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace snapnav::glue {

int8_t ParseFrameEncoding(const std::string& name) {
  if (name == "gray8") return omni_frame_t::GRAY8;
  if (name == "rgb8") return omni_frame_t::RGB8;
  if (name == "jpeg") return omni_frame_t::JPEG;
  if (name == "png") return omni_frame_t::PNG;
  throw std::invalid_argument("unknown encoding '" + name + "' (gray8, rgb8, jpeg or png)");
}

std::string FrameEncodingName(int8_t encoding) {
  switch (encoding) {
    case omni_frame_t::GRAY8: return "gray8";
    case omni_frame_t::RGB8: return "rgb8";
    case omni_frame_t::JPEG: return "jpeg";
    case omni_frame_t::PNG: return "png";
    default: return "?";
  }
}

omni_frame_t ImageToFrame(const cv::Mat& input, int8_t encoding, int jpeg_quality) {
  if (input.empty()) throw std::invalid_argument("cannot make a frame from an empty image");
  if (input.depth() != CV_8U || (input.channels() != 1 && input.channels() != 3 && input.channels() != 4)) {
    throw std::invalid_argument("frames hold 8-bit grey, BGR or BGRA images (got depth " +
                                std::to_string(input.depth()) + ", " + std::to_string(input.channels()) + " channels)");
  }
  cv::Mat image = input;
  if (input.channels() == 4) cv::cvtColor(input, image, cv::COLOR_BGRA2BGR);  // alpha is dropped
  omni_frame_t f{};
  f.utime = 0;
  f.kind = omni_frame_t::RAW_OMNI;
  f.width = image.cols;
  f.height = image.rows;
  f.encoding = encoding;
  cv::Mat pixels;
  switch (encoding) {
    case omni_frame_t::GRAY8:
      if (image.channels() == 3) cv::cvtColor(image, pixels, cv::COLOR_BGR2GRAY); else pixels = image;
      f.row_stride = image.cols;
      break;
    case omni_frame_t::RGB8:
      if (image.channels() == 1) cv::cvtColor(image, pixels, cv::COLOR_GRAY2RGB); else cv::cvtColor(image, pixels, cv::COLOR_BGR2RGB);
      f.row_stride = 3 * image.cols;
      break;
    case omni_frame_t::JPEG:
    case omni_frame_t::PNG: {
      std::vector<uint8_t> bytes;
      // JPEG with optimised Huffman tables: about 2 % smaller, the same pixels.
      const std::vector<int> params =
          encoding == omni_frame_t::JPEG
              ? std::vector<int>{cv::IMWRITE_JPEG_QUALITY, jpeg_quality, cv::IMWRITE_JPEG_OPTIMIZE, 1}
              : std::vector<int>{cv::IMWRITE_PNG_COMPRESSION, 1};
      if (!cv::imencode(encoding == omni_frame_t::JPEG ? ".jpg" : ".png", image, bytes, params) || bytes.empty()) {
        throw std::runtime_error("OpenCV could not encode a " + std::to_string(image.cols) + "x" +
                                 std::to_string(image.rows) + " image as " +
                                 (encoding == omni_frame_t::JPEG ? "JPEG" : "PNG"));
      }
      f.row_stride = 0;
      f.data = std::move(bytes);
      f.data_size = static_cast<int32_t>(f.data.size());
      return f;
    }
    default:
      throw std::invalid_argument("unknown frame encoding " + std::to_string(encoding));
  }
  f.data.resize(static_cast<size_t>(f.row_stride) * f.height);
  for (int y = 0; y < f.height; ++y) std::memcpy(&f.data[static_cast<size_t>(y) * f.row_stride], pixels.ptr(y), f.row_stride);
  f.data_size = static_cast<int32_t>(f.data.size());
  return f;
}

std::optional<cv::Size> CompressedImageSize(const std::vector<uint8_t>& b, int8_t encoding) {
  auto be16 = [&](size_t at) { return (b[at] << 8) | b[at + 1]; };
  auto be32 = [&](size_t at) { return (uint32_t{b[at]} << 24) | (uint32_t{b[at + 1]} << 16) | (b[at + 2] << 8) | b[at + 3]; };
  if (encoding == omni_frame_t::PNG) {
    static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a};
    if (b.size() < 24 || std::memcmp(b.data(), kSignature, 8) != 0 || std::memcmp(&b[12], "IHDR", 4) != 0) {
      return std::nullopt;
    }
    const uint32_t w = be32(16), h = be32(20);
    if (w > INT32_MAX || h > INT32_MAX) return cv::Size(-1, -1);
    return cv::Size(static_cast<int>(w), static_cast<int>(h));
  }
  if (encoding == omni_frame_t::JPEG) {
    if (b.size() < 4 || b[0] != 0xff || b[1] != 0xd8) return std::nullopt;
    // Segments up to the first start-of-frame marker (SOF0..SOF15 but DHT, JPG, DAC), which
    // holds the height and width.
    for (size_t at = 2; at + 4 <= b.size();) {
      if (b[at] != 0xff) return std::nullopt;
      const uint8_t marker = b[at + 1];
      if (marker == 0xff) {  // fill byte
        ++at;
        continue;
      }
      if (marker == 0xd8 || (marker >= 0xd0 && marker <= 0xd7) || marker == 0x01) {  // no length
        at += 2;
        continue;
      }
      const size_t length = static_cast<size_t>(be16(at + 2));
      if (marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc) {
        if (at + 9 > b.size() || length < 7) return std::nullopt;
        return cv::Size(be16(at + 7), be16(at + 5));
      }
      if (length < 2) return std::nullopt;
      at += 2 + length;
    }
    return std::nullopt;
  }
  return std::nullopt;
}

cv::Mat FrameToImage(const omni_frame_t& f) {
  if (f.width <= 0 || f.height <= 0) throw std::invalid_argument("frame has no pixels (" + std::to_string(f.width) + "x" + std::to_string(f.height) + ")");
  if (static_cast<int64_t>(f.width) * f.height > kMaxFramePixels) {
    throw std::invalid_argument("frame of " + std::to_string(f.width) + "x" + std::to_string(f.height) +
                                " pixels is larger than " + std::to_string(kMaxFramePixels) + " pixels");
  }
  if (static_cast<size_t>(f.data_size) != f.data.size()) throw std::invalid_argument("frame data_size does not match its data");
  switch (f.encoding) {
    case omni_frame_t::GRAY8:
    case omni_frame_t::RGB8: {
      const int channels = f.encoding == omni_frame_t::GRAY8 ? 1 : 3;
      if (f.row_stride < int64_t{channels} * f.width) throw std::invalid_argument("frame row_stride smaller than a row of pixels");
      if (static_cast<int64_t>(f.row_stride) * f.height > f.data_size) {
        throw std::invalid_argument("frame holds " + std::to_string(f.data_size) + " bytes, its size needs " +
                                    std::to_string(static_cast<int64_t>(f.row_stride) * f.height));
      }
      const cv::Mat view(f.height, f.width, channels == 1 ? CV_8UC1 : CV_8UC3, const_cast<uint8_t*>(f.data.data()),
                         f.row_stride);
      cv::Mat out;
      if (channels == 3) cv::cvtColor(view, out, cv::COLOR_RGB2BGR); else out = view.clone();
      return out;
    }
    case omni_frame_t::JPEG:
    case omni_frame_t::PNG: {
      // The header's size first: OpenCV allocates what the header says before it reads a pixel.
      const char* format = f.encoding == omni_frame_t::JPEG ? "JPEG" : "PNG";
      const auto header = CompressedImageSize(f.data, f.encoding);
      if (!header) throw std::invalid_argument(std::string("frame: data is not a ") + format + " file");
      if (header->width != f.width || header->height != f.height) {
        throw std::invalid_argument(std::string("frame: the ") + format + " header says " +
                                    std::to_string(header->width) + "x" + std::to_string(header->height) +
                                    ", the frame " + std::to_string(f.width) + "x" + std::to_string(f.height));
      }
      cv::Mat out = cv::imdecode(f.data, cv::IMREAD_UNCHANGED);
      if (out.empty()) throw std::invalid_argument("frame: compressed image does not decode");
      if (out.cols != f.width || out.rows != f.height) throw std::invalid_argument("frame: decoded size differs from width/height");
      if (out.depth() != CV_8U) out.convertTo(out, CV_8U, 1.0 / 256);
      if (out.channels() == 4) cv::cvtColor(out, out, cv::COLOR_BGRA2BGR);
      return out;
    }
    default:
      throw std::invalid_argument("frame has unknown encoding " + std::to_string(f.encoding));
  }
}

void SetMirror(const nav::MirrorModel& m, omni_frame_t* f) {
  f->mirror_center_x_px = static_cast<float>(m.center_x_px);
  f->mirror_center_y_px = static_cast<float>(m.center_y_px);
  f->mirror_inner_radius_px = static_cast<float>(m.inner_radius_px);
  f->mirror_outer_radius_px = static_cast<float>(m.outer_radius_px);
  f->mirror_elevation_inner_rad = static_cast<float>(m.elevation_inner_rad);
  f->mirror_elevation_outer_rad = static_cast<float>(m.elevation_outer_rad);
}

void SetPanorama(const nav::PanoramaModel& p, omni_frame_t* f) {
  f->bearing_col0_rad = static_cast<float>(p.bearing_col0_rad);
  f->elevation_top_rad = static_cast<float>(p.elevation_top_rad);
  f->elevation_bottom_rad = static_cast<float>(p.elevation_bottom_rad);
}

nav::MirrorModel MirrorOf(const omni_frame_t& f) {
  nav::MirrorModel m;
  m.center_x_px = f.mirror_center_x_px;
  m.center_y_px = f.mirror_center_y_px;
  m.inner_radius_px = f.mirror_inner_radius_px;
  m.outer_radius_px = f.mirror_outer_radius_px;
  m.elevation_inner_rad = f.mirror_elevation_inner_rad;
  m.elevation_outer_rad = f.mirror_elevation_outer_rad;
  return m;
}

nav::PanoramaModel PanoramaOf(const omni_frame_t& f) {
  nav::PanoramaModel p;
  p.width_px = f.width;
  p.height_px = f.height;
  p.bearing_col0_rad = f.bearing_col0_rad;
  p.elevation_top_rad = f.elevation_top_rad;
  p.elevation_bottom_rad = f.elevation_bottom_rad;
  return p;
}

nav::MirrorModel ReadMirrorConfig(const IniFile& ini, const std::string& section) {
  constexpr double kDeg = M_PI / 180;
  nav::MirrorModel m;
  m.center_x_px = ini.GetDouble(section, "center_x_px");
  m.center_y_px = ini.GetDouble(section, "center_y_px");
  m.inner_radius_px = ini.GetDouble(section, "inner_radius_px");
  m.outer_radius_px = ini.GetDouble(section, "outer_radius_px");
  m.elevation_inner_rad = ini.GetDouble(section, "elevation_inner_deg") * kDeg;
  m.elevation_outer_rad = ini.GetDouble(section, "elevation_outer_deg") * kDeg;
  return m;
}

nav::PanoramaModel ReadPanoramaConfig(const IniFile& ini, const std::string& section) {
  constexpr double kDeg = M_PI / 180;
  nav::PanoramaModel p;
  p.width_px = ini.GetInt(section, "width_px");
  p.height_px = ini.GetInt(section, "height_px");
  p.elevation_top_rad = ini.GetDouble(section, "elevation_top_deg") * kDeg;
  p.elevation_bottom_rad = ini.GetDouble(section, "elevation_bottom_deg") * kDeg;
  return p;
}

void PrintMirrorConfig(std::ostream& out, const nav::MirrorModel& m, const std::string& section) {
  constexpr double kDeg = M_PI / 180;
  out << "[" << section << "]\ncenter_x_px = " << m.center_x_px << "\ncenter_y_px = " << m.center_y_px
      << "\ninner_radius_px = " << m.inner_radius_px << "\nouter_radius_px = " << m.outer_radius_px
      << "\nelevation_inner_deg = " << m.elevation_inner_rad / kDeg
      << "\nelevation_outer_deg = " << m.elevation_outer_rad / kDeg << "\n";
}

void PrintMirrorConfig(std::ostream& out, const nav::MirrorModel& m, const std::string& mask_path,
                       const std::string& section) {
  PrintMirrorConfig(out, m, section);
  out << "mask = " << mask_path << "\n";
}

std::string ReadMirrorMaskPath(const IniFile& ini, const std::string& section) {
  const std::string value = ini.GetString(section, "mask");
  if (value.empty() || value[0] == '/') return value;
  // Relative to the config file's folder (a calibration writes the mask beside its ini).
  const std::filesystem::path origin(ini.origin());
  if (std::filesystem::exists(origin)) return (origin.parent_path() / value).lexically_normal().string();
  return value;
}

cv::Mat LoadMask(const std::string& path, cv::Size expected) {
  if (!std::filesystem::exists(path)) throw std::runtime_error("mask " + path + ": no such file");
  cv::Mat m = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (m.empty()) throw std::runtime_error("mask " + path + ": not an image OpenCV can read");
  if (expected.width > 0 && m.size() != expected) {
    throw std::runtime_error("mask " + path + ": " + std::to_string(m.cols) + "x" + std::to_string(m.rows) +
                             ", the camera's images are " + std::to_string(expected.width) + "x" +
                             std::to_string(expected.height));
  }
  return m;
}

MirrorMask ReadMirrorMask(const IniFile& ini, cv::Size expected, const std::string& section) {
  MirrorMask m;
  m.path = ReadMirrorMaskPath(ini, section);
  if (m.path.empty()) return m;
  try {
    m.mask = LoadMask(m.path, expected);
  } catch (const std::exception& e) {
    ini.FailKey(section, "mask", e.what());
  }
  return m;
}

void ApplyMaskFlag(const std::string& mask_file, IniFile* ini, const std::string& section) {
  if (mask_file.empty()) return;
  if (!std::filesystem::exists(mask_file)) throw ConfigError("--mask " + mask_file + ": no such file");
  ini->Set(section, "mask", std::filesystem::absolute(mask_file).lexically_normal().string(), "--mask");
}

void PrintPanoramaConfig(std::ostream& out, const nav::PanoramaModel& p, const std::string& section) {
  constexpr double kDeg = M_PI / 180;
  out << "[" << section << "]\nwidth_px = " << p.width_px << "\nheight_px = " << p.height_px
      << "\nelevation_top_deg = " << p.elevation_top_rad / kDeg
      << "\nelevation_bottom_deg = " << p.elevation_bottom_rad / kDeg << "\n";
}

}  // namespace snapnav::glue
