#include "grid_folder.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/nav/homing/unwrap.hpp"

namespace snapnav::eval {

namespace {

namespace fs = std::filesystem;

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream s(line);
  while (std::getline(s, field, ',')) {
    while (!field.empty() && (field.back() == ' ' || field.back() == '\r')) field.pop_back();
    while (!field.empty() && field.front() == ' ') field.erase(field.begin());
    out.push_back(field);
  }
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

std::string Size(cv::Size s) { return std::to_string(s.width) + "x" + std::to_string(s.height); }

}  // namespace

GridFolder LoadGridFolder(const std::string& dir) {
  GridFolder g;
  g.dir = dir;
  if (!fs::is_directory(dir)) throw std::runtime_error("grid folder " + dir + ": missing or not a folder");
  const fs::path csv_path = fs::path(dir) / "positions.csv";
  const std::string csv = csv_path.string();
  std::ifstream in(csv_path);
  if (!in) throw std::runtime_error(csv + ": missing (a grid folder has images and positions.csv, as gridgen writes)");
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(csv + ":1: empty (expected the header file,ix,iy,x_m,y_m,heading_rad)");
  const auto header = SplitCsv(line);
  std::map<std::string, size_t> col;
  for (size_t i = 0; i < header.size(); ++i) col[header[i]] = i;
  for (const char* name : {"file", "ix", "iy", "x_m", "y_m", "heading_rad"}) {
    if (!col.count(name)) {
      throw std::runtime_error(csv + ":1: the header has no column '" + name +
                               "' (expected file,ix,iy,x_m,y_m,heading_rad[,utime], as gridgen writes)");
    }
  }
  const fs::path camera = fs::path(dir) / "camera.ini";
  if (fs::exists(camera)) {
    const auto ini = glue::IniFile::Load(camera.string());
    if (ini.Has("mirror", "center_x_px") || !ini.Keys("mirror").empty()) {
      g.raw = true;
      g.mirror = glue::ReadMirrorConfig(ini);
      if (ini.Has("mirror", "mask")) g.mask_path = glue::ReadMirrorMaskPath(ini);
    }
  }
  std::map<std::pair<int, int>, int> seen;
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line == "\r") continue;
    const std::string where = csv + ":" + std::to_string(number) + ": ";
    const auto f = SplitCsv(line);
    if (f.size() != header.size()) {
      throw std::runtime_error(where + std::to_string(f.size()) + " fields, the header has " +
                               std::to_string(header.size()));
    }
    auto number_of = [&](const char* name) {
      const std::string& text = f[col.at(name)];
      try {
        size_t used = 0;
        const double v = std::stod(text, &used);
        if (used != text.size() || !std::isfinite(v)) throw std::invalid_argument(text);
        return v;
      } catch (const std::exception&) {
        throw std::runtime_error(where + "column " + name + ": '" + text + "' is not a number");
      }
    };
    auto index_of = [&](const char* name) {
      const double v = number_of(name);
      if (v < 0 || v != static_cast<int>(v) || v > 100000) {
        throw std::runtime_error(where + "column " + name + ": '" + f[col.at(name)] + "' is not a grid index (0, 1, 2 ...)");
      }
      return static_cast<int>(v);
    };
    GridFolderImage im;
    im.line = number;
    im.file = f[col.at("file")];
    if (im.file.empty()) throw std::runtime_error(where + "column file is empty");
    im.ix = index_of("ix");
    im.iy = index_of("iy");
    im.pose = {number_of("x_m"), number_of("y_m"), number_of("heading_rad")};
    if (const auto [it, added] = seen.emplace(std::make_pair(im.ix, im.iy), number); !added) {
      throw std::runtime_error(where + "a second image at ix " + std::to_string(im.ix) + ", iy " + std::to_string(im.iy) +
                               " (the first on line " + std::to_string(it->second) + ")");
    }
    const fs::path file = fs::path(dir) / im.file;
    im.image = cv::imread(file.string(), cv::IMREAD_COLOR);
    if (im.image.empty()) throw std::runtime_error(where + file.string() + ": missing or not an image");
    if (g.images.empty()) {
      g.size = im.image.size();
    } else if (im.image.size() != g.size) {
      throw std::runtime_error(where + file.string() + " is " + Size(im.image.size()) + ", the first image (" +
                               g.images.front().file + ", line " + std::to_string(g.images.front().line) + ") is " +
                               Size(g.size));
    }
    g.nx = std::max(g.nx, im.ix + 1);
    g.ny = std::max(g.ny, im.iy + 1);
    g.images.push_back(std::move(im));
  }
  if (g.images.empty()) throw std::runtime_error(csv + ": no images (only the header)");
  return g;
}

std::vector<cv::Mat> GridFolderPanoramas(const GridFolder& g, const nav::PanoramaModel& panorama, cv::Mat* panorama_mask) {
  std::vector<cv::Mat> out;
  if (panorama_mask) panorama_mask->release();
  if (!g.raw) {
    if (g.size != cv::Size(panorama.width_px, panorama.height_px)) {
      throw std::runtime_error(g.dir + ": the images are " + Size(g.size) + " panoramas (no [mirror] in " +
                               (fs::path(g.dir) / "camera.ini").string() + "), the config's [panorama] is " +
                               std::to_string(panorama.width_px) + "x" + std::to_string(panorama.height_px));
    }
    for (const auto& im : g.images) out.push_back(im.image);
    return out;
  }
  const std::string camera = (fs::path(g.dir) / "camera.ini").string();
  std::unique_ptr<nav::Unwrapper> unwrapper;
  try {
    unwrapper = std::make_unique<nav::Unwrapper>(g.mirror, panorama, g.size);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(camera + ": [mirror] and the config's [panorama] do not fit: " + std::string(e.what()));
  }
  if (!g.mask_path.empty()) {
    unwrapper->SetMask(glue::LoadMask(g.mask_path, g.size));
    if (panorama_mask) *panorama_mask = unwrapper->panorama_mask();
  }
  for (const auto& im : g.images) {
    cv::Mat pano;
    unwrapper->Unwrap(im.image, &pano);
    out.push_back(pano);
  }
  return out;
}

}  // namespace snapnav::eval
