// eval-features' app (feature_validation.hpp): our SURF (libnav/surf) validated against OpenCV's SIFT on
// real images under known transforms (rotation, scale, Gaussian blur): repeatability of the keypoints,
// precision of ratio-test matches against the ground truth, keypoint counts and time per image; and
// extraction + matching time on a 720 x 120 panorama, the size homing works on.
//
// Repeatability (after Mikolajczyk et al.): keypoints of the original image A and the
// transformed image B are kept when they lie at least kMarginPx inside both images (mapped
// through the known transform); a kept keypoint of A is repeated when B has a kept keypoint
// within kRepeatPx of its mapped position whose size is within a factor kScaleTolerance of its
// mapped size. Repeatability = repeated / min(kept in A, kept in B).
// Precision: each kept keypoint of A is matched to its nearest neighbour among the kept
// keypoints of B (L2 on the descriptors) with Lowe's ratio test (kRatio); a match is correct
// when B's keypoint lies within kCorrectPx of the mapped position. Precision = correct /
// matches; matching score = correct / min(kept in A, kept in B).
#include "feature_validation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>
#include <numeric>
#include <sstream>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "report_text.hpp"
#include "results.hpp"
#include "stats.hpp"
#include "timing.hpp"
#include "snapnav/glue/flags.hpp"
#include "snapnav/nav/landmarks/surf.hpp"

