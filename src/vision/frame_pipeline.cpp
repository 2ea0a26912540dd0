#include "binbow/vision/frame_pipeline.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <map>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include "binbow/error.h"

namespace binbow::vision {
namespace {

unsigned resolve_threads(unsigned threads) {
  if (threads > kMaxPipelineThreads)
    throw InvalidArgument("FramePipeline: threads must be at most " +
                          std::to_string(kMaxPipelineThreads));
  if (threads != 0) return threads;
  return std::clamp(std::thread::hardware_concurrency(), 1u, kMaxPipelineThreads);
}

// Describes frame.frame (read), releasing its image.
void describe(const FeatureExtractor& extractor, ExtractedFrame& frame) {
  const auto start = std::chrono::steady_clock::now();
  if (frame.frame.unreadable.empty())
    frame.features = extract_features(extractor, frame.frame.image, frame.frame.name);
  else
    frame.features = Features{{}, DescriptorMatrix(extractor.code_size())};
  frame.features_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  frame.frame.image.release();
}

}  // namespace

struct FramePipeline::Impl {
  // A frame taken from the source: described, or the error reading or
  // describing it.
  struct Slot {
    ExtractedFrame frame;
    std::exception_ptr error;
  };

  Impl(ImageSource source_in, std::shared_ptr<const FeatureExtractor> extractor_in,
       const FramePipelineOptions& options)
      : source(std::move(source_in)),
        extractor(std::move(extractor_in)),
        threads(resolve_threads(options.threads)),
        queue_frames(options.queue_frames != 0 ? options.queue_frames
                                               : 2 * static_cast<std::size_t>(threads)) {
    if (!extractor) throw InvalidArgument("FramePipeline: null extractor");
  }

  ~Impl() { stop(); }

  // The source, read by one worker at a time, in order.
  mutable std::mutex source_mutex;
  ImageSource source;
  std::size_t next_sequence = 0;  // of the next frame taken from the source
  // source.unreadable_frames() after the latest read, for readers that do
  // not take source_mutex.
  std::atomic<std::size_t> unreadable_frames{0};

  std::shared_ptr<const FeatureExtractor> extractor;
  unsigned threads;
  std::size_t queue_frames;

  // The queue: frames taken (or being taken) and not yet returned.
  mutable std::mutex mutex;
  std::condition_variable space;  // a slot became free, or stopping
  std::condition_variable ready;  // a frame was described, or the source ended
  std::map<std::size_t, Slot> done;
  std::size_t in_flight = 0;
  std::size_t peak_in_flight = 0;
  std::size_t next_returned = 0;  // sequence number next() returns next
  std::size_t end = SIZE_MAX;     // sequence number at which the source ended
  bool stopping = false;
  std::vector<std::thread> workers;
  std::exception_ptr start_error;  // why the workers could not be started

  void start() {
    workers.reserve(threads);
    try {
      for (unsigned i = 0; i < threads; ++i) workers.emplace_back([this] { work(); });
    } catch (...) {
      start_error = std::current_exception();
      stop();
    }
  }

  void stop() {
    {
      const std::lock_guard<std::mutex> lock(mutex);
      stopping = true;
    }
    space.notify_all();
    for (std::thread& worker : workers) worker.join();
    workers.clear();
  }

  void work() {
    for (;;) {
      {
        std::unique_lock<std::mutex> lock(mutex);
        space.wait(lock,
                   [this] { return stopping || end != SIZE_MAX || in_flight < queue_frames; });
        if (stopping || end != SIZE_MAX) return;
        peak_in_flight = std::max(peak_in_flight, ++in_flight);
      }
      Slot slot;
      std::size_t sequence = 0;
      bool read = false;
      {
        const std::lock_guard<std::mutex> lock(source_mutex);
        sequence = next_sequence++;
        try {
          read = source.next(slot.frame.frame);
        } catch (...) {
          slot.error = std::current_exception();
          read = true;  // the source continues after the frame that failed
        }
        unreadable_frames = source.unreadable_frames();
      }
      if (!read) {
        {
          const std::lock_guard<std::mutex> lock(mutex);
          --in_flight;
          end = std::min(end, sequence);
        }
        ready.notify_all();
        space.notify_all();
        return;
      }
      if (!slot.error) {
        try {
          describe(*extractor, slot.frame);
        } catch (...) {
          slot.error = std::current_exception();
        }
      }
      {
        const std::lock_guard<std::mutex> lock(mutex);
        done.emplace(sequence, std::move(slot));
      }
      ready.notify_all();
    }
  }

  bool next_in_caller(ExtractedFrame& frame) {
    const bool read = source.next(frame.frame);
    unreadable_frames = source.unreadable_frames();
    if (!read) return false;
    peak_in_flight = 1;
    describe(*extractor, frame);
    return true;
  }

  bool next(ExtractedFrame& frame) {
    if (threads == 1) return next_in_caller(frame);
    if (workers.empty() && !stopping) start();
    if (start_error) std::rethrow_exception(start_error);
    Slot slot;
    {
      std::unique_lock<std::mutex> lock(mutex);
      ready.wait(lock, [this] { return done.count(next_returned) != 0 || next_returned >= end; });
      const auto it = done.find(next_returned);
      if (it == done.end()) return false;
      slot = std::move(it->second);
      done.erase(it);
      ++next_returned;
      --in_flight;
    }
    space.notify_one();
    if (slot.error) std::rethrow_exception(slot.error);
    frame = std::move(slot.frame);
    return true;
  }
};

FramePipeline::FramePipeline(ImageSource source, std::shared_ptr<const FeatureExtractor> extractor,
                             FramePipelineOptions options)
    : impl_(std::make_unique<Impl>(std::move(source), std::move(extractor), options)) {}

FramePipeline::FramePipeline(FramePipeline&&) noexcept = default;
FramePipeline& FramePipeline::operator=(FramePipeline&&) noexcept = default;
FramePipeline::~FramePipeline() = default;

bool FramePipeline::next(ExtractedFrame& frame) {
  return impl_->next(frame);
}

long long FramePipeline::size() const {
  const std::lock_guard<std::mutex> lock(impl_->source_mutex);
  return impl_->source.size();
}

double FramePipeline::frame_rate() const {
  const std::lock_guard<std::mutex> lock(impl_->source_mutex);
  return impl_->source.frame_rate();
}

std::size_t FramePipeline::unreadable_frames() const noexcept {
  return impl_->unreadable_frames;
}

unsigned FramePipeline::threads() const noexcept {
  return impl_->threads;
}

std::size_t FramePipeline::queue_frames() const noexcept {
  return impl_->queue_frames;
}

std::size_t FramePipeline::peak_frames_in_flight() const {
  const std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->peak_in_flight;
}

}  // namespace binbow::vision
