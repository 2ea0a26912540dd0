// Conversions between OpenCV's keypoints/descriptors and binbow's Features.
#include <cstring>

#include "binbow/error.h"
#include "binbow/vision/features.h"

namespace binbow::vision {

Features features_from_opencv(const std::vector<cv::KeyPoint>& keypoints,
                              const cv::Mat& descriptors, std::size_t empty_code_size) {
  Features features;
  if (descriptors.empty()) {
    if (!keypoints.empty()) {
      throw InvalidArgument("features_from_opencv: " + std::to_string(keypoints.size()) +
                            " keypoints but no descriptors");
    }
    features.descriptors = DescriptorMatrix(empty_code_size);
    return features;
  }
  if (descriptors.depth() != CV_8U || descriptors.channels() != 1 ||
      static_cast<std::size_t>(descriptors.rows) != keypoints.size()) {
    throw InvalidArgument(
        "features_from_opencv: descriptors must be CV_8UC1 with one row per "
        "keypoint; got type " +
        cv::typeToString(descriptors.type()) + ", " + std::to_string(descriptors.rows) +
        " rows for " + std::to_string(keypoints.size()) + " keypoints");
  }
  const auto rows = static_cast<std::size_t>(descriptors.rows);
  const auto code_size = static_cast<std::size_t>(descriptors.cols);
  features.descriptors = DescriptorMatrix(rows, code_size);
  for (std::size_t i = 0; i < rows; ++i) {
    std::memcpy(features.descriptors.row(i), descriptors.ptr(static_cast<int>(i)), code_size);
  }
  features.keypoints.reserve(rows);
  for (const cv::KeyPoint& source : keypoints) {
    Keypoint keypoint;
    keypoint.x = source.pt.x;
    keypoint.y = source.pt.y;
    keypoint.size = source.size;
    keypoint.angle = source.angle;
    keypoint.response = source.response;
    keypoint.octave = source.octave;
    features.keypoints.push_back(keypoint);
  }
  return features;
}

std::vector<cv::KeyPoint> to_opencv(const std::vector<Keypoint>& keypoints) {
  std::vector<cv::KeyPoint> converted;
  converted.reserve(keypoints.size());
  for (const Keypoint& keypoint : keypoints) {
    converted.emplace_back(cv::Point2f(keypoint.x, keypoint.y), keypoint.size, keypoint.angle,
                           keypoint.response, keypoint.octave);
  }
  return converted;
}

}  // namespace binbow::vision
