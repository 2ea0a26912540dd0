// vision::FramePipeline: frames read and described on worker threads come out
// in order, equal to one thread's to the bit, errors included, with at most
// queue_frames frames in flight, and the workers joined on every path.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "binbow/error.h"
#include "binbow/vision/features.h"
#include "binbow/vision/frame_pipeline.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::samples_folder;
using test::TempDir;
using vision::ExtractedFrame;
using vision::FramePipeline;

// What next() returned, or the error it threw, for every call until the end.
struct Delivered {
  std::vector<ExtractedFrame> frames;
  std::vector<std::string> errors;  // "" for a frame, else what() of the error
};

Delivered run(const std::vector<std::string>& inputs, unsigned threads,
              std::shared_ptr<const vision::FeatureExtractor> extractor,
              vision::ImageSourceOptions options = {}, std::size_t queue_frames = 0) {
  FramePipeline pipeline(vision::ImageSource(inputs, options), std::move(extractor),
                         {threads, queue_frames});
  Delivered delivered;
  for (;;) {
    ExtractedFrame frame;
    try {
      if (!pipeline.next(frame)) break;
      delivered.frames.push_back(std::move(frame));
      delivered.errors.emplace_back();
    } catch (const FileError& e) {
      delivered.errors.push_back(e.what());
    }
  }
  return delivered;
}

void expect_same(const Delivered& a, const Delivered& b) {
  ASSERT_EQ(a.errors, b.errors);
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (std::size_t i = 0; i < a.frames.size(); ++i) {
    SCOPED_TRACE("frame " + std::to_string(i));
    const ExtractedFrame& x = a.frames[i];
    const ExtractedFrame& y = b.frames[i];
    EXPECT_EQ(x.frame.name, y.frame.name);
    EXPECT_EQ(x.frame.index, y.frame.index);
    EXPECT_EQ(x.frame.scale, y.frame.scale);
    EXPECT_EQ(x.frame.unreadable, y.frame.unreadable);
    EXPECT_TRUE(x.frame.image.empty());
    ASSERT_EQ(x.features.keypoints.size(), y.features.keypoints.size());
    for (std::size_t k = 0; k < x.features.keypoints.size(); ++k) {
      EXPECT_EQ(x.features.keypoints[k].x, y.features.keypoints[k].x);
      EXPECT_EQ(x.features.keypoints[k].y, y.features.keypoints[k].y);
      EXPECT_EQ(x.features.keypoints[k].angle, y.features.keypoints[k].angle);
      EXPECT_EQ(x.features.keypoints[k].octave, y.features.keypoints[k].octave);
    }
    const DescriptorMatrix& dx = x.features.descriptors;
    const DescriptorMatrix& dy = y.features.descriptors;
    ASSERT_EQ(dx.code_size(), dy.code_size());
    ASSERT_EQ(dx.rows(), dy.rows());
    EXPECT_TRUE(std::equal(dx.data(), dx.data() + dx.rows() * dx.code_size(), dy.data()));
  }
}

std::vector<std::string> corridor(int count) {
  std::vector<std::string> files;
  for (int i = 1; i <= count; ++i)
    files.push_back(samples_folder() + "/" + std::to_string(i) + ".jpg");
  return files;
}

// The corridor's first `count` frames, frame `damaged` (1-based) cut to half
// its bytes.
std::vector<std::string> with_truncated_jpeg(const TempDir& dir, int count, int damaged) {
  std::vector<std::string> files = corridor(count);
  std::vector<std::uint8_t> bytes = test::read_file(files[damaged - 1]);
  bytes.resize(bytes.size() / 2);
  files[damaged - 1] = dir.file("truncated.jpg");
  test::write_file(files[damaged - 1], bytes);
  return files;
}

