// viewer_png_check PNG [--homing] CHANNEL...: checks a viewer snapshot is not blank. Each pose
// CHANNEL's colour must cover at least 100 pixels of the top view (a trajectory, not just its
// legend swatch), the panorama area must not be uniform, and with --homing the homing arrow's
// colour must be in the top view. Exit 0 when all hold; each failure is printed.
#include <iostream>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "viewer_render.hpp"

int main(int argc, char** argv) {
  using namespace snapnav::viewer;
  const char* usage =
      "usage: viewer_png_check PNG [--homing] CHANNEL...\n"
      "Checks a viewer snapshot is not blank: each pose CHANNEL's colour covers at least 100 pixels of\n"
      "the top view, the panorama is not uniform, and with --homing the homing arrow is drawn.\n"
      "Exit 0 when all hold; 1 when a check fails; 2 on a usage error or an unreadable PNG.\n";
  if (argc >= 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::cout << usage;
    return 0;
  }
  if (argc < 2) {
    std::cerr << usage;
    return 2;
  }
  const cv::Mat img = cv::imread(argv[1], cv::IMREAD_COLOR);
  if (img.empty()) {
    std::cerr << "viewer_png_check: cannot read " << argv[1] << "\n";
    return 2;
  }
  const Layout layout = ComputeLayout(img.size());
  auto count = [&](const cv::Scalar& colour, const cv::Rect& roi) {
    cv::Mat mask;
    cv::inRange(img(roi), colour, colour, mask);
    return cv::countNonZero(mask);
  };
  int failures = 0;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool homing = arg == "--homing";
    const int n = count(homing ? kHomingColour : ChannelColour(arg), layout.map);
    const bool ok = n >= (homing ? 30 : 100);
    std::cout << (ok ? "ok   " : "FAIL ") << (homing ? "homing arrow" : arg) << ": " << n << " pixels in the top view\n";
    failures += !ok;
  }
  cv::Mat grey;
  cv::cvtColor(img(layout.panorama), grey, cv::COLOR_BGR2GRAY);
  cv::Scalar mean, sd;
  cv::meanStdDev(grey, mean, sd);
  const bool pano_ok = sd[0] > 15;
  std::cout << (pano_ok ? "ok   " : "FAIL ") << "panorama: grey level std. dev. " << sd[0] << " (mean " << mean[0]
            << ")\n";
  failures += !pano_ok;
  return failures == 0 ? 0 : 1;
}
