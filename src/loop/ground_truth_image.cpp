#include <cstdint>
#include <string>

#include "binbow/error.h"
#include "binbow/vision/image_source.h"
#include "loop/ground_truth_readers.h"

namespace binbow::loop::detail {

LoadedGroundTruth read_ground_truth_image(const std::string& path,
                                          const GroundTruthOptions& options) {
  const cv::Mat image = vision::read_grey_image(path, options.max_image_pixels);
  if (image.rows != image.cols) {
    throw FileError(path, "ground-truth image is " + std::to_string(image.cols) + "x" +
                              std::to_string(image.rows) +
                              " pixels; it must be square (row = query, column = match)");
  }
  LoadedGroundTruth loaded;
  loaded.frames = cut_to_run(static_cast<std::size_t>(image.rows), options);
  // Row q lists the earlier images that share a place with q, merged from
  // row q left of the diagonal and column q above it: increasing, so the
  // runs come out sorted and whole.
  RunCollector runs(loaded.frames);
  const int n = static_cast<int>(loaded.frames);
  for (int q = 0; q < n; ++q) {
    const std::uint8_t* row = image.ptr<std::uint8_t>(q);
    for (int j = 0; j < q; ++j)
      if (row[j] != 0 || image.ptr<std::uint8_t>(j)[q] != 0) runs.add(q, j);
  }
  loaded.runs = runs.take();
  return loaded;
}

}  // namespace binbow::loop::detail
