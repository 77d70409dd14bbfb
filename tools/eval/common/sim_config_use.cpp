#include "sim_config_use.hpp"

#include <stdexcept>

#include "snapnav/glue/flags.hpp"

namespace snapnav::eval {

namespace {

SimConfigUse CameraUse(const std::string& tool) {
  SimConfigUse u;
  u.tool = tool;
  u.sections = {"mirror", "panorama", "effects"};
  u.keys = {{"sim", "seed"},          {"camera", "preset"},   {"camera", "width_px"},
            {"camera", "height_px"},  {"camera", "height_m"}, {"camera", "offset_x_m"}};
  return u;
}

}  // namespace

SimConfigUse HomingSimConfigUse() { return CameraUse("eval homing"); }

SimConfigUse LocalizationSimConfigUse() {
  SimConfigUse u = CameraUse("eval localization");
  for (const char* k : {"max_linear_mps", "max_angular_radps", "heading_drift_deg_per_m", "linear_noise_frac",
                        "angular_noise_radps", "odometry_linear_noise_frac", "odometry_angular_noise_frac", "radius_m"}) {
    u.keys.insert({"robot", k});
  }
  return u;
}

void RefuseUnusedSimKeys(const glue::IniFile& file, const glue::IniFile& shipped, const SimConfigUse& use) {
  for (const auto& section : file.SectionsInFileOrder()) {
    for (const auto& key : file.Keys(section)) {
      if (use.Uses(section, key)) continue;
      const std::string value = file.GetString(section, key);
      if (shipped.Has(section, key) && shipped.GetString(section, key) == value) continue;
      std::string why = use.tool + " does not use it: it renders its views itself";
      if (section == "sim" && key == "scene") why += " (give the scene with --scene)";
      else if (section == "sim") why += " (no bus, no clock: the grid and test views are rendered at their poses)";
      else if (section == "camera") why += " (it renders raw images without the bus' rate or encoding)";
      else if (section == "laser") why += " (it uses no laser)";
      else if (section == "channels") why += " (it uses no bus)";
      else if (section == "robot") why += " (it drives no robot with this key)";
      throw glue::ConfigError(file.origin() + ":" + std::to_string(file.KeyLine(section, key)) + ": [" + section + "] " +
                              key + " = " + value + ": " + why + "; remove it or set the shipped value" +
                              (shipped.Has(section, key) ? " (" + shipped.GetString(section, key) + ")" : ""));
    }
  }
}

processes::SimConfig LoadSimConfigFor(const std::string& path, const SimConfigUse& use) {
  const auto ini = glue::IniFile::Load(path);
  auto sim = processes::SimConfig::FromIni(ini, "");
  RefuseUnusedSimKeys(ini, glue::IniFile::Load(SNAPNAV_CONFIG_DIR "/sim.ini"), use);
  return sim;
}

void ApplyCameraFlag(const std::string& preset, uint64_t seed, nav::sim::OmniCameraOptions* camera) {
  if (preset.empty()) return;
  try {
    camera->optics = nav::sim::CameraOpticsPreset(preset);
  } catch (const std::invalid_argument& e) {
    throw glue::FlagError(std::string("--camera: ") + e.what());
  }
  camera->optics.seed = seed ^ 0x0b71c5ULL;
}

}  // namespace snapnav::eval
