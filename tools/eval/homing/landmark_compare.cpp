#include "landmark_compare.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>

#include "landmark_eval.hpp"
#include "progress.hpp"
#include "report_text.hpp"
#include "results.hpp"
#include "scene_file.hpp"
#include "snapnav/nav/homing/image_mask.hpp"
#include "snapnav/plot/plot.hpp"

namespace snapnav::eval {
namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

nav::LandmarkHomingConfig WithAlv(nav::LandmarkHomingConfig c, nav::AlvVariant variant, int top_n) {
  c.alv.variant = variant;
  c.alv.top_n = top_n;
  return c;
}

// The ALV rows of the comparison: the thesis' three variants, and the scale ALV with consensus.
struct AlvRow {
  nav::AlvVariant variant;
  bool consensus;
  const char* label;
};
const AlvRow kAlvRows[] = {{nav::AlvVariant::kUnit, false, "unit"},
                           {nav::AlvVariant::kWeighted, false, "weighted"},
                           {nav::AlvVariant::kScale, false, "scale"},
                           {nav::AlvVariant::kScale, true, "scale+consensus"}};

std::string NText(int top_n) { return top_n > 0 ? std::to_string(top_n) : "all"; }
std::string OrDash(double v, int digits) { return std::isnan(v) ? "-" : Fixed(v, digits); }

// One row of the comparison.
struct Row {
  std::string scene, method, alv, n;
  std::string fusion = "none";          // none | persistent | median
  int home_frames = 1, current_frames = 1;
  double aae = kNaN, median = kNaN, ret = kNaN, ms = kNaN, landmarks = kNaN, matches = kNaN;
  int failures = 0, positions = 0;
  double aae_without_people = kNaN;  // the same scene with its people removed
  std::string Frames() const { return std::to_string(home_frames) + "/" + std::to_string(current_frames); }
  std::string Label() const {
    return (method == "hog" ? method : method + " " + alv + " " + n) +
           (fusion == "none" ? std::string() : ", " + fusion + " " + Frames());
  }
};

GridOptions MakeGridOptions(const LandmarkEvalSetup& setup, const FrameProtocol& frames) {
  GridOptions grid;
  grid.seed = setup.seed;
  grid.input = setup.input;
  grid.effects = setup.effects;
  grid.frames = frames;
  grid.random_headings = setup.random_headings;
  return grid;
}

// The frames the return runs use: home_frames of the home, current_frames per step.
ReturnOptions WithFrames(ReturnOptions r, const FrameProtocol& protocol, int home_frames, int current_frames,
                         uint64_t seed) {
  r.frames = protocol;
  r.frames.home_frames = home_frames;
  r.frames.current_frames = current_frames;
  r.seed = seed;
  return r;
}

std::string FusionText(const std::string& fusion, const FrameProtocol& f) {
  if (!f.fused()) return "";
  return ", " + fusion + " " + std::to_string(f.home_frames) + "/" + std::to_string(f.current_frames) + " frames";
}

}  // namespace