// ORB that fails on one image size, and counts the calls running at once.
class FailingOnSize final : public vision::FeatureExtractor {
 public:
  explicit FailingOnSize(int failing_width) : failing_width_(failing_width) {}
  vision::Features extract(const cv::Mat& image) const override {
    const int running = ++running_;
    for (int peak = peak_; running > peak && !peak_.compare_exchange_weak(peak, running);) {
    }
    struct Leave {
      std::atomic<int>& running;
      ~Leave() { --running; }
    } leave{running_};
    if (image.cols == failing_width_) throw InvalidArgument("no features at this width");
    return orb_->extract(image);
  }
  std::size_t code_size() const override { return 32; }
  std::string name() const override { return "orb"; }
  int peak_concurrency() const { return peak_; }

 private:
  int failing_width_;
  std::unique_ptr<vision::FeatureExtractor> orb_ = vision::make_orb_extractor();
  mutable std::atomic<int> running_{0};
  mutable std::atomic<int> peak_{0};
};

TEST(FramePipeline, AnyNumberOfThreadsGivesOneThreadsFramesInOrder) {
  const std::vector<std::string> inputs = {samples_folder()};
  std::shared_ptr<const vision::FeatureExtractor> orb = vision::make_orb_extractor();
  const Delivered one = run(inputs, 1, orb);
  ASSERT_EQ(one.frames.size(), 84u);
  std::size_t keypoints = 0;
  for (std::size_t i = 0; i < one.frames.size(); ++i) {
    EXPECT_EQ(one.frames[i].frame.index, i);
    keypoints += one.frames[i].features.keypoints.size();
  }
  EXPECT_GT(keypoints, 84u * 300) << "too few features to compare";
  for (const unsigned threads : {2u, 4u, 7u}) {
    SCOPED_TRACE(std::to_string(threads) + " threads");
    expect_same(one, run(inputs, threads, orb));
  }
  // Downscaled frames keep their scale; BRIEF too.
  vision::ImageSourceOptions half;
  half.max_width = 256;
  std::shared_ptr<const vision::FeatureExtractor> brief = vision::make_brief_extractor();
  const Delivered small = run(inputs, 1, brief, half);
  EXPECT_EQ(small.frames.at(0).frame.scale, 0.5);
  expect_same(small, run(inputs, 3, brief, half));
}

TEST(FramePipeline, DescribesFramesInParallel) {
  const auto extractor = std::make_shared<FailingOnSize>(-1);
  const Delivered delivered = run(corridor(40), 4, extractor);
  EXPECT_EQ(delivered.frames.size(), 40u);
  EXPECT_GE(extractor->peak_concurrency(), 2) << "no two frames were ever described at once";
}

TEST(FramePipeline, FramesInFlightNeverExceedTheQueue) {
  const std::vector<std::string> inputs = corridor(60);
  std::shared_ptr<const vision::FeatureExtractor> brief = vision::make_brief_extractor();
  for (const std::size_t queue : {std::size_t{1}, std::size_t{3}}) {
    FramePipeline pipeline(vision::ImageSource(inputs), brief, {4, queue});
    EXPECT_EQ(pipeline.queue_frames(), queue);
    ExtractedFrame frame;
    std::size_t frames = 0;
    // A consumer slower than four describing threads: they fill the queue
    // and wait.
    while (pipeline.next(frame)) {
      ++frames;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      EXPECT_LE(pipeline.peak_frames_in_flight(), queue);
    }
    EXPECT_EQ(frames, inputs.size());
    EXPECT_EQ(pipeline.peak_frames_in_flight(), queue) << "the queue never filled: no bound tested";
  }
  FramePipeline defaults(vision::ImageSource(inputs), brief, {3, 0});
  EXPECT_EQ(defaults.threads(), 3u);
  EXPECT_EQ(defaults.queue_frames(), 6u);
  EXPECT_GE(FramePipeline(vision::ImageSource(inputs), brief).threads(), 1u);
}

