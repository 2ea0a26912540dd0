// Vocabulary building: k=10, L=5 from 150,000 real ORB descriptors, on 1 and
// 2 threads, with the mean quantisation error (bits between a training
// descriptor and its word) as a counter. The descriptors come from every image
// of rtabmap-samples, opencv-doc-samples and dbow2-demo-images at up to 2000
// features each (77k), then from the same images mirrored left–right (ORB is
// not mirror-invariant, so these are new real descriptors) until 150k.
//
// BINBOW_BENCH_DESCRIPTORS=<file> also writes the training set there (raw
// rows of 32 bytes preceded by one little-endian uint32 row count per image
// and a uint32 image count) so other libraries can be timed on the same data.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "binbow/descriptors.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "binbow/vocabulary.h"

namespace binbow::bench {
namespace {

constexpr std::size_t kMaxDescriptors = 150000;
constexpr int kFeaturesPerImage = 2000;

struct TrainingSet {
  DescriptorMatrix descriptors{32};
  std::vector<std::size_t> offsets{0};

  std::vector<DescriptorView> views() const {
    std::vector<DescriptorView> result;
    for (std::size_t i = 0; i + 1 < offsets.size(); ++i) {
      result.push_back(descriptors.view().slice(offsets[i], offsets[i + 1] - offsets[i]));
    }
    return result;
  }
};

std::vector<std::string> training_images() {
  namespace fs = std::filesystem;
  const std::string root = BINBOW_SHARED_DATA_DIR;
  std::vector<std::string> images;
  for (const char* folder :
       {"rtabmap-samples/samples", "opencv-doc-samples", "dbow2-demo-images"}) {
    std::vector<std::string> files;
    for (const auto& entry : fs::directory_iterator(root + "/" + folder)) {
      const std::string extension = entry.path().extension().string();
      if (extension == ".jpg" || extension == ".png") files.push_back(entry.path().string());
    }
    std::sort(files.begin(), files.end());
    images.insert(images.end(), files.begin(), files.end());
  }
  return images;
}

void write_training_set(const TrainingSet& set, const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return;
  const auto images = static_cast<std::uint32_t>(set.offsets.size() - 1);
  std::fwrite(&images, sizeof images, 1, file);
  for (std::size_t i = 0; i < images; ++i) {
    const auto rows = static_cast<std::uint32_t>(set.offsets[i + 1] - set.offsets[i]);
    std::fwrite(&rows, sizeof rows, 1, file);
    std::fwrite(set.descriptors.row(set.offsets[i]), 32, rows, file);
  }
  std::fclose(file);
}

const TrainingSet& training_set() {
  static const TrainingSet set = [] {
    TrainingSet result;
    const auto extractor = vision::make_extractor("orb", kFeaturesPerImage);
    const std::vector<std::string> paths = training_images();
    for (const bool mirrored : {false, true}) {
      for (const std::string& path : paths) {
        if (result.descriptors.rows() == kMaxDescriptors) break;
        cv::Mat image = vision::read_grey_image(path);
        if (mirrored) cv::flip(image, image, 1);
        const vision::Features features = extractor->extract(image);
        const std::size_t room = kMaxDescriptors - result.descriptors.rows();
        result.descriptors.append(
            features.descriptors.view().slice(0, std::min(room, features.descriptors.rows())));
        result.offsets.push_back(result.descriptors.rows());
      }
    }
    std::fprintf(stderr, "training set: %zu ORB descriptors from %zu real images\n",
                 result.descriptors.rows(), result.offsets.size() - 1);
    if (const char* dump = std::getenv("BINBOW_BENCH_DESCRIPTORS"))
      write_training_set(result, dump);
    return result;
  }();
  return set;
}

void BM_BuildVocabulary(benchmark::State& state) {
  const TrainingSet& set = training_set();
  const std::vector<DescriptorView> images = set.views();
  BuildOptions options;
  options.branching = 10;
  options.levels = 5;
  options.threads = static_cast<unsigned>(state.range(0));
  Vocabulary vocabulary;
  for (auto _ : state) {
    vocabulary = Vocabulary::build(images, options);
    benchmark::DoNotOptimize(vocabulary);
  }
  state.counters["descriptors"] = static_cast<double>(set.descriptors.rows());
  state.counters["words"] = static_cast<double>(vocabulary.word_count());
  state.counters["quantisation_error"] = vocabulary.mean_quantisation_error(set.descriptors.view());
}
BENCHMARK(BM_BuildVocabulary)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(5)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

}  // namespace
}  // namespace binbow::bench

BENCHMARK_MAIN();
