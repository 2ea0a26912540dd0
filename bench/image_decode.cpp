// JPEG decoding side by side, on the 84 512x384 frames of rtabmap-samples
// (cycled, files in the page cache): binbow's reader (file read, header
// checks, libjpeg decode with the damage checks) against cv::imread, and the
// decoders alone on bytes in memory against cv::imdecode. All to 8-bit grey.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "binbow/vision/image_source.h"
#include "vision/jpeg_decoder.h"

namespace binbow::vision {
namespace {

const std::vector<std::string>& files() {
  static const std::vector<std::string> paths = [] {
    std::vector<std::string> found;
    const char* data = std::getenv("BINBOW_SHARED_DATA_DIR");  // as the tests read it
    const std::string dir =
        std::string(data != nullptr ? data : BINBOW_SHARED_DATA_DIR) + "/rtabmap-samples/samples";
    for (const auto& entry : std::filesystem::directory_iterator(dir))
      if (entry.path().extension() == ".jpg") found.push_back(entry.path().string());
    std::sort(found.begin(), found.end());
    if (found.empty()) throw std::runtime_error("no JPEG in " + dir);
    return found;
  }();
  return paths;
}

const std::vector<std::vector<std::uint8_t>>& file_bytes() {
  static const std::vector<std::vector<std::uint8_t>> all = [] {
    std::vector<std::vector<std::uint8_t>> read;
    for (const std::string& path : files()) {
      std::ifstream in(path, std::ios::binary);
      read.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    return read;
  }();
  return all;
}

template <class Decode>
void run(benchmark::State& state, Decode decode) {
  cv::setNumThreads(1);
  std::size_t i = 0;
  for (auto _ : state) {
    cv::Mat image = decode(i++ % files().size());
    benchmark::DoNotOptimize(image.data);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

void BM_BinbowReadGreyImage(benchmark::State& state) {
  run(state, [](std::size_t i) { return read_grey_image(files()[i]); });
}
BENCHMARK(BM_BinbowReadGreyImage)->Unit(benchmark::kMicrosecond);

void BM_CvImreadGrey(benchmark::State& state) {
  run(state, [](std::size_t i) { return cv::imread(files()[i], cv::IMREAD_GRAYSCALE); });
}
BENCHMARK(BM_CvImreadGrey)->Unit(benchmark::kMicrosecond);

void BM_BinbowDecodeJpeg(benchmark::State& state) {
  run(state, [](std::size_t i) {
    const std::vector<std::uint8_t>& bytes = file_bytes()[i];
    return decode_jpeg(bytes.data(), bytes.size(), true).image;
  });
}
BENCHMARK(BM_BinbowDecodeJpeg)->Unit(benchmark::kMicrosecond);

void BM_CvImdecodeGrey(benchmark::State& state) {
  run(state, [](std::size_t i) {
    const std::vector<std::uint8_t>& bytes = file_bytes()[i];
    return cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
  });
}
BENCHMARK(BM_CvImdecodeGrey)->Unit(benchmark::kMicrosecond);

// Frames wanted 128 wide (--max-width 128): binbow's ImageSource decodes at
// half size in libjpeg's inverse DCT, then resizes; OpenCV reads whole, then
// resizes.
void BM_BinbowImageSourceMaxWidth128(benchmark::State& state) {
  ImageSourceOptions options;
  options.max_width = 128;
  std::size_t i = 0;
  for (auto _ : state) {
    ImageSource source({files()[i++ % files().size()]}, options);
    Frame frame;
    source.next(frame);
    benchmark::DoNotOptimize(frame.image.data);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_BinbowImageSourceMaxWidth128)->Unit(benchmark::kMicrosecond);

void BM_CvImreadGreyResize128(benchmark::State& state) {
  run(state, [](std::size_t i) {
    const cv::Mat full = cv::imread(files()[i], cv::IMREAD_GRAYSCALE);
    cv::Mat small;
    cv::resize(full, small, cv::Size(128, full.rows * 128 / full.cols), 0, 0, cv::INTER_AREA);
    return small;
  });
}
BENCHMARK(BM_CvImreadGreyResize128)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace binbow::vision

BENCHMARK_MAIN();
