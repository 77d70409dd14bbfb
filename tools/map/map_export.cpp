#include "map_export.hpp"

#include <filesystem>
#include <fstream>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <map>
#include <sstream>
#include <stdexcept>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace snapnav::map {

namespace {
// map_saver's trinary values.
uint8_t Trinary(int8_t occupancy, const nav::OccupancyGridOptions& o) {
  if (occupancy < 0) return 205;
  if (occupancy >= 100.0 * o.occupied_threshold) return 0;
  if (occupancy <= 100.0 * o.free_threshold) return 254;
  return 205;
}
}  // namespace

void WriteRosMap(const nav::OccupancyCells& cells, const nav::OccupancyGridOptions& options, const std::string& dir,
                 const std::string& name) {
  std::filesystem::create_directories(dir);
  const std::string pgm = (std::filesystem::path(dir) / (name + ".pgm")).string();
  {
    std::ofstream f(pgm, std::ios::binary);
    if (!f) throw std::runtime_error(pgm + ": cannot write");
    f << "P5\n# snapnav map export, " << cells.resolution_m << " m/pixel\n" << cells.width << " " << cells.height << "\n255\n";
    std::vector<char> row(static_cast<size_t>(cells.width));
    for (int y = cells.height - 1; y >= 0; --y) {
      for (int x = 0; x < cells.width; ++x) {
        row[static_cast<size_t>(x)] = static_cast<char>(
            Trinary(cells.cells[static_cast<size_t>(y) * static_cast<size_t>(cells.width) + static_cast<size_t>(x)], options));
      }
      f.write(row.data(), static_cast<std::streamsize>(row.size()));
    }
    if (!f) throw std::runtime_error(pgm + ": write failed");
  }
  const std::string yaml = (std::filesystem::path(dir) / (name + ".yaml")).string();
  std::ofstream f(yaml);
  if (!f) throw std::runtime_error(yaml + ": cannot write");
  // MRPT's cells are floats: the resolution as given (0.05, not 0.0500000007), the origin exact.
  f << "image: " << name << ".pgm\nmode: trinary\nresolution: " << std::setprecision(6) << cells.resolution_m
    << std::setprecision(9) << "\norigin: [" << cells.origin_x_m << ", " << cells.origin_y_m << ", 0.0]\nnegate: 0\noccupied_thresh: "
    << options.occupied_threshold << "\nfree_thresh: " << options.free_threshold << "\n";
  if (!f) throw std::runtime_error(yaml + ": write failed");
}

void WriteGridmap(const mrpt::maps::COccupancyGridMap2D& grid, const std::string& path) {
  mrpt::io::CFileGZOutputStream f;
  if (!f.open(path)) throw std::runtime_error(path + ": cannot write");
  mrpt::serialization::archiveFrom(f) << grid;
}

void WriteSimplemap(const mrpt::maps::CSimpleMap& map, const std::string& path) {
  mrpt::io::CFileGZOutputStream f;
  if (!f.open(path)) throw std::runtime_error(path + ": cannot write");
  mrpt::serialization::archiveFrom(f) << map;
}

namespace {
// An MRPT serialization (gzip-compressed or not, as MRPT's apps write them) of a `T`.
template <class T>
T ReadMrptFile(const std::string& path, const std::string& what) {
  mrpt::io::CFileGZInputStream f;
  if (!f.open(path)) throw std::runtime_error(path + ": cannot open");
  T object;
  try {
    mrpt::serialization::archiveFrom(f) >> object;
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": not an MRPT " + what + ": " + std::string(e.what()).substr(0, 200));
  }
  return object;
}
}  // namespace

mrpt::maps::COccupancyGridMap2D ReadGridmap(const std::string& path) {
  return ReadMrptFile<mrpt::maps::COccupancyGridMap2D>(path, "occupancy grid (.gridmap)");
}

namespace {
std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r\"'");
  if (a == std::string::npos) return "";
  const size_t b = s.find_last_not_of(" \t\r\"'");
  return s.substr(a, b - a + 1);
}
double Number(const std::string& path, const std::string& key, const std::string& v) {
  char* end = nullptr;
  const double d = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || !std::isfinite(d)) throw std::runtime_error(path + ": " + key + ": not a number: '" + v + "'");
  return d;
}
}  // namespace

mrpt::maps::COccupancyGridMap2D GridFromSimplemap(const std::string& path, const nav::OccupancyGridOptions& options) {
  const auto keyframes = ReadMrptFile<mrpt::maps::CSimpleMap>(path, "simple map (.simplemap)");
  if (keyframes.empty()) throw std::runtime_error(path + ": the simple map holds no keyframes");
  // As map-export builds its grids (OccupancyGridBuilder): a beam with no return clears nothing.
  mrpt::maps::COccupancyGridMap2D grid(-1, 1, -1, 1, static_cast<float>(options.resolution_m));
  grid.insertionOptions.considerInvalidRangesAsFreeSpace = false;
  grid.insertionOptions.maxDistanceInsertion =
      options.max_range_m > 0 ? static_cast<float>(options.max_range_m) : 1e4f;
  grid.loadFromSimpleMap(keyframes);
  return grid;
}

