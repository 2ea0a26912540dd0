// Loop detection per frame (the paper's Table III setting): the 84 real
// frames of rtabmap-samples (a corridor walked twice, so the second half
// closes loops and runs the geometric check) processed after a database of
// 1,000 or 10,000 other frames.
//
//   BM_Detect:            detection without features (transform, query,
//                         islands, verification, insertion); BRIEF features
//                         of the frames upscaled to 640x480, extracted once.
//   BM_FeaturesAndDetect: the same including FAST + BRIEF extraction on the
//                         640x480 frame.
// Vocabularies: the real DBoW2 BRIEF vocabulary brief_lite (k=10, L=6, 24,830
// words), and a paper-sized random tree (k=10, L=6, 1,000,000 words) to time
// the descent at the size of DLoopDetector's vocabulary.
//
// The database frames are mixtures of real descriptors of other places (the
// BRIEF features of opencv-doc-samples and dbow2-demo-images, each with 16
// random bits flipped, drawn with a skewed popularity), so word statistics
// and posting lists look like real images while no two of them show one place.
//
// Counters: median_ms, p90_ms, max_ms per frame over the 84 real frames
// (the Google Benchmark time column is the mean), loops detected.
//
//   BM_DetectOnline:      LoopDetector::online (no pre-trained vocabulary,
//                         default options) over a stream of 1,000 or 10,000
//                         frames of 1,000 real ORB features, every frame
//                         timed (process() only: features are extracted
//                         beforehand). The stream cycles through the 84
//                         rtabmap-samples frames (ORB, 1,000 features, their
//                         real keypoints); every pass after the first flips
//                         20 random bits (seeded by frame) of every
//                         descriptor, so each frame is distinct and a revisit
//                         of an earlier place, and the vocabulary keeps
//                         creating and purging words as in a long run.
//                         Counters: median_ms and mean_ms per frame over the
//                         whole stream, last_median_ms over its last 10%,
//                         cpu_median_ms and cpu_mean_ms (the thread's CPU
//                         time: what a shared machine's wall clock inflates),
//                         memory per frame (vocabulary, database, stored
//                         features) at the end, live words, largest word id.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "bench_support.h"
#include "binbow/formats.h"
#include "binbow/loop/loop_detector.h"
#include "binbow/online_vocabulary.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"

