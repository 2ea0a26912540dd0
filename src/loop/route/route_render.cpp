#include <cmath>
#include <opencv2/imgproc.hpp>

#include "binbow/error.h"
#include "binbow/loop/route.h"

namespace binbow::loop {

cv::Mat render_route_frame(const Route& route, std::size_t index, const cv::Mat& photograph) {
  if (index >= route.frames.size())
    throw InvalidArgument("render_route_frame: frame " + std::to_string(index) + " of " +
                          std::to_string(route.frames.size()));
  if (photograph.type() != CV_8UC1)
    throw InvalidArgument("render_route_frame: the photograph must be grey");
  const RouteFrame& frame = route.frames[index];
  const cv::Size size(route.options.width, route.options.height);
  // The homography maps frame pixels to photograph pixels: the inverse map
  // warpPerspective samples with. Views stay inside their cell, so no border
  // is ever sampled.
  cv::Mat view;
  cv::warpPerspective(photograph, view,
                      cv::Mat(3, 3, CV_64F, const_cast<double*>(frame.homography.data())), size,
                      cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REFLECT);
  cv::Mat table(1, 256, CV_8U);
  for (int v = 0; v < 256; ++v)
    table.at<std::uint8_t>(v) = cv::saturate_cast<std::uint8_t>(
        frame.gain * 255 * std::pow(v / 255.0, frame.gamma) + frame.bias);
  cv::LUT(view, table, view);
  if (frame.blur_sigma > 0.05) cv::GaussianBlur(view, view, cv::Size(), frame.blur_sigma);
  if (frame.noise_sigma > 0) {
    // cv::RNG is OpenCV's own generator: the same noise for the same seed.
    cv::Mat noise(size, CV_32F);
    cv::RNG rng(frame.noise_seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, frame.noise_sigma);
    cv::Mat sum;
    view.convertTo(sum, CV_32F);
    sum += noise;
    sum.convertTo(view, CV_8U);
  }
  return view;
}

}  // namespace binbow::loop
