#include "scene_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

#include "snapnav/nav/sim/textures.hpp"

namespace snapnav::processes {
namespace {

class Parser {
 public:
  Parser(std::string path, int line, std::vector<std::string> tokens)
      : path_(std::move(path)), line_(line), tokens_(std::move(tokens)) {}

  [[noreturn]] void Fail(const std::string& why) const {
    throw std::runtime_error(path_ + ":" + std::to_string(line_) + ": " + why);
  }
  void Expect(size_t n_args, const std::string& usage) const {
    if (tokens_.size() != n_args + 1) Fail("'" + tokens_[0] + "' takes " + std::to_string(n_args) + " values: " + usage);
  }
  const std::string& Str(size_t i) const { return tokens_.at(i); }
  double Num(size_t i) const {
    char* end = nullptr;
    const double v = std::strtod(tokens_.at(i).c_str(), &end);
    if (*end != '\0' || tokens_[i].empty() || !std::isfinite(v)) Fail("'" + tokens_[i] + "' is not a number");
    return v;
  }
  int Int(size_t i) const {
    const double v = Num(i);
    if (v != static_cast<int>(v)) Fail("'" + tokens_[i] + "' is not an integer");
    return static_cast<int>(v);
  }
  cv::Vec3b Color(size_t i) const {
    std::stringstream ss(tokens_.at(i));
    std::string part;
    int c[3], k = 0;
    while (std::getline(ss, part, ',')) {
      if (k == 3) break;
      char* end = nullptr;
      const long v = std::strtol(part.c_str(), &end, 10);
      if (*end != '\0' || part.empty() || v < 0 || v > 255) Fail("'" + tokens_[i] + "' is not a B,G,R colour");
      c[k++] = static_cast<int>(v);
    }
    if (k != 3) Fail("'" + tokens_[i] + "' is not a B,G,R colour");
    return cv::Vec3b(c[0], c[1], c[2]);
  }
  Eigen::Vector2d Point(size_t i) const {
    const auto comma = tokens_.at(i).find(',');
    if (comma == std::string::npos) Fail("'" + tokens_[i] + "' is not an X,Y point");
    Parser sub(path_, line_, {"", tokens_[i].substr(0, comma), tokens_[i].substr(comma + 1)});
    return {sub.Num(1), sub.Num(2)};
  }
  size_t size() const { return tokens_.size(); }

 private:
  std::string path_;
  int line_;
  std::vector<std::string> tokens_;
};

std::string FindPhoto(const std::string& file, const Parser& p) {
  if (std::filesystem::path(file).is_absolute()) {
    if (std::filesystem::exists(file)) return file;
    p.Fail("photo '" + file + "' does not exist");
  }
  std::string searched;
  for (const auto& dir : PhotoSearchPath()) {
    const auto candidate = std::filesystem::path(dir) / file;
    if (std::filesystem::exists(candidate)) return candidate.string();
    searched += "\n    " + dir;
  }
  p.Fail("photo '" + file + "' not found in:" + searched +
         "\n  (it comes with Debian's opencv-doc or mrpt-common package: ./snapnav setup installs them)");
}

}  // namespace

std::vector<std::string> PhotoSearchPath() {
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("SNAPNAV_PHOTO_PATH")) {
    std::stringstream ss(env);
    std::string d;
    while (std::getline(ss, d, ':'))
      if (!d.empty()) dirs.push_back(d);
  }
  dirs.push_back("/usr/share/doc/opencv-doc/examples/data");
  dirs.push_back("/usr/share/mrpt/datasets");
  return dirs;
}

std::string SceneFilePath(const std::string& name_or_path) {
  if (name_or_path.find('/') != std::string::npos || name_or_path.find(".scene") != std::string::npos) {
    return name_or_path;
  }
  return std::string(SNAPNAV_CONFIG_DIR) + "/scenes/" + name_or_path + ".scene";
}

