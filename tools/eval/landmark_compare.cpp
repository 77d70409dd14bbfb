#include "landmark_compare.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>

#include "landmark_eval.hpp"
#include "report_text.hpp"
#include "scene_file.hpp"
#include "snapnav/plot/plot.hpp"

namespace snapnav::eval {
namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void Progress(const std::string& what, int done, int total) {
  if (done == total || done % 10 == 0) {
    std::cerr << "eval-homing: " << what << " " << done << "/" << total << (done == total ? "\n" : "\r") << std::flush;
  }
}

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
  double aae = kNaN, median = kNaN, ret = kNaN, ms = kNaN, landmarks = kNaN, matches = kNaN;
  int failures = 0, positions = 0;
  double aae_without_people = kNaN;  // the same scene with its people removed
};

}  // namespace

int RunLandmarkEval(const LandmarkEvalSetup& setup, const std::string& scene_name, nav::LandmarkMethod method,
                    nav::AlvVariant variant, int top_n, bool no_return, const std::string& out_dir) {
  fs::create_directories(out_dir);
  const fs::path out(out_dir);
  const auto scene = processes::LoadSceneFile(processes::SceneFilePath(scene_name));
  nav::LandmarkExtractorConfig extractor = setup.extractor;
  extractor.method = method;
  const auto homing = WithAlv(setup.homing(method), variant, top_n);
  const std::string label = LandmarkLabel(method, variant, top_n);
  std::cerr << "eval-homing: scene " << scene.name << ", " << scene.grid.nx << "x" << scene.grid.ny << " grid, " << label
            << "\n";
  ViewRenderer renderer(scene, setup.camera, setup.seed);
  const Grid g = RenderScene(scene, setup.input, setup.seed, renderer,
                             [&](int d, int t) { Progress("rendering " + scene.name, d, t); });
  const auto cache = ExtractAll(g.panos, extractor);
  LandmarkMethod m(extractor, homing, setup.camera.panorama, &cache);
  const auto result = EvaluatePanoramas(g.db, g.panos, m);
  const double ms = cache.ms_per_panorama() + (result.method_calls ? result.seconds_in_method * 1000 / result.method_calls : 0);
  const double mean_matches = m.estimates() ? static_cast<double>(m.matches()) / m.estimates() : 0;
  std::cerr << "eval-homing: AAE " << Fixed(result.aae_deg) << " deg (median " << Fixed(result.median_deg) << ", "
            << result.failures << " without an answer), " << Fixed(cache.mean_landmarks, 1) << " landmarks and "
            << Fixed(mean_matches, 1) << " matches per view, " << Fixed(ms) << " ms per frame\n";
  ReturnResult returns;
  if (!no_return) {
    CameraPipeline pipeline;
    pipeline.input = setup.input;
    LandmarkMethod live(extractor, homing, setup.camera.panorama);
    returns = EvaluateReturn(g.db, live, renderer, pipeline, setup.ret, [](int d, int t) { Progress("return runs", d, t); });
    std::cerr << "eval-homing: return ratio " << Fixed(returns.ratio, 3) << " (" << returns.successes << "/"
              << returns.starts << ")\n";
  }
  plot::SavePng(DrawVectorMap(g.db, result,
                              scene.name + " " + label + ": AAE " + Fixed(result.aae_deg, 1) + " deg" +
                                  (no_return ? std::string() : ", return ratio " + Fixed(returns.ratio, 2)),
                              no_return ? nullptr : &returns),
                (out / "vector_map.png").string());
  std::ofstream json(out / "summary.json");
  json << "{\n  \"scene\": " << JsonString(scene.name) << ",\n  \"method\": "
       << JsonString(nav::LandmarkMethodName(method)) << ",\n  \"alv\": " << JsonString(nav::AlvVariantName(variant))
       << ",\n  \"landmarks\": " << JsonString(NText(top_n)) << ",\n  \"grid_positions\": " << result.positions
       << ",\n  \"average_angular_error_deg\": " << Fixed(result.aae_deg, 4)
       << ",\n  \"median_angular_error_deg\": " << Fixed(result.median_deg, 4)
       << ",\n  \"max_angular_error_deg\": " << Fixed(result.max_deg, 4)
       << ",\n  \"positions_without_answer\": " << result.failures
       << ",\n  \"compass_mean_error_deg\": " << Fixed(result.compass_mean_deg, 4)
       << ",\n  \"mean_landmarks_per_view\": " << Fixed(cache.mean_landmarks, 2)
       << ",\n  \"mean_matches\": " << Fixed(mean_matches, 2) << ",\n  \"ms_per_frame\": " << Fixed(ms, 3);
  if (!no_return) {
    json << ",\n  \"return_ratio\": " << Fixed(returns.ratio, 4) << ",\n  \"return_starts\": " << returns.starts
         << ",\n  \"return_successes\": " << returns.successes;
  }
  json << ",\n  \"figures\": [\"vector_map.png\"]\n}\n";
  std::ofstream(out / "report.md") << "# Homing evaluation: " << scene.name << ", " << label << "\n\n"
                                   << "| AAE [deg] | median | max | without answer | return ratio | landmarks/view | matches | ms/frame |\n"
                                   << "|---|---|---|---|---|---|---|---|\n| " << Fixed(result.aae_deg) << " | "
                                   << Fixed(result.median_deg) << " | " << Fixed(result.max_deg) << " | "
                                   << result.failures << " | " << (no_return ? "-" : Fixed(returns.ratio, 3)) << " | "
                                   << Fixed(cache.mean_landmarks, 1) << " | " << Fixed(mean_matches, 1) << " | "
                                   << Fixed(ms) << " |\n\n![vector map](vector_map.png)\n";
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
  std::vector<Row> rows;
  std::vector<std::string> figures;
  std::ostringstream md;
  md << "# Homing with feature landmarks: HOG, vertical lines, SIFT, SURF (thesis 4.1-4.3)\n\n"
     << "AAE over each scene's grid (home at the centre, all views at heading 0, the rotation estimated from the\n"
     << "matches), return ratio of closed-loop runs (step " << setup.ret.step_m << " m) for each method and ALV at\n"
     << "its best landmark count, and milliseconds per frame (extraction + matching + ALV, one core).\n"
     << "Vertical lines have no keypoint scale: their scale ALV equals the unit ALV and is not listed.\n"
     << "scale is the thesis' scale-compensated ALV (4.2.3); scale+consensus is snapnav's: the mean of the\n"
     << "per-landmark directions that agree with their mode, with the rotation refined to the best agreement.\n\n";
  for (const auto& scene_name : options.scenes) {
    const auto scene = processes::LoadSceneFile(processes::SceneFilePath(scene_name));
    ViewRenderer renderer(scene, setup.camera, setup.seed);
    const Grid g = RenderScene(scene, setup.input, setup.seed, renderer,
                               [&](int d, int t) { Progress("rendering " + scene.name, d, t); });
    // The same room without its people, for the degradation the people cause.
    std::optional<Grid> empty;
    if (scene.people.count > 0) {
      nav::sim::Scene quiet = scene;
      quiet.people.count = 0;
      ViewRenderer r2(quiet, setup.camera, setup.seed);
      empty = RenderScene(quiet, setup.input, setup.seed, r2,
                          [&](int d, int t) { Progress("rendering " + quiet.name + " without people", d, t); });
    }
    md << "## " << scene.name << " (" << scene.grid.nx << "x" << scene.grid.ny << " grid"
       << (scene.people.count > 0 ? ", " + std::to_string(scene.people.count) + " people walking" : std::string()) << ")\n\n"
       << "| method | ALV | landmarks | AAE [deg] | median | no answer | return ratio | ms/frame | landmarks/view | matches |"
       << (empty ? " AAE without people |" : "") << "\n|---|---|---|---|---|---|---|---|---|---|" << (empty ? "---|" : "")
       << "\n";
    auto emit = [&](const Row& r) {
      md << "| " << r.method << " | " << r.alv << " | " << r.n << " | " << Fixed(r.aae) << " | " << Fixed(r.median)
         << " | " << r.failures << " | " << OrDash(r.ret, 3) << " | " << OrDash(r.ms, 2) << " | "
         << OrDash(r.landmarks, 1) << " | " << OrDash(r.matches, 1) << " |"
         << (empty ? " " + OrDash(r.aae_without_people, 2) + " |" : "") << "\n";
      rows.push_back(r);
    };
    std::vector<plot::BarGroup> groups;
    // HOG (chapter 3) with the homing config.
    {
      HogMethod hog(setup.hog, setup.camera.panorama);
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
        ret = EvaluateReturn(g.db, hog, renderer, pipeline, setup.ret, [](int d, int t) { Progress("return runs hog", d, t); });
        r.ret = ret.ratio;
      }
      emit(r);
      groups.push_back({"hog", {r.aae, kNaN, kNaN, kNaN}});
      plot::SavePng(DrawVectorMap(g.db, res, scene.name + " hog: AAE " + Fixed(r.aae, 1) + " deg" +
                                                 (options.returns ? ", return " + Fixed(r.ret, 2) : std::string()),
                                  options.returns ? &ret : nullptr),
                    (out / ("vector_map_" + scene.name + "_hog.png")).string());
      figures.push_back("vector_map_" + scene.name + "_hog.png");
    }
    for (const auto method : methods) {
      nav::LandmarkExtractorConfig extractor = setup.extractor;
      extractor.method = method;
      const std::string mname = nav::LandmarkMethodName(method);
      const auto cache = ExtractAll(g.panos, extractor);
      std::optional<LandmarkCache> empty_cache;
      if (empty) empty_cache = ExtractAll(empty->panos, extractor);
      std::cerr << "eval-homing: " << scene.name << " " << mname << ": " << Fixed(cache.mean_landmarks, 1)
                << " landmarks per view, " << Fixed(cache.ms_per_panorama()) << " ms extraction\n";
      plot::BarGroup group{mname, {}};
      double best_method_aae = 1e9;
      GridResult best_method_result;
      std::string best_method_label;
      ReturnResult best_method_return;
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
            r.aae_without_people = EvaluatePanoramas(empty->db, empty->panos, me).aae_deg;
          }
          if (vrows.empty() || r.aae < vrows[best].aae) best = static_cast<int>(vrows.size());
          vrows.push_back(r);
          vresults.push_back(res);
        }
        ReturnResult ret;
        if (options.returns) {
          auto homing = WithAlv(setup.homing(method), variant, options.top_n[best]);
          homing.alv.consensus = alv.consensus;
          LandmarkMethod live(extractor, homing, setup.camera.panorama);
          ret = EvaluateReturn(g.db, live, renderer, pipeline, setup.ret, [&](int d, int t) {
            Progress("return runs " + mname + " " + alv.label, d, t);
          });
          vrows[best].ret = ret.ratio;
        }
        for (const auto& r : vrows) emit(r);
        group.values.push_back(vrows[best].aae);
        if (vrows[best].aae < best_method_aae) {
          best_method_aae = vrows[best].aae;
          best_method_result = vresults[best];
          best_method_label = mname + " " + alv.label + " " + NText(options.top_n[best]);
          best_method_return = ret;
        }
      }
      groups.push_back(group);
      const std::string name = "vector_map_" + scene.name + "_" + mname + ".png";
      plot::SavePng(DrawVectorMap(g.db, best_method_result,
                                  scene.name + " " + best_method_label + ": AAE " + Fixed(best_method_aae, 1) + " deg" +
                                      (options.returns ? ", return " + Fixed(best_method_return.ratio, 2) : std::string()),
                                  options.returns ? &best_method_return : nullptr),
                    (out / name).string());
      figures.push_back(name);
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

  // Summary: the best landmark configuration per scene, weighted vs unit with all matches.
  std::map<std::string, const Row*> best_per_scene;
  for (const auto& r : rows) {
    if (r.method == "hog") continue;
    auto& b = best_per_scene[r.scene];
    if (!b || r.aae < b->aae) b = &r;
  }
  md << "## Summary\n\n| scene | best landmark configuration | AAE [deg] | return ratio | AAE without people |\n"
     << "|---|---|---|---|---|\n";
  for (const auto& [scene, r] : best_per_scene) {
    md << "| " << scene << " | " << r->method << " " << r->alv << " " << r->n << " | " << Fixed(r->aae) << " | "
       << OrDash(r->ret, 3) << " | " << OrDash(r->aae_without_people, 2) << " |\n";
  }
  md << "\nWeighted against unit ALV with all matches (thesis 4.3.2):\n\n| scene | method | unit AAE | weighted AAE |\n"
     << "|---|---|---|---|\n";
  for (const auto& u : rows) {
    if (u.alv != "unit" || u.n != "all") continue;
    for (const auto& w : rows) {
      if (w.scene == u.scene && w.method == u.method && w.alv == "weighted" && w.n == "all") {
        md << "| " << u.scene << " | " << u.method << " | " << Fixed(u.aae) << " | " << Fixed(w.aae) << " |\n";
      }
    }
  }
  std::ofstream(out / "compare.md") << md.str();
  std::ofstream csv(out / "compare.csv");
  csv << "scene,method,alv,landmarks,aae_deg,median_deg,no_answer,positions,return_ratio,ms_per_frame,landmarks_per_view,"
         "matches,aae_without_people_deg\n";
  for (const auto& r : rows) {
    csv << r.scene << "," << r.method << "," << r.alv << "," << r.n << "," << Fixed(r.aae, 3) << "," << Fixed(r.median, 3)
        << "," << r.failures << "," << r.positions << "," << OrDash(r.ret, 4) << "," << OrDash(r.ms, 3) << ","
        << OrDash(r.landmarks, 2) << "," << OrDash(r.matches, 2) << "," << OrDash(r.aae_without_people, 3) << "\n";
  }
  auto num = [](double v) { return std::isnan(v) ? std::string("null") : Fixed(v, 4); };
  std::ofstream json(out / "summary.json");
  json << "{\n  \"best_per_scene\": {";
  bool first = true;
  for (const auto& [scene, r] : best_per_scene) {
    json << (first ? "\n" : ",\n") << "    " << JsonString(scene) << ": {\"method\": " << JsonString(r->method)
         << ", \"alv\": " << JsonString(r->alv) << ", \"landmarks\": " << JsonString(r->n)
         << ", \"aae_deg\": " << num(r->aae) << ", \"return_ratio\": " << num(r->ret)
         << ", \"aae_without_people_deg\": " << num(r->aae_without_people) << "}";
    first = false;
  }
  json << "\n  },\n  \"rows\": [";
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    json << (i ? ",\n" : "\n") << "    {\"scene\": " << JsonString(r.scene) << ", \"method\": " << JsonString(r.method)
         << ", \"alv\": " << JsonString(r.alv) << ", \"landmarks\": " << JsonString(r.n) << ", \"aae_deg\": " << num(r.aae)
         << ", \"median_deg\": " << num(r.median) << ", \"no_answer\": " << r.failures
         << ", \"return_ratio\": " << num(r.ret) << ", \"ms_per_frame\": " << num(r.ms)
         << ", \"landmarks_per_view\": " << num(r.landmarks) << ", \"matches\": " << num(r.matches)
         << ", \"aae_without_people_deg\": " << num(r.aae_without_people) << "}";
  }
  json << "\n  ],\n  \"figures\": [";
  for (size_t i = 0; i < figures.size(); ++i) json << (i ? ", " : "") << JsonString(figures[i]);
  json << "]\n}\n";
  std::cout << md.str();
  std::cerr << "eval-homing: wrote " << (out / "compare.md").string() << ", compare.csv, summary.json and "
            << figures.size() << " figures\n";
  return 0;
}

}  // namespace snapnav::eval
