// The inputs of dvision_brief_golden.txt: an image, test pairs and
// keypoints made from fixed numbers, so that DLib's DVision::BRIEF (which
// made the golden bits) and binbow's see the same ones without an image
// file or a decoder in between. C++11, OpenCV core only.
#ifndef BINBOW_TESTS_COMPAT_VINS_BRIEF_TEST_INPUT_H
#define BINBOW_TESTS_COMPAT_VINS_BRIEF_TEST_INPUT_H

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace brief_test_input {

// Numerical Recipes' linear congruential generator.
inline std::uint32_t next(std::uint32_t& state) {
  state = state * 1664525u + 1013904223u;
  return state >> 8;
}

// 160 x 120 grey levels: a ramp, a bright disc and noise, so that both
// outcomes of a test occur and smoothing matters.
inline cv::Mat image() {
  cv::Mat im(120, 160, CV_8UC1);
  std::uint32_t state = 7;
  for (int y = 0; y < im.rows; ++y)
    for (int x = 0; x < im.cols; ++x) {
      const int dx = x - 90, dy = y - 50;
      const int disc = dx * dx + dy * dy < 900 ? 90 : 0;
      const int noise = static_cast<int>(next(state) % 64);
      im.at<unsigned char>(y, x) = static_cast<unsigned char>((x + y) / 3 + disc + noise);
    }
  return im;
}

// 256 pairs within DLib's 48-pixel patch (coordinates -24..24).
inline void pairs(std::vector<int>& x1, std::vector<int>& y1, std::vector<int>& x2,
                  std::vector<int>& y2) {
  std::uint32_t state = 11;
  x1.clear();
  y1.clear();
  x2.clear();
  y2.clear();
  for (int i = 0; i < 256; ++i) {
    x1.push_back(static_cast<int>(next(state) % 49) - 24);
    y1.push_back(static_cast<int>(next(state) % 49) - 24);
    x2.push_back(static_cast<int>(next(state) % 49) - 24);
    y2.push_back(static_cast<int>(next(state) % 49) - 24);
  }
}

// Keypoints inside, near and beyond the borders, at fractional positions
// (negative ones included: DLib truncates toward zero).
inline std::vector<cv::KeyPoint> keypoints() {
  std::vector<cv::KeyPoint> points;
  const float fixed[][2] = {{0.f, 0.f},   {-0.5f, 10.f},   {159.9f, 119.9f}, {23.5f, 60.25f},
                            {24.f, 24.f}, {135.75f, 95.f}, {80.f, 60.f},     {90.2f, 50.7f},
                            {-3.f, -3.f}, {170.f, 60.f},   {5.5f, 114.5f},   {120.f, 24.f}};
  for (std::size_t i = 0; i < sizeof(fixed) / sizeof(fixed[0]); ++i)
    points.push_back(cv::KeyPoint(fixed[i][0], fixed[i][1], 7.f));
  std::uint32_t state = 13;
  for (int i = 0; i < 28; ++i) {
    const float x = static_cast<float>(next(state) % 1600) / 10.f;
    const float y = static_cast<float>(next(state) % 1200) / 10.f;
    points.push_back(cv::KeyPoint(x, y, 7.f));
  }
  return points;
}

}  // namespace brief_test_input

#endif