namespace {

namespace fs = std::filesystem;
using namespace snapnav;
using eval::Fixed;
using eval::Mean;
using eval::Median;

constexpr double kMarginPx = 16;         // keypoints this close to an image border are left out
constexpr double kRepeatPx = 2.5;        // repeated: a keypoint of B this close to the mapped position
constexpr double kScaleTolerance = 1.5;  // ... whose size is within this factor of the mapped size
constexpr double kCorrectPx = 3.0;       // correct match: within this distance of the mapped position
constexpr double kRatio = 0.8;           // Lowe's ratio test

const char* const kDefaultDataDir = "/usr/share/doc/opencv-doc/examples/data";
const char* const kDefaultImages[] = {"graf1.png", "box.png", "building.jpg", "home.jpg", "baboon.jpg", "leuvenA.jpg"};

// Keypoints of one detector on one image: positions, sizes (each detector's own KeyPoint::size
// convention; only compared within a detector) and descriptor rows.
struct Features {
  std::vector<cv::Point2f> points;
  std::vector<float> sizes;
  cv::Mat descriptors;
  int size() const { return static_cast<int>(points.size()); }
};

struct Detector {
  std::string key;   // summary.json prefix
  std::string name;  // table heading
  std::function<Features(const cv::Mat&)> run;
};

std::vector<Detector> MakeDetectors(const nav::SurfOptions& surf) {
  nav::SurfOptions upright = surf;
  upright.upright = true;
  const auto ours = [](const nav::SurfOptions& options) {
    return [options](const cv::Mat& gray) {
      const nav::LandmarkSet set = nav::DetectSurf(gray, options);
      Features f;
      for (const nav::Landmark& l : set.landmarks) {
        f.points.emplace_back(l.x_px, l.y_px);
        f.sizes.push_back(l.scale_px);
      }
      f.descriptors = set.descriptors;
      return f;
    };
  };
  const cv::Ptr<cv::SIFT> sift = cv::SIFT::create();
  return {{"surf", "SURF", ours(surf)},
          {"usurf", "U-SURF", ours(upright)},
          {"sift", "SIFT (OpenCV)", [sift](const cv::Mat& gray) {
             std::vector<cv::KeyPoint> keypoints;
             Features f;
             sift->detectAndCompute(gray, cv::noArray(), keypoints, f.descriptors);
             for (const cv::KeyPoint& k : keypoints) {
               f.points.push_back(k.pt);
               f.sizes.push_back(k.size);
             }
             return f;
           }}};
}

// A known transform of an image: B = warp(A), positions map by the 2x3 affine A -> B.
struct Transformed {
  std::string name;   // "rotate 30", "scale 0.5", "blur 2"
  std::string group;  // rotation, scale, blur
  cv::Mat image;
  cv::Matx23d affine;
};

Transformed Rotate(const cv::Mat& image, double angle_deg) {
  // Turned counter-clockwise on screen about the centre, on a canvas that holds the whole image;
  // the corners are filled by reflection rather than black so they add no straight edges.
  const cv::Point2f center((image.cols - 1) * 0.5f, (image.rows - 1) * 0.5f);
  cv::Mat m = cv::getRotationMatrix2D(center, angle_deg, 1.0);
  const cv::Rect2f box =
      cv::RotatedRect(center, cv::Size2f(image.size()), static_cast<float>(-angle_deg)).boundingRect2f();
  const int width = static_cast<int>(std::lround(box.width)), height = static_cast<int>(std::lround(box.height));
  m.at<double>(0, 2) += (width - 1) * 0.5 - center.x;
  m.at<double>(1, 2) += (height - 1) * 0.5 - center.y;
  Transformed t;
  t.name = "rotate " + Fixed(angle_deg, 0);
  t.group = "rotation";
  cv::warpAffine(image, t.image, m, cv::Size(width, height), cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
  t.affine = cv::Matx23d(m);
  return t;
}

Transformed Scale(const cv::Mat& image, double zoom) {
  Transformed t;
  t.name = "scale " + Fixed(zoom, zoom == std::floor(zoom) ? 0 : 2);
  t.group = "scale";
  cv::resize(image, t.image, cv::Size(), zoom, zoom, zoom < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
  // cv::resize maps pixel centres: x_B = (x_A + 0.5) zoom' - 0.5 with the realised zoom per axis.
  const double zx = static_cast<double>(t.image.cols) / image.cols, zy = static_cast<double>(t.image.rows) / image.rows;
  t.affine = cv::Matx23d(zx, 0, 0.5 * zx - 0.5, 0, zy, 0.5 * zy - 0.5);
  return t;
}

Transformed Blur(const cv::Mat& image, double sigma_px) {
  Transformed t;
  t.name = "blur " + Fixed(sigma_px, 0);
  t.group = "blur";
  cv::GaussianBlur(image, t.image, cv::Size(), sigma_px);
  t.affine = cv::Matx23d(1, 0, 0, 0, 1, 0);
  return t;
}

std::vector<Transformed> MakeTransforms(const cv::Mat& image) {
  std::vector<Transformed> out;
  for (const double a : {15.0, 30.0, 45.0, 90.0, 180.0}) out.push_back(Rotate(image, a));
  for (const double z : {0.5, 0.75, 1.5, 2.0}) out.push_back(Scale(image, z));
  for (const double s : {1.0, 2.0, 3.0}) out.push_back(Blur(image, s));
  return out;
}

cv::Point2f Map(const cv::Matx23d& m, const cv::Point2f& p) {
  return {static_cast<float>(m(0, 0) * p.x + m(0, 1) * p.y + m(0, 2)),
          static_cast<float>(m(1, 0) * p.x + m(1, 1) * p.y + m(1, 2))};
}

bool Inside(const cv::Point2f& p, const cv::Size& size) {
  return p.x >= kMarginPx && p.y >= kMarginPx && p.x <= size.width - 1 - kMarginPx &&
         p.y <= size.height - 1 - kMarginPx;
}

struct PairResult {
  int kept_a = 0, kept_b = 0, repeated = 0, matches = 0, correct = 0;
  double repeatability() const { return Ratio(repeated, std::min(kept_a, kept_b)); }
  double precision() const { return Ratio(correct, matches); }
  double matching_score() const { return Ratio(correct, std::min(kept_a, kept_b)); }
  static double Ratio(int a, int b) { return b > 0 ? std::min(1.0, static_cast<double>(a) / b) : 0.0; }
};

PairResult Compare(const Features& a, const cv::Size& size_a, const Features& b, const cv::Size& size_b,
                   const cv::Matx23d& affine) {
  cv::Matx23d inverse;
  cv::invertAffineTransform(affine, inverse);
  const double zoom = std::sqrt(std::abs(affine(0, 0) * affine(1, 1) - affine(0, 1) * affine(1, 0)));

  std::vector<int> kept_a, kept_b;
  for (int i = 0; i < a.size(); ++i) {
    if (Inside(a.points[i], size_a) && Inside(Map(affine, a.points[i]), size_b)) kept_a.push_back(i);
  }
  for (int j = 0; j < b.size(); ++j) {
    if (Inside(b.points[j], size_b) && Inside(Map(inverse, b.points[j]), size_a)) kept_b.push_back(j);
  }
  PairResult r;
  r.kept_a = static_cast<int>(kept_a.size());
  r.kept_b = static_cast<int>(kept_b.size());
  if (kept_a.empty() || kept_b.empty()) return r;

  // Repeatability: B's kept keypoints sorted by x, searched in a window around each mapped point.
  std::vector<int> by_x = kept_b;
  std::sort(by_x.begin(), by_x.end(), [&b](int p, int q) { return b.points[p].x < b.points[q].x; });
  for (const int i : kept_a) {
    const cv::Point2f p = Map(affine, a.points[i]);
    const float mapped_size = static_cast<float>(a.sizes[i] * zoom);
    auto it = std::lower_bound(by_x.begin(), by_x.end(), p.x - kRepeatPx,
                               [&b](int j, double x) { return b.points[j].x < x; });
    for (; it != by_x.end() && b.points[*it].x <= p.x + kRepeatPx; ++it) {
      const float ratio = b.sizes[*it] / mapped_size;
      if (cv::norm(b.points[*it] - p) <= kRepeatPx && ratio <= kScaleTolerance && ratio >= 1 / kScaleTolerance) {
        ++r.repeated;
        break;
      }
    }
  }

  // Matching precision with the ratio test.
  cv::Mat query(r.kept_a, a.descriptors.cols, a.descriptors.type()),
      train(r.kept_b, b.descriptors.cols, b.descriptors.type());
  for (int k = 0; k < r.kept_a; ++k) a.descriptors.row(kept_a[k]).copyTo(query.row(k));
  for (int k = 0; k < r.kept_b; ++k) b.descriptors.row(kept_b[k]).copyTo(train.row(k));
  std::vector<std::vector<cv::DMatch>> knn;
  cv::BFMatcher(cv::NORM_L2).knnMatch(query, train, knn, 2);
  for (const auto& m : knn) {
    if (m.empty() || (m.size() == 2 && !(m[0].distance < kRatio * m[1].distance))) continue;
    ++r.matches;
    const cv::Point2f truth = Map(affine, a.points[kept_a[m[0].queryIdx]]);
    if (cv::norm(b.points[kept_b[m[0].trainIdx]] - truth) <= kCorrectPx) ++r.correct;
  }
  return r;
}

// Time of one detector on one image: medians over the runs of the process CPU time (all threads;
// robust to other load on the machine) and of the wall time.
struct Timing {
  double cpu_ms = 0, wall_ms = 0;
};

// Runs every detector `runs` times on `gray`, in turns (so that load changes hit them alike);
// the features of each detector's last run go to `features`.
std::map<std::string, Timing> TimeDetectors(const std::vector<Detector>& detectors, const cv::Mat& gray, int runs,
                                            std::map<std::string, Features>* features) {
  std::map<std::string, std::vector<double>> cpu, wall;
  for (int k = 0; k < runs; ++k) {
    for (const Detector& d : detectors) {
      const std::clock_t cpu_start = std::clock();
      const auto wall_start = std::chrono::steady_clock::now();
      (*features)[d.key] = d.run(gray);
      wall[d.key].push_back(eval::MsSince(wall_start));
      cpu[d.key].push_back(1000.0 * static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC);
    }
  }
  std::map<std::string, Timing> out;
  for (const Detector& d : detectors) out[d.key] = {Median(cpu[d.key]), Median(wall[d.key])};
  return out;
}

std::vector<std::string> ImagePaths(const std::string& spec) {
  std::vector<std::string> paths;
  if (spec.empty()) {
    for (const char* name : kDefaultImages) {
      const fs::path p = fs::path(kDefaultDataDir) / name;
      if (fs::is_regular_file(p)) {
        paths.push_back(p.string());
      } else {
        std::cerr << "eval-features: default image " << p.string() << " not found, skipped\n";
      }
    }
    if (paths.empty()) {
      throw std::runtime_error(std::string("none of the default images is in ") + kDefaultDataDir +
                               " (install opencv-doc or pass --images)");
    }
    return paths;
  }
  for (const std::string& item : glue::SplitList(spec)) {
    if (fs::is_directory(item)) {
      std::vector<std::string> files;
      for (const auto& entry : fs::directory_iterator(item)) {
        std::string ext = entry.path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
        if (entry.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" ||
                                        ext == ".ppm" || ext == ".bmp" || ext == ".tif" || ext == ".tiff")) {
          files.push_back(entry.path().string());
        }
      }
      if (files.empty()) throw std::runtime_error("--images " + item + ": no image files in this folder");
      std::sort(files.begin(), files.end());
      paths.insert(paths.end(), files.begin(), files.end());
    } else {
      paths.push_back(item);
    }
  }
  return paths;
}

cv::Mat ReadGray(const std::string& path) {
  if (!fs::exists(path)) throw std::runtime_error("image " + path + ": no such file");
  cv::Mat gray = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (gray.empty()) throw std::runtime_error("image " + path + ": cannot be read as an image");
  return gray;
}

// A 720 x 120 panorama-like strip when none is given: the middle band of an image scaled to 720
// columns.
cv::Mat PanoramaLike(const cv::Mat& gray) {
  cv::Mat wide;
  const double zoom = 720.0 / gray.cols;
  cv::resize(gray, wide, cv::Size(720, std::max(120, static_cast<int>(std::lround(gray.rows * zoom)))), 0, 0,
             zoom < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
  return wide(cv::Rect(0, (wide.rows - 120) / 2, 720, 120)).clone();
}

struct Row {
  std::string image, transform, group, detector;
  PairResult result;
};

}  // namespace

namespace snapnav::eval {

bool EvalFeaturesApp::Initialize(int argc, char** argv) {
  glue::Flags flags("eval-features",
                    "Validates our SURF (and U-SURF) against OpenCV's SIFT: on each image under rotation (15, 30,\n"
                    "45, 90, 180 deg), scale (0.5, 0.75, 1.5, 2) and Gaussian blur (sigma 1, 2, 3 px), the\n"
                    "repeatability of the keypoints and the precision of ratio-test (0.8) matches against the\n"
                    "known transform; keypoints and median time per image; extraction + matching time on a\n"
                    "720 x 120 panorama. Writes OUT/features.md, features.csv, timing.csv and summary.json.");
  flags.AddString("images", &images_spec,
                  std::string("comma-separated image files or folders (default: graf1, box, building, home, baboon, "
                              "leuvenA from ") +
                      kDefaultDataDir + ")");
  flags.AddString("panorama", &panorama_path,
                  "a panorama image for the timing (default: a 720 x 120 strip of the first image)");
  flags.AddString("out", &out_dir, "output folder (required)");
  flags.AddInt("runs", &runs, "timing runs per image and detector (the median is reported)");
  flags.AddInt("threads", &threads, "OpenCV threads (SIFT is parallel; our SURF runs on one core)");
  flags.AddDouble("hessian-threshold", &surf.hessian_threshold, "SURF: det(H) threshold, grey levels^2");
  flags.AddInt("octaves", &surf.octaves, "SURF: octaves");
  if (!flags.Parse(argc, argv)) return false;
  if (out_dir.empty()) throw glue::FlagError("--out DIR is required");
  if (runs < 1) throw glue::FlagError("--runs must be >= 1");
  if (threads < 1) throw glue::FlagError("--threads must be >= 1");
  surf.Validate();
  return true;
}

int EvalFeaturesApp::Run() {
  cv::setNumThreads(threads);

  // Read every image first, so a bad path fails before the long run.
  const std::vector<std::string> paths = ImagePaths(images_spec);
  std::vector<cv::Mat> images;
  for (const std::string& p : paths) images.push_back(ReadGray(p));
  const cv::Mat panorama = panorama_path.empty() ? PanoramaLike(images.front()) : ReadGray(panorama_path);
  fs::create_directories(out_dir);
  const fs::path out(out_dir);

  const std::vector<Detector> detectors = MakeDetectors(surf);
  std::vector<Row> rows;
  std::map<std::string, std::vector<double>> ms_by_detector;  // per image median CPU time
  std::map<std::string, std::vector<double>> keypoints_by_detector;
  std::ostringstream timing_md;
  std::ofstream timing_csv(out / "timing.csv");
  timing_csv << "image,width_px,height_px,detector,keypoints,cpu_ms_median,wall_ms_median\n";
  timing_md << "| image | size | SURF kp | SURF ms | U-SURF ms | SIFT kp | SIFT ms | SIFT / SURF time |\n"
            << "|---|---|---:|---:|---:|---:|---:|---:|\n";
  std::vector<std::string> image_names;
  for (size_t n = 0; n < images.size(); ++n) {
    const cv::Mat& image = images[n];
    const std::string name = fs::path(paths[n]).filename().string();
    image_names.push_back(name);
    std::cerr << "eval-features: " << name << " (" << image.cols << "x" << image.rows << ")\n";
    std::map<std::string, Features> original;
    const std::map<std::string, Timing> timing = TimeDetectors(detectors, image, runs, &original);
    std::map<std::string, double> ms;
    for (const Detector& d : detectors) {
      ms[d.key] = timing.at(d.key).cpu_ms;
      ms_by_detector[d.key].push_back(ms[d.key]);
      keypoints_by_detector[d.key].push_back(original[d.key].size());
      timing_csv << name << "," << image.cols << "," << image.rows << "," << d.key << "," << original[d.key].size()
                 << "," << Fixed(timing.at(d.key).cpu_ms, 3) << "," << Fixed(timing.at(d.key).wall_ms, 3) << "\n";
    }
    timing_md << "| " << name << " | " << image.cols << "x" << image.rows << " | " << original["surf"].size() << " | "
              << Fixed(ms["surf"], 1) << " | " << Fixed(ms["usurf"], 1) << " | " << original["sift"].size() << " | "
              << Fixed(ms["sift"], 1) << " | " << Fixed(ms["sift"] / std::max(ms["surf"], 1e-9), 1) << "x |\n";
    for (const Transformed& t : MakeTransforms(image)) {
      std::cerr << "  " << t.name << ":";
      for (const Detector& d : detectors) {
        const Features b = d.run(t.image);
        const PairResult r = Compare(original[d.key], image.size(), b, t.image.size(), t.affine);
        rows.push_back({name, t.name, t.group, d.key, r});
        std::cerr << " " << d.key << " rep " << Fixed(r.repeatability()) << " prec " << Fixed(r.precision());
      }
      std::cerr << "\n";
    }
  }

  // Panorama: extraction of one panorama and matching against the same panorama turned by 45 deg
  // (columns rolled); CPU time, median of at least 9 runs.
  struct PanoramaTiming {
    int keypoints = 0;
    double extract_ms = 0, match_ms = 0;
  };
  std::map<std::string, PanoramaTiming> pano;
  {
    const int pano_runs = std::max(runs, 9);
    const int roll = panorama.cols / 8;
    cv::Mat rolled;
    cv::hconcat(panorama.colRange(roll, panorama.cols), panorama.colRange(0, roll), rolled);
    std::map<std::string, Features> a, b;
    const std::map<std::string, Timing> timing = TimeDetectors(detectors, panorama, pano_runs, &a);
    for (const Detector& d : detectors) {
      b[d.key] = d.run(rolled);
      std::vector<double> ms;
      for (int k = 0; k < pano_runs; ++k) {
        const std::clock_t start = std::clock();
        std::vector<std::vector<cv::DMatch>> knn;
        if (!a[d.key].descriptors.empty() && !b[d.key].descriptors.empty())
          cv::BFMatcher(cv::NORM_L2).knnMatch(b[d.key].descriptors, a[d.key].descriptors, knn, 2);
        ms.push_back(1000.0 * static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC);
      }
      pano[d.key] = {a[d.key].size(), timing.at(d.key).cpu_ms, Median(ms)};
    }
  }

  // Aggregates.
  const std::vector<std::string> groups = {"rotation", "scale", "blur"};
  std::vector<std::string> transform_names;
  for (const Row& r : rows) {
    if (std::find(transform_names.begin(), transform_names.end(), r.transform) == transform_names.end())
      transform_names.push_back(r.transform);
  }
  const auto mean_of = [&rows](const std::function<bool(const Row&)>& select,
                               const std::function<double(const Row&)>& value) {
    std::vector<double> v;
    for (const Row& r : rows) {
      if (select(r)) v.push_back(value(r));
    }
    return Mean(v);
  };
  const auto rep = [](const Row& r) { return r.result.repeatability(); };
  const auto prec = [](const Row& r) { return r.result.precision(); };
  const auto correct = [](const Row& r) { return static_cast<double>(r.result.correct); };
  const auto score = [](const Row& r) { return r.result.matching_score(); };

  std::ostringstream md;
  md << "# Feature validation: SURF (ours) against OpenCV SIFT\n\n"
     << "Images: ";
  for (size_t n = 0; n < image_names.size(); ++n) md << (n ? ", " : "") << image_names[n];
  md << ". SURF hessian threshold " << surf.hessian_threshold << ", " << surf.octaves << " octaves; SIFT "
     << "cv::SIFT::create() defaults. OpenCV threads: " << threads << ".\n\n"
     << "Repeatability: keypoints within " << kRepeatPx << " px of the mapped position at a size within x"
     << kScaleTolerance << ", over min(kept A, kept B) (keypoints " << kMarginPx
     << " px inside both images). Precision: correct (within " << kCorrectPx << " px) / matches after the ratio test "
     << kRatio << ". Mean over the images.\n\n"
     << "| transform | SURF rep | U-SURF rep | SIFT rep | SURF prec | U-SURF prec | SIFT prec | SURF correct | "
        "U-SURF correct | SIFT correct |\n"
     << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  const auto table_row = [&](const std::string& label, const std::function<bool(const Row&)>& select) {
    md << "| " << label;
    for (const auto& value : {std::function<double(const Row&)>(rep), std::function<double(const Row&)>(prec)}) {
      for (const char* det : {"surf", "usurf", "sift"}) {
        md << " | " << Fixed(mean_of([&](const Row& r) { return select(r) && r.detector == det; }, value), 3);
      }
    }
    for (const char* det : {"surf", "usurf", "sift"}) {
      md << " | " << Fixed(mean_of([&](const Row& r) { return select(r) && r.detector == det; }, correct), 0);
    }
    md << " |\n";
  };
  for (const std::string& t : transform_names) table_row(t, [&t](const Row& r) { return r.transform == t; });
  for (const std::string& g : groups) table_row("**" + g + "**", [&g](const Row& r) { return r.group == g; });
  table_row("**all**", [](const Row&) { return true; });

  md << "\n## Time per image (detection + description; process CPU time [ms], median of " << runs << " runs)\n\n"
     << timing_md.str();
  const double surf_ms = Mean(ms_by_detector["surf"]), usurf_ms = Mean(ms_by_detector["usurf"]),
               sift_ms = Mean(ms_by_detector["sift"]);
  md << "| **mean** | | " << Fixed(Mean(keypoints_by_detector["surf"]), 0) << " | " << Fixed(surf_ms, 1) << " | "
     << Fixed(usurf_ms, 1) << " | " << Fixed(Mean(keypoints_by_detector["sift"]), 0) << " | " << Fixed(sift_ms, 1)
     << " | " << Fixed(sift_ms / std::max(surf_ms, 1e-9), 1) << "x |\n";
  md << "\n## Panorama " << panorama.cols << "x" << panorama.rows << " ("
     << (panorama_path.empty() ? "strip of " + image_names.front() : fs::path(panorama_path).filename().string())
     << "): extraction, and matching (k = 2 nearest neighbours, brute force L2) against the panorama turned by "
        "45 deg; process CPU time [ms]\n\n"
     << "| detector | keypoints | extract ms | match ms | total ms |\n|---|---:|---:|---:|---:|\n";
  for (const Detector& d : detectors) {
    const PanoramaTiming& p = pano[d.key];
    md << "| " << d.name << " | " << p.keypoints << " | " << Fixed(p.extract_ms, 2) << " | " << Fixed(p.match_ms, 2)
       << " | " << Fixed(p.extract_ms + p.match_ms, 2) << " |\n";
  }

  {
    std::ofstream csv(out / "features.csv");
    csv << "image,transform,group,detector,kept_a,kept_b,repeated,repeatability,matches,correct_matches,precision,"
           "matching_score\n";
    for (const Row& r : rows) {
      const PairResult& p = r.result;
      csv << r.image << "," << r.transform << "," << r.group << "," << r.detector << "," << p.kept_a << "," << p.kept_b
          << "," << p.repeated << "," << Fixed(p.repeatability(), 4) << "," << p.matches << "," << p.correct << ","
          << Fixed(p.precision(), 4) << "," << Fixed(p.matching_score(), 4) << "\n";
    }
  }
  std::ofstream(out / "features.md") << md.str();

  const auto fixed = [](double v, int digits) { return results::Rounded(v, digits); };
  results::Json json;
  json["images"] = images.size();
  json["transforms"] = transform_names.size();
  json["opencv_threads"] = threads;
  json["surf_hessian_threshold"] = results::Significant(surf.hessian_threshold);
  for (const char* det : {"surf", "usurf", "sift"}) {
    const auto is = [det](const Row& r) { return r.detector == det; };
    const std::string d = det;
    json[d + "_mean_repeatability"] = fixed(mean_of(is, rep), 4);
    json[d + "_mean_precision"] = fixed(mean_of(is, prec), 4);
    json[d + "_mean_matching_score"] = fixed(mean_of(is, score), 4);
    json[d + "_mean_correct_matches"] = fixed(mean_of(is, correct), 1);
    for (const std::string& g : groups) {
      const auto in_group = [det, &g](const Row& r) { return r.detector == det && r.group == g; };
      json[d + "_" + g + "_repeatability"] = fixed(mean_of(in_group, rep), 4);
      json[d + "_" + g + "_precision"] = fixed(mean_of(in_group, prec), 4);
    }
    json[d + "_mean_keypoints"] = fixed(Mean(keypoints_by_detector[det]), 1);
    json[d + "_ms"] = fixed(Mean(ms_by_detector[det]), 3);
    json[d + "_panorama_keypoints"] = pano[det].keypoints;
    json[d + "_panorama_extract_ms"] = fixed(pano[det].extract_ms, 3);
    json[d + "_panorama_match_ms"] = fixed(pano[det].match_ms, 3);
    json[d + "_panorama_total_ms"] = fixed(pano[det].extract_ms + pano[det].match_ms, 3);
  }
  json["surf_speedup_vs_sift"] = fixed(sift_ms / std::max(surf_ms, 1e-9), 3);
  json["surf_panorama_speedup_vs_sift"] = fixed(
      (pano["sift"].extract_ms + pano["sift"].match_ms) / std::max(pano["surf"].extract_ms + pano["surf"].match_ms, 1e-9),
      3);
  json["panorama"] = panorama_path.empty() ? "strip of " + paths.front() : panorama_path;
  json["panorama_width_px"] = panorama.cols;
  json["panorama_height_px"] = panorama.rows;
  results::WriteJsonFile((out / "summary.json").string(), json);

  std::cout << md.str();
  std::cerr << "eval-features: wrote " << (out / "features.md").string()
            << ", features.csv, timing.csv, summary.json\n";
  return 0;
}

}  // namespace snapnav::eval
