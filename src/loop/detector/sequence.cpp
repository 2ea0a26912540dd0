#include "binbow/loop/sequence.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "binbow/error.h"

namespace binbow::loop {

namespace {

std::shared_ptr<const vision::FeatureExtractor> extractor_of(const SequenceOptions& options) {
  if (options.extractor) return options.extractor;
  return vision::make_extractor(options.descriptor, options.max_features);
}

// A frame's label in the detector: its file, and its scale when not 1.
std::string frame_label(const std::string& file, double scale) {
  if (scale == 1) return file;
  char text[40];
  std::snprintf(text, sizeof text, "\t%.17g", scale);
  return file + text;
}

// The file and scale of a frame_label(); a label without a scale (or not
// made by frame_label) is a file at scale 1.
void parse_frame_label(const std::string& label, std::string& file, double& scale) {
  const std::size_t tab = label.rfind('\t');
  if (tab != std::string::npos) {
    char* end = nullptr;
    const double value = std::strtod(label.c_str() + tab + 1, &end);
    if (end != label.c_str() + tab + 1 && *end == '\0' && value > 0 && std::isfinite(value)) {
      file = label.substr(0, tab);
      scale = value;
      return;
    }
  }
  file = label;
  scale = 1;
}

LoopDetectorParams defaults_for(double frame_rate) {
  return frame_rate > 0 ? LoopDetectorParams::for_frequency(frame_rate) : LoopDetectorParams{};
}

}  // namespace

struct SequenceDetector::Impl {
  Impl(const std::vector<std::string>& inputs, const SequenceOptions& options)
      : extractor(extractor_of(options)),
        frames(vision::ImageSource(inputs, vision::limit_for_extractor(options.source, *extractor)),
               extractor, {options.threads, 0}),
        frame_rate(frames.frame_rate()),
        defaults(defaults_for(frame_rate)) {}

  std::shared_ptr<const vision::FeatureExtractor> extractor;
  vision::FramePipeline frames;
  double frame_rate;
  LoopDetectorParams defaults;
  bool params_given = false;
  bool resumed = false;  // from a saved detector, which brought its parameters
  std::unique_ptr<LoopDetector> detector;
  // Of every frame of this run (entry ids from first_entry on): a
  // loop's match_file, and Frame::scale for inliers in file pixels.
  std::vector<std::string> files;
  std::vector<double> scales;
  EntryId first_entry = 0;
  StatusCounts status_counts{};
  std::size_t skipped_frames = 0;
  vision::ExtractedFrame extracted;

  void start(Vocabulary vocabulary, const LoopDetectorParams& params) {
    if (vocabulary.code_size() != extractor->code_size())
      throw InvalidArgument(
          "the vocabulary's words have " + std::to_string(vocabulary.code_size()) + " bytes but " +
          extractor->name() + " descriptors have " + std::to_string(extractor->code_size()) +
          "; use a vocabulary trained on " + extractor->name() + " descriptors");
    detector = std::make_unique<LoopDetector>(std::move(vocabulary), params);
  }
  // The defaults for the source's frame rate, then the parameter file's keys,
  // then the overrides'.
  LoopDetectorParams params_of(const SequenceOptions& options) const {
    const LoopDetectorParams from_file =
        options.params_file.empty() ? defaults
                                    : LoopDetectorParams::load(options.params_file, defaults);
    if (options.params_overrides.empty()) return from_file;
    return LoopDetectorParams::from_json(options.params_overrides, "the parameter flags",
                                         from_file);
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

SequenceDetector::SequenceDetector(const std::vector<std::string>& inputs, LoopDetector detector,
                                   const SequenceOptions& options)
    : impl_(std::make_unique<Impl>(inputs, options)) {
  const std::size_t code_size = detector.online_vocabulary() != nullptr
                                    ? detector.online_vocabulary()->code_size()
                                    : detector.database().vocabulary().code_size();
  if (code_size != impl_->extractor->code_size())
    throw InvalidArgument("the saved detector's descriptors have " + std::to_string(code_size) +
                          " bytes but " + impl_->extractor->name() + " descriptors have " +
                          std::to_string(impl_->extractor->code_size()));
  impl_->resumed = true;
  impl_->first_entry = static_cast<EntryId>(detector.size());
  impl_->detector = std::make_unique<LoopDetector>(std::move(detector));
}

SequenceDetector::SequenceDetector(SequenceDetector&&) noexcept = default;
SequenceDetector& SequenceDetector::operator=(SequenceDetector&&) noexcept = default;
SequenceDetector::~SequenceDetector() = default;

bool SequenceDetector::next(SequenceFrame& out) {
  Impl& d = *impl_;
  // An unreadable frame (skip_unreadable) still takes its entry, with no
  // features: it matches nothing, and the entries after it keep the frames'
  // indices.
  if (!d.frames.next(d.extracted)) return false;
  const vision::Frame& frame = d.extracted.frame;
  const vision::Features& features = d.extracted.features;
  out.features_ms = d.extracted.features_ms;
  out.result = d.detector->process(features);
  out.file = frame.name;
  out.unreadable = frame.unreadable;
  d.files.push_back(frame.name);
  d.scales.push_back(frame.scale);
  d.detector->set_label(out.result.query, frame_label(frame.name, frame.scale));
  if (out.unreadable.empty())
    ++d.status_counts[static_cast<std::size_t>(out.result.status)];
  else
    ++d.skipped_frames;

  out.match_file.clear();
  out.inlier_points.clear();
  if (out.result.detection()) {
    double scale = 1;
    if (out.result.match >= d.first_entry) {
      out.match_file = d.files[out.result.match - d.first_entry];
      scale = d.scales[out.result.match - d.first_entry];
    } else {
      parse_frame_label(d.detector->label(out.result.match), out.match_file, scale);
    }
    const Span<vision::Keypoint> match_points = d.detector->keypoints(out.result.match);
    const auto query_scale = static_cast<float>(frame.scale);
    const auto match_scale = static_cast<float>(scale);
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
  if (impl_->resumed) return "the saved state";
  if (impl_->params_given) return "the parameters given";
  if (params().frequency != impl_->defaults.frequency) return "--params";
  if (impl_->frame_rate > 0) return "video frames processed per second";
  return "the paper's default; images have no frame rate";
}

long long SequenceDetector::size() const {
  return impl_->frames.size();
}

std::size_t SequenceDetector::frames_processed() const noexcept {
  return impl_->files.size();
}

const StatusCounts& SequenceDetector::status_counts() const noexcept {
  return impl_->status_counts;
}

std::size_t SequenceDetector::skipped_frames() const noexcept {
  return impl_->skipped_frames;
}

std::size_t SequenceDetector::unreadable_frames() const noexcept {
  return impl_->frames.unreadable_frames();
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
