#include "binbow/loop/loop_detector.h"

#include <algorithm>
#include <chrono>
#include <string>

#include "binbow/error.h"
#include "loop/islands.h"

namespace binbow::loop {

using vision::check_fundamental;
using vision::Correspondence;
using vision::Features;
using vision::FundamentalCheckParams;
using vision::FundamentalCheckResult;
using vision::Keypoint;
using vision::match_direct_index;
using vision::match_exhaustive;
using vision::MatchOptions;
namespace {

using Clock = std::chrono::steady_clock;

double milliseconds_since(Clock::time_point& start) {
  const Clock::time_point now = Clock::now();
  const double ms = std::chrono::duration<double, std::milli>(now - start).count();
  start = now;
  return ms;
}

DatabaseOptions database_options(const LoopDetectorParams& params) {
  DatabaseOptions options;
  options.direct_index = params.geometric_check == GeometricCheck::kDirectIndex;
  options.direct_index_levels_up = static_cast<unsigned>(std::max(0, params.direct_index_levels));
  return options;
}

}  // namespace

struct LoopDetector::Impl {
  Impl(Vocabulary vocabulary, const LoopDetectorParams& p)
      : params(p),
        database(std::move(vocabulary), database_options(p)),
        window(p.max_distance_between_islands, p.max_distance_between_queries) {}

  LoopDetectorParams params;
  Database database;
  detail::TemporalWindow window;
  BowVector previous_bow;
  // Images with features so far: the time axis of the temporal window when
  // featureless frames are skipped.
  EntryId featured_frames = 0;
  // Features of every image, one contiguous array each; entry e owns
  // [offsets[e], offsets[e + 1]).
  std::vector<Keypoint> keypoints;
  std::vector<std::uint8_t> descriptor_bytes;
  std::vector<std::size_t> offsets{0};
  std::size_t code_size = 0;
  // Scratch reused across frames.
  std::vector<detail::Candidate> candidates;
  std::vector<detail::Island> islands;

  bool keeps_features() const { return params.geometric_check != GeometricCheck::kNone; }

