#include "map_export.hpp"

#include <filesystem>
#include <fstream>
#include <iomanip>
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

mrpt::maps::COccupancyGridMap2D ReadGridmap(const std::string& path) {
  mrpt::io::CFileGZInputStream f;
  if (!f.open(path)) throw std::runtime_error(path + ": cannot open");
  mrpt::maps::COccupancyGridMap2D grid;
  try {
    mrpt::serialization::archiveFrom(f) >> grid;
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": not an MRPT occupancy grid (.gridmap): " + std::string(e.what()).substr(0, 200));
  }
  return grid;
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