nav::OccupancyCells ReadMapFile(const std::string& path, const nav::OccupancyGridOptions& options) {
  const std::filesystem::path p(path);
  // The kind by the extension, a gzip's ".gz" aside (MRPT reads both).
  const std::string kind = (p.extension() == ".gz" ? p.stem() : p).extension().string();
  if (kind == ".gridmap") {
    nav::OccupancyCells cells = nav::ToOccupancyCells(ReadGridmap(path), options);
    return cells;
  }
  if (kind == ".simplemap") {
    nav::OccupancyCells cells = nav::ToOccupancyCells(GridFromSimplemap(path, options), options);
    if (cells.occupied == 0 || cells.free == 0) throw std::runtime_error(path + ": the simple map holds no 2D laser scan");
    return cells;
  }
  if (p.extension() != ".yaml" && p.extension() != ".yml") {
    throw std::runtime_error(path + ": not a map file (map.yaml of ROS map_server, or MRPT's .gridmap or .simplemap)");
  }
  std::ifstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open");
  std::map<std::string, std::string> kv;
  std::string line;
  while (std::getline(f, line)) {
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line = line.substr(0, hash);
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    kv[Trim(line.substr(0, colon))] = Trim(line.substr(colon + 1));
  }
  for (const char* key : {"image", "resolution", "origin"}) {
    if (!kv.count(key)) throw std::runtime_error(path + ": no '" + key + "' (not a map_server YAML)");
  }
  const double resolution = Number(path, "resolution", kv["resolution"]);
  if (!(resolution > 0)) throw std::runtime_error(path + ": resolution must be positive");
  std::string origin = kv["origin"];
  if (origin.size() < 2 || origin.front() != '[' || origin.back() != ']') throw std::runtime_error(path + ": origin must be [x, y, yaw]");
  std::vector<double> o;
  {
    std::stringstream ss(origin.substr(1, origin.size() - 2));
    std::string item;
    while (std::getline(ss, item, ',')) o.push_back(Number(path, "origin", Trim(item)));
  }
  if (o.size() != 3) throw std::runtime_error(path + ": origin must be [x, y, yaw]");
  if (std::abs(o[2]) > 1e-9) throw std::runtime_error(path + ": origin yaw " + std::to_string(o[2]) + ": only 0 is supported");
  const bool negate = kv.count("negate") && Number(path, "negate", kv["negate"]) != 0;
  const double occ = kv.count("occupied_thresh") ? Number(path, "occupied_thresh", kv["occupied_thresh"]) : 0.65;
  const double fre = kv.count("free_thresh") ? Number(path, "free_thresh", kv["free_thresh"]) : 0.196;
  const std::string mode = kv.count("mode") ? kv["mode"] : "trinary";
  if (mode != "trinary" && mode != "scale") throw std::runtime_error(path + ": mode " + mode + ": only trinary and scale are supported");
  std::filesystem::path image(kv["image"]);
  if (image.is_relative()) image = p.parent_path() / image;
  const cv::Mat img = cv::imread(image.string(), cv::IMREAD_GRAYSCALE);
  if (img.empty()) throw std::runtime_error(image.string() + ": cannot read the map image (named by " + path + ")");
  nav::OccupancyCells cells;
  cells.resolution_m = resolution;
  cells.origin_x_m = o[0];
  cells.origin_y_m = o[1];
  cells.width = img.cols;
  cells.height = img.rows;
  cells.cells.resize(static_cast<size_t>(img.cols) * static_cast<size_t>(img.rows));
  for (int r = 0; r < img.rows; ++r) {
    for (int c = 0; c < img.cols; ++c) {
      const double v = img.at<uint8_t>(r, c);
      const double occupancy = negate ? v / 255.0 : (255.0 - v) / 255.0;
      int8_t cell;
      if (occupancy > occ) cell = 100;
      else if (occupancy < fre) cell = 0;
      else if (mode == "scale") cell = static_cast<int8_t>(std::lround(99 * (occupancy - fre) / (occ - fre)));
      else cell = -1;
      cells.cells[static_cast<size_t>(img.rows - 1 - r) * static_cast<size_t>(img.cols) + static_cast<size_t>(c)] = cell;
    }
  }
  cells.Count(options.occupied_threshold, options.free_threshold);
  return cells;
}

void WriteMapPng(const nav::OccupancyCells& cells, const nav::OccupancyGridOptions& options,
                 const std::vector<nav::Pose2>& trajectory, const std::string& path) {
  cv::Mat img(cells.height, cells.width, CV_8UC3);
  for (int y = 0; y < cells.height; ++y) {
    for (int x = 0; x < cells.width; ++x) {
      const uint8_t v = Trinary(cells.cells[static_cast<size_t>(y) * static_cast<size_t>(cells.width) + static_cast<size_t>(x)], options);
      img.at<cv::Vec3b>(cells.height - 1 - y, x) = cv::Vec3b(v, v, v);
    }
  }
  const auto pixel = [&](const nav::Pose2& p) {
    return cv::Point(static_cast<int>((p.x_m - cells.origin_x_m) / cells.resolution_m),
                     cells.height - 1 - static_cast<int>((p.y_m - cells.origin_y_m) / cells.resolution_m));
  };
  for (size_t i = 1; i < trajectory.size(); ++i) {
    cv::line(img, pixel(trajectory[i - 1]), pixel(trajectory[i]), cv::Scalar(0, 0, 220), 1, cv::LINE_AA);
  }
  if (!cv::imwrite(path, img)) throw std::runtime_error(path + ": cannot write");
}

}  // namespace snapnav::map
