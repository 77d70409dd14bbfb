#pragma once
// eval-features (./snapnav eval features) as an app: our SURF (and U-SURF) against OpenCV's SIFT
// under known transforms: repeatability, precision of ratio-test matches, keypoints and time per
// image (feature_validation.cpp says how each is measured).
#include <string>

#include "snapnav/nav/landmarks/surf.hpp"

namespace snapnav::eval {

class EvalFeaturesApp {
 public:
  // Reads the flags into the fields below; false after --help. Throws glue::FlagError on bad flags.
  bool Initialize(int argc, char** argv);
  // Every image under every transform, the timing; writes OUT/features.md, features.csv, timing.csv, summary.json.
  int Run();

  // The flags' values (Initialize sets them; a caller may set them itself and call Run).
  std::string images_spec, out_dir, panorama_path;
  int runs = 5, threads = 1;
  nav::SurfOptions surf;
};

}  // namespace snapnav::eval
