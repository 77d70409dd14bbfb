#include "people_diagnosis.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>

#include "landmark_eval.hpp"
#include "people_view.hpp"
#include "progress.hpp"
#include "report_text.hpp"
#include "results.hpp"
#include "scene_file.hpp"
#include "stats.hpp"
#include "snapnav/nav/landmarks/view_fusion.hpp"
#include "snapnav/plot/plot.hpp"

namespace snapnav::eval {
namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct MethodRow {
  std::string label;
  nav::LandmarkMethod method;  // kHog: the HOG homing
  nav::AlvVariant variant = nav::AlvVariant::kUnit;
  bool consensus = false;
};

// The grid's panoramas with the home view taken from another rendering of the same grid.
std::vector<cv::Mat> WithHome(const Grid& current, const Grid& home) {
  std::vector<cv::Mat> panos = current.panos;
  panos[current.db.home_index] = home.panos[home.db.home_index];
  return panos;
}


}  // namespace

int RunPeopleDiagnosis(const LandmarkEvalSetup& setup, const std::string& scene_name, const FrameProtocol& frames,
                       const std::string& out_dir) {
  fs::create_directories(out_dir);
  const fs::path out(out_dir);
  const auto scene = processes::LoadSceneFile(processes::SceneFilePath(scene_name));
  if (scene.people.count == 0) throw std::runtime_error("scene '" + scene.name + "' has no people");
  ViewRenderer renderer(scene, setup.camera, setup.seed);
  GridOptions grid;
  grid.seed = setup.seed;
  grid.input = setup.input;
  grid.effects = setup.effects;
  GridOptions framed = grid;  // the people grid with its frames of a still robot, for the fused views
  framed.frames = frames;
  const Grid g = RenderScene(scene, framed, renderer,
                             [&](int d, int t) { Progress("eval-homing", "rendering " + scene.name, d, t); });
  nav::sim::Scene quiet = scene;
  quiet.people.count = 0;
  ViewRenderer r2(quiet, setup.camera, setup.seed);
  const Grid e = RenderScene(quiet, grid, r2,
                             [&](int d, int t) { Progress("eval-homing", "rendering " + scene.name + " without people", d, t); });

  // 1. Where the people are in each grid image.
  const PeopleView pv(scene, setup.camera);
  std::ofstream csv(out / "people_per_image.csv");
  csv << "index,ix,iy,x_m,y_m,is_home,people,nearest_surface_m,camera_inside,occluded_fraction\n";
  std::vector<double> nearest, occluded;
  int inside_images = 0, within_30cm = 0, half_covered = 0;
  PeopleInView home_view;
  for (size_t i = 0; i < g.db.poses.size(); ++i) {
    const auto m = pv.Measure(g.db.poses[i], g.db.people[i]);
    const auto& p = g.db.poses[i];
    const bool is_home = static_cast<int>(i) == g.db.home_index;
    if (is_home) home_view = m;
    csv << i << "," << i % g.db.nx << "," << i / g.db.nx << "," << Fixed(p.x_m, 2) << "," << Fixed(p.y_m, 2) << ","
        << is_home << "," << m.people << "," << Fixed(m.nearest_surface_m, 3) << "," << m.inside << ","
        << Fixed(m.occluded_fraction, 4) << "\n";
    nearest.push_back(m.nearest_surface_m);
    occluded.push_back(m.occluded_fraction);
    if (m.inside > 0) ++inside_images;
    if (m.nearest_surface_m < 0.3) ++within_30cm;
    if (m.occluded_fraction > 0.5) ++half_covered;
  }
  double occluded_mean = 0;
  for (double o : occluded) occluded_mean += o;
  occluded_mean /= std::max<size_t>(1, occluded.size());
  std::ostringstream md;
  md << "# People in the homing evaluation: " << scene.name << "\n\n"
     << "Grid images rendered as `eval homing` renders them (the crowd walks 2 s between images; seed " << setup.seed
     << "). Nearest person: distance from the camera to the nearest person's surface (negative: the camera stands "
        "inside a person). Occluded: share of the panorama showing a person.\n\n"
     << "| | images | camera inside a person | nearest person < 0.3 m | occluded > 50% | nearest person, median [m] "
        "| occluded, mean | occluded, max |\n|---|---|---|---|---|---|---|---|\n"
     << "| grid | " << g.db.poses.size() << " | " << inside_images << " | " << within_30cm << " | " << half_covered << " | "
     << Fixed(Median(nearest, kNaN), 2) << " | " << Fixed(occluded_mean, 3) << " | "
     << Fixed(*std::max_element(occluded.begin(), occluded.end()), 3) << " |\n"
     << "| home snapshot | 1 | " << home_view.inside << " | " << (home_view.nearest_surface_m < 0.3) << " | "
     << (home_view.occluded_fraction > 0.5) << " | " << Fixed(home_view.nearest_surface_m, 2) << " | "
     << Fixed(home_view.occluded_fraction, 3) << " | |\n\n";

  // 2. AAE with and without people in the home view and in the current views.
  const MethodRow rows[] = {{"hog", nav::LandmarkMethod::kHog},
                            {"vline unit", nav::LandmarkMethod::kVline, nav::AlvVariant::kUnit},
                            {"vline weighted", nav::LandmarkMethod::kVline, nav::AlvVariant::kWeighted},
                            {"sift unit", nav::LandmarkMethod::kSift, nav::AlvVariant::kUnit},
                            {"sift weighted", nav::LandmarkMethod::kSift, nav::AlvVariant::kWeighted},
                            {"sift scale", nav::LandmarkMethod::kSift, nav::AlvVariant::kScale},
                            {"sift scale+consensus", nav::LandmarkMethod::kSift, nav::AlvVariant::kScale, true},
                            {"surf unit", nav::LandmarkMethod::kSurf, nav::AlvVariant::kUnit},
                            {"surf weighted", nav::LandmarkMethod::kSurf, nav::AlvVariant::kWeighted},
                            {"surf scale", nav::LandmarkMethod::kSurf, nav::AlvVariant::kScale},
                            {"surf scale+consensus", nav::LandmarkMethod::kSurf, nav::AlvVariant::kScale, true}};
  const std::vector<cv::Mat> pp = g.panos, ee = e.panos, ep = WithHome(g, e), pe = WithHome(e, g);
  std::vector<cv::Mat> all = g.panos;
  all.insert(all.end(), e.panos.begin(), e.panos.end());
  md << "## AAE [deg] by where the people are (all matches)\n\n"
     << "| method | people in home and current views (the evaluation) | people-free home, people in the current views "
        "| people in the home, people-free current views | no people |\n|---|---|---|---|---|\n";
  results::Json json_aae = results::Json::object(), json_on = results::Json::object();
  std::ostringstream md_on;
  md_on << "## Matched landmarks on people (people in every view)\n\n"
        << "A landmark is on a person when its panorama pixel shows a person; \"near\" adds its outline (half the "
           "keypoint size, at least 3 px, either side). Matches after the descriptor checks, and the ones the "
           "estimate used.\n\n"
        << "| method | landmarks per view | of them on people | home landmarks on people | matches per view | home "
           "side on people | current side on people | either side near people | used per view | used, either side on people |\n"
        << "|---|---|---|---|---|---|---|---|---|---|\n";
  nav::LandmarkMethod cached_method = nav::LandmarkMethod::kHog;
  LandmarkCache cache;
  for (const auto& row : rows) {
    double aae[4];
    const std::vector<cv::Mat>* sets[4] = {&pp, &ep, &pe, &ee};
    if (row.method == nav::LandmarkMethod::kHog) {
      for (int k = 0; k < 4; ++k) {
        HogMethod hog(setup.hog, setup.camera.panorama);
        aae[k] = EvaluatePanoramas(g.db, *sets[k], hog).aae_deg;
      }
    } else {
      nav::LandmarkExtractorConfig extractor = setup.extractor;
      extractor.method = row.method;
      if (cached_method != row.method) {
        std::cerr << "eval-homing: extracting " << nav::LandmarkMethodName(row.method) << " landmarks\n";
        cache = ExtractAll(all, extractor);
        cached_method = row.method;
      }
      nav::LandmarkHomingConfig homing = setup.homing(row.method);
      homing.alv.variant = row.variant;
      homing.alv.top_n = 0;
      homing.alv.consensus = row.consensus;
      for (int k = 0; k < 4; ++k) {
        LandmarkMethod m(extractor, homing, setup.camera.panorama, &cache);
        aae[k] = EvaluatePanoramas(g.db, *sets[k], m).aae_deg;
      }
      // Which landmarks and matches lie on people.
      const auto& hs = cache.sets[g.db.home_index];
      const nav::Pose2& hpose = g.db.home;
      const auto& hpeople = g.db.people[g.db.home_index];
      auto on = [&](const nav::Pose2& pose, const std::vector<nav::sim::Cylinder>& people, const nav::Landmark& l) {
        return pv.PersonAt(pose, people, l.x_px, l.y_px) >= 0;
      };
      auto near = [&](const nav::Pose2& pose, const std::vector<nav::sim::Cylinder>& people, const nav::Landmark& l) {
        return pv.NearPerson(pose, people, l.x_px, l.y_px, std::max(3.0, l.scale_px / 2.0));
      };
      int64_t landmarks = 0, landmarks_on = 0, matches = 0, home_on = 0, cur_on = 0, either_near = 0, used = 0,
              used_on = 0, views = 0;
      int home_landmarks_on = 0;
      for (const auto& l : hs.landmarks) home_landmarks_on += on(hpose, hpeople, l);
      nav::LandmarkHomer homer(homing, setup.camera.panorama);
      homer.SetHome(hs);
      for (size_t i = 0; i < g.db.poses.size(); ++i) {
        if (static_cast<int>(i) == g.db.home_index) continue;
        const auto& cs = cache.sets[i];
        const auto& pose = g.db.poses[i];
        const auto& people = g.db.people[i];
        ++views;
        landmarks += cs.size();
        for (const auto& l : cs.landmarks) landmarks_on += on(pose, people, l);
        const auto r = homer.Home(cs);
        if (!r) continue;
        std::vector<char> is_used(r->matched.size(), 0);
        for (int u : r->used) is_used[u] = 1;
        for (size_t k = 0; k < r->matched.size(); ++k) {
          const auto& mt = r->matched[k];
          const bool h_on = on(hpose, hpeople, hs.landmarks[mt.home]);
          const bool c_on = on(pose, people, cs.landmarks[mt.current]);
          ++matches;
          home_on += h_on;
          cur_on += c_on;
          either_near += near(hpose, hpeople, hs.landmarks[mt.home]) || near(pose, people, cs.landmarks[mt.current]);
          if (is_used[k]) {
            ++used;
            used_on += h_on || c_on;
          }
        }
      }
      auto frac = [](int64_t a, int64_t b) { return b > 0 ? static_cast<double>(a) / b : 0.0; };
      auto per = [&](int64_t a) { return views > 0 ? static_cast<double>(a) / views : 0.0; };
      md_on << "| " << row.label << " | " << Fixed(per(landmarks), 1) << " | " << Fixed(frac(landmarks_on, landmarks), 3)
            << " | " << home_landmarks_on << "/" << hs.size() << " | " << Fixed(per(matches), 1) << " | "
            << Fixed(frac(home_on, matches), 3) << " | " << Fixed(frac(cur_on, matches), 3) << " | "
            << Fixed(frac(either_near, matches), 3) << " | " << Fixed(per(used), 1) << " | "
            << Fixed(frac(used_on, used), 3) << " |\n";
      results::Json& row_on = json_on[row.label];
      row_on["landmarks_on_people_frac"] = results::Rounded(frac(landmarks_on, landmarks), 4);
      row_on["home_landmarks_on_people"] = home_landmarks_on;
      row_on["home_landmarks"] = hs.size();
      row_on["matches_home_on_people_frac"] = results::Rounded(frac(home_on, matches), 4);
      row_on["matches_current_on_people_frac"] = results::Rounded(frac(cur_on, matches), 4);
      row_on["matches_near_people_frac"] = results::Rounded(frac(either_near, matches), 4);
      row_on["used_on_people_frac"] = results::Rounded(frac(used_on, used), 4);
    }
    md << "| " << row.label << " | " << Fixed(aae[0]) << " | " << Fixed(aae[1]) << " | " << Fixed(aae[2]) << " | "
       << Fixed(aae[3]) << " |\n";
    json_aae[row.label] = {{"people_home_people_current_deg", results::Rounded(aae[0], 3)},
                           {"empty_home_people_current_deg", results::Rounded(aae[1], 3)},
                           {"people_home_empty_current_deg", results::Rounded(aae[2], 3)},
                           {"empty_home_empty_current_deg", results::Rounded(aae[3], 3)}};
    std::cerr << "eval-homing: " << row.label << ": AAE " << Fixed(aae[0]) << " / " << Fixed(aae[1]) << " / "
              << Fixed(aae[2]) << " / " << Fixed(aae[3]) << " deg\n";
  }
  md << "\n" << md_on.str();

  // 3. The home view over the frames of a still robot, and what fusing them leaves.
  {
    const int h = g.db.home_index;
    std::vector<cv::Mat> strip;
    md << "\n## The home view over " << g.frames[h].size() << " frames " << frames.home_interval_s
       << " s apart (fused views)\n\n![home frames](home_frames.png)\n\nFrom the top: each frame, their per-pixel "
          "median, the room without people.\n\n";
    for (const auto& f : g.frames[h]) strip.push_back(f);
    strip.push_back(nav::MedianImage(g.frames[h]));
    strip.push_back(e.panos[e.db.home_index]);
    cv::Mat all_rows;
    cv::vconcat(strip, all_rows);
    plot::SavePng(all_rows, (out / "home_frames.png").string());
    // Landmarks of the fused home: how many, and how many of them the people-free home has at the
    // same place (within 3 px; vertical lines: the column) - the static room - against frame 0.
    md << "| method | home landmarks: frame 0 | persistent | median panorama | empty room | of them in the empty "
          "room: frame 0 | persistent | median | frame 0 on people |\n|---|---|---|---|---|---|---|---|---|\n";
    for (const auto method : {nav::LandmarkMethod::kVline, nav::LandmarkMethod::kSift, nav::LandmarkMethod::kSurf}) {
      nav::LandmarkExtractorConfig extractor = setup.extractor;
      extractor.method = method;
      std::vector<nav::LandmarkSet> sets;
      for (const auto& f : g.frames[h]) sets.push_back(nav::ExtractLandmarks(f, extractor));
      const auto persistent = nav::PersistentLandmarks(sets, setup.fusion.persistence);
      const auto median = nav::ExtractLandmarks(nav::MedianImage(g.frames[h]), extractor);
      const auto quiet_set = nav::ExtractLandmarks(e.panos[e.db.home_index], extractor);
      const double width = setup.camera.panorama.width_px;
      auto in_empty = [&](const nav::LandmarkSet& set) {
        int n = 0;
        for (const auto& l : set.landmarks) {
          bool found = false;
          for (const auto& q : quiet_set.landmarks) {
            double dx = std::fmod(std::abs(l.x_px - q.x_px), width);
            dx = std::min(dx, width - dx);
            if (dx <= 3 && (method == nav::LandmarkMethod::kVline || std::abs(l.y_px - q.y_px) <= 3)) {
              found = true;
              break;
            }
          }
          n += found;
        }
        return n;
      };
      int on0 = 0;
      for (const auto& l : sets[0].landmarks) on0 += pv.PersonAt(g.db.home, g.frame_people[h][0], l.x_px, l.y_px) >= 0;
      md << "| " << nav::LandmarkMethodName(method) << " | " << sets[0].size() << " | " << persistent.size() << " | "
         << median.size() << " | " << quiet_set.size() << " | " << in_empty(sets[0]) << " | " << in_empty(persistent)
         << " | " << in_empty(median) << " | " << on0 << " |\n";
    }
    md << "\n| frame | people occluded share | nearest person [m] |\n|---|---|---|\n";
    for (size_t k = 0; k < g.frame_people[h].size(); ++k) {
      const auto m = pv.Measure(g.db.home, g.frame_people[h][k]);
      md << "| " << k << " | " << Fixed(m.occluded_fraction, 3) << " | " << Fixed(m.nearest_surface_m, 2) << " |\n";
    }
  }
  std::ofstream(out / "people.md") << md.str();
  results::Json json;
  json["scene"] = scene.name;
  json["grid_images"] = g.db.poses.size();
  json["images_camera_inside_person"] = inside_images;
  json["images_person_within_0_3_m"] = within_30cm;
  json["images_occluded_over_half"] = half_covered;
  json["nearest_person_median_m"] = results::Rounded(Median(nearest, kNaN), 3);
  json["occluded_fraction_mean"] = results::Rounded(occluded_mean, 4);
  json["home_nearest_person_m"] = results::Rounded(home_view.nearest_surface_m, 3);
  json["home_camera_inside_person"] = home_view.inside;
  json["home_occluded_fraction"] = results::Rounded(home_view.occluded_fraction, 4);
  json["aae"] = json_aae;
  json["on_people"] = json_on;
  results::WriteJsonFile((out / "summary.json").string(), json);
  std::cout << md.str();
  std::cerr << "eval-homing: wrote " << (out / "people.md").string() << ", people_per_image.csv, summary.json\n";
  return 0;
}

}  // namespace snapnav::eval
