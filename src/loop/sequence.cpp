#include "binbow/loop/sequence.h"

#include <chrono>
#include <cstdio>

#include "binbow/error.h"

namespace binbow::loop {

const char* const kStageNames[kStageCount] = {"features", "transform",    "query",
                                              "islands",  "verification", "insertion"};

std::array<double, kStageCount> SequenceFrame::stage_ms() const {
  const LoopStageTimes& t = result.times;
  return {features_ms, t.transform_ms, t.query_ms, t.islands_ms, t.verification_ms, t.insertion_ms};
}

namespace {

std::shared_ptr<const vision::FeatureExtractor> extractor_of(const SequenceOptions& options) {
  if (options.extractor) return options.extractor;
  return vision::make_extractor(options.descriptor, options.max_features);
}

LoopDetectorParams defaults_for(double frame_rate) {
  return frame_rate > 0 ? LoopDetectorParams::for_frequency(frame_rate) : LoopDetectorParams{};
}

}  // namespace

struct SequenceDetector::Impl {
  Impl(const std::vector<std::string>& inputs, const SequenceOptions& options)
      : source(inputs, options.source),
        extractor(extractor_of(options)),
        defaults(defaults_for(source.frame_rate())) {}

  vision::ImageSource source;
  std::shared_ptr<const vision::FeatureExtractor> extractor;
  LoopDetectorParams defaults;
  bool params_given = false;
  std::unique_ptr<LoopDetector> detector;
  std::vector<std::string> files;  // of every frame: a loop's match_file
  std::vector<double> scales;      // Frame::scale of every frame, for inliers in file pixels
  StatusCounts status_counts{};
  vision::Frame frame;

  void start(Vocabulary vocabulary, const LoopDetectorParams& params) {
    if (vocabulary.code_size() != extractor->code_size())
      throw InvalidArgument(
          "the vocabulary's words have " + std::to_string(vocabulary.code_size()) + " bytes but " +
          extractor->name() + " descriptors have " + std::to_string(extractor->code_size()) +
          "; use a vocabulary trained on " + extractor->name() + " descriptors");
    detector = std::make_unique<LoopDetector>(std::move(vocabulary), params);
  }
  // The defaults for the source's frame rate, then the parameter file's keys.
  LoopDetectorParams params_of(const SequenceOptions& options) const {
    return options.params_file.empty() ? defaults
                                       : LoopDetectorParams::load(options.params_file, defaults);
  }

  void start(OnlineVocabularyOptions vocabulary_options, const LoopDetectorParams& params) {
    if (vocabulary_options.descriptor.empty()) vocabulary_options.descriptor = extractor->name();
    detector = std::make_unique<LoopDetector>(
        LoopDetector::online(extractor->code_size(), std::move(vocabulary_options), params));
  }
};

SequenceDetector::SequenceDetector(const std::vector<std::string>& inputs, Vocabulary vocabulary,
                                   const SequenceOptions& options)
    : impl_(std::make_unique<Impl>(inputs, options)) {
  impl_->start(std::move(vocabulary), impl_->params_of(options));
}

SequenceDetector::SequenceDetector(const std::vector<std::string>& inputs, Vocabulary vocabulary,
                                   const SequenceOptions& options, const LoopDetectorParams& params)
    : impl_(std::make_unique<Impl>(inputs, options)) {
  impl_->params_given = true;
  impl_->start(std::move(vocabulary), params);
}

SequenceDetector::SequenceDetector(const std::vector<std::string>& inputs,
                                   OnlineVocabularyOptions vocabulary_options,
                                   const SequenceOptions& options)
    : impl_(std::make_unique<Impl>(inputs, options)) {
  impl_->start(std::move(vocabulary_options), impl_->params_of(options));
}

SequenceDetector::SequenceDetector(const std::vector<std::string>& inputs,
                                   OnlineVocabularyOptions vocabulary_options,
                                   const SequenceOptions& options, const LoopDetectorParams& params)
    : impl_(std::make_unique<Impl>(inputs, options)) {
  impl_->params_given = true;
  impl_->start(std::move(vocabulary_options), params);
}

SequenceDetector::SequenceDetector(SequenceDetector&&) noexcept = default;
SequenceDetector& SequenceDetector::operator=(SequenceDetector&&) noexcept = default;
SequenceDetector::~SequenceDetector() = default;

bool SequenceDetector::next(SequenceFrame& out) {
  Impl& d = *impl_;
  if (!d.source.next(d.frame)) return false;
  const auto start = std::chrono::steady_clock::now();
  const vision::Features features = d.extractor->extract(d.frame.image);
  out.features_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  out.result = d.detector->process(features);
  out.file = d.frame.name;
  d.files.push_back(d.frame.name);
  d.scales.push_back(d.frame.scale);
  ++d.status_counts[static_cast<std::size_t>(out.result.status)];

  out.match_file.clear();
  out.inlier_points.clear();
  if (out.result.detection()) {
    out.match_file = d.files[out.result.match];
    const Span<vision::Keypoint> match_points = d.detector->keypoints(out.result.match);
    const auto query_scale = static_cast<float>(d.frame.scale);
    const auto match_scale = static_cast<float>(d.scales[out.result.match]);
    out.inlier_points.reserve(out.result.inliers.size());
    for (const vision::Correspondence& c : out.result.inliers) {
      const vision::Keypoint& q = features.keypoints[c.first];
      const vision::Keypoint& m = match_points[c.second];
      out.inlier_points.push_back(
          {q.x / query_scale, q.y / query_scale, m.x / match_scale, m.y / match_scale});
    }
  }
  return true;
}

const LoopDetectorParams& SequenceDetector::params() const noexcept {
  return impl_->detector->params();
}

std::string SequenceDetector::frequency_origin() const {
  if (impl_->params_given) return "the parameters given";
  if (params().frequency != impl_->defaults.frequency) return "--params";
  if (impl_->source.frame_rate() > 0) return "video frames processed per second";
  return "the paper's default; images have no frame rate";
}

long long SequenceDetector::size() const {
  return impl_->source.size();
}

std::size_t SequenceDetector::frames_processed() const noexcept {
  return impl_->files.size();
}

const StatusCounts& SequenceDetector::status_counts() const noexcept {
  return impl_->status_counts;
}

std::size_t SequenceDetector::unreadable_frames() const noexcept {
  return impl_->source.unreadable_frames();
}

const LoopDetector& SequenceDetector::detector() const noexcept {
  return *impl_->detector;
}

std::vector<SequenceFrame> detect_sequence(
    SequenceDetector& sequence,
    const std::function<void(std::size_t done, std::size_t total)>& on_frame) {
  const long long known = sequence.size();
  const std::size_t total = known > 0 ? static_cast<std::size_t>(known) : 0;
  std::vector<SequenceFrame> frames;
  SequenceFrame frame;
  while (sequence.next(frame)) {
    frames.push_back(std::move(frame));
    if (on_frame) on_frame(frames.size(), total);
  }
  return frames;
}

std::string no_candidate_reason(const LoopDetectorParams& params, std::size_t frames) {
  if (static_cast<std::size_t>(params.dislocal) + 1 < frames) return {};
  return "no frame can have a loop candidate: candidates must be more than dislocal = " +
         std::to_string(params.dislocal) +
         " frames older than the query, and the sequence has only " + std::to_string(frames) +
         " frames";
}

}  // namespace binbow::loop
