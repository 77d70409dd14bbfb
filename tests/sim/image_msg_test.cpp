#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "snapnav/glue/image_msg.hpp"

namespace snapnav::glue {
namespace {

cv::Mat Sample() {
  cv::Mat m(20, 30, CV_8UC3, cv::Scalar(10, 20, 200));  // BGR: red-ish
  cv::rectangle(m, cv::Rect(5, 5, 10, 10), cv::Scalar(255, 0, 0), cv::FILLED);
  return m;
}

TEST(ImageMsg, RoundTripsEveryEncoding) {
  const cv::Mat img = Sample();
  for (const int8_t enc : {omni_frame_t::RGB8, omni_frame_t::PNG, omni_frame_t::JPEG}) {
    const omni_frame_t f = ImageToFrame(img, enc);
    EXPECT_EQ(f.width, 30);
    EXPECT_EQ(f.height, 20);
    const cv::Mat back = FrameToImage(f);
    ASSERT_EQ(back.type(), CV_8UC3);
    if (enc == omni_frame_t::JPEG) {
      EXPECT_LE(cv::norm(back, img, cv::NORM_L1) / img.total() / 3, 20.0);  // lossy: mean error (a BGR/RGB swap gives > 100)
    } else {
      EXPECT_EQ(cv::norm(back, img, cv::NORM_INF), 0) << int(enc);
    }
  }
  const omni_frame_t rgb = ImageToFrame(img, omni_frame_t::RGB8);
  EXPECT_EQ(rgb.data[0], 200);  // R first
  const omni_frame_t gray = ImageToFrame(img, omni_frame_t::GRAY8);
  EXPECT_EQ(FrameToImage(gray).type(), CV_8UC1);
}

TEST(ImageMsg, InconsistentFramesAreErrors) {
  omni_frame_t f = ImageToFrame(Sample(), omni_frame_t::RGB8);
  f.height = 21;  // more rows than data
  EXPECT_THROW(FrameToImage(f), std::invalid_argument);
  f = ImageToFrame(Sample(), omni_frame_t::RGB8);
  f.encoding = 9;
  EXPECT_THROW(FrameToImage(f), std::invalid_argument);
  f = ImageToFrame(Sample(), omni_frame_t::PNG);
  f.data.resize(10);
  f.data_size = 10;
  EXPECT_THROW(FrameToImage(f), std::invalid_argument);
  EXPECT_THROW(ImageToFrame(cv::Mat(), omni_frame_t::RGB8), std::invalid_argument);
}

}  // namespace
}  // namespace snapnav::glue
