// Argument check shared by the extractors.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "binbow/error.h"

namespace binbow::vision {

// Throws InvalidArgument unless `image` is empty or 8-bit single-channel.
inline void check_grey_image(const cv::Mat& image, const char* extractor) {
  if (!image.empty() && image.type() != CV_8UC1) {
    throw InvalidArgument(std::string(extractor) +
                          ": image must be 8-bit grey (CV_8UC1), got OpenCV type " +
                          cv::typeToString(image.type()));
  }
}

}  // namespace binbow::vision
