#include "snapnav/nav/sim/textures.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace snapnav::nav::sim {
namespace {

cv::Scalar Scaled(const cv::Vec3b& c, double f) { return cv::Scalar(c[0] * f, c[1] * f, c[2] * f); }

// Smooth value noise in [-1, 1] at `cells` control points per side.
cv::Mat ValueNoise(cv::Size size, int cells, std::mt19937_64& rng) {
  cv::Mat small(cells, cells, CV_32FC1);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (int y = 0; y < cells; ++y)
    for (int x = 0; x < cells; ++x) small.at<float>(y, x) = u(rng);
  cv::Mat big;
  cv::resize(small, big, size, 0, 0, cv::INTER_CUBIC);
  return big;
}

void AddNoise(cv::Mat* img, double amplitude, std::mt19937_64& rng) {
  cv::Mat n = ValueNoise(img->size(), 24, rng) * 0.6 + ValueNoise(img->size(), 96, rng) * 0.4;
  std::vector<cv::Mat> ch;
  cv::split(*img, ch);
  for (auto& c : ch) {
    cv::Mat f;
    c.convertTo(f, CV_32F);
    f += n * amplitude;
    f.convertTo(c, CV_8U);
  }
  cv::merge(ch, *img);
}

}  // namespace

const std::vector<std::string>& PatternKinds() {
  static const std::vector<std::string> kinds{"bricks", "tiles", "stripes", "panels", "cabinet",
                                              "window", "noise",  "plain",   "checker", "bark"};
  return kinds;
}

cv::Mat MakePattern(const std::string& kind, const cv::Vec3b& color, cv::Size size, uint64_t seed) {
  if (size.width < 8 || size.height < 8) throw std::invalid_argument("pattern size must be at least 8x8 pixels");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int w = size.width, h = size.height;
  cv::Mat img(size, CV_8UC3, Scaled(color, 1.0));
  if (kind == "bricks") {
    img.setTo(cv::Scalar(180, 185, 190));  // mortar
    const int rows = 8, cols = 4;
    const int bh = h / rows, bw = w / cols;
    for (int r = 0; r < rows; ++r) {
      const int shift = (r % 2) * bw / 2;
      for (int c = -1; c <= cols; ++c) {
        const cv::Rect rect(c * bw + shift + 2, r * bh + 2, bw - 4, bh - 4);
        cv::rectangle(img, rect, Scaled(color, 0.75 + 0.45 * u(rng)), cv::FILLED);
      }
    }
    AddNoise(&img, 10, rng);
  } else if (kind == "tiles") {
    const int n = 4;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        cv::rectangle(img, cv::Rect(x * w / n, y * h / n, w / n, h / n), Scaled(color, 0.85 + 0.25 * u(rng)), cv::FILLED);
    for (int k = 0; k <= n; ++k) {
      cv::line(img, {k * w / n, 0}, {k * w / n, h}, Scaled(color, 0.45), 3);
      cv::line(img, {0, k * h / n}, {w, k * h / n}, Scaled(color, 0.45), 3);
    }
    AddNoise(&img, 8, rng);
  } else if (kind == "stripes") {
    int x = 0;
    while (x < w) {
      const int sw = 6 + static_cast<int>(u(rng) * w / 6);
      cv::rectangle(img, cv::Rect(x, 0, sw, h), Scaled(color, 0.5 + 0.8 * u(rng)), cv::FILLED);
      x += sw;
    }
    AddNoise(&img, 6, rng);
  } else if (kind == "panels") {  // a door or wooden panelling: vertical edges, frames
    AddNoise(&img, 14, rng);
    cv::rectangle(img, cv::Rect(w / 10, h / 12, w * 8 / 10, h * 4 / 12), Scaled(color, 0.7), 4);
    cv::rectangle(img, cv::Rect(w / 10, h * 6 / 12, w * 8 / 10, h * 5 / 12), Scaled(color, 0.7), 4);
    cv::circle(img, {w * 8 / 10, h / 2}, std::max(3, w / 30), cv::Scalar(60, 170, 200), cv::FILLED);
    cv::rectangle(img, cv::Rect(0, 0, w, h), Scaled(color, 0.45), 6);
  } else if (kind == "cabinet") {  // shelves with books or boxes of random colours
    const int shelves = 5;
    for (int s = 0; s < shelves; ++s) {
      int x = 4;
      const int y0 = s * h / shelves + 6, y1 = (s + 1) * h / shelves - 2;
      while (x < w - 4) {
        const int bw = 4 + static_cast<int>(u(rng) * w / 14);
        const int top = y0 + static_cast<int>(u(rng) * (y1 - y0) / 3);
        const cv::Vec3b c(static_cast<uint8_t>(40 + 200 * u(rng)), static_cast<uint8_t>(40 + 200 * u(rng)),
                          static_cast<uint8_t>(40 + 200 * u(rng)));
        cv::rectangle(img, cv::Rect(x, top, std::min(bw, w - 4 - x), y1 - top), Scaled(c, 1.0), cv::FILLED);
        x += bw + 1;
      }
      cv::line(img, {0, (s + 1) * h / shelves - 1}, {w, (s + 1) * h / shelves - 1}, Scaled(color, 0.5), 4);
    }
    cv::rectangle(img, cv::Rect(0, 0, w, h), Scaled(color, 0.5), 6);
  } else if (kind == "window") {
    img.setTo(cv::Scalar(250, 235, 215));
    AddNoise(&img, 12, rng);
    const int n = 3;
    for (int k = 0; k <= n; ++k) cv::line(img, {k * (w - 1) / n, 0}, {k * (w - 1) / n, h}, Scaled(color, 1.0), 8);
    cv::line(img, {0, h / 2}, {w, h / 2}, Scaled(color, 1.0), 8);
    cv::rectangle(img, cv::Rect(0, 0, w, h), Scaled(color, 1.0), 10);
  } else if (kind == "noise") {
    AddNoise(&img, 28, rng);
  } else if (kind == "plain") {
    AddNoise(&img, 3, rng);
  } else if (kind == "checker") {
    const int n = 8;
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        if ((x + y) % 2) cv::rectangle(img, cv::Rect(x * w / n, y * h / n, w / n, h / n), Scaled(color, 0.35), cv::FILLED);
  } else if (kind == "bark") {
    cv::Mat n = ValueNoise({w / 8 + 1, h}, 40, rng);
    cv::resize(n, n, size, 0, 0, cv::INTER_LINEAR);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double f = 0.6 + 0.35 * n.at<float>(y, x);
        img.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<uint8_t>(color[0] * f), cv::saturate_cast<uint8_t>(color[1] * f),
                                            cv::saturate_cast<uint8_t>(color[2] * f));
      }
  } else {
    std::string known;
    for (const auto& k : PatternKinds()) known += " " + k;
    throw std::invalid_argument("unknown pattern '" + kind + "' (known:" + known + ")");
  }
  return img;
}

}  // namespace snapnav::nav::sim
