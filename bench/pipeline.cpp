// Where a frame's time goes end to end, stage by stage, at 640x480 (the DBoW2
// demo images) and 768x576 (OpenCV's vtest.avi, from Debian's opencv-doc):
// decode, grey conversion, ORB and FAST+BRIEF features, then the detector's
// transform, query and geometric check; and detect-loops' wall time per frame
// with the frame pipeline on 1 and 2 threads. Each benchmark reports medians
// over its repetitions; the stages run on one OpenCV thread.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "binbow/loop/loop_detector.h"
#include "binbow/loop/sequence.h"
#include "binbow/vision/features.h"
#include "binbow/vision/frame_pipeline.h"
#include "binbow/vision/image_source.h"

namespace binbow::vision {
namespace {

constexpr int kVideoFrames = 300;

// The shared data folder: $BINBOW_SHARED_DATA_DIR, else the one beside the
// source tree.
std::string data(const std::string& relative) {
  const char* folder = std::getenv("BINBOW_SHARED_DATA_DIR");
  return std::string(folder != nullptr ? folder : BINBOW_SHARED_DATA_DIR) + "/" + relative;
}

// vtest.avi where Debian's opencv-doc puts it; empty when not installed.
std::string vtest() {
  for (const char* path : {"/usr/share/doc/opencv-doc/examples/data/vtest.avi",
                           "/usr/share/opencv4/samples/data/vtest.avi"})
    if (std::filesystem::exists(path)) return path;
  return {};
}

bool skip_without_vtest(benchmark::State& state) {
  if (!vtest().empty()) return false;
  state.SkipWithError("vtest.avi not found: apt-get install opencv-doc");
  return true;
}

// The first kVideoFrames frames of vtest.avi as decoded (BGR).
const std::vector<cv::Mat>& video_frames() {
  static const std::vector<cv::Mat> frames = [] {
    std::vector<cv::Mat> read;
    cv::VideoCapture capture(vtest());
    cv::Mat frame;
    while (static_cast<int>(read.size()) < kVideoFrames && capture.read(frame))
      read.push_back(frame.clone());
    return read;
  }();
  return frames;
}

// 640x480 grey: the four DBoW2 demo images; 768x576: vtest.avi's frames.
const std::vector<cv::Mat>& grey_frames(int width) {
  static const std::vector<cv::Mat> demo = [] {
    cv::setNumThreads(1);
    std::vector<cv::Mat> images;
    for (int i = 0; i < 4; ++i)
      images.push_back(
          read_grey_image(data("dbow2-demo-images/image" + std::to_string(i) + ".png")));
    return images;
  }();
  static const std::vector<cv::Mat> video = [] {
    std::vector<cv::Mat> images;
    for (const cv::Mat& frame : video_frames()) {
      cv::Mat grey;
      cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
      images.push_back(grey);
    }
    return images;
  }();
  return width == 640 ? demo : video;
}

std::unique_ptr<FeatureExtractor> extractor(int kind) {
  return kind == 0 ? make_orb_extractor() : make_brief_extractor();
}

void BM_DecodeVideoFrame(benchmark::State& state) {
  if (skip_without_vtest(state)) return;
  cv::setNumThreads(1);
  cv::VideoCapture capture(vtest());
  cv::Mat frame;
  for (auto _ : state) {
    if (!capture.read(frame)) {
      state.PauseTiming();
      capture.open(vtest());
      state.ResumeTiming();
      capture.read(frame);
    }
    benchmark::DoNotOptimize(frame.data);
  }
}
BENCHMARK(BM_DecodeVideoFrame)->Unit(benchmark::kMillisecond);

// A 640x480 JPEG (a demo image re-encoded at quality 95) decoded to grey.
void BM_DecodeJpegGrey(benchmark::State& state) {
  std::vector<std::uint8_t> jpeg;
  cv::imencode(".jpg", grey_frames(640)[0], jpeg, {cv::IMWRITE_JPEG_QUALITY, 95});
  for (auto _ : state) {
    const cv::Mat grey = cv::imdecode(jpeg, cv::IMREAD_GRAYSCALE);
    benchmark::DoNotOptimize(grey.data);
  }
}
BENCHMARK(BM_DecodeJpegGrey)->Unit(benchmark::kMillisecond);

void BM_Grey(benchmark::State& state) {
  if (skip_without_vtest(state)) return;
  const std::vector<cv::Mat>& frames = video_frames();
  cv::Mat grey;
  std::size_t i = 0;
  for (auto _ : state) {
    cv::cvtColor(frames[i++ % frames.size()], grey, cv::COLOR_BGR2GRAY);
    benchmark::DoNotOptimize(grey.data);
  }
}
BENCHMARK(BM_Grey)->Unit(benchmark::kMillisecond);

// Arguments: 0 ORB-1000 / 1 BRIEF-300, frame width 640 or 768.
void BM_Features(benchmark::State& state) {
  const int width = static_cast<int>(state.range(1));
  if (width == 768 && skip_without_vtest(state)) return;
  cv::setNumThreads(1);
  const std::vector<cv::Mat>& frames = grey_frames(width);
  const auto features = extractor(static_cast<int>(state.range(0)));
  std::size_t i = 0;
  for (auto _ : state) {
    const Features f = features->extract(frames[i++ % frames.size()]);
    benchmark::DoNotOptimize(f.descriptors.data());
  }
}
BENCHMARK(BM_Features)
    ->ArgsProduct({{0, 1}, {640, 768}})
    ->ArgNames({"brief", "width"})
    ->Unit(benchmark::kMillisecond);

double median(std::vector<double> values) {
  if (values.empty()) return 0;
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

// The detector's own stages over vtest.avi's frames (features precomputed):
// medians per frame of transform, query (with islands, on the frames
// queried) and the geometric check (correspondences and RANSAC, on the
// frames that reach it), as counters.
void BM_DetectorStages(benchmark::State& state) {
  if (skip_without_vtest(state)) return;
  const auto orb = make_orb_extractor();
  std::vector<Features> features;
  for (const cv::Mat& grey : grey_frames(768)) features.push_back(orb->extract(grey));
  const Vocabulary vocabulary =
      Vocabulary::load(std::string(BINBOW_SOURCE_DIR) + "/data/vocab/orb_default.bbw");
  std::vector<double> transform, query, check;
  for (auto _ : state) {
    loop::LoopDetector detector(vocabulary, loop::LoopDetectorParams::for_frequency(10));
    for (const Features& f : features) {
      const loop::LoopResult result = detector.process(f);
      transform.push_back(result.times.transform_ms);
      // Frames younger than the detector's dislocal are not queried.
      if (result.times.query_ms > 0)
        query.push_back(result.times.query_ms + result.times.islands_ms);
      if (result.times.verification_ms > 0) check.push_back(result.times.verification_ms);
    }
  }
  state.counters["transform_ms"] = median(transform);
  state.counters["query_ms"] = median(query);
  state.counters["check_ms"] = median(check);
  state.counters["queried_frames"] =
      static_cast<double>(query.size()) / static_cast<double>(state.iterations());
  state.counters["checked_frames"] =
      static_cast<double>(check.size()) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_DetectorStages)->Unit(benchmark::kMillisecond)->Iterations(1);

// detect-loops over vtest.avi's first kVideoFrames frames (read, decoded,
// described, detected): wall time per frame with the frame pipeline on
// `threads` threads.
void BM_DetectLoopsWall(benchmark::State& state) {
  if (skip_without_vtest(state)) return;
  const Vocabulary vocabulary =
      Vocabulary::load(std::string(BINBOW_SOURCE_DIR) + "/data/vocab/orb_default.bbw");
  loop::SequenceOptions options;
  options.threads = static_cast<unsigned>(state.range(0));
  for (auto _ : state) {
    loop::SequenceDetector sequence({vtest()}, vocabulary, options);
    loop::SequenceFrame frame;
    for (int i = 0; i < kVideoFrames && sequence.next(frame); ++i) {
    }
  }
  state.SetItemsProcessed(state.iterations() * kVideoFrames);
}
BENCHMARK(BM_DetectLoopsWall)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace binbow::vision

BENCHMARK_MAIN();