nav::sim::Scene LoadSceneFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    std::string known;
    const auto dir = std::filesystem::path(SNAPNAV_CONFIG_DIR) / "scenes";
    if (std::filesystem::exists(dir)) {
      for (const auto& e : std::filesystem::directory_iterator(dir))
        if (e.path().extension() == ".scene") known += " " + e.path().stem().string();
    }
    throw std::runtime_error("cannot open scene file '" + path + "' (shipped scenes:" + known + ")");
  }
  nav::sim::Scene scene;
  scene.name = std::filesystem::path(path).stem().string();
  std::map<std::string, int> texture_ids;
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (const auto hash = line.find('#'); hash != std::string::npos) line = line.substr(0, hash);
    std::istringstream ss(line);
    std::vector<std::string> tokens;
    for (std::string t; ss >> t;) tokens.push_back(t);
    if (tokens.empty()) continue;
    const Parser p(path, lineno, tokens);
    const std::string& kw = tokens[0];
    auto texture = [&](size_t i) {
      const auto it = texture_ids.find(p.Str(i));
      if (it == texture_ids.end()) p.Fail("texture '" + p.Str(i) + "' is not defined above");
      return it->second;
    };
    auto optional_texture = [&](size_t i) { return p.Str(i) == "-" ? -1 : texture(i); };
    try {
      if (kw == "name") {
        p.Expect(1, "NAME");
        scene.name = p.Str(1);
      } else if (kw == "texture") {
        if (p.size() < 3) p.Fail("texture NAME photo|pattern ...");
        if (texture_ids.count(p.Str(1))) p.Fail("texture '" + p.Str(1) + "' defined twice");
        cv::Mat image;
        double w_m = 0, h_m = 0;
        if (p.Str(2) == "photo") {
          p.Expect(5, "NAME photo FILE WIDTH_M HEIGHT_M");
          const std::string file = FindPhoto(p.Str(3), p);
          image = cv::imread(file, cv::IMREAD_COLOR);
          if (image.empty()) p.Fail("cannot decode photo '" + file + "'");
          w_m = p.Num(4);
          h_m = p.Num(5);
        } else if (p.Str(2) == "pattern") {
          p.Expect(7, "NAME pattern KIND B,G,R WIDTH_M HEIGHT_M SEED");
          w_m = p.Num(5);
          h_m = p.Num(6);
          const double px_per_m = 160;
          const cv::Size size(std::clamp(static_cast<int>(w_m * px_per_m), 16, 1024),
                              std::clamp(static_cast<int>(h_m * px_per_m), 16, 1024));
          image = nav::sim::MakePattern(p.Str(3), p.Color(4), size, static_cast<uint64_t>(p.Int(7)));
        } else {
          p.Fail("texture source must be 'photo' or 'pattern', got '" + p.Str(2) + "'");
        }
        texture_ids[p.Str(1)] = static_cast<int>(scene.textures.size());
        scene.textures.push_back(nav::sim::MakeTexture(p.Str(1), image, w_m, h_m));
      } else if (kw == "floor") {
        p.Expect(2, "TEXTURE|- B,G,R");
        scene.floor_texture = optional_texture(1);
        scene.floor_bgr = p.Color(2);
      } else if (kw == "ceiling") {
        p.Expect(3, "HEIGHT_M TEXTURE|- B,G,R");
        scene.ceiling_height_m = p.Num(1);
        scene.ceiling_texture = optional_texture(2);
        (scene.ceiling_height_m > 0 ? scene.ceiling_bgr : scene.sky_bgr) = p.Color(3);
      } else if (kw == "wall" || kw == "door") {
        p.Expect(6, "X1 Y1 X2 Y2 HEIGHT_M TEXTURE");
        nav::sim::Wall w;
        w.a = {p.Num(1), p.Num(2)};
        w.b = {p.Num(3), p.Num(4)};
        w.height_m = p.Num(5);
        w.texture = texture(6);
        scene.walls.push_back(w);
      } else if (kw == "poster") {
        p.Expect(7, "X1 Y1 X2 Y2 BOTTOM_M TOP_M TEXTURE");
        nav::sim::Wall w;
        w.a = {p.Num(1), p.Num(2)};
        w.b = {p.Num(3), p.Num(4)};
        w.bottom_m = p.Num(5);
        w.height_m = p.Num(6);
        w.texture = texture(7);
        scene.walls.push_back(w);
      } else if (kw == "box") {
        p.Expect(7, "CX CY SIZE_X SIZE_Y YAW_DEG HEIGHT_M TEXTURE");
        scene.AddBox({p.Num(1), p.Num(2)}, p.Num(3), p.Num(4), p.Num(5) * M_PI / 180, p.Num(6), texture(7));
      } else if (kw == "cylinder") {
        p.Expect(5, "CX CY RADIUS_M HEIGHT_M TEXTURE");
        nav::sim::Cylinder c;
        c.center = {p.Num(1), p.Num(2)};
        c.radius_m = p.Num(3);
        c.height_m = p.Num(4);
        c.texture = texture(5);
        scene.cylinders.push_back(c);
      } else if (kw == "grid") {
        p.Expect(5, "ORIGIN_X ORIGIN_Y SPACING_M NX NY");
        scene.grid = {p.Num(1), p.Num(2), p.Num(3), p.Int(4), p.Int(5)};
        if (scene.grid.spacing_m <= 0 || scene.grid.nx < 1 || scene.grid.ny < 1) p.Fail("grid needs spacing > 0 and NX, NY >= 1");
      } else if (kw == "start") {
        p.Expect(3, "X Y THETA_DEG");
        scene.start_pose = {p.Num(1), p.Num(2), p.Num(3) * M_PI / 180};
      } else if (kw == "route") {
        if (p.size() < 2) p.Fail("route needs at least one X,Y waypoint");
        scene.route.clear();
        for (size_t i = 1; i < p.size(); ++i) scene.route.push_back(p.Point(i));
      } else if (kw == "people") {
        p.Expect(9, "COUNT RADIUS_M HEIGHT_M SPEED_MPS XMIN YMIN XMAX YMAX TEXTURE[,TEXTURE...]");
        auto& pp = scene.people;
        pp.count = p.Int(1);
        pp.radius_m = p.Num(2);
        pp.height_m = p.Num(3);
        pp.speed_mps = p.Num(4);
        pp.area_min = {p.Num(5), p.Num(6)};
        pp.area_max = {p.Num(7), p.Num(8)};
        std::stringstream ss9(p.Str(9));
        pp.textures.clear();
        for (std::string t; std::getline(ss9, t, ',');) {
          const auto it = texture_ids.find(t);
          if (it == texture_ids.end()) p.Fail("texture '" + t + "' is not defined above");
          pp.textures.push_back(it->second);
        }
      } else {
        p.Fail("unknown keyword '" + kw + "'");
      }
    } catch (const std::invalid_argument& e) {
      p.Fail(e.what());
    }
  }
  try {
    scene.Validate();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  if (scene.walls.empty() && scene.cylinders.empty()) throw std::runtime_error(path + ": the scene has no surfaces");
  return scene;
}

}  // namespace snapnav::processes
