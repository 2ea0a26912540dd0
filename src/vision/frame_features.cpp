#include <new>
#include <string>

#include "binbow/error.h"
#include "binbow/vision/features.h"

namespace binbow::vision {

Features extract_features(const FeatureExtractor& extractor, const cv::Mat& image,
                          const std::string& file) {
  try {
    return extractor.extract(image);
  } catch (const FileError&) {
    throw;
  } catch (const Error& e) {
    throw FileError(file, e.what());
  } catch (const std::bad_alloc&) {
    throw FileError(file, "out of memory extracting " + extractor.name() + " features from its " +
                              std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                              " pixels; downscale it (--max-width) or free memory");
  }
}

}  // namespace binbow::vision