  void verify(LoopResult& result, Span<Keypoint> query_keypoints,
              const DescriptorView& query_descriptors, const FeatureVector& query_nodes) const;
};

void LoopDetector::Impl::verify(LoopResult& result, Span<Keypoint> query_keypoints,
                                const DescriptorView& query_descriptors,
                                const FeatureVector& query_nodes) const {
  if (params.geometric_check == GeometricCheck::kNone) {
    result.status = LoopStatus::kLoopDetected;
    return;
  }
  const EntryId match = result.match;
  const std::size_t begin = offsets[match], end = offsets[match + 1];
  const Span<Keypoint> match_keypoints{keypoints.data() + begin, end - begin};
  const DescriptorView match_descriptors{descriptor_bytes.data() + begin * code_size, end - begin,
                                         code_size};
  FundamentalCheckParams check;
  check.min_inliers = params.min_inliers;
  check.max_reprojection_error = params.max_reprojection_error;
  check.confidence = params.ransac_confidence;
  check.max_iterations = params.max_ransac_iterations;
  check.estimator = params.fundamental_estimator;
  check.min_inlier_ratio = params.min_inlier_ratio;
  check.min_inlier_spread = params.min_inlier_spread;

  MatchOptions matching;
  matching.max_neighbor_ratio = params.max_neighbor_ratio;
  matching.max_distance_fraction = params.max_match_distance;
  matching.accept_single_candidate = params.accept_single_candidate;
  matching.mutual = params.mutual_matching;
  std::vector<Correspondence> correspondences;
  if (params.geometric_check == GeometricCheck::kDirectIndex) {
    correspondences = match_direct_index(query_descriptors, query_nodes, match_descriptors,
                                         database.feature_vector(match), matching);
  } else {
    correspondences = match_exhaustive(query_descriptors, match_descriptors, matching);
  }
  FundamentalCheckResult fit =
      check_fundamental(query_keypoints, match_keypoints, correspondences, check);
  if (!fit.consistent && params.geometric_check == GeometricCheck::kDirectIndex &&
      params.exhaustive_fallback) {
    correspondences = match_exhaustive(query_descriptors, match_descriptors, matching);
    fit = check_fundamental(query_keypoints, match_keypoints, correspondences, check);
    result.exhaustive_fallback_used = true;
  }
  result.correspondences = correspondences.size();
  result.inliers = std::move(fit.inliers);
  result.status = fit.consistent ? LoopStatus::kLoopDetected : LoopStatus::kNoGeometricConsistency;
}

LoopDetector::LoopDetector(Vocabulary vocabulary, LoopDetectorParams params) {
  params.validate();
  if (vocabulary.empty()) throw InvalidArgument("loop detector needs a non-empty vocabulary");
  impl_ = std::make_unique<Impl>(std::move(vocabulary), params);
  impl_->code_size = impl_->database.vocabulary().code_size();
}

LoopDetector::LoopDetector(LoopDetector&&) noexcept = default;
LoopDetector& LoopDetector::operator=(LoopDetector&&) noexcept = default;
LoopDetector::~LoopDetector() = default;

LoopResult LoopDetector::process(const Features& features) {
  return process(Span<Keypoint>{features.keypoints.data(), features.keypoints.size()},
                 features.descriptors.view());
}

LoopResult LoopDetector::process(Span<Keypoint> keypoints, const DescriptorView& descriptors) {
  Impl& d = *impl_;
  const LoopDetectorParams& p = d.params;
  if (keypoints.size() != descriptors.rows)
    throw InvalidArgument("loop detector: " + std::to_string(keypoints.size()) + " keypoints but " +
                          std::to_string(descriptors.rows) + " descriptors");
  if (!descriptors.empty() && descriptors.code_size != d.code_size)
    throw InvalidArgument("loop detector: descriptors of " + std::to_string(descriptors.code_size) +
                          " bytes, vocabulary has " + std::to_string(d.code_size));

  LoopResult result;
  Clock::time_point clock = Clock::now();
  BowVector bow;
  FeatureVector nodes;
  if (!descriptors.empty()) {
    if (p.geometric_check == GeometricCheck::kDirectIndex)
      d.database.vocabulary().transform(descriptors, bow, nodes,
                                        static_cast<unsigned>(p.direct_index_levels));
    else
      d.database.vocabulary().transform(descriptors, bow);
  }
  result.times.transform_ms = milliseconds_since(clock);

  const EntryId entry = d.database.next_entry_id();
  result.query = entry;
  result.status = LoopStatus::kNoDatabaseResults;
  if (static_cast<long long>(entry) > p.dislocal) {
    // DLoopDetector's bound (DBoW2's max_id is exclusive): j < t − dislocal.
    const EntryId newest_candidate = entry - static_cast<EntryId>(p.dislocal) - 1;
    const std::vector<QueryResult> found =
        d.database.query(bow, static_cast<std::size_t>(p.max_db_results), newest_candidate);
    double factor = 1;
    if (!found.empty()) {
      result.has_candidate = true;
      result.match = found.front().entry;
      result.score = found.front().score;
      if (p.use_normalised_score) {
        factor = d.database.vocabulary().score(bow, d.previous_bow);
        result.normalisation_score = factor;
      }
      result.normalised_score = factor > 0 ? result.score / factor : 0;
    }
    result.times.query_ms = milliseconds_since(clock);

    if (found.empty()) {
      result.status = LoopStatus::kNoDatabaseResults;
    } else if (p.use_normalised_score && factor < p.min_normalisation_score) {
      result.status = LoopStatus::kLowNormalisationScore;
    } else {
      d.candidates.clear();
      for (const QueryResult& r : found) {
        const double eta = r.score / factor;
        if (eta >= p.alpha) d.candidates.push_back({r.entry, eta});
      }
      if (d.candidates.empty()) {
        result.status = LoopStatus::kLowScores;
      } else {
        detail::compute_islands(d.candidates, p.max_intra_island_gap, p.min_matches_per_island,
                                d.islands);
        const detail::Island* island = detail::best_island(d.islands);
        if (island == nullptr) {
          result.status = LoopStatus::kNoIslands;
        } else {
          result.consistent_queries =
              d.window.update(*island, p.skip_featureless_frames ? d.featured_frames : entry);
          result.match = island->best_entry;
          result.normalised_score = island->best_score;
          result.score = island->best_score * factor;
          result.island_score = island->score;
          result.island_first = island->first;
          result.island_last = island->last;
          result.status = result.consistent_queries > p.k ? LoopStatus::kNoGeometricConsistency
                                                          : LoopStatus::kNoTemporalConsistency;
        }
      }
      result.times.islands_ms = milliseconds_since(clock);
      if (result.status == LoopStatus::kNoGeometricConsistency) {
        d.verify(result, keypoints, descriptors, nodes);
        if (!result.detection() && p.max_verified_entries > 1) {
          // The island, not its best entry, is what passed the temporal test:
          // its other images of the same place get a chance, best η first.
          std::vector<detail::Candidate> others;
          for (const detail::Candidate& c : d.candidates)
            if (c.entry >= result.island_first && c.entry <= result.island_last &&
                c.entry != result.match)
              others.push_back(c);
          std::stable_sort(others.begin(), others.end(),
                           [](const detail::Candidate& a, const detail::Candidate& b) {
                             return a.score > b.score;
                           });
          const std::size_t tries =
              std::min(others.size(), static_cast<std::size_t>(p.max_verified_entries - 1));
          for (std::size_t i = 0; i < tries && !result.detection(); ++i) {
            LoopResult attempt = result;
            attempt.match = others[i].entry;
            attempt.normalised_score = others[i].score;
            attempt.score = others[i].score * factor;
            d.verify(attempt, keypoints, descriptors, nodes);
            if (attempt.detection()) result = std::move(attempt);
          }
        }
        result.times.verification_ms = milliseconds_since(clock);
      }
    }
  }

  d.database.add(bow, nodes);
  if (d.keeps_features()) {
    d.keypoints.insert(d.keypoints.end(), keypoints.begin(), keypoints.end());
    if (!descriptors.empty())
      d.descriptor_bytes.insert(d.descriptor_bytes.end(), descriptors.data,
                                descriptors.data + descriptors.rows * descriptors.code_size);
  }
  d.offsets.push_back(d.keypoints.size());
  if (!bow.empty() || !p.skip_featureless_frames) d.previous_bow = std::move(bow);
  if (!descriptors.empty()) ++d.featured_frames;
  result.times.insertion_ms = milliseconds_since(clock);
  return result;
}

std::size_t LoopDetector::size() const noexcept {
  return impl_->offsets.size() - 1;
}
const LoopDetectorParams& LoopDetector::params() const noexcept {
  return impl_->params;
}
const Database& LoopDetector::database() const noexcept {
  return impl_->database;
}

Span<Keypoint> LoopDetector::keypoints(EntryId entry) const {
  if (entry >= size()) throw InvalidArgument("no image " + std::to_string(entry));
  const std::size_t begin = impl_->offsets[entry], end = impl_->offsets[entry + 1];
  return {impl_->keypoints.data() + begin, end - begin};
}

DescriptorView LoopDetector::descriptors(EntryId entry) const {
  if (entry >= size()) throw InvalidArgument("no image " + std::to_string(entry));
  const std::size_t begin = impl_->offsets[entry], end = impl_->offsets[entry + 1];
  return {impl_->descriptor_bytes.data() + begin * impl_->code_size, end - begin, impl_->code_size};
}

void LoopDetector::clear() {
  Impl& d = *impl_;
  d.database.clear();
  d.window.clear();
  d.previous_bow.clear();
  d.featured_frames = 0;
  d.keypoints.clear();
  d.descriptor_bytes.clear();
  d.offsets.assign(1, 0);
}

}  // namespace binbow::loop