TEST(FramePipeline, AnUnreadableFrameFailsInItsPlaceAndTheNextCallGoesOn) {
  TempDir dir;
  const std::vector<std::string> inputs = with_truncated_jpeg(dir, 30, 12);
  std::shared_ptr<const vision::FeatureExtractor> orb = vision::make_orb_extractor();
  const Delivered one = run(inputs, 1, orb);
  ASSERT_EQ(one.errors.size(), 30u);
  EXPECT_EQ(one.frames.size(), 29u);
  EXPECT_NE(one.errors[11].find(inputs[11] + ": damaged JPEG"), std::string::npos)
      << one.errors[11];
  for (const unsigned threads : {2u, 4u}) {
    SCOPED_TRACE(std::to_string(threads) + " threads");
    expect_same(one, run(inputs, threads, orb, {}, 2));
  }
  // Skipped, the frame keeps its index, with empty features of ORB's size.
  vision::ImageSourceOptions skip;
  skip.skip_unreadable = true;
  const Delivered skipped = run(inputs, 4, orb, skip);
  ASSERT_EQ(skipped.frames.size(), 30u);
  EXPECT_FALSE(skipped.frames[11].frame.unreadable.empty());
  EXPECT_EQ(skipped.frames[11].frame.index, 11u);
  EXPECT_EQ(skipped.frames[11].features.descriptors.rows(), 0u);
  EXPECT_EQ(skipped.frames[11].features.descriptors.code_size(), 32u);
  expect_same(run(inputs, 1, orb, skip), skipped);
}

TEST(FramePipeline, AnExtractorErrorIsOneThreadsErrorInItsPlace) {
  // The corridor's frames are 512 pixels wide; one of OpenCV's samples is not.
  std::vector<std::string> inputs = corridor(20);
  const std::string odd = test::shared_data("opencv-doc-samples/box.png");
  inputs.insert(inputs.begin() + 7, odd);
  const auto extractor = std::make_shared<FailingOnSize>(cv::imread(odd).cols);
  const Delivered one = run(inputs, 1, extractor);
  ASSERT_EQ(one.errors.size(), 21u);
  EXPECT_EQ(one.errors[7].rfind(odd + ": ", 0), 0u) << one.errors[7];
  EXPECT_NE(one.errors[7].find("no features at this width"), std::string::npos) << one.errors[7];
  expect_same(one, run(inputs, 4, extractor));
}

TEST(FramePipeline, StopsItsWorkersWhereverTheConsumerStops) {
  TempDir dir;
  const std::vector<std::string> inputs = with_truncated_jpeg(dir, 40, 3);
  std::shared_ptr<const vision::FeatureExtractor> orb = vision::make_orb_extractor();
  for (const int taken : {0, 1, 2, 5}) {
    // Destroyed before its first frame, after some, at an error, with
    // workers reading and describing ahead: the destructor joins them.
    FramePipeline pipeline(vision::ImageSource(inputs), orb, {4, 0});
    ExtractedFrame frame;
    for (int i = 0; i < taken; ++i) {
      try {
        pipeline.next(frame);
      } catch (const FileError&) {
        break;
      }
    }
  }
  FramePipeline moved(vision::ImageSource(inputs), orb, {2, 0});
  ExtractedFrame frame;
  ASSERT_TRUE(moved.next(frame));
  FramePipeline owner = std::move(moved);
  ASSERT_TRUE(owner.next(frame));
  EXPECT_EQ(frame.frame.index, 1u);
}

TEST(FramePipeline, RefusesANullExtractorAndTooManyThreads) {
  const std::vector<std::string> inputs = corridor(2);
  EXPECT_THROW(FramePipeline(vision::ImageSource(inputs), nullptr), InvalidArgument);
  EXPECT_THROW(FramePipeline(vision::ImageSource(inputs), vision::make_orb_extractor(),
                             {vision::kMaxPipelineThreads + 1, 0}),
               InvalidArgument);
}

}  // namespace
}  // namespace binbow
