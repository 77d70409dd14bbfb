// eval-homing's app (eval_homing_app.hpp): the flags, the grid views, the AAE and return runs,
// the figures, the tables and summary.json.
#include "eval_homing_app.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "calibrated_mask.hpp"
#include "grid_folder.hpp"
#include "json_values.hpp"
#include "landmark_compare.hpp"
#include "people_diagnosis.hpp"
#include "progress.hpp"
#include "report_text.hpp"
#include "results.hpp"
#include "scene_file.hpp"
#include "sim_config_use.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/landmarks.hpp"
#include "snapnav/nav/homing/image_mask.hpp"
#include "snapnav/plot/plot.hpp"

namespace snapnav::eval {

namespace {

namespace fs = std::filesystem;

nav::HogHomingConfig Apply(nav::HogHomingConfig c, const HogOverrides& o) {
  if (o.cell > 0) c.hog.cell_size_px = o.cell;
  if (o.bins > 0) c.hog.bins = o.bins;
  if (!o.range.empty()) {
    const auto r = nav::ParseOrientationRange(o.range);
    if (!r) throw glue::FlagError("--range must be all, vertical, horizontal or narrow_vertical, not '" + o.range + "'");
    c.hog.range = *r;
  }
  if (!o.weight.empty()) {
    if (o.weight == "magnitude") c.alv.weight = nav::CellWeight::kMagnitude;
    else if (o.weight == "log") c.alv.weight = nav::CellWeight::kLog;
    else throw glue::FlagError("--weight must be magnitude or log, not '" + o.weight + "'");
  }
  if (!o.difference.empty()) {
    if (o.difference == "current_minus_home") c.alv.difference = nav::AlvDifference::kCurrentMinusHome;
    else if (o.difference == "home_minus_current") c.alv.difference = nav::AlvDifference::kHomeMinusCurrent;
    else throw glue::FlagError("--difference must be current_minus_home or home_minus_current");
  }
  if (!o.band.empty()) {
    const auto parts = glue::SplitList(o.band);
    if (parts.size() != 2) throw glue::FlagError("--band must be TOP,HEIGHT in pixel rows");
    c.hog.band_top_px = std::stoi(parts[0]);
    c.hog.band_height_px = std::stoi(parts[1]);
  }
  if (o.threshold >= 0) c.alv.threshold_frac = o.threshold;
  if (o.no_compass) c.use_compass = false;
  if (o.equalize) c.equalize_histogram = true;
  if (o.warp) c.warp_compensation = true;
  // Whole cells of the band only: a band shorter than a cell is widened to one cell.
  if (c.hog.band_height_px > 0 && c.hog.band_height_px < c.hog.cell_size_px) c.hog.band_height_px = c.hog.cell_size_px;
  c.Validate();
  return c;
}

std::string WeightName(nav::CellWeight w) { return w == nav::CellWeight::kLog ? "log" : "magnitude"; }
std::string DifferenceName(nav::AlvDifference d) {
  return d == nav::AlvDifference::kCurrentMinusHome ? "current_minus_home" : "home_minus_current";
}

std::string Describe(const nav::HogHomingConfig& c) {
  std::ostringstream s;
  s << "band " << c.hog.band_top_px << "+" << c.hog.band_height_px << " px, cell " << c.hog.cell_size_px << " px, "
    << c.hog.bins << " bins, range " << nav::OrientationRangeName(c.hog.range) << ", threshold "
    << c.alv.threshold_frac << ", weight " << WeightName(c.alv.weight) << ", " << DifferenceName(c.alv.difference)
    << ", compass " << (c.use_compass ? "hog" : "off") << (c.equalize_histogram ? ", equalised" : "")
    << (c.warp_compensation ? ", warp-compensated" : "");
  return s.str();
}

// The thesis' configuration (3.1.3-3.1.4): all bins, every orientation, 40 px cells, 8 bins,
// magnitude weights, home - current.
nav::HogHomingConfig ThesisConfig(nav::HogHomingConfig c) {
  c.hog.cell_size_px = 40;
  c.hog.bins = 8;
  c.hog.range = nav::OrientationRange::kAll;
  c.alv.threshold_frac = 0;
  c.alv.weight = nav::CellWeight::kMagnitude;
  c.alv.difference = nav::AlvDifference::kHomeMinusCurrent;
  if (c.hog.band_height_px > 0 && c.hog.band_height_px < 40) c.hog.band_height_px = 40;
  return c;
}

double Aae(const eval::GridDatabase& db, const std::vector<cv::Mat>& panos, const nav::HogHomingConfig& c,
           const nav::PanoramaModel& pm, const cv::Mat& mask, eval::GridResult* out = nullptr) {
  eval::HogMethod m(c, pm);
  m.SetMask(mask);
  auto r = eval::EvaluatePanoramas(db, panos, m);
  if (out) *out = r;
  return r.aae_deg;
}

// The thesis' 3.1.4 protocol: the 5x5 positions of the grid around the home (fig. 3.6), the home
// at its centre. Throws a FlagError when the home is less than 2 positions from the grid's edge.
struct SubGrid {
  eval::GridDatabase db;
  std::vector<cv::Mat> panos;
};
SubGrid Thesis5x5(const eval::GridDatabase& db, const std::vector<cv::Mat>& panos) {
  const int hx = db.home_index % db.nx, hy = db.home_index / db.nx;
  if (hx < 2 || hy < 2 || hx + 2 >= db.nx || hy + 2 >= db.ny) {
    throw glue::FlagError("--protocols thesis-5x5 needs the home at least 2 grid positions from the grid's edge");
  }
  SubGrid s;
  s.db.nx = s.db.ny = 5;
  for (int iy = hy - 2; iy <= hy + 2; ++iy) {
    for (int ix = hx - 2; ix <= hx + 2; ++ix) {
      const int i = iy * db.nx + ix;
      if (i == db.home_index) s.db.home_index = static_cast<int>(s.db.poses.size());
      s.db.poses.push_back(db.poses[i]);
      s.db.sensor.push_back(db.sensor[i]);
      s.db.people.push_back(db.people[i]);
      s.panos.push_back(panos[i]);
    }
  }
  s.db.home = db.home;
  return s;
}

plot::Axes MakeAxes(const std::string& title, const std::string& x_label, const std::string& y_label) {
  plot::Axes axes;
  axes.title = title;
  axes.x_label = x_label;
  axes.y_label = y_label;
  return axes;
}

// The protocols side by side (issue 21): the shipped configuration and the thesis' at the
// thesis' 40-60 px cells and the shipped 20 px, over the whole grid and the thesis' 5x5.
struct ProtocolRow {
  std::string key, label;
  nav::HogHomingConfig config;
  double snapnav = 0, thesis5 = 0;
};
struct Protocols {
  std::vector<ProtocolRow> rows;  // rows[0]: the configuration under test, rows[3]: the thesis'
  SubGrid five;
  eval::GridResult five_result;   // rows[0] on the 5x5
};
Protocols CompareProtocols(const eval::GridDatabase& db, const std::vector<cv::Mat>& panos,
                           const nav::HogHomingConfig& config, const nav::PanoramaModel& pm, const cv::Mat& mask) {
  Protocols p;
  p.five = Thesis5x5(db, panos);
  auto cell = [&](nav::HogHomingConfig c, int px) {
    c.hog.cell_size_px = px;
    if (c.hog.band_height_px > 0 && c.hog.band_height_px < px) c.hog.band_height_px = px;
    if (c.hog.band_top_px + std::max(c.hog.band_height_px, px) > pm.height_px) c.hog.band_top_px = pm.height_px - px;
    return c;
  };
  const std::string shipped = std::to_string(config.hog.cell_size_px) + " px";
  nav::HogHomingConfig lambrinos = ThesisConfig(config);
  lambrinos.alv.difference = nav::AlvDifference::kCurrentMinusHome;
  p.rows = {{"configuration", "this configuration (" + shipped + " cells)", config},
            {"configuration_cell40", "this configuration at 40 px cells", cell(config, 40)},
            {"configuration_cell60", "this configuration at 60 px cells", cell(config, 60)},
            {"thesis_configuration", "thesis configuration (40 px, 8 bins, all, home - current)", ThesisConfig(config)},
            {"thesis_configuration_current_minus_home_cell20", "thesis configuration with current - home, 20 px cells",
             cell(lambrinos, 20)},
            {"thesis_configuration_current_minus_home", "thesis configuration with current - home, 40 px cells", lambrinos},
            {"thesis_configuration_current_minus_home_cell60", "thesis configuration with current - home, 60 px cells",
             cell(lambrinos, 60)}};
  for (size_t k = 0; k < p.rows.size(); ++k) {
    auto& r = p.rows[k];
    r.snapnav = Aae(db, panos, r.config, pm, mask);
    r.thesis5 = Aae(p.five.db, p.five.panos, r.config, pm, mask, k == 0 ? &p.five_result : nullptr);
  }
  std::cerr << "eval-homing: thesis 5x5 protocol (" << p.five_result.positions << " positions): AAE "
            << Fixed(p.rows[0].thesis5) << " deg, thesis configuration " << Fixed(p.rows[3].thesis5)
            << " deg (thesis 18.11 deg)\n";
  return p;
}

void WriteProtocols(std::ostream& report, const eval::GridDatabase& db, int positions, const Protocols& p) {
  report << "## Protocols (thesis 3.1.4 beside ours)\n\nsnapnav: every position of the " << db.nx << "x" << db.ny
         << " grid (" << positions << " positions); thesis-5x5: the 5x5 positions around the home (fig. 3.6, "
         << p.five_result.positions << " positions), the same images.\n\n"
         << "| configuration | snapnav AAE [deg] | thesis-5x5 AAE [deg] |\n|---|---|---|\n";
  for (const auto& r : p.rows) report << "| " << r.label << " | " << Fixed(r.snapnav) << " | " << Fixed(r.thesis5) << " |\n";
  report << "| thesis' own figure (3.1.4) | | 18.11 |\n\n";
}

// The keys both grids' summary.json share: the home, the configuration and its errors.
void WriteGridResultJson(results::Json& json, const eval::GridDatabase& db, const nav::HogHomingConfig& config,
                         const eval::GridResult& result) {
  json["home_x_m"] = R4(db.home.x_m);
  json["home_y_m"] = R4(db.home.y_m);
  json["configuration"] = Describe(config);
  json["grid_positions"] = R4(result.positions);
  json["average_angular_error_deg"] = R4(result.aae_deg);
  json["median_angular_error_deg"] = R4(result.median_deg);
  json["max_angular_error_deg"] = R4(result.max_deg);
  json["positions_without_answer"] = R4(result.failures);
  json["compass_mean_error_deg"] = R4(result.compass_mean_deg);
}

void WriteProtocolsJson(results::Json& json, const Protocols& p) {
  json["protocols"] = {"snapnav", "thesis-5x5"};
  json["thesis_5x5_positions"] = R4(p.five_result.positions);
  for (const auto& r : p.rows) {
    json["snapnav_" + r.key + "_aae_deg"] = R4(r.snapnav);
    json["thesis_5x5_" + r.key + "_aae_deg"] = R4(r.thesis5);
  }
}

// eval homing --grid DIR: HOG homing over a lab's own image grid (grid_folder.hpp): AAE of the
// configuration and the thesis', the protocols with --protocols thesis-5x5, the vector map. No
// return runs and no rotation test (they render views the folder does not have).
int RunGridFolder(const std::string& dir, const nav::HogHomingConfig& config, const nav::PanoramaModel& pm,
                  const std::string& home_text, bool thesis_5x5, const fs::path& out) {
  const auto folder = eval::LoadGridFolder(dir);
  const std::string csv = (fs::path(dir) / "positions.csv").string();
  if (!folder.complete()) {
    throw std::runtime_error(csv + ": " + std::to_string(folder.images.size()) + " images for a " +
                             std::to_string(folder.nx) + "x" + std::to_string(folder.ny) +
                             " grid (the largest ix and iy): eval homing needs an image at every (ix, iy)");
  }
  cv::Mat mask;
  const auto images = eval::GridFolderPanoramas(folder, pm, &mask);
  eval::GridDatabase db;
  db.nx = folder.nx;
  db.ny = folder.ny;
  db.poses.resize(folder.images.size());
  db.sensor.resize(folder.images.size());
  db.people.resize(folder.images.size());
  db.more_sensor.resize(folder.images.size());
  db.more_people.resize(folder.images.size());
  std::vector<cv::Mat> panos(folder.images.size());
  for (size_t k = 0; k < folder.images.size(); ++k) {
    const auto& im = folder.images[k];
    const int i = im.iy * db.nx + im.ix;
    db.poses[i] = im.pose;
    db.sensor[i] = images[k];
    panos[i] = images[k];
  }
  db.home_index = (db.ny / 2) * db.nx + db.nx / 2;
  if (!home_text.empty()) {
    const auto parts = glue::SplitList(home_text);
    if (parts.size() != 2) throw glue::FlagError("--home must be X,Y");
    const Eigen::Vector2d home(std::stod(parts[0]), std::stod(parts[1]));
    double best = 1e18;
    for (size_t i = 0; i < db.poses.size(); ++i) {
      const double d = (Eigen::Vector2d(db.poses[i].x_m, db.poses[i].y_m) - home).norm();
      if (d < best) {
        best = d;
        db.home_index = static_cast<int>(i);
      }
    }
    if (best > 0.01) throw glue::FlagError("--home " + home_text + " is " + Fixed(best, 3) + " m from the nearest image of " + csv);
  }
  db.home = db.poses[db.home_index];
  std::cerr << "eval-homing: grid folder " << dir << ": " << folder.images.size() << " " << (folder.raw ? "raw" : "panorama")
            << " images of " << folder.size.width << "x" << folder.size.height << ", " << db.nx << "x" << db.ny
            << " grid, home (" << db.home.x_m << ", " << db.home.y_m << ")" << (mask.empty() ? "" : ", masked") << "\n";
  eval::GridResult result, thesis_result;
  Aae(db, panos, config, pm, mask, &result);
  const double thesis_aae = Aae(db, panos, ThesisConfig(config), pm, mask, &thesis_result);
  std::optional<Protocols> protocol;
  if (thesis_5x5) protocol = CompareProtocols(db, panos, config, pm, mask);
  fs::create_directories(out);
  std::vector<std::string> figures;
  auto save = [&](const cv::Mat& img, const std::string& name) {
    plot::SavePng(img, (out / name).string());
    figures.push_back(name);
  };
  const std::string name = fs::path(dir).filename().string().empty() ? dir : fs::path(dir).filename().string();
  save(eval::DrawVectorMap(db, result, name + " hog: AAE " + Fixed(result.aae_deg, 1) + " deg"), "vector_map.png");
  save(eval::DrawVectorMap(db, thesis_result, name + " thesis configuration: AAE " + Fixed(thesis_aae, 1) + " deg"),
       "vector_map_thesis_config.png");
  if (protocol) {
    save(eval::DrawVectorMap(protocol->five.db, protocol->five_result,
                             name + " thesis 5x5 protocol: AAE " + Fixed(protocol->five_result.aae_deg, 1) + " deg"),
         "vector_map_thesis_5x5.png");
  }
  std::ostringstream report;
  report << "# Homing evaluation: grid folder " << dir << "\n\n- configuration: " << Describe(config) << "\n- images: "
         << folder.images.size() << (folder.raw ? " raw omni images, unwrapped with its camera.ini [mirror]" : " panoramas")
         << (mask.empty() ? "" : ", masked") << "\n- home (" << db.home.x_m << ", " << db.home.y_m << ")\n\n"
         << "| | AAE [deg] | median | max | positions without an answer |\n|---|---|---|---|---|\n"
         << "| this configuration | " << Fixed(result.aae_deg) << " | " << Fixed(result.median_deg) << " | "
         << Fixed(result.max_deg) << " | " << result.failures << " |\n"
         << "| thesis configuration (40 px, 8 bins, all, home - current) | " << Fixed(thesis_aae) << " | | | |\n\n"
         << "Visual compass over the grid: mean error " << Fixed(result.compass_mean_deg) << " deg.\n\n";
  if (protocol) WriteProtocols(report, db, result.positions, *protocol);
  std::ofstream(out / "report.md") << report.str();
  results::Json json;
  json["grid"] = dir;
  json["input"] = folder.raw ? "raw" : "panorama";
  json["grid_nx"] = R4(db.nx);
  json["grid_ny"] = R4(db.ny);
  WriteGridResultJson(json, db, config, result);
  json["thesis_configuration_aae_deg"] = R4(thesis_aae);
  json["thesis_reported_aae_deg"] = 18.11;
  if (protocol) WriteProtocolsJson(json, *protocol);
  json["figures"] = figures;
  results::WriteJsonFile((out / "summary.json").string(), json);
  std::cerr << "eval-homing: wrote " << (out / "summary.json").string() << ", report.md and " << figures.size() << " figures\n";
  std::cout << "average_angular_error_deg " << Fixed(result.aae_deg) << "\n";
  if (protocol) std::cout << "thesis_5x5_average_angular_error_deg " << Fixed(protocol->rows[0].thesis5) << "\n";
  return 0;
}

}  // namespace

bool EvalHomingApp::Initialize(int argc, char** argv) {
  glue::Flags flags("eval-homing",
                    "Evaluates snapshot homing over a scene's grid database (thesis 3.1.4): angular error at every\n"
                    "grid position, AAE, closed-loop return ratio, vector map; figures (AAE by cell size and\n"
                    "descriptor range, by noise, entropy by cell size) and, with --sweep, a parameter table.\n"
                    "Writes OUT/summary.json, PNGs, and OUT/report.md.");
  flags.AddString("scene", &scene_name, "scene name (config/scenes) or file");
  flags.AddString("grid", &grid_dir,
                  "HOG over a lab's own image grid instead of a scene: a folder as gridgen writes (positions.csv; raw "
                  "images with a camera.ini [mirror], or panoramas of --config's [panorama]); AAE, vector map, --protocols");
  flags.AddString("method", &method, "homing method: hog | vline | sift | surf (feature landmarks, thesis 4.1-4.3)");
  flags.AddString("alv", &alv, "landmark methods: unit | weighted | scale ALV");
  flags.AddInt("landmarks", &top_n, "landmark methods: use the N best matches (thesis 3, 5, 20); 0: all");
  flags.AddString("landmarks-config", &landmarks_config_path, "extractor config ([vline], [sift], [surf])");
  flags.AddBool("compare", &compare,
                "compare HOG, vertical lines, SIFT and SURF x ALV variant x landmark count on --scenes: compare.md, "
                "compare.csv, summary.json, vector maps");
  flags.AddBool("people-diagnosis", &people_diagnosis,
                "on --scene (one with people): where the people are in each grid image, the AAE with people-free "
                "home or current views, matched landmarks on people (people.md, people_per_image.csv, summary.json)");
  flags.AddString("scenes", &compare_scenes, "--compare: scenes");
  flags.AddInt("home-frames", &home_frames,
               "frames fused into the home view (the robot stands, people walk); default: [view_fusion] home_frames");
  flags.AddDouble("home-interval-s", &home_interval_s, "time between home frames [s]; default: [view_fusion]");
  flags.AddInt("current-frames", &current_frames,
               "frames fused into each current view (the robot pauses); default: [view_fusion] current_frames");
  flags.AddDouble("current-interval-s", &current_interval_s, "time between current frames [s]; default: [view_fusion]");
  flags.AddString("fusion", &fusion, "persistent | median: how landmark methods fuse frames (default: [view_fusion] fusion)");
  flags.AddDouble("min-fraction", &min_fraction, "override: [view_fusion] min_fraction of the persistent fusion");
  flags.AddInt("fusion-home-frames", &fused.home_frames,
               "--compare (scenes with people) and --people-diagnosis: home frames of the fused rows; 1: none");
  flags.AddDouble("fusion-home-interval-s", &fused.home_interval_s, "... the time between them [s]");
  flags.AddInt("fusion-current-frames", &fused.current_frames, "... current frames of the fused rows; 1: none");
  flags.AddDouble("fusion-current-interval-s", &fused.current_interval_s, "... the time between them [s]");
  flags.AddBool("return-best-only", &return_best_only, "--compare: return runs only for each method's best rows");
  flags.AddInt("return-stride", &return_stride, "return runs from every n-th start only (a stated sample)");
  flags.AddString("counts", &counts, "--compare: landmark counts (N or all)");
  flags.AddString("home", &home_text, "home position X,Y [m] (a grid position; default: the grid centre)");
  flags.AddString("config", &config_path, "homing config (its [hog], [compass], [alv], [preprocess])");
  flags.AddString("sim-config", &sim_config_path,
                  "simulator config: its camera, [mirror], [panorama], [effects] and seed apply; a changed key it does not "
                  "use is refused");
  flags.AddString("input", &input, "raw (render catadioptric images and unwrap) or panorama (render panoramas)");
  flags.AddString("camera", &camera, "camera preset, overrides --sim-config's [camera] preset: clean | realistic");
  flags.AddString("mask", &mask_source,
                  "self-occlusion mask of the raw images: calibrated (calibrate-mirror's, from 60 frames of the camera) | "
                  "none | truth (the renderer's robot parts) | FILE (black = masked); default: calibrated with the "
                  "realistic camera, none with the clean one");
  flags.AddString("protocols", &protocols,
                  "HOG: snapnav (the scene's whole grid; always run) and/or thesis-5x5 (thesis 3.1.4: the 5x5 positions "
                  "around the home): AAE of the shipped configuration and of the thesis' at 20, 40 and 60 px cells under each");
  flags.AddBool("random-headings", &random_headings, "grid images at random headings (exercises the compass)");
  flags.AddInt("seed", &seed, "seed for headings, people and noise");
  flags.AddInt("cell", &overrides.cell, "override: cell size [px]");
  flags.AddInt("bins", &overrides.bins, "override: orientation bins");
  flags.AddString("range", &overrides.range, "override: all|vertical|horizontal|narrow_vertical");
  flags.AddDouble("threshold", &overrides.threshold, "override: dominant-bin threshold fraction");
  flags.AddString("weight", &overrides.weight, "override: magnitude|log");
  flags.AddString("difference", &overrides.difference, "override: current_minus_home|home_minus_current");
  flags.AddString("band", &overrides.band, "override: TOP,HEIGHT band rows");
  flags.AddBool("no-compass", &overrides.no_compass, "override: assume the views share a heading");
  flags.AddBool("equalize", &overrides.equalize, "override: histogram equalisation (3.1.5)");
  flags.AddBool("warp", &overrides.warp, "override: warping compensation (3.1.6)");
  flags.AddDouble("step-m", &ret.step_m, "return run: step length [m]");
  flags.AddBool("no-return", &no_return, "skip the closed-loop return runs");
  flags.AddBool("quick", &quick, "AAE, vector map and return ratio only (no figures)");
  flags.AddBool("sweep", &sweep, "also write sweep.md/sweep.csv: AAE for cell x bins x threshold x range x weight");
  flags.AddString("entropy-scenes", &entropy_scenes, "scenes of the entropy figure");
  flags.AddString("out", &out_dir, "output folder (required)");
  if (!flags.Parse(argc, argv)) return false;
  if (out_dir.empty()) throw glue::FlagError("--out DIR is required");
  if (!nav::ParseLandmarkMethod(method)) {
    throw glue::FlagError("--method '" + method + "' is not available (hog, vline, sift, surf)");
  }
  if (!nav::ParseAlvVariant(alv)) throw glue::FlagError("--alv must be unit, weighted or scale, not '" + alv + "'");
  if (top_n < 0) throw glue::FlagError("--landmarks must be >= 0 (0: all)");
  if (input != "raw" && input != "panorama") throw glue::FlagError("--input must be raw or panorama");
  for (const auto& p : glue::SplitList(protocols)) {
    if (p == "thesis-5x5") thesis_5x5 = true;
    else if (p != "snapnav") throw glue::FlagError("--protocols takes snapnav and thesis-5x5, not '" + p + "'");
  }
  if (thesis_5x5 && (compare || people_diagnosis || method != "hog")) {
    throw glue::FlagError("--protocols thesis-5x5 is for HOG's single evaluation (--method hog)");
  }
  return true;
}

int EvalHomingApp::Run() {
  fs::create_directories(out_dir);
  const fs::path out(out_dir);

  // All of the file applies ([effects] on every rendered image) or it is refused.
  auto sim = LoadSimConfigFor(sim_config_path, HomingSimConfigUse());
  if (!camera.empty()) {
    ApplyCameraFlag(camera, static_cast<uint64_t>(seed), &sim.camera);
    sim.camera_preset = camera;
  }
  if (mask_source.empty()) {  // the default: as a lab calibrates its camera (modes without masks: none)
    mask_source = people_diagnosis || !grid_dir.empty() || input != "raw" ? "none" : eval::MaskOrDefault("", sim.camera);
  }
  if (mask_source != "none" && input != "raw") throw glue::FlagError("--mask needs --input raw (the mask is of raw images)");
  if (sim.camera.optics.enabled && input != "raw") {
    throw glue::FlagError(
        "--input panorama renders panoramas directly, without the realistic camera's optics (they act on the raw "
        "image): use --input raw, or --camera clean");
  }
  const auto homing_ini = glue::IniFile::Load(config_path);
  const auto homing = processes::HomingConfig::FromIni(homing_ini, "");
  const nav::PanoramaModel& pm = sim.camera.panorama;
  if (homing.panorama.width_px != pm.width_px || homing.panorama.height_px != pm.height_px) {
    throw glue::ConfigError(config_path + ": [panorama] is " + std::to_string(homing.panorama.width_px) + "x" +
                            std::to_string(homing.panorama.height_px) + ", the camera of " + sim_config_path + " makes " +
                            std::to_string(pm.width_px) + "x" + std::to_string(pm.height_px));
  }
  const nav::HogHomingConfig config = Apply(homing.homing, overrides);
  if (!grid_dir.empty()) {
    if (compare || people_diagnosis || method != "hog" || sweep || mask_source != "none" || random_headings) {
      throw glue::FlagError("--grid is for HOG's evaluation (--method hog; no --compare, --people-diagnosis, --sweep, "
                            "--mask or --random-headings: the folder's camera.ini [mirror] mask and headings apply)");
    }
    return RunGridFolder(grid_dir, config, homing.panorama, home_text, thesis_5x5, out);
  }
  if (compare || people_diagnosis || method != "hog") return RunLandmarkMethods(sim, homing, config);
  return RunScene(sim, config, out);
}

int EvalHomingApp::RunLandmarkMethods(const processes::SimConfig& sim, const processes::HomingConfig& homing,
                                      const nav::HogHomingConfig& config) {
  eval::LandmarkEvalSetup setup;
  setup.camera = sim.camera;
  setup.effects = sim.effects;
  setup.hog = config;
  setup.extractor = glue::ReadLandmarkExtractor(glue::IniFile::Load(landmarks_config_path));
  setup.keypoint_homing = homing.keypoint_homing;
  setup.vline_homing = homing.vline_homing;
  setup.input = input == "raw" ? CameraPipeline::Input::kRaw : CameraPipeline::Input::kPanorama;
  setup.ret = ret;
  setup.ret.start_stride = return_stride;
  setup.seed = static_cast<uint64_t>(seed);
  setup.mask = mask_source;
  if (mask_source != "none" && people_diagnosis) {
    throw glue::FlagError("--mask is not for --people-diagnosis (it looks at the people, the robot's parts aside)");
  }
  setup.fusion.mode = homing.fusion.mode;
  setup.fusion.persistence = homing.fusion.persistence;
  setup.frames.home_frames = home_frames >= 0 ? home_frames : homing.fusion.home_frames;
  setup.frames.current_frames = current_frames >= 0 ? current_frames : homing.fusion.current_frames;
  setup.frames.home_interval_s = home_interval_s >= 0 ? home_interval_s : homing.fusion.home_interval_s;
  setup.frames.current_interval_s = current_interval_s >= 0 ? current_interval_s : homing.fusion.current_interval_s;
  if (min_fraction >= 0) setup.fusion.persistence.min_fraction = min_fraction;
  if (!fusion.empty()) {
    const auto f = nav::ParseViewFusion(fusion);
    if (!f) throw glue::FlagError("--fusion must be persistent or median, not '" + fusion + "'");
    setup.fusion.mode = *f;
  }
  try {
    setup.frames.Validate();
    fused.Validate();
  } catch (const std::invalid_argument& e) {
    throw glue::FlagError(std::string("--home-frames, --current-frames, --fusion-*: ") + e.what());
  }
  if (return_stride < 1) throw glue::FlagError("--return-stride must be >= 1");
  if (random_headings && (compare || people_diagnosis)) {
    throw glue::FlagError("--random-headings is for a single method's evaluation (not --compare or --people-diagnosis)");
  }
  setup.random_headings = random_headings;
  if (people_diagnosis) return eval::RunPeopleDiagnosis(setup, scene_name, fused, out_dir);
  if (compare) {
    eval::CompareOptions c;
    c.scenes = glue::SplitList(compare_scenes);
    c.top_n.clear();
    for (const auto& n : glue::SplitList(counts)) c.top_n.push_back(n == "all" ? 0 : std::stoi(n));
    if (c.scenes.empty() || c.top_n.empty()) throw glue::FlagError("--scenes and --counts must not be empty");
    c.returns = !no_return;
    c.return_best_only = return_best_only;
    c.fused = fused;
    return eval::RunCompare(setup, c, out_dir);
  }
  return eval::RunLandmarkEval(setup, scene_name, *nav::ParseLandmarkMethod(method), *nav::ParseAlvVariant(alv), top_n,
                               no_return, out_dir);
}

int EvalHomingApp::RunScene(const processes::SimConfig& sim, const nav::HogHomingConfig& config, const fs::path& out) {
  const nav::PanoramaModel& pm = sim.camera.panorama;
  const auto scene = processes::LoadSceneFile(processes::SceneFilePath(scene_name));

  eval::GridOptions grid;
  if (!home_text.empty()) {
    const auto parts = glue::SplitList(home_text);
    if (parts.size() != 2) throw glue::FlagError("--home must be X,Y");
    grid.home = Eigen::Vector2d(std::stod(parts[0]), std::stod(parts[1]));
  }
  grid.random_headings = random_headings;
  grid.seed = static_cast<uint64_t>(seed);
  grid.input = input == "raw" ? CameraPipeline::Input::kRaw : CameraPipeline::Input::kPanorama;
  CameraPipeline pipeline;
  pipeline.input = grid.input;
  pipeline.effects = sim.effects;

  std::cerr << "eval-homing: scene " << scene.name << ", " << scene.grid.nx << "x" << scene.grid.ny << " grid, input "
            << input << ", " << Describe(config) << "\n";
  eval::ViewRenderer renderer(scene, sim.camera, static_cast<uint64_t>(seed));
  const cv::Mat mask = eval::UseMask(mask_source, renderer, cv::Size(sim.camera.omni_width_px, sim.camera.omni_height_px),
                                     static_cast<uint64_t>(seed));
  std::cerr << "eval-homing: camera " << sim.camera_preset << ", mask " << mask_source << " ("
            << Fixed(100 * nav::MaskedFraction(mask), 1) << " % of the panorama)\n";
  const auto db = eval::RenderGrid(scene, renderer, grid, [](int d, int t) { Progress("eval-homing", "rendering grid", d, t); });
  std::vector<cv::Mat> panos;
  for (const auto& s : db.sensor) panos.push_back(renderer.ToPanorama(s, pipeline));

  eval::GridResult result;
  Aae(db, panos, config, pm, mask, &result);
  const double fps = result.seconds_in_method > 0 ? result.method_calls / result.seconds_in_method : 0;
  std::cerr << "eval-homing: AAE " << Fixed(result.aae_deg) << " deg (median " << Fixed(result.median_deg) << ", max "
            << Fixed(result.max_deg) << ", " << result.failures << " without an answer), compass error "
            << Fixed(result.compass_mean_deg) << " deg, " << Fixed(fps, 0) << " vectors/s\n";
  // Visual compass on pure rotations: views at the home position at 36 headings.
  std::vector<double> rotation_errors;
  {
    nav::HogHomingConfig with_compass = config;
    with_compass.use_compass = true;
    nav::HogHomer compass(with_compass, pm);
    compass.SetMask(mask);
    compass.SetHome(panos[db.home_index]);
    for (int k = 0; k < 36; ++k) {
      const double heading = nav::WrapAngle(0.1 + k * 2 * M_PI / 36 + 0.0123 * k);
      nav::Pose2 pose = db.home;
      pose.theta_rad = heading;
      const auto e = compass.Home(renderer.ToPanorama(renderer.Sensor(pose, grid.input, {}), pipeline));
      rotation_errors.push_back(e ? std::abs(nav::WrapAngle(e->compass_rotation_rad - heading)) * 180 / M_PI : 180.0);
    }
    std::sort(rotation_errors.begin(), rotation_errors.end());
  }
  const double rotation_median = rotation_errors[rotation_errors.size() / 2];
  std::cerr << "eval-homing: visual compass on pure rotations at home: median error " << Fixed(rotation_median)
            << " deg, max " << Fixed(rotation_errors.back()) << " deg\n";
  eval::GridResult thesis_result;
  const double thesis_aae = Aae(db, panos, ThesisConfig(config), pm, mask, &thesis_result);
  nav::HogHomingConfig thesis_lambrinos = ThesisConfig(config);
  thesis_lambrinos.alv.difference = nav::AlvDifference::kCurrentMinusHome;
  const double thesis_lambrinos_aae = Aae(db, panos, thesis_lambrinos, pm, mask);
  std::cerr << "eval-homing: thesis configuration AAE " << Fixed(thesis_aae) << " deg (with current - home: "
            << Fixed(thesis_lambrinos_aae) << " deg)\n";

  // The protocols side by side (issue 21).
  std::optional<Protocols> protocol;
  if (thesis_5x5) protocol = CompareProtocols(db, panos, config, pm, mask);

  eval::ReturnResult returns;
  if (!no_return) {
    eval::HogMethod m(config, pm);
    m.SetMask(mask);
    returns = eval::EvaluateReturn(db, m, renderer, pipeline, ret, [](int d, int t) { Progress("eval-homing", "return runs", d, t); });
    std::cerr << "eval-homing: return ratio " << Fixed(returns.ratio, 3) << " (" << returns.successes << "/"
              << returns.starts << "), mean path / straight line " << Fixed(returns.mean_path_ratio) << "\n";
  }
  std::vector<std::string> figures;
  auto save = [&](const cv::Mat& img, const std::string& name) {
    plot::SavePng(img, (out / name).string());
    figures.push_back(name);
  };
  save(eval::DrawVectorMap(db, result,
                           scene.name + " hog: AAE " + Fixed(result.aae_deg, 1) + " deg" +
                               (no_return ? std::string() : ", return ratio " + Fixed(returns.ratio, 2)),
                           no_return ? nullptr : &returns),
       "vector_map.png");
  save(eval::DrawVectorMap(db, thesis_result, scene.name + " thesis configuration: AAE " + Fixed(thesis_aae, 1) + " deg"),
       "vector_map_thesis_config.png");
  if (protocol) {
    save(eval::DrawVectorMap(protocol->five.db, protocol->five_result,
                             scene.name + " thesis 5x5 protocol: AAE " + Fixed(protocol->five_result.aae_deg, 1) + " deg"),
         "vector_map_thesis_5x5.png");
  }

  std::ostringstream report;
  report << "# Homing evaluation: " << scene.name << "\n\n"
         << "- configuration: " << Describe(config) << "\n- camera: " << sim.camera_preset << ", mask " << mask_source
         << "\n- input: " << input << ", headings "
         << (random_headings ? "random" : "all 0") << ", home (" << db.home.x_m << ", " << db.home.y_m << ")\n\n"
         << "| | AAE [deg] | median | max | return ratio |\n|---|---|---|---|---|\n"
         << "| this configuration | " << Fixed(result.aae_deg) << " | " << Fixed(result.median_deg) << " | "
         << Fixed(result.max_deg) << " | " << (no_return ? "-" : Fixed(returns.ratio, 3)) << " |\n"
         << "| thesis configuration (40 px, 8 bins, all, home - current) | " << Fixed(thesis_aae) << " | | | |\n"
         << "| thesis configuration with current - home | " << Fixed(thesis_lambrinos_aae) << " | | | |\n"
         << "| thesis' own figure (3.1.4) | 18.11 | | | |\n\n"
         ;
  if (protocol) WriteProtocols(report, db, result.positions, *protocol);
  report << "Visual compass over the grid (parallax included): mean error " << Fixed(result.compass_mean_deg)
         << " deg. On pure rotations at the home position (36 headings): median " << Fixed(rotation_median)
         << " deg, max " << Fixed(rotation_errors.back()) << " deg.\n\n";

  // Cell sizes of the figures; a band lower than a cell is widened to one cell.
  const std::vector<int> cells = {10, 20, 30, 40, 60, 80};
  const std::vector<nav::OrientationRange> ranges = {nav::OrientationRange::kAll, nav::OrientationRange::kVertical,
                                                      nav::OrientationRange::kHorizontal,
                                                      nav::OrientationRange::kNarrowVertical};
  auto with = [&](int cell, nav::OrientationRange range, double thr) {
    nav::HogHomingConfig c = config;
    c.hog.cell_size_px = cell;
    c.hog.range = range;
    c.alv.threshold_frac = thr;
    if (c.hog.band_height_px > 0 && c.hog.band_height_px < cell) c.hog.band_height_px = cell;
    if (c.hog.band_top_px + std::max(c.hog.band_height_px, cell) > pm.height_px) c.hog.band_top_px = pm.height_px - cell;
    return c;
  };
  if (!quick) {
    // AAE by cell size and descriptor range (fig. 3.9), at thresholds 0, 0.3 and 0.5.
    report << "## AAE by cell size and descriptor range (thesis fig. 3.9)\n\n| threshold | cell [px] |";
    for (auto r : ranges) report << " " << nav::OrientationRangeName(r) << " |";
    report << "\n|---|---|---|---|---|---|\n";
    for (double thr : {0.0, 0.3, 0.5}) {
      std::vector<plot::BarGroup> groups;
      for (int c : cells) {
        plot::BarGroup g{std::to_string(c) + " px", {}};
        report << "| " << thr << " | " << c << " |";
        for (auto r : ranges) {
          g.values.push_back(Aae(db, panos, with(c, r, thr), pm, mask));
          report << " " << Fixed(g.values.back(), 1) << " |";
        }
        report << "\n";
        groups.push_back(g);
      }
      std::vector<std::string> names;
      for (auto r : ranges) names.push_back(nav::OrientationRangeName(r));
      plot::Axes axes = MakeAxes("AAE by cell size and descriptor range, threshold " + Fixed(thr, 1) + " (" + scene.name + ")",
                      "cell size", "average angular error [deg]");
      axes.value_labels = true;
      save(plot::BarChart(axes, names, groups), "aae_by_cell_range_thr" + Fixed(thr, 1) + ".png");
      std::cerr << "eval-homing: AAE by cell and range at threshold " << thr << " done\n";
    }
    report << "\n";
    // AAE by noise type and level (fig. 3.12).
    struct Noise { std::string name, unit; std::vector<double> levels; };
    const std::vector<Noise> noises = {{"Gaussian blur", "sigma [px]", {0, 1, 2, 4, 8}},
                                       {"low resolution", "scale", {1.0, 0.5, 0.3, 0.2, 0.1}},
                                       {"salt and pepper", "fraction", {0, 0.01, 0.05, 0.1, 0.2}},
                                       {"Gaussian noise", "sigma [grey levels]", {0, 5, 10, 20, 40}}};
    report << "## AAE by noise type and level (thesis fig. 3.12)\n\n| noise | level | AAE [deg] |\n|---|---|---|\n";
    std::vector<cv::Mat> charts;
    for (size_t k = 0; k < noises.size(); ++k) {
      plot::Series s{scene.name, {}, {}};
      for (double level : noises[k].levels) {
        CameraPipeline p = pipeline;
        if (k == 0) p.effects.blur_sigma_px = level;
        if (k == 1) p.low_resolution_scale = level;
        if (k == 2) p.effects.salt_pepper_fraction = level;
        if (k == 3) p.effects.noise_sigma = level;
        std::vector<cv::Mat> noisy;
        for (const auto& img : db.sensor) noisy.push_back(renderer.ToPanorama(img, p));
        s.x.push_back(level);
        s.y.push_back(Aae(db, noisy, config, pm, mask));
        report << "| " << noises[k].name << " | " << level << " | " << Fixed(s.y.back(), 1) << " |\n";
      }
      plot::Axes axes = MakeAxes(noises[k].name, noises[k].unit, "AAE [deg]");
      axes.y_from_zero = true;
      charts.push_back(plot::LineChart(axes, {s}, {600, 400}));
      std::cerr << "eval-homing: noise '" << noises[k].name << "' done\n";
    }
    cv::Mat top, bottom, all;
    cv::hconcat(charts[0], charts[1], top);
    cv::hconcat(charts[2], charts[3], bottom);
    cv::vconcat(top, bottom, all);
    save(all, "aae_by_noise.png");
    // Preprocessing (3.1.5, 3.1.6): histogram equalisation and warping compensation, on the
    // plain images and with an illumination change of every current view (home unchanged).
    {
      CameraPipeline dim = pipeline;
      dim.effects.gain = 0.6;
      dim.effects.offset = 30;
      std::vector<cv::Mat> changed;
      for (size_t i = 0; i < db.sensor.size(); ++i) {
        changed.push_back(static_cast<int>(i) == db.home_index ? panos[i] : renderer.ToPanorama(db.sensor[i], dim));
      }
      report << "\n## Preprocessing (thesis 3.1.5, 3.1.6)\n\n| preprocessing | AAE [deg] | AAE, current views dimmed (gain 0.6, +30) |\n|---|---|---|\n";
      std::vector<plot::BarGroup> groups;
      for (int k = 0; k < 4; ++k) {
        nav::HogHomingConfig c = config;
        c.equalize_histogram = k == 1 || k == 3;
        c.warp_compensation = k >= 2;
        const std::string name = k == 0 ? "none" : k == 1 ? "equalised" : k == 2 ? "warp-compensated" : "both";
        groups.push_back({name, {Aae(db, panos, c, pm, mask), Aae(db, changed, c, pm, mask)}});
        report << "| " << name << " | " << Fixed(groups.back().values[0], 1) << " | " << Fixed(groups.back().values[1], 1)
               << " |\n";
      }
      plot::Axes axes = MakeAxes("AAE by preprocessing (" + scene.name + ")", "preprocessing", "AAE [deg]");
      axes.value_labels = true;
      save(plot::BarChart(axes, {"same illumination", "current views dimmed"}, groups), "aae_by_preprocessing.png");
      std::cerr << "eval-homing: preprocessing done\n";
    }
    report << "\n## Entropy by cell size (thesis fig. 3.13)\n\n| scene | cell [px] | entropy [bits] |\n|---|---|---|\n";
    // Entropy by cell size (fig. 3.13), per scene.
    std::vector<plot::Series> entropy;
    for (const auto& name : glue::SplitList(entropy_scenes)) {
      const auto s = name == scene.name ? scene : processes::LoadSceneFile(processes::SceneFilePath(name));
      std::vector<cv::Mat> images;
      if (name == scene.name) {
        images = panos;
      } else {
        eval::ViewRenderer r(s, sim.camera, static_cast<uint64_t>(seed));
        eval::GridOptions g;
        g.input = CameraPipeline::Input::kPanorama;
        g.seed = static_cast<uint64_t>(seed);
        const auto other = eval::RenderGrid(s, r, g);
        CameraPipeline p;
        p.input = CameraPipeline::Input::kPanorama;
        p.effects = sim.effects;
        for (const auto& img : other.sensor) images.push_back(r.ToPanorama(img, p));
      }
      plot::Series series{s.name, {}, {}};
      for (int c : cells) {
        const auto cfg = with(c, config.hog.range, 0);
        double sum = 0;
        for (const auto& img : images) {
          cv::Mat gray;
          cv::cvtColor(img, gray, cv::COLOR_BGR2GRAY);
          sum += nav::CellEntropyBits(nav::CellsAtShift(nav::ColumnHistograms(gray, cfg.hog), c, 0));
        }
        series.x.push_back(c);
        series.y.push_back(sum / images.size());
        report << "| " << s.name << " | " << c << " | " << Fixed(series.y.back(), 3) << " |\n";
      }
      entropy.push_back(series);
    }
    plot::Axes axes = MakeAxes("Mean cell entropy by cell size (" + std::string(nav::OrientationRangeName(config.hog.range)) + ")",
                    "cell size [px]", "entropy [bits]");
    save(plot::LineChart(axes, entropy), "entropy_by_cell.png");
    std::cerr << "eval-homing: entropy done\n";
  }

  if (sweep) {
    std::ofstream csv(out / "sweep.csv");
    csv << "cell_px,bins,threshold,range,weight,aae_deg,median_deg,failures\n";
    std::ostringstream md;
    md << "# AAE sweep: " << scene.name << " (" << input << ", headings " << (random_headings ? "random" : "0")
       << ", compass " << (config.use_compass ? "hog" : "off") << ", band " << config.hog.band_top_px << "+"
       << config.hog.band_height_px << ")\n\n| cell | bins | threshold | range | weight | AAE [deg] | median | failures |\n"
       << "|---|---|---|---|---|---|---|---|\n";
    const std::vector<int> bins = {8, 16, 36};
    const int total = static_cast<int>(cells.size() * bins.size() * 3 * ranges.size() * 2);
    int done = 0;
    double best = 1e9;
    std::string best_row;
    for (int c : cells) {
      for (int b : bins) {
        for (double thr : {0.0, 0.3, 0.5}) {
          for (auto r : ranges) {
            for (auto w : {nav::CellWeight::kMagnitude, nav::CellWeight::kLog}) {
              auto cfg = with(c, r, thr);
              cfg.hog.bins = b;
              cfg.alv.weight = w;
              eval::GridResult gr;
              Aae(db, panos, cfg, pm, mask, &gr);
              csv << c << "," << b << "," << thr << "," << nav::OrientationRangeName(r) << "," << WeightName(w) << ","
                  << Fixed(gr.aae_deg, 3) << "," << Fixed(gr.median_deg, 3) << "," << gr.failures << "\n";
              const std::string row = "| " + std::to_string(c) + " | " + std::to_string(b) + " | " + Fixed(thr, 1) +
                                      " | " + nav::OrientationRangeName(r) + " | " + WeightName(w) + " | " +
                                      Fixed(gr.aae_deg) + " | " + Fixed(gr.median_deg) + " | " +
                                      std::to_string(gr.failures) + " |\n";
              md << row;
              if (gr.aae_deg < best) {
                best = gr.aae_deg;
                best_row = row;
              }
              Progress("eval-homing", "sweep", ++done, total);
            }
          }
        }
      }
    }
    md << "\nBest: \n\n| cell | bins | threshold | range | weight | AAE [deg] | median | failures |\n"
       << "|---|---|---|---|---|---|---|---|\n" << best_row;
    std::ofstream(out / "sweep.md") << md.str();
    report << "\n## Sweep\n\nBest of " << total << " configurations (sweep.md, sweep.csv):\n\n"
           << "| cell | bins | threshold | range | weight | AAE [deg] | median | failures |\n"
           << "|---|---|---|---|---|---|---|---|\n" << best_row;
  }

  results::Json json;
  json["scene"] = scene.name;
  json["method"] = method;
  json["input"] = input;
  json["camera"] = sim.camera_preset;
  json["mask"] = mask_source;
  json["effects"] = {{"blur_sigma_px", R4(pipeline.effects.blur_sigma_px)},
                     {"noise_sigma", R4(pipeline.effects.noise_sigma)},
                     {"salt_pepper_fraction", R4(pipeline.effects.salt_pepper_fraction)},
                     {"illumination_gain", R4(pipeline.effects.gain)},
                     {"illumination_offset", R4(pipeline.effects.offset)}};
  json["masked_fraction"] = R4(nav::MaskedFraction(mask));
  json["random_headings"] = random_headings;
  WriteGridResultJson(json, db, config, result);
  json["compass_pure_rotation_median_error_deg"] = R4(rotation_median);
  json["compass_pure_rotation_max_error_deg"] = R4(rotation_errors.back());
  json["thesis_configuration_aae_deg"] = R4(thesis_aae);
  json["thesis_configuration_current_minus_home_aae_deg"] = R4(thesis_lambrinos_aae);
  json["thesis_reported_aae_deg"] = 18.11;
  if (protocol) WriteProtocolsJson(json, *protocol);
  if (!no_return) {
    json["return_ratio"] = R4(returns.ratio);
    json["return_starts"] = R4(returns.starts);
    json["return_successes"] = R4(returns.successes);
    json["return_mean_path_ratio"] = R4(returns.mean_path_ratio);
    json["return_step_m"] = R4(ret.step_m);
  }
  json["frames_per_second"] = R4(fps);
  json["ms_per_frame"] = R4(fps > 0 ? 1000 / fps : 0);
  json["figures"] = figures;
  results::WriteJsonFile((out / "summary.json").string(), json);
  std::ofstream(out / "report.md") << report.str();
  std::cerr << "eval-homing: wrote " << (out / "summary.json").string() << ", report.md and " << figures.size()
            << " figures\n";
  std::cout << "average_angular_error_deg " << Fixed(result.aae_deg) << "\n";
  if (protocol) {
    std::cout << "thesis_5x5_average_angular_error_deg " << Fixed(protocol->rows[0].thesis5) << "\n"
              << "thesis_5x5_thesis_configuration_aae_deg " << Fixed(protocol->rows[3].thesis5) << "\n";
  }
  if (!no_return) std::cout << "return_ratio " << Fixed(returns.ratio, 3) << "\n";
  return 0;
}

}  // namespace snapnav::eval
