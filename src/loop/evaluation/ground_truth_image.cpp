#include <cstdint>
#include <string>

#include "binbow/error.h"
#include "binbow/vision/image_source.h"
#include "core/regular_file.h"
#include "loop/evaluation/ground_truth_readers.h"
#include "vision/image_header.h"
#include "vision/media_module.h"

namespace binbow::loop::detail {

LoadedGroundTruth read_ground_truth_image(const std::string& path,
                                          const GroundTruthOptions& options) {
  // Decoded by binbow_media alone, as vision::read_grey_image does after the
  // same checks, so that evaluating links no OpenCV.
  const std::string bytes = binbow::detail::read_regular_file(path, vision::kMaxImageFileBytes);
  const vision::ImageDimensions declared =
      vision::check_image_header(path, bytes, options.max_image_pixels);
  vision::check_image_allocation(path, declared, bytes.size(), options.max_image_pixels);
  media::GreyPixels image;
  const std::string problem = vision::media_module().decode_grey_pixels(
      reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(), image);
  if (!problem.empty()) throw FileError(path, "cannot decode image: " + problem);
  if (image.pixels.empty()) {
    throw FileError(path,
                    "cannot decode image (unknown format, corrupted, truncated or 0x0 pixels)");
  }
  vision::check_pixel_count(path, "decoded image", static_cast<std::uint64_t>(image.width),
                            static_cast<std::uint64_t>(image.height), options.max_image_pixels);
  if (image.height != image.width) {
    throw FileError(path, "ground-truth image is " + std::to_string(image.width) + "x" +
                              std::to_string(image.height) +
                              " pixels; it must be square (row = query, column = match)");
  }
  const auto pixel = [&](int row, int column) {
    return image.pixels[static_cast<std::size_t>(row) * static_cast<std::size_t>(image.width) +
                        static_cast<std::size_t>(column)];
  };
  LoadedGroundTruth loaded;
  loaded.frames = cut_to_run(static_cast<std::size_t>(image.height), options);
  // Row q lists the earlier images that share a place with q, merged from
  // row q left of the diagonal and column q above it: increasing, so the
  // runs come out sorted and whole.
  RunCollector runs(loaded.frames);
  const int n = static_cast<int>(loaded.frames);
  for (int q = 0; q < n; ++q)
    for (int j = 0; j < q; ++j)
      if (pixel(q, j) != 0 || pixel(j, q) != 0) runs.add(q, j);
  loaded.runs = runs.take();
  return loaded;
}

}  // namespace binbow::loop::detail