int RunLandmarkEval(const LandmarkEvalSetup& setup, const std::string& scene_name, nav::LandmarkMethod method,
                    nav::AlvVariant variant, int top_n, bool no_return, const std::string& out_dir) {
  fs::create_directories(out_dir);
  const fs::path out(out_dir);
  const auto scene = processes::LoadSceneFile(processes::SceneFilePath(scene_name));
  nav::LandmarkExtractorConfig extractor = setup.extractor;
  extractor.method = method;
  const auto homing = WithAlv(setup.homing(method), variant, top_n);
  const std::string label = LandmarkLabel(method, variant, top_n) +
                            FusionText(nav::ViewFusionName(setup.fusion.mode), setup.frames);
  std::cerr << "eval-homing: scene " << scene.name << ", " << scene.grid.nx << "x" << scene.grid.ny << " grid, " << label
            << "\n";
  ViewRenderer renderer(scene, setup.camera, setup.seed);
  const cv::Size raw_size(setup.camera.omni_width_px, setup.camera.omni_height_px);
  const cv::Mat raw_mask = RawMask(setup.mask, renderer, raw_size, setup.seed);
  const cv::Mat mask = UseRawMask(raw_mask, renderer);
  const Grid g = RenderScene(scene, MakeGridOptions(setup, setup.frames), renderer,
                             [&](int d, int t) { Progress("eval-homing", "rendering " + scene.name, d, t); });
  const auto cache = ExtractAll(g.AllPanoramas(), extractor, mask);
  LandmarkMethod m(extractor, homing, setup.camera.panorama, &cache, setup.fusion);
  m.SetMask(mask);
  const auto result = EvaluateFrames(g.db, g.Frames(setup.frames.home_frames, setup.frames.current_frames), m);
  const double ms = cache.ms_per_panorama() * setup.frames.current_frames +
                    (result.method_calls ? result.seconds_in_method * 1000 / result.method_calls : 0);
  const double mean_matches = m.estimates() ? static_cast<double>(m.matches()) / m.estimates() : 0;
  std::cerr << "eval-homing: AAE " << Fixed(result.aae_deg) << " deg (median " << Fixed(result.median_deg) << ", "
            << result.failures << " without an answer), " << Fixed(cache.mean_landmarks, 1) << " landmarks and "
            << Fixed(mean_matches, 1) << " matches per view, " << Fixed(ms) << " ms per frame\n";
  // A scene with people: the same room without them (single frames: its frames are all alike).
  double aae_empty = kNaN;
  if (scene.people.count > 0) {
    nav::sim::Scene quiet = scene;
    quiet.people.count = 0;
    ViewRenderer r2(quiet, setup.camera, setup.seed);
    UseRawMask(raw_mask, r2);  // the same camera: its calibration, not another
    const Grid e = RenderScene(quiet, MakeGridOptions(setup, FrameProtocol{}), r2,
                               [&](int d, int t) { Progress("eval-homing", "rendering " + quiet.name + " without people", d, t); });
    const auto empty_cache = ExtractAll(e.panos, extractor, mask);
    LandmarkMethod me(extractor, homing, setup.camera.panorama, &empty_cache);
    me.SetMask(mask);
    aae_empty = EvaluatePanoramas(e.db, e.panos, me).aae_deg;
    std::cerr << "eval-homing: without the people: AAE " << Fixed(aae_empty) << " deg (degradation "
              << Fixed(result.aae_deg - aae_empty) << " deg)\n";
  }
  ReturnResult returns;
  if (!no_return) {
    CameraPipeline pipeline;
    pipeline.input = setup.input;
    pipeline.effects = setup.effects;
    LandmarkMethod live(extractor, homing, setup.camera.panorama, nullptr, setup.fusion);
    live.SetMask(mask);
    returns = EvaluateReturn(g.db, live, renderer, pipeline,
                             WithFrames(setup.ret, setup.frames, setup.frames.home_frames, setup.frames.current_frames,
                                        setup.seed),
                             [](int d, int t) { Progress("eval-homing", "return runs", d, t); }, &g.frames);
    std::cerr << "eval-homing: return ratio " << Fixed(returns.ratio, 3) << " (" << returns.successes << "/"
              << returns.starts << ")\n";
  }
  plot::SavePng(DrawVectorMap(g.db, result,
                              scene.name + " " + label + ": AAE " + Fixed(result.aae_deg, 1) + " deg" +
                                  (no_return ? std::string() : ", return ratio " + Fixed(returns.ratio, 2)),
                              no_return ? nullptr : &returns),
                (out / "vector_map.png").string());
  results::Json json;
  json["scene"] = scene.name;
  json["camera"] = setup.camera.optics.enabled ? "realistic" : "clean";
  json["mask"] = setup.mask;
  json["masked_fraction"] = results::Rounded(nav::MaskedFraction(mask), 4);
  json["random_headings"] = setup.random_headings;
  json["method"] = nav::LandmarkMethodName(method);
  json["alv"] = nav::AlvVariantName(variant);
  json["landmarks"] = NText(top_n);
  json["fusion"] = setup.frames.fused() ? nav::ViewFusionName(setup.fusion.mode) : "none";
  json["home_frames"] = setup.frames.home_frames;
  json["home_interval_s"] = results::Significant(setup.frames.home_interval_s);
  json["current_frames"] = setup.frames.current_frames;
  json["current_interval_s"] = results::Significant(setup.frames.current_interval_s);
  json["grid_positions"] = result.positions;
  json["average_angular_error_deg"] = results::Rounded(result.aae_deg, 4);
  json["median_angular_error_deg"] = results::Rounded(result.median_deg, 4);
  json["max_angular_error_deg"] = results::Rounded(result.max_deg, 4);
  json["positions_without_answer"] = result.failures;
  json["compass_mean_error_deg"] = results::Rounded(result.compass_mean_deg, 4);
  json["mean_landmarks_per_view"] = results::Rounded(cache.mean_landmarks, 2);
  json["mean_matches"] = results::Rounded(mean_matches, 2);
  json["ms_per_frame"] = results::Rounded(ms, 3);
  if (!std::isnan(aae_empty)) {
    json["average_angular_error_without_people_deg"] = results::Rounded(aae_empty, 4);
    json["degradation_deg"] = results::Rounded(result.aae_deg - aae_empty, 4);
  }
  if (!no_return) {
    json["return_ratio"] = results::Rounded(returns.ratio, 4);
    json["return_starts"] = returns.starts;
    json["return_successes"] = returns.successes;
  }
  json["figures"] = {"vector_map.png"};
  results::WriteJsonFile((out / "summary.json").string(), json);
  std::ofstream(out / "report.md") << "# Homing evaluation: " << scene.name << ", " << label << "\n\n"
                                   << "| AAE [deg] | median | max | without answer | return ratio | landmarks/view | matches | ms/frame | AAE without people |\n"
                                   << "|---|---|---|---|---|---|---|---|---|\n| " << Fixed(result.aae_deg) << " | "
                                   << Fixed(result.median_deg) << " | " << Fixed(result.max_deg) << " | "
                                   << result.failures << " | " << (no_return ? "-" : Fixed(returns.ratio, 3)) << " | "
                                   << Fixed(cache.mean_landmarks, 1) << " | " << Fixed(mean_matches, 1) << " | "
                                   << Fixed(ms) << " | " << OrDash(aae_empty, 2) << " |\n\n![vector map](vector_map.png)\n";
  std::cout << "average_angular_error_deg " << Fixed(result.aae_deg) << "\n";
  if (!no_return) std::cout << "return_ratio " << Fixed(returns.ratio, 3) << "\n";
  return 0;
}