namespace binbow::bench {
namespace {

using loop::LoopDetector;
using vision::Features;

constexpr std::size_t kFeaturesPerFrame = 300;

const std::vector<cv::Mat>& frames_640x480() {
  static const std::vector<cv::Mat> frames = [] {
    std::vector<cv::Mat> result;
    vision::ImageSource source({std::string(BINBOW_SHARED_DATA_DIR) + "/rtabmap-samples/samples"});
    vision::Frame frame;
    while (source.next(frame)) {
      cv::Mat resized;
      cv::resize(frame.image, resized, cv::Size(640, 480), 0, 0, cv::INTER_LINEAR);
      result.push_back(resized);
    }
    return result;
  }();
  return frames;
}

const std::vector<Features>& real_features() {
  static const std::vector<Features> features = [] {
    const auto extractor = vision::make_brief_extractor();
    std::vector<Features> result;
    for (const cv::Mat& image : frames_640x480()) result.push_back(extractor->extract(image));
    return result;
  }();
  return features;
}

const Vocabulary& vocabulary(int which) {
  static const Vocabulary brief_lite = load_vocabulary(std::string(BINBOW_SHARED_DATA_DIR) +
                                                       "/vins-lite-brief-vocab/brief_lite.voc.gz");
  if (which == 0) return brief_lite;
  static const Vocabulary paper_size = full_random_vocabulary(10, 6);
  return paper_size;
}

Features synthetic_frame(std::mt19937_64& rng, const DescriptorMatrix& pool) {
  Features f;
  f.descriptors = DescriptorMatrix(kFeaturesPerFrame, 32);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (std::size_t r = 0; r < kFeaturesPerFrame; ++r) {
    const auto pick =
        static_cast<std::size_t>(static_cast<double>(pool.rows()) * std::pow(uniform(rng), 2.0));
    std::uint8_t* row = f.descriptors.row(r);
    std::memcpy(row, pool.row(pick), 32);
    for (int flip = 0; flip < 16; ++flip) {
      const auto bit = rng() % 256;
      row[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    }
    f.keypoints.push_back({float(rng() % 640), float(rng() % 480), 48, -1, 1, 0});
  }
  return f;
}

// A detector already holding `database_frames` synthetic frames.
std::unique_ptr<LoopDetector> prefilled_detector(int which_vocabulary,
                                                 std::size_t database_frames) {
  static const DescriptorMatrix pool = [] {
    DescriptorMatrix descriptors(32);
    const auto extractor = vision::make_brief_extractor();
    vision::ImageSource source({std::string(BINBOW_SHARED_DATA_DIR) + "/opencv-doc-samples",
                                std::string(BINBOW_SHARED_DATA_DIR) + "/dbow2-demo-images"});
    vision::Frame frame;
    while (source.next(frame))
      descriptors.append(extractor->extract(frame.image).descriptors.view());
    return descriptors;
  }();
  auto detector = std::make_unique<LoopDetector>(vocabulary(which_vocabulary));
  std::mt19937_64 rng(database_frames);
  for (std::size_t i = 0; i < database_frames; ++i) detector->process(synthetic_frame(rng, pool));
  return detector;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Medians of each stage, to see where the time goes.
struct StageTimes {
  std::vector<double> transform, query, verification, insertion;
  void add(const loop::LoopStageTimes& t) {
    transform.push_back(t.transform_ms);
    query.push_back(t.query_ms + t.islands_ms);
    verification.push_back(t.verification_ms);
    insertion.push_back(t.insertion_ms);
  }
  void report(benchmark::State& state) const {
    state.counters["transform_med"] = median(transform);
    state.counters["query_med"] = median(query);
    state.counters["verify_mean"] =
        std::accumulate(verification.begin(), verification.end(), 0.0) / verification.size();
    state.counters["insert_med"] = median(insertion);
  }
};

void report(benchmark::State& state, std::vector<double> ms, std::size_t loops) {
  std::sort(ms.begin(), ms.end());
  state.counters["median_ms"] = ms[ms.size() / 2];
  state.counters["p90_ms"] = ms[ms.size() * 9 / 10];
  state.counters["max_ms"] = ms.back();
  state.counters["loops"] = static_cast<double>(loops);
}

void BM_Detect(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  const auto database_frames = static_cast<std::size_t>(state.range(1));
  const auto& features = real_features();
  std::vector<double> ms;
  std::size_t loops = 0;
  StageTimes stages;
  for (auto _ : state) {
    state.PauseTiming();
    auto detector = prefilled_detector(which, database_frames);
    ms.clear();
    loops = 0;
    stages = {};
    state.ResumeTiming();
    for (const Features& f : features) {
      const auto start = std::chrono::steady_clock::now();
      const loop::LoopResult r = detector->process(f);
      ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count());
      loops += r.detection();
      stages.add(r.times);
    }
    state.PauseTiming();
    detector.reset();
    state.ResumeTiming();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * features.size()));
  report(state, ms, loops);
  stages.report(state);
}

void BM_FeaturesAndDetect(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  const auto database_frames = static_cast<std::size_t>(state.range(1));
  const auto extractor = vision::make_brief_extractor();
  std::vector<double> ms;
  std::size_t loops = 0;
  for (auto _ : state) {
    state.PauseTiming();
    auto detector = prefilled_detector(which, database_frames);
    ms.clear();
    loops = 0;
    state.ResumeTiming();
    for (const cv::Mat& image : frames_640x480()) {
      const auto start = std::chrono::steady_clock::now();
      const loop::LoopResult r = detector->process(extractor->extract(image));
      ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count());
      loops += r.detection();
    }
    state.PauseTiming();
    detector.reset();
    state.ResumeTiming();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * frames_640x480().size()));
  report(state, ms, loops);
}

