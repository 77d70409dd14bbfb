#include "test_lab.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>

#include "scene_file.hpp"
#include "snapnav/glue/image_msg.hpp"
#include "snapnav/nav/sim/omni_renderer.hpp"
#include "snapnav/nav/sim/scene.hpp"

namespace snapnav::processes::test {

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string Edit(const std::string& text, const std::string& section, const std::string& key, const char* value) {
  std::istringstream in(text);
  std::ostringstream out;
  std::string line, current;
  bool found = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '[') current = line.substr(1, line.find(']') - 1);
    const auto eq = line.find('=');
    if (current == section && !line.empty() && line[0] != '#' && line[0] != ';' && eq != std::string::npos &&
        line.substr(0, line.find_first_of(" \t=")) == key) {
      found = true;
      if (value) out << key << " = " << value << "\n";
      continue;
    }
    out << line << "\n";
  }
  EXPECT_TRUE(found) << "[" << section << "] " << key << " not in the shipped config";
  return out.str();
}

std::string ConfigText(std::initializer_list<Override> overrides) {
  std::string text = ReadText(kShippedConfig);
  for (const auto& o : overrides) text = Edit(text, o.section, o.key, o.value);
  return text;
}

PlaceCellsConfig Config(const std::string& prefix, std::initializer_list<Override> overrides,
                        const std::string& origin) {
  return PlaceCellsConfig::FromIni(glue::IniFile::Parse(ConfigText(overrides), origin), prefix);
}

struct Indoor13::Impl {
  nav::sim::Scene scene;
  nav::sim::OmniCameraOptions camera;
  std::optional<nav::sim::OmniRenderer> renderer;
};

Indoor13::Indoor13() : impl_(new Impl) {
  impl_->scene = LoadSceneFile(SceneFilePath("indoor13"));
  const auto ini = glue::IniFile::Load(kShippedConfig);
  impl_->camera.panorama = glue::ReadPanoramaConfig(ini);
  impl_->camera.mirror = glue::ReadMirrorConfig(ini);
  impl_->renderer.emplace(impl_->scene, impl_->camera);
}

Indoor13& Indoor13::Get() {
  static Indoor13* lab = new Indoor13;  // lives until the process ends
  return *lab;
}

const nav::PanoramaModel& Indoor13::panorama() const { return impl_->camera.panorama; }

cv::Mat Indoor13::Panorama(const nav::Pose2& robot) {
  cv::Mat img;
  impl_->renderer->RenderPanorama(robot, {}, &img);
  return img;
}

omni_frame_t Indoor13::PanoramaFrame(const nav::Pose2& robot, int64_t utime) {
  omni_frame_t f = glue::ImageToFrame(Panorama(robot), omni_frame_t::RGB8);
  f.utime = utime;
  f.sensor_name = "test";
  f.kind = omni_frame_t::PANORAMA;
  glue::SetPanorama(impl_->camera.panorama, &f);
  return f;
}

omni_frame_t Indoor13::RawFrame(const nav::Pose2& robot, int64_t utime) {
  cv::Mat img;
  impl_->renderer->RenderOmni(robot, {}, &img);
  omni_frame_t f = glue::ImageToFrame(img, omni_frame_t::RGB8);
  f.utime = utime;
  f.sensor_name = "test";
  f.kind = omni_frame_t::RAW_OMNI;
  glue::SetMirror(impl_->camera.mirror, &f);
  return f;
}

}  // namespace snapnav::processes::test
