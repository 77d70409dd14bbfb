// A folder of images plus a positions CSV -> OMNI_FRAME and POSE_GROUND_TRUTH.
//
// The CSV's first line names the columns: file, x_m, y_m, heading_rad and optionally utime
// [microseconds], in any order (other columns are ignored and named in a note). Each row
// becomes one omni_frame_t carrying the image file's bytes unchanged (PNG or JPEG; the size
// comes from decoding the file) and one pose_t (estimator "ground_truth").

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "import_util.hpp"
#include "importers.hpp"
#include "snapnav/glue/conversions.hpp"
#include "snapnav/omni_frame_t.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::importers {
namespace {

constexpr size_t kMaxCsvLineBytes = 64 * 1024;
constexpr char kPoseFrame[] = "map";

std::string Trim(std::string_view text) {
  const auto b = text.find_first_not_of(" \t");
  if (b == std::string_view::npos) return "";
  const auto e = text.find_last_not_of(" \t");
  std::string out(text.substr(b, e - b + 1));
  if (out.size() >= 2 && out.front() == '"' && out.back() == '"') out = out.substr(1, out.size() - 2);
  return out;
}

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> fields;
  size_t start = 0;
  for (;;) {
    const auto comma = line.find(',', start);
    fields.push_back(
        Trim(std::string_view(line).substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return fields;
}

bool IsBlankOrComment(const std::string& line) {
  const auto b = line.find_first_not_of(" \t");
  return b == std::string::npos || line[b] == '#';
}

std::string JoinPath(const std::string& folder, const std::string& file) {
  if (!file.empty() && file.front() == '/') return file;
  if (folder.empty()) return file;
  return folder.back() == '/' ? folder + file : folder + "/" + file;
}

// Reads a whole file of at most max_bytes; returns an error text or "".
std::string ReadFile(const std::string& path, size_t max_bytes, std::vector<uint8_t>* data) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return std::string("cannot read image '") + path + "': " + std::strerror(errno);
  if (!S_ISREG(st.st_mode)) return "image '" + path + "' is not a regular file";
  if (static_cast<uint64_t>(st.st_size) > max_bytes) {
    return "image '" + path + "' has " + std::to_string(st.st_size) + " bytes, more than the limit of " +
           std::to_string(max_bytes);
  }
  std::ifstream in(path, std::ios::binary);
  data->resize(static_cast<size_t>(st.st_size));
  if (!in || !in.read(reinterpret_cast<char*>(data->data()), static_cast<std::streamsize>(data->size()))) {
    return "cannot read image '" + path + "'";
  }
  return "";
}

}  // namespace

void ImageOptions::Validate() const {
  if (!(rate_hz > 0 && rate_hz <= 1e6)) throw std::invalid_argument("synthesized rate must be in (0, 1e6] Hz");
  const double raw_only[] = {mirror_center_x_px,     mirror_center_y_px,         mirror_inner_radius_px,
                             mirror_outer_radius_px, mirror_elevation_inner_rad, mirror_elevation_outer_rad};
  const double panorama_only[] = {bearing_col0_rad, elevation_top_rad, elevation_bottom_rad};
  for (double v : raw_only) {
    if (!std::isfinite(v)) throw std::invalid_argument("image options must be finite numbers");
    if (panorama && v != 0) {
      throw std::invalid_argument("the mirror calibration applies to raw omni images, not to panoramas");
    }
  }
  for (double v : panorama_only) {
    if (!std::isfinite(v)) throw std::invalid_argument("image options must be finite numbers");
    if (!panorama && v != 0) {
      throw std::invalid_argument("the bearing and row elevations apply to panoramas, not to raw omni images");
    }
  }
  if (mirror_inner_radius_px < 0 || mirror_outer_radius_px < 0 ||
      (mirror_outer_radius_px > 0 && mirror_inner_radius_px > mirror_outer_radius_px)) {
    throw std::invalid_argument("mirror radii must satisfy 0 <= inner <= outer");
  }
  if (sensor_name.empty()) throw std::invalid_argument("sensor name must not be empty");
}

ImportReport ImportImages(const std::string& folder, const std::string& positions_csv, Sink& sink,
                          const ImageOptions& options) {
  options.Validate();
  ImportReport report;
  report.input = folder;
  std::ifstream csv(positions_csv, std::ios::binary);
  if (!csv) {
    report.AddError(positions_csv + ": cannot open the positions CSV: " + std::strerror(errno));
    return report;
  }
  auto fail = [&](int64_t line, const std::string& reason) {
    report.AddError(positions_csv + ":" + std::to_string(line) + ": " + reason);
  };

  // All lines first: the CSV is small, and the row count makes progress reports meaningful.
  std::vector<std::pair<int64_t, std::string>> lines;
  internal::LineReader reader(csv, kMaxCsvLineBytes);
  for (;;) {
    const auto status = reader.Next();
    if (status == internal::LineReader::Status::kEnd) break;
    if (status == internal::LineReader::Status::kTooLong) {
      fail(reader.line_number(), "line longer than " + std::to_string(kMaxCsvLineBytes) + " bytes; skipped");
      continue;
    }
    if (IsBlankOrComment(reader.line())) continue;
    lines.emplace_back(reader.line_number(), reader.line());
  }
  if (lines.empty()) {
    report.AddError(positions_csv + ": no header line (expected file,x_m,y_m,heading_rad[,utime])");
    return report;
  }

  // Header.
  const auto header = SplitCsv(lines.front().second);
  std::map<std::string, size_t> column;
  std::vector<std::string> ignored;
  for (size_t i = 0; i < header.size(); ++i) {
    const std::string& name = header[i];
    if (name == "file" || name == "x_m" || name == "y_m" || name == "heading_rad" || name == "utime") {
      if (column.count(name)) {
        fail(lines.front().first, "column '" + name + "' appears twice in the header");
        return report;
      }
      column[name] = i;
    } else {
      ignored.push_back(name.empty() ? "(unnamed)" : name);
    }
  }
  for (const char* required : {"file", "x_m", "y_m", "heading_rad"}) {
    if (!column.count(required)) {
      fail(lines.front().first, std::string("header lacks column '") + required +
                                    "' (expected file,x_m,y_m,heading_rad[,utime]; got '" + lines.front().second +
                                    "')");
      return report;
    }
  }
  if (!ignored.empty()) {
    std::string names;
    for (const auto& n : ignored) names += (names.empty() ? "" : ", ") + n;
    report.notes.push_back("CSV columns ignored: " + names);
  }
  const bool has_utime = column.count("utime") > 0;
  if (!has_utime) {
    char rate[32];
    std::snprintf(rate, sizeof rate, "%g", options.rate_hz);
    report.notes.push_back(std::string("the CSV has no utime column: times synthesized at ") + rate + " Hz from " +
                           internal::FormatUtime(kSynthesizedStartUtime) + " s");
  }

  internal::Emitter emitter(sink, report);
  const int64_t rows = static_cast<int64_t>(lines.size()) - 1;
  std::vector<uint8_t> data;
  for (int64_t row = 0; row < rows; ++row) {
    const auto& [line_number, line] = lines[static_cast<size_t>(row) + 1];
    if (options.progress && row > 0 && row % options.progress_every_rows == 0) {
      options.progress({row, rows, "rows"});
    }
    const auto fields = SplitCsv(line);
    if (fields.size() != header.size()) {
      fail(line_number, std::to_string(fields.size()) + " fields, but the header has " + std::to_string(header.size()));
      continue;
    }
    const std::string& file = fields[column["file"]];
    if (file.empty()) {
      fail(line_number, "empty file name");
      continue;
    }
    const auto x = internal::ParseDouble(fields[column["x_m"]]);
    const auto y = internal::ParseDouble(fields[column["y_m"]]);
    const auto heading = internal::ParseDouble(fields[column["heading_rad"]]);
    if (!x || !y || !heading) {
      fail(line_number, "x_m, y_m and heading_rad must be numbers, got " + internal::Quote(fields[column["x_m"]]) +
                            ", " + internal::Quote(fields[column["y_m"]]) + ", " +
                            internal::Quote(fields[column["heading_rad"]]));
      continue;
    }
    int64_t utime = 0;
    if (has_utime) {
      const auto u = internal::ParseInt64(fields[column["utime"]]);
      if (!u || *u < 0) {
        fail(line_number,
             "utime must be a non-negative integer [microseconds], got " + internal::Quote(fields[column["utime"]]));
        continue;
      }
      utime = *u;
    } else {
      utime = kSynthesizedStartUtime + std::llround(static_cast<double>(row) * 1e6 / options.rate_hz);
    }

    const std::string path = JoinPath(folder, file);
    if (const std::string error = ReadFile(path, options.max_image_bytes, &data); !error.empty()) {
      fail(line_number, error);
      continue;
    }
    int8_t encoding = 0;
    static const uint8_t kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (data.size() >= 8 && std::equal(kPng, kPng + 8, data.begin())) {
      encoding = omni_frame_t::PNG;
    } else if (data.size() >= 3 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF) {
      encoding = omni_frame_t::JPEG;
    } else {
      fail(line_number, "image '" + path + "' is neither PNG nor JPEG");
      continue;
    }
    cv::Mat image;
    try {
      image = cv::imdecode(cv::Mat(1, static_cast<int>(data.size()), CV_8UC1, data.data()), cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception&) {
      image.release();
    }
    if (image.empty()) {
      fail(line_number, "image '" + path + "' cannot be decoded (corrupt or truncated?)");
      continue;
    }

    omni_frame_t frame{};  // value-initialized: a field added to the type later is 0, not garbage
    frame.utime = utime;
    frame.sensor_name = options.sensor_name;
    frame.kind = options.panorama ? omni_frame_t::PANORAMA : omni_frame_t::RAW_OMNI;
    frame.width = image.cols;
    frame.height = image.rows;
    frame.row_stride = 0;
    frame.encoding = encoding;
    frame.mirror_center_x_px = static_cast<float>(options.mirror_center_x_px);
    frame.mirror_center_y_px = static_cast<float>(options.mirror_center_y_px);
    frame.mirror_inner_radius_px = static_cast<float>(options.mirror_inner_radius_px);
    frame.mirror_outer_radius_px = static_cast<float>(options.mirror_outer_radius_px);
    frame.mirror_elevation_inner_rad = static_cast<float>(options.mirror_elevation_inner_rad);
    frame.mirror_elevation_outer_rad = static_cast<float>(options.mirror_elevation_outer_rad);
    frame.bearing_col0_rad = static_cast<float>(options.bearing_col0_rad);
    frame.elevation_top_rad = static_cast<float>(options.elevation_top_rad);
    frame.elevation_bottom_rad = static_cast<float>(options.elevation_bottom_rad);
    frame.data_size = static_cast<int32_t>(data.size());
    frame.data = data;
    emitter.Emit(options.channels.omni_frame, frame);
    emitter.Emit(options.channels.pose_ground_truth,
                 glue::ToPoseMsg(utime, kGroundTruthEstimator, kPoseFrame, nav::Pose2{*x, *y, *heading},
                                 Eigen::Matrix3d::Zero()));
    if (!has_utime) report.synthesized_utimes += 2;  // the frame and its pose
  }
  if (rows == 0) report.AddError(positions_csv + ": the CSV has a header but no rows");
  return report;
}

}  // namespace snapnav::importers