const std::vector<Features>& real_orb_features() {
  static const std::vector<Features> features = [] {
    const auto orb = vision::make_extractor("orb", 1000);
    std::vector<Features> result;
    vision::ImageSource source({std::string(BINBOW_SHARED_DATA_DIR) + "/rtabmap-samples/samples"});
    vision::Frame frame;
    while (source.next(frame)) result.push_back(orb->extract(frame.image));
    return result;
  }();
  return features;
}

double thread_cpu_ms() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) * 1e-6;
}

// Frame `index` of the endless stream described at the top of the file.
Features online_stream_frame(std::size_t index) {
  const std::vector<Features>& real = real_orb_features();
  Features frame = real[index % real.size()];
  if (index < real.size()) return frame;
  std::mt19937_64 rng(index);
  const std::size_t bits = frame.descriptors.code_size() * 8;
  for (std::size_t r = 0; r < frame.descriptors.rows(); ++r) {
    std::uint8_t* row = frame.descriptors.row(r);
    for (int flip = 0; flip < 20; ++flip) {
      const std::size_t bit = rng() % bits;
      row[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    }
  }
  return frame;
}

void BM_DetectOnline(benchmark::State& state) {
  const auto frames = static_cast<std::size_t>(state.range(0));
  std::vector<double> ms, cpu_ms;
  std::size_t loops = 0;
  std::size_t stored_bytes = 0;
  StageTimes stages;
  std::unique_ptr<LoopDetector> detector;
  for (auto _ : state) {
    state.PauseTiming();
    detector = std::make_unique<LoopDetector>(LoopDetector::online(32));
    ms.clear();
    cpu_ms.clear();
    stages = {};
    loops = 0;
    stored_bytes = 0;
    for (std::size_t i = 0; i < frames; ++i) {
      const Features f = online_stream_frame(i);
      state.ResumeTiming();
      const double cpu_start = thread_cpu_ms();
      const auto start = std::chrono::steady_clock::now();
      const loop::LoopResult r = detector->process(f);
      ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count());
      cpu_ms.push_back(thread_cpu_ms() - cpu_start);
      state.PauseTiming();
      loops += r.detection();
      stages.add(r.times);
      stored_bytes +=
          detector->keypoints(r.query).size() * sizeof(vision::Keypoint) +
          detector->descriptors(r.query).rows * detector->descriptors(r.query).code_size;
    }
    state.ResumeTiming();
  }
  const std::vector<double> last(ms.end() - static_cast<std::ptrdiff_t>(ms.size() / 10), ms.end());
  report(state, ms, loops);
  state.counters["mean_ms"] = std::accumulate(ms.begin(), ms.end(), 0.0) / ms.size();
  state.counters["last_median_ms"] = median(last);
  stages.report(state);
  state.counters["cpu_median_ms"] = median(cpu_ms);
  state.counters["cpu_mean_ms"] =
      std::accumulate(cpu_ms.begin(), cpu_ms.end(), 0.0) / cpu_ms.size();
  const OnlineVocabularyStats words = detector->online_vocabulary()->stats();
  const double n = static_cast<double>(frames);
  state.counters["vocab_B_per_frame"] = static_cast<double>(words.memory_bytes) / n;
  state.counters["db_B_per_frame"] = static_cast<double>(detector->database().memory_usage()) / n;
  state.counters["features_B_per_frame"] = static_cast<double>(stored_bytes) / n;
  state.counters["words"] = static_cast<double>(words.words);
  state.counters["next_word_id"] = static_cast<double>(words.next_word_id);
}
// Arg: frames in the stream.
BENCHMARK(BM_DetectOnline)->Arg(1000)->Arg(10000)->Iterations(1)->Unit(benchmark::kMillisecond);

// Args: vocabulary (0 brief_lite, 1 paper-sized 1M words), database frames.
BENCHMARK(BM_Detect)
    ->Args({0, 1000})
    ->Args({0, 10000})
    ->Args({1, 1000})
    ->Args({1, 10000})
    ->Iterations(3)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FeaturesAndDetect)
    ->Args({0, 10000})
    ->Args({1, 10000})
    ->Iterations(3)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace binbow::bench

BENCHMARK_MAIN();