int RunCompare(const LandmarkEvalSetup& setup, const CompareOptions& options, const std::string& out_dir) {
  fs::create_directories(out_dir);
  const fs::path out(out_dir);
  const std::vector<nav::LandmarkMethod> methods = {nav::LandmarkMethod::kVline, nav::LandmarkMethod::kSift,
                                                    nav::LandmarkMethod::kSurf};
  CameraPipeline pipeline;
  pipeline.input = setup.input;
  pipeline.effects = setup.effects;
  std::vector<Row> rows;
  std::vector<std::string> figures;
  std::ostringstream md;
  md << "# Homing with feature landmarks: HOG, vertical lines, SIFT, SURF (thesis 4.1-4.3)\n\n"
     << "Camera: " << (setup.camera.optics.enabled ? "realistic" : "clean") << ", mask " << setup.mask << ".\n\n"
     << "AAE over each scene's grid (home at the centre, all views at heading 0, the rotation estimated from the\n"
     << "matches), return ratio of closed-loop runs (step " << setup.ret.step_m << " m, people walking "
     << setup.ret.people_dt_s << " s per step around the robot) for each method and ALV at its best landmark count"
     << (options.return_best_only ? " (here: only for each method's best row)" : "")
     << (setup.ret.start_stride > 1 ? " (a sample: every " + std::to_string(setup.ret.start_stride) + "th start)" : "")
     << ",\n"
     << "and milliseconds per frame (extraction + matching + ALV, one core; fused rows: per fused view).\n"
     << "Vertical lines have no keypoint scale: their scale ALV equals the unit ALV and is not listed.\n"
     << "scale is the thesis' scale-compensated ALV (4.2.3); scale+consensus is snapnav's: the mean of the\n"
     << "per-landmark directions that agree with their mode, with the rotation refined to the best agreement.\n\n";
  const FrameProtocol& fp = options.fused;
  fp.Validate();
  for (const auto& scene_name : options.scenes) {
    const auto scene = processes::LoadSceneFile(processes::SceneFilePath(scene_name));
    const bool people = scene.people.count > 0;
    const bool fused = people && fp.fused();
    ViewRenderer renderer(scene, setup.camera, setup.seed);
    const cv::Size raw_size(setup.camera.omni_width_px, setup.camera.omni_height_px);
    const cv::Mat raw_mask = RawMask(setup.mask, renderer, raw_size, setup.seed);
    const cv::Mat mask = UseRawMask(raw_mask, renderer);
    const Grid g = RenderScene(scene, MakeGridOptions(setup, fused ? fp : FrameProtocol{}), renderer,
                               [&](int d, int t) { Progress("eval-homing", "rendering " + scene.name, d, t); });
    // The same room without its people, for the degradation the people cause.
    std::optional<Grid> empty;
    if (people) {
      nav::sim::Scene quiet = scene;
      quiet.people.count = 0;
      ViewRenderer r2(quiet, setup.camera, setup.seed);
      UseRawMask(raw_mask, r2);  // the same camera: its calibration, not another
      empty = RenderScene(quiet, MakeGridOptions(setup, FrameProtocol{}), r2,
                          [&](int d, int t) { Progress("eval-homing", "rendering " + quiet.name + " without people", d, t); });
    }
    const std::string header =
        std::string("| method | ALV | landmarks |") + (fused ? " fusion | frames home/current |" : "") +
        " AAE [deg] | median | no answer | return ratio | ms/frame | landmarks/view | matches |" +
        (empty ? " AAE without people | degradation |" : "") + "\n|---|---|---|" + (fused ? "---|---|" : "") +
        "---|---|---|---|---|---|---|" + (empty ? "---|---|" : "") + "\n";
    md << "## " << scene.name << " (" << scene.grid.nx << "x" << scene.grid.ny << " grid"
       << (people ? ", " + std::to_string(scene.people.count) + " people walking" : std::string()) << ")\n\n";
    auto emit = [&](const Row& r) { rows.push_back(r); };
    auto vector_map = [&](const GridResult& res, const std::string& label, double aae, const ReturnResult* ret,
                          const std::string& name) {
      plot::SavePng(DrawVectorMap(g.db, res,
                                  scene.name + " " + label + ": AAE " + Fixed(aae, 1) + " deg" +
                                      (ret ? ", return " + Fixed(ret->ratio, 2) : std::string()),
                                  ret),
                    (out / name).string());
      figures.push_back(name);
    };
    // The fused configurations: the home view alone, and the home and current views.
    struct Fusion {
      nav::ViewFusion mode;
      int home, current;
    };
    std::vector<Fusion> fusions;
    if (fused) {
      for (const auto mode : {nav::ViewFusion::kPersistent, nav::ViewFusion::kMedian}) {
        if (fp.home_frames > 1) fusions.push_back({mode, fp.home_frames, 1});
        if (fp.current_frames > 1) fusions.push_back({mode, fp.home_frames, fp.current_frames});
      }
    }
    std::vector<plot::BarGroup> groups;
    // HOG (chapter 3) with the homing config; fused by the median panorama.
    {
      HogMethod hog(setup.hog, setup.camera.panorama);
      hog.SetMask(mask);
      const auto res = EvaluatePanoramas(g.db, g.panos, hog);
      Row r{scene.name, "hog", "hog", "cells"};
      r.aae = res.aae_deg;
      r.median = res.median_deg;
      r.failures = res.failures;
      r.positions = res.positions;
      r.ms = res.method_calls ? res.seconds_in_method * 1000 / res.method_calls : kNaN;
      if (empty) r.aae_without_people = EvaluatePanoramas(empty->db, empty->panos, hog).aae_deg;
      ReturnResult ret;
      if (options.returns) {
        ret = EvaluateReturn(g.db, hog, renderer, pipeline, WithFrames(setup.ret, fp, 1, 1, setup.seed),
                             [](int d, int t) { Progress("eval-homing", "return runs hog", d, t); }, &g.frames);
        r.ret = ret.ratio;
      }
      emit(r);
      groups.push_back({"hog", {r.aae, kNaN, kNaN, kNaN}});
      vector_map(res, "hog", r.aae, options.returns ? &ret : nullptr, "vector_map_" + scene.name + "_hog.png");
      // HOG fuses by the median panorama: one row per frame protocol, each with its return runs.
      for (const auto& f : fusions) {
        if (f.mode != nav::ViewFusion::kMedian) continue;
        HogMethod fm(setup.hog, setup.camera.panorama, true);
        fm.SetMask(mask);
        const auto fr = EvaluateFrames(g.db, g.Frames(f.home, f.current), fm);
        Row q = r;
        q.fusion = "median";
        q.home_frames = f.home;
        q.current_frames = f.current;
        q.aae = fr.aae_deg;
        q.median = fr.median_deg;
        q.failures = fr.failures;
        q.ms = fr.method_calls ? fr.seconds_in_method * 1000 / fr.method_calls : kNaN;
        q.ret = kNaN;
        ReturnResult fret;
        if (options.returns) {
          fret = EvaluateReturn(g.db, fm, renderer, pipeline, WithFrames(setup.ret, fp, f.home, f.current, setup.seed),
                                [&](int d, int t) { Progress("eval-homing", "return runs " + q.Label(), d, t); }, &g.frames);
          q.ret = fret.ratio;
        }
        emit(q);
        vector_map(fr, q.Label(), q.aae, options.returns ? &fret : nullptr,
                   "vector_map_" + scene.name + "_hog_" + (f.current > 1 ? "fused" : "fused_home") + ".png");
      }
    }
    for (const auto method : methods) {
      nav::LandmarkExtractorConfig extractor = setup.extractor;
      extractor.method = method;
      const std::string mname = nav::LandmarkMethodName(method);
      const auto cache = ExtractAll(g.AllPanoramas(), extractor, mask);
      std::optional<LandmarkCache> empty_cache;
      if (empty) empty_cache = ExtractAll(empty->panos, extractor, mask);
      std::cerr << "eval-homing: " << scene.name << " " << mname << ": " << Fixed(cache.mean_landmarks, 1)
                << " landmarks per view, " << Fixed(cache.ms_per_panorama()) << " ms extraction\n";
      plot::BarGroup group{mname, {}};
      // Per ALV: the rows at each count, the best count; the method's best single-frame and fused rows.
      struct Best {
        double aae = 1e9;
        size_t row = 0;
        GridResult result;
        nav::LandmarkHomingConfig homing;
        FrameFusion fusion;
        int home = 1, current = 1;
      };
      Best best_single;
      std::map<int, Best> best_fused;  // by current frames: the home fused alone, and the current views too
      std::vector<std::pair<size_t, nav::LandmarkHomingConfig>> returns_wanted;  // row, config (single frames)
      for (const auto& alv : kAlvRows) {
        const auto variant = alv.variant;
        if (method == nav::LandmarkMethod::kVline && variant == nav::AlvVariant::kScale) {
          group.values.push_back(kNaN);
          continue;
        }
        std::vector<Row> vrows;
        std::vector<GridResult> vresults;
        int best = 0;
        for (const int n : options.top_n) {
          auto homing = WithAlv(setup.homing(method), variant, n);
          homing.alv.consensus = alv.consensus;
          LandmarkMethod m(extractor, homing, setup.camera.panorama, &cache);
          m.SetMask(mask);
          const auto res = EvaluatePanoramas(g.db, g.panos, m);
          Row r{scene.name, mname, alv.label, NText(n)};
          r.aae = res.aae_deg;
          r.median = res.median_deg;
          r.failures = res.failures;
          r.positions = res.positions;
          r.ms = cache.ms_per_panorama() + (res.method_calls ? res.seconds_in_method * 1000 / res.method_calls : 0);
          r.landmarks = cache.mean_landmarks;
          r.matches = m.estimates() ? static_cast<double>(m.matches()) / m.estimates() : 0;
          if (empty) {
            LandmarkMethod me(extractor, homing, setup.camera.panorama, &*empty_cache);
            me.SetMask(mask);
            r.aae_without_people = EvaluatePanoramas(empty->db, empty->panos, me).aae_deg;
          }
          if (vrows.empty() || r.aae < vrows[best].aae) best = static_cast<int>(vrows.size());
          vrows.push_back(r);
          vresults.push_back(res);
        }
        auto best_homing = WithAlv(setup.homing(method), variant, options.top_n[best]);
        best_homing.alv.consensus = alv.consensus;
        for (size_t k = 0; k < vrows.size(); ++k) {
          emit(vrows[k]);
          if (static_cast<int>(k) == best) {
            if (!options.return_best_only) returns_wanted.push_back({rows.size() - 1, best_homing});
            if (vrows[k].aae < best_single.aae) {
              best_single = Best{vrows[k].aae, rows.size() - 1, vresults[k], best_homing, {}, 1, 1};
            }
          }
        }
        group.values.push_back(vrows[best].aae);
        // Fused views, at the variant's best count.
        for (const auto& f : fusions) {
          FrameFusion fusion = setup.fusion;
          fusion.mode = f.mode;
          LandmarkMethod m(extractor, best_homing, setup.camera.panorama, &cache, fusion);
          m.SetMask(mask);
          const auto res = EvaluateFrames(g.db, g.Frames(f.home, f.current), m);
          Row r = vrows[best];
          r.fusion = nav::ViewFusionName(f.mode);
          r.home_frames = f.home;
          r.current_frames = f.current;
          r.aae = res.aae_deg;
          r.median = res.median_deg;
          r.failures = res.failures;
          r.ret = kNaN;
          // Extraction of every frame (persistent) or of the median panorama, matching and ALV.
          const double method_ms = res.method_calls ? res.seconds_in_method * 1000 / res.method_calls : 0;
          r.ms = (f.mode == nav::ViewFusion::kPersistent ? cache.ms_per_panorama() * f.current : 0) + method_ms;
          r.matches = m.estimates() ? static_cast<double>(m.matches()) / m.estimates() : 0;
          emit(r);
          auto& bf = best_fused[f.current];
          if (r.aae < bf.aae) bf = Best{r.aae, rows.size() - 1, res, best_homing, fusion, f.home, f.current};
        }
      }
      if (options.return_best_only) returns_wanted.push_back({best_single.row, best_single.homing});
      ReturnResult best_single_return;
      if (options.returns) {
        for (const auto& [row, homing] : returns_wanted) {
          LandmarkMethod live(extractor, homing, setup.camera.panorama);
          live.SetMask(mask);
          const auto ret = EvaluateReturn(g.db, live, renderer, pipeline,
                                          WithFrames(setup.ret, fp, 1, 1, setup.seed),
                                          [&](int d, int t) { Progress("eval-homing", "return runs " + rows[row].Label(), d, t); },
                                          &g.frames);
          rows[row].ret = ret.ratio;
          if (row == best_single.row) best_single_return = ret;
        }
      }
      groups.push_back(group);
      vector_map(best_single.result, rows[best_single.row].Label(), best_single.aae,
                 options.returns ? &best_single_return : nullptr, "vector_map_" + scene.name + "_" + mname + ".png");
      for (const auto& [current, bf] : best_fused) {
        ReturnResult fret;
        if (options.returns) {
          LandmarkMethod live(extractor, bf.homing, setup.camera.panorama, nullptr, bf.fusion);
          live.SetMask(mask);
          fret = EvaluateReturn(g.db, live, renderer, pipeline, WithFrames(setup.ret, fp, bf.home, bf.current, setup.seed),
                                [&](int d, int t) { Progress("eval-homing", "return runs " + rows[bf.row].Label(), d, t); },
                                &g.frames);
          rows[bf.row].ret = fret.ratio;
        }
        vector_map(bf.result, rows[bf.row].Label(), bf.aae, options.returns ? &fret : nullptr,
                   "vector_map_" + scene.name + "_" + mname + "_" + (current > 1 ? "fused" : "fused_home") + ".png");
      }
    }
    // This scene's tables (after the return runs).
    {
      std::ostringstream single, fused_rows;
      for (const auto& r : rows) {
        if (r.scene != scene.name) continue;
        std::ostream& o = r.fusion == "none" ? static_cast<std::ostream&>(single) : fused_rows;
        o << "| " << r.method << " | " << r.alv << " | " << r.n << " |"
          << (fused ? " " + r.fusion + " | " + r.Frames() + " |" : std::string()) << " " << Fixed(r.aae) << " | "
          << Fixed(r.median) << " | " << r.failures << " | " << OrDash(r.ret, 3) << " | " << OrDash(r.ms, 2) << " | "
          << OrDash(r.landmarks, 1) << " | " << OrDash(r.matches, 1) << " |"
          << (empty ? " " + OrDash(r.aae_without_people, 2) + " | " + OrDash(r.aae - r.aae_without_people, 2) + " |"
                    : std::string())
          << "\n";
      }
      if (fused) md << "### Single frames (the thesis' protocol)\n\n";
      md << header << single.str();
      if (fused) {
        md << "\n### Fused views (snapnav): the robot stands still while the people walk\n\n"
           << "The home view from " << fp.home_frames << " frames " << Fixed(fp.home_interval_s, 1)
           << " s apart (frames home/current " << fp.home_frames << "/1); also each current view from "
           << fp.current_frames << " frames " << Fixed(fp.current_interval_s, 1) << " s apart (" << fp.home_frames
           << "/" << fp.current_frames << ", a robot that pauses to look; the return runs pause so at every step). "
           << "persistent: the landmarks found again at the same place in at least "
           << Fixed(setup.fusion.persistence.min_fraction * 100, 0)
           << "% of the frames; median: landmarks of the per-pixel median panorama (HOG: its median panorama). "
              "Each ALV at its best count above. The room without people gives identical frames, so its AAE is the "
              "single-frame one.\n\n"
           << header << fused_rows.str();
      }
    }
    plot::Axes axes;
    axes.title = "AAE by method and ALV, best landmark count (" + scene.name + ")";
    axes.x_label = "method";
    axes.y_label = "average angular error [deg]";
    axes.value_labels = true;
    const std::string chart = "aae_by_method_" + scene.name + ".png";
    plot::SavePng(plot::BarChart(axes, {"unit (hog: cells)", "weighted", "scale", "scale+consensus"}, groups),
                  (out / chart).string());
    figures.push_back(chart);
    md << "\n![AAE by method](" << chart << ")\n\n";
  }

  // Summary: the best landmark configuration per scene (single frames, and fused), weighted vs unit with all matches.
  std::map<std::string, const Row*> best_per_scene, best_fused_per_scene;
  std::map<std::pair<std::string, std::string>, const Row*> best_single_method, best_home_method, best_fused_method;
  for (const auto& r : rows) {
    auto& bm = (r.fusion == "none" ? best_single_method
                : r.current_frames == 1 ? best_home_method
                                        : best_fused_method)[{r.scene, r.method}];
    if (!bm || r.aae < bm->aae) bm = &r;
    if (r.method == "hog") continue;
    auto& b = (r.fusion == "none" ? best_per_scene : best_fused_per_scene)[r.scene];
    if (!b || r.aae < b->aae) b = &r;
  }
  md << "## Summary\n\n| scene | best landmark configuration, single frames | AAE [deg] | return ratio | AAE without "
        "people | degradation |\n|---|---|---|---|---|---|\n";
  for (const auto& [scene, r] : best_per_scene) {
    md << "| " << scene << " | " << r->Label() << " | " << Fixed(r->aae) << " | " << OrDash(r->ret, 3) << " | "
       << OrDash(r->aae_without_people, 2) << " | " << OrDash(r->aae - r->aae_without_people, 2) << " |\n";
  }
  if (!best_home_method.empty() || !best_fused_method.empty()) {
    md << "\nEach method's best configuration: single frames (the thesis' protocol), the home fused, the home and the "
          "current views fused (AAE [deg] / return ratio; degradation against the room without people):\n\n"
       << "| scene | method | best single-frame | AAE / return | best, home fused | AAE / return | best, home and "
          "current fused | AAE / return | AAE without people | degradation: single / home / both |\n"
       << "|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& [key, s1] : best_single_method) {
      if (!best_home_method.count(key) && !best_fused_method.count(key)) continue;
      const Row* h = best_home_method.count(key) ? best_home_method[key] : nullptr;
      const Row* f = best_fused_method.count(key) ? best_fused_method[key] : nullptr;
      auto cell = [](const Row* r) { return r ? r->Label() + " | " + Fixed(r->aae) + " / " + OrDash(r->ret, 3) : std::string("- | -"); };
      auto deg = [](const Row* r) { return r ? OrDash(r->aae - r->aae_without_people, 2) : std::string("-"); };
      md << "| " << key.first << " | " << key.second << " | " << cell(s1) << " | " << cell(h) << " | " << cell(f)
         << " | " << OrDash(s1->aae_without_people, 2) << " | " << deg(s1) << " / " << deg(h) << " / " << deg(f) << " |\n";
    }
  }
  md << "\nWeighted against unit ALV with all matches (thesis 4.3.2):\n\n| scene | method | unit AAE | weighted AAE |\n"
     << "|---|---|---|---|\n";
  for (const auto& u : rows) {
    if (u.alv != "unit" || u.n != "all" || u.fusion != "none") continue;
    for (const auto& w : rows) {
      if (w.scene == u.scene && w.method == u.method && w.alv == "weighted" && w.n == "all" && w.fusion == "none") {
        md << "| " << u.scene << " | " << u.method << " | " << Fixed(u.aae) << " | " << Fixed(w.aae) << " |\n";
      }
    }
  }
  std::ofstream(out / "compare.md") << md.str();
  std::ofstream csv(out / "compare.csv");
  csv << "scene,method,alv,landmarks,fusion,home_frames,current_frames,aae_deg,median_deg,no_answer,positions,"
         "return_ratio,ms_per_frame,landmarks_per_view,matches,aae_without_people_deg\n";
  for (const auto& r : rows) {
    csv << r.scene << "," << r.method << "," << r.alv << "," << r.n << "," << r.fusion << "," << r.home_frames << ","
        << r.current_frames << "," << Fixed(r.aae, 3) << "," << Fixed(r.median, 3) << "," << r.failures << ","
        << r.positions << "," << OrDash(r.ret, 4) << "," << OrDash(r.ms, 3) << "," << OrDash(r.landmarks, 2) << ","
        << OrDash(r.matches, 2) << "," << OrDash(r.aae_without_people, 3) << "\n";
  }
  auto num = [](double v) { return results::Rounded(v, 4); };
  auto row_json = [&](const Row& r) {
    results::Json j;
    j["scene"] = r.scene;
    j["method"] = r.method;
    j["alv"] = r.alv;
    j["landmarks"] = r.n;
    j["fusion"] = r.fusion;
    j["home_frames"] = r.home_frames;
    j["current_frames"] = r.current_frames;
    j["aae_deg"] = num(r.aae);
    j["median_deg"] = num(r.median);
    j["no_answer"] = r.failures;
    j["return_ratio"] = num(r.ret);
    j["ms_per_frame"] = num(r.ms);
    j["landmarks_per_view"] = num(r.landmarks);
    j["matches"] = num(r.matches);
    j["aae_without_people_deg"] = num(r.aae_without_people);
    return j;
  };
  auto best_map = [&](const std::map<std::string, const Row*>& m) {
    results::Json j = results::Json::object();
    for (const auto& [scene, r] : m) j[scene] = row_json(*r);
    return j;
  };
  results::Json json;
  json["camera"] = setup.camera.optics.enabled ? "realistic" : "clean";
  json["mask"] = setup.mask;
  json["best_per_scene"] = best_map(best_per_scene);
  json["best_fused_per_scene"] = best_map(best_fused_per_scene);
  json["rows"] = results::Json::array();
  for (const auto& r : rows) json["rows"].push_back(row_json(r));
  json["figures"] = figures;
  results::WriteJsonFile((out / "summary.json").string(), json);
  std::cout << md.str();
  std::cerr << "eval-homing: wrote " << (out / "compare.md").string() << ", compare.csv, summary.json and "
            << figures.size() << " figures\n";
  return 0;
}

}  // namespace snapnav::eval
