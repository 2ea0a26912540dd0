// Feature extraction on 640x480 frames, one thread (cv::setNumThreads(1)):
// BRIEF-300 and its stages (FAST, Gaussian smoothing, the 256 tests), ORB-1000,
// AKAZE and BRISK, and image decoding. The paper spent 14.4 ms per 640x480
// frame on FAST + smoothing + BRIEF (2011).
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"

namespace binbow::vision {
namespace {

std::string data(const std::string& relative) {
  return std::string(BINBOW_SHARED_DATA_DIR) + "/" + relative;
}

// The four 640x480 DBoW2 demo images, cycled so that each iteration sees
// another frame, as in a sequence.
const std::vector<cv::Mat>& frames() {
  static const std::vector<cv::Mat> images = [] {
    cv::setNumThreads(1);
    std::vector<cv::Mat> loaded;
    for (int i = 0; i < 4; ++i) {
      loaded.push_back(
          read_grey_image(data("dbow2-demo-images/image" + std::to_string(i) + ".png")));
    }
    return loaded;
  }();
  return images;
}

void run_extractor(benchmark::State& state, const FeatureExtractor& extractor) {
  const std::vector<cv::Mat>& images = frames();
  std::size_t i = 0, keypoints = 0;
  for (auto _ : state) {
    const Features features = extractor.extract(images[i++ % images.size()]);
    keypoints += features.keypoints.size();
    benchmark::DoNotOptimize(features.descriptors.data());
  }
  state.counters["keypoints"] =
      benchmark::Counter(static_cast<double>(keypoints) / static_cast<double>(state.iterations()));
}

void BM_Brief(benchmark::State& state) {
  BriefOptions options;
  options.max_features = static_cast<int>(state.range(0));
  run_extractor(state, *make_brief_extractor(options));
}
BENCHMARK(BM_Brief)->Arg(300)->Arg(1000)->Unit(benchmark::kMicrosecond);

void BM_Orb(benchmark::State& state) {
  OrbOptions options;
  options.max_features = static_cast<int>(state.range(0));
  run_extractor(state, *make_orb_extractor(options));
}
BENCHMARK(BM_Orb)->Arg(300)->Arg(1000)->Unit(benchmark::kMicrosecond);

void BM_Akaze(benchmark::State& state) {
  run_extractor(state, *make_extractor("akaze", 1000));
}
BENCHMARK(BM_Akaze)->Unit(benchmark::kMillisecond);

void BM_Brisk(benchmark::State& state) {
  run_extractor(state, *make_extractor("brisk", 1000));
}
BENCHMARK(BM_Brisk)->Unit(benchmark::kMillisecond);

// The stages of BRIEF, for the record of where its time goes.
void BM_BriefStageFast(benchmark::State& state) {
  const std::vector<cv::Mat>& images = frames();
  std::size_t i = 0;
  std::vector<cv::KeyPoint> corners;
  for (auto _ : state) {
    cv::FAST(images[i++ % images.size()], corners, 10, true);
    benchmark::DoNotOptimize(corners.data());
  }
}
BENCHMARK(BM_BriefStageFast)->Unit(benchmark::kMicrosecond);

void BM_BriefStageSmoothing(benchmark::State& state) {
  const std::vector<cv::Mat>& images = frames();
  std::size_t i = 0;
  cv::Mat smoothed;
  for (auto _ : state) {
    cv::GaussianBlur(images[i++ % images.size()], smoothed, cv::Size(9, 9), 2, 2);
    benchmark::DoNotOptimize(smoothed.data);
  }
}
BENCHMARK(BM_BriefStageSmoothing)->Unit(benchmark::kMicrosecond);

void BM_ReadGreyImage(benchmark::State& state) {
  const std::string path = state.range(0) == 0 ? data("dbow2-demo-images/image1.png")
                                               : data("rtabmap-samples/samples/12.jpg");
  state.SetLabel(state.range(0) == 0 ? "640x480 png" : "512x384 jpg");
  for (auto _ : state) {
    const cv::Mat image = read_grey_image(path);
    benchmark::DoNotOptimize(image.data);
  }
}
BENCHMARK(BM_ReadGreyImage)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace binbow::vision

BENCHMARK_MAIN();
