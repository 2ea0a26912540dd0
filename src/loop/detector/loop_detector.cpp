#include "binbow/loop/loop_detector.h"

#include <algorithm>
#include <chrono>
#include <optional>
#include <string>

#include "binbow/error.h"
#include "loop/detector/loop_detector_impl.h"

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

}  // namespace

std::size_t detail::shared_query_features(Span<Keypoint> query_keypoints,
                                          const std::vector<Correspondence>& first,
                                          const std::vector<Correspondence>& second) {
  constexpr float r2 = vision::kDistinctInlierRadius * vision::kDistinctInlierRadius;
  std::size_t shared = 0;
  for (const Correspondence& b : second) {
    const Keypoint& q = query_keypoints[b.first];
    shared += std::any_of(first.begin(), first.end(), [&](const Correspondence& a) {
      const Keypoint& p = query_keypoints[a.first];
      const float dx = p.x - q.x, dy = p.y - q.y;
      return dx * dx + dy * dy <= r2;
    });
  }
  return shared;
}

DatabaseOptions detail::database_options(const LoopDetectorParams& params) {
  DatabaseOptions options;
  options.direct_index = params.geometric_check == GeometricCheck::kDirectIndex;
  options.direct_index_levels_up = static_cast<unsigned>(std::max(0, params.direct_index_levels));
  return options;
}

TrailCheck LoopDetector::Impl::geometric_check(Span<Keypoint> query_keypoints,
                                               const DescriptorView& query_descriptors,
                                               const FeatureVector& query_nodes, EntryId match,
                                               bool strong_fit_only,
                                               std::size_t rival_inliers) const {
  TrailCheck out;
  out.entry = match;
  out.before_temporal_consistency = strong_fit_only;
  out.rival_inliers = rival_inliers;
  const Span<Keypoint> match_keypoints = keypoints_of(match);
  const DescriptorView match_descriptors = descriptors_of(match);
  FundamentalCheckParams check;
  check.min_inliers = out.inliers_asked(params);
  check.max_reprojection_error = params.max_reprojection_error;
  check.confidence = params.ransac_confidence;
  check.max_iterations = params.max_ransac_iterations;
  check.estimator = params.fundamental_estimator;
  check.min_inlier_ratio = params.min_inlier_ratio;
  check.min_inlier_spread = params.min_inlier_spread;
  check.reject_degenerate = params.reject_degenerate_fits;

  MatchOptions matching;
  matching.max_neighbor_ratio = params.max_neighbor_ratio;
  matching.max_distance_fraction = params.max_match_distance;
  matching.accept_single_candidate = params.accept_single_candidate;
  matching.mutual = params.mutual_matching;
  std::vector<Correspondence> correspondences;
  if (params.geometric_check == GeometricCheck::kDirectIndex) {
    correspondences = match_direct_index(query_descriptors, query_nodes, match_descriptors,
                                         database.feature_vector(match), matching);
    out.direct_index_correspondences = static_cast<long long>(correspondences.size());
  } else {
    correspondences = match_exhaustive(query_descriptors, match_descriptors, matching);
  }
  FundamentalCheckResult fit =
      check_fundamental(query_keypoints, match_keypoints, correspondences, check);
  if (!fit.consistent && params.geometric_check == GeometricCheck::kDirectIndex &&
      params.exhaustive_fallback && rival_inliers == 0) {
    correspondences = match_exhaustive(query_descriptors, match_descriptors, matching);
    fit = check_fundamental(query_keypoints, match_keypoints, correspondences, check);
    out.exhaustive_fallback_used = true;
  }
  out.correspondences = std::move(correspondences);
  out.fit = std::move(fit);
  return out;
}

void LoopDetector::Impl::verify(LoopResult& result, Span<Keypoint> query_keypoints,
                                const DescriptorView& query_descriptors,
                                const FeatureVector& query_nodes, bool before_temporal_consistency,
                                std::size_t rival_inliers) const {
  if (params.geometric_check == GeometricCheck::kNone) {
    result.status = LoopStatus::kLoopDetected;
    result.accepted_by = LoopEvidence::kUnchecked;
    return;
  }
  TrailCheck check = geometric_check(query_keypoints, query_descriptors, query_nodes, result.match,
                                     before_temporal_consistency, rival_inliers);
  if (check.exhaustive_fallback_used) result.exhaustive_fallback_used = true;
  const FundamentalCheckResult& fit = check.fit;
  result.correspondences = fit.correspondences;
  result.inlier_ratio = fit.inlier_ratio;
  result.inlier_spread = fit.inlier_spread;
  result.distinct_inliers = fit.distinct_inliers;
  result.inlier_thickness = fit.inlier_thickness;
  result.inliers = fit.inliers;
  result.fit_evidence = fit.determinacy.evidence;
  // Before temporal consistency a consistent fit has min_uncorroborated_inliers
  // inliers (geometric_check asks for them), so it never needs corroboration.
  const auto strong = static_cast<std::size_t>(params.min_uncorroborated_inliers);
  result.corroboration.needed = fit.consistent && strong > 0 && result.inliers.size() < strong;
  if (result.corroboration.needed)
    corroborate(result, query_keypoints, query_descriptors, query_nodes);
  check.normalised_score = result.normalised_score;
  check.corroboration = result.corroboration;
  const bool accepted = check.accepted();
  result.status = accepted                      ? LoopStatus::kLoopDetected
                  : before_temporal_consistency ? LoopStatus::kNoTemporalConsistency
                                                : LoopStatus::kNoGeometricConsistency;
  result.accepted_by = LoopEvidence::kNone;
  if (accepted)
    result.accepted_by = before_temporal_consistency ? LoopEvidence::kStrongFitAlone
                         : !result.corroboration.needed
                             ? LoopEvidence::kStrongFit
                             : detail::corroborating_evidence(result.corroboration);
  if (trail != nullptr) trail->checks.push_back(std::move(check));
}

LoopEvidence detail::corroborating_evidence(const LoopCorroboration& c) {
  return c.neighbour_checked       ? LoopEvidence::kNeighbour
         : c.previous_loop_at_pace ? LoopEvidence::kRevisitPace
                                   : LoopEvidence::kNearPreviousLoop;
}

// Near the latest loop, or else at the revisit's pace since it: the match
// as many entries from its match as the query is queries from its query.
void LoopDetector::Impl::corroborate_by_previous_loop(LoopCorroboration& c, EntryId query,
                                                      EntryId match) const {
  c.has_previous_loop = has_previous_loop;
  c.previous_loop_query = previous_loop_query;
  c.previous_loop_match = previous_loop_match;
  if (!has_previous_loop) return;
  const auto distance = [](EntryId a, EntryId b) { return a > b ? a - b : b - a; };
  const EntryId queries = distance(query, previous_loop_query);
  const EntryId entries = distance(match, previous_loop_match);
  const auto near = static_cast<EntryId>(params.corroboration_distance);
  if (queries <= near && entries <= near) {
    c.corroborated = true;
    return;
  }
  c.previous_loop_at_pace = queries <= static_cast<EntryId>(params.corroboration_horizon) &&
                            static_cast<double>(distance(entries, queries)) <=
                                params.corroboration_pace_tolerance * static_cast<double>(queries);
  c.corroborated = c.previous_loop_at_pace;
}

// The latest loop first; without one near enough or at the revisit's pace,
// the match's neighbours (match − 1, then match + 1) against the query.
void LoopDetector::Impl::corroborate(LoopResult& result, Span<Keypoint> query_keypoints,
                                     const DescriptorView& query_descriptors,
                                     const FeatureVector& query_nodes) const {
  corroborate_by_previous_loop(result.corroboration, result.query, result.match);
  for (const long long neighbour :
       {static_cast<long long>(result.match) - 1, static_cast<long long>(result.match) + 1}) {
    if (result.corroboration.corroborated) return;
    if (neighbour < 0 || neighbour >= static_cast<long long>(result.query)) continue;
    const auto entry = static_cast<EntryId>(neighbour);
    if (!database.contains(entry) || frames[entry].keypoints.empty()) continue;
    const FundamentalCheckResult fit =
        geometric_check(query_keypoints, query_descriptors, query_nodes, entry).fit;
    const std::size_t shared =
        detail::shared_query_features(query_keypoints, result.inliers, fit.inliers);
    if (!result.corroboration.neighbour_checked ||
        fit.inliers.size() > result.corroboration.neighbour_inliers) {
      result.corroboration.corroborating_neighbour = entry;
      result.corroboration.neighbour_inliers = fit.inliers.size();
      result.corroboration.neighbour_shared_inliers = shared;
    }
    result.corroboration.neighbour_checked = true;
    result.corroboration.corroborated = fit.consistent && (result.corroboration.view_unexplained ||
                                                           2 * shared <= fit.inliers.size());
  }
}

LoopDetector::LoopDetector(Vocabulary vocabulary, LoopDetectorParams params) {
  params.validate();
  if (vocabulary.empty()) throw InvalidArgument("loop detector needs a non-empty vocabulary");
  const std::size_t code_size = vocabulary.code_size();
  impl_ = std::make_unique<Impl>(Database(std::move(vocabulary), detail::database_options(params)),
                                 params, code_size);
}

LoopDetector::LoopDetector(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

LoopDetector LoopDetector::online(std::size_t code_size, OnlineVocabularyOptions vocabulary_options,
                                  LoopDetectorParams params) {
  params.validate();
  OnlineVocabulary vocabulary(code_size, std::move(vocabulary_options));
  auto impl = std::make_unique<Impl>(
      Database::over_word_ids(vocabulary.options().scoring, detail::database_options(params)),
      params, code_size);
  impl->online.emplace(std::move(vocabulary));
  return LoopDetector(std::move(impl));
}

LoopDetector::LoopDetector(LoopDetector&&) noexcept = default;
LoopDetector& LoopDetector::operator=(LoopDetector&&) noexcept = default;
LoopDetector::~LoopDetector() = default;

LoopResult LoopDetector::process(const Features& features) {
  return process(Span<Keypoint>{features.keypoints.data(), features.keypoints.size()},
                 features.descriptors.view());
}

void LoopDetector::Impl::check_input(Span<Keypoint> image_keypoints,
                                     const DescriptorView& descriptors) const {
  if (image_keypoints.size() != descriptors.rows)
    throw InvalidArgument("loop detector: " + std::to_string(image_keypoints.size()) +
                          " keypoints but " + std::to_string(descriptors.rows) + " descriptors");
  if (!descriptors.empty() && descriptors.code_size != code_size)
    throw InvalidArgument("loop detector: descriptors of " + std::to_string(descriptors.code_size) +
                          " bytes, vocabulary has " + std::to_string(code_size));
}

void LoopDetector::Impl::transform(const DescriptorView& descriptors, BowVector& bow,
                                   FeatureVector& nodes) {
  if (descriptors.empty()) return;
  if (online) {
    online->add_image(descriptors, image_words);
    online->weigh(image_words.words.data(), image_words.words.size(), bow);
    // Every feature under its word, stop words (weight 0) included: the
    // geometric check wants correspondences, not weights.
    if (params.geometric_check == GeometricCheck::kDirectIndex)
      nodes = FeatureVector::from_assignment(image_words.words.data(), image_words.words.size());
    return;
  }
  if (params.geometric_check == GeometricCheck::kDirectIndex)
    database.vocabulary().transform(descriptors, bow, nodes,
                                    static_cast<unsigned>(params.direct_index_levels));
  else
    database.vocabulary().transform(descriptors, bow);
}

// The best entries older than dislocal, and the normalisation score.
std::vector<QueryResult> LoopDetector::Impl::query(const BowVector& bow, LoopResult& result) const {
  // DLoopDetector's bound (DBoW2's max_id is exclusive): j < t − dislocal.
  const EntryId newest_candidate = result.query - static_cast<EntryId>(params.dislocal) - 1;
  QueryOptions options;
  options.mode = params.fast_queries ? QueryMode::kFast : QueryMode::kExact;
  std::vector<QueryResult> found = database.query(
      bow, static_cast<std::size_t>(params.max_db_results), newest_candidate, options);
  if (!found.empty()) {
    result.has_candidate = true;
    result.match = found.front().entry;
    result.score = found.front().score;
    if (params.use_normalised_score)
      result.normalisation_score = score_bow(bow, previous_bow, database.scoring());
    const double factor = normalisation_factor(result);
    result.normalised_score = factor > 0 ? result.score / factor : 0;
  }
  if (trail != nullptr) {
    trail->queried = true;
    trail->newest_candidate = newest_candidate;
    trail->normalisation_score = result.normalisation_score;
    const double factor = normalisation_factor(result);
    for (const QueryResult& r : found)
      trail->candidates.push_back({r.entry, r.score, factor > 0 ? r.score / factor : 0});
  }
  return found;
}

// Section V-A: a frame whose previous image shares almost nothing with it has
// no meaningful η.
bool LoopDetector::Impl::passes_normalisation(const std::vector<QueryResult>& found,
                                              LoopResult& result) const {
  if (found.empty()) {
    result.status = LoopStatus::kNoDatabaseResults;
    return false;
  }
  if (params.use_normalised_score && result.normalisation_score < params.min_normalisation_score) {
    result.status = LoopStatus::kLowNormalisationScore;
    return false;
  }
  return true;
}

// Sections V-A to V-C: candidates reaching α, their best island, and its
// agreement with the islands of the previous queries.
void LoopDetector::Impl::select_island(const std::vector<QueryResult>& found, LoopResult& result) {
  const double factor = normalisation_factor(result);
  candidates.clear();
  for (const QueryResult& r : found) {
    const double eta = r.score / factor;
    if (eta >= params.alpha) candidates.push_back({r.entry, eta});
  }
  if (candidates.empty()) {
    result.status = LoopStatus::kLowScores;
    return;
  }
  detail::compute_islands(candidates, params.max_intra_island_gap, params.min_matches_per_island,
                          islands);
  if (trail != nullptr) record_islands();
  const detail::Island* island = detail::best_island(islands);
  if (island == nullptr) {
    result.status = LoopStatus::kNoIslands;
    return;
  }
  const EntryId position = params.skip_featureless_frames ? featured_frames : result.query;
  const detail::TemporalWindow::State before = window.state();
  result.consistent_queries = window.update(*island, position);
  if (trail != nullptr) record_temporal(*island, before, position, result.consistent_queries);
  result.match = island->best_entry;
  result.normalised_score = island->best_score;
  result.score = island->best_score * factor;
  result.island_score = island->score;
  result.island_first = island->first;
  result.island_last = island->last;
  result.status = result.consistent_queries > params.k ? LoopStatus::kNoGeometricConsistency
                                                       : LoopStatus::kNoTemporalConsistency;
}

// The candidates of result's island other than its match, best η first.
std::vector<detail::Candidate> LoopDetector::Impl::other_island_candidates(
    const LoopResult& result) const {
  std::vector<detail::Candidate> others;
  for (const detail::Candidate& c : candidates)
    if (c.entry >= result.island_first && c.entry <= result.island_last && c.entry != result.match)
      others.push_back(c);
  std::stable_sort(
      others.begin(), others.end(),
      [](const detail::Candidate& a, const detail::Candidate& b) { return a.score > b.score; });
  return others;
}

// result with another candidate of its island as its match, to be verified.
LoopResult LoopDetector::Impl::with_match(const LoopResult& result,
                                          const detail::Candidate& candidate) const {
  LoopResult attempt = result;
  attempt.match = candidate.entry;
  attempt.normalised_score = candidate.score;
  attempt.score = candidate.score * normalisation_factor(result);
  return attempt;
}

// Section V-D for the island's best entry, then (max_verified_entries > 1)
// its other entries, best η first: the island, not its best entry, is what
// passed the temporal test, and its other images show the same place.
void LoopDetector::Impl::verify_island(LoopResult& result, Span<Keypoint> query_keypoints,
                                       const DescriptorView& query_descriptors,
                                       const FeatureVector& query_nodes) {
  verify(result, query_keypoints, query_descriptors, query_nodes);
  if (result.detection() || params.max_verified_entries <= 1) return;
  const std::vector<detail::Candidate> others = other_island_candidates(result);
  const std::size_t tries =
      std::min(others.size(), static_cast<std::size_t>(params.max_verified_entries - 1));
  for (std::size_t i = 0; i < tries && !result.detection(); ++i) {
    LoopResult attempt = with_match(result, others[i]);
    verify(attempt, query_keypoints, query_descriptors, query_nodes);
    if (attempt.detection()) result = std::move(attempt);
  }
}

double LoopDetector::Impl::measure_view_agreement(const LoopResult& result,
                                                  Span<Keypoint> query_keypoints,
                                                  const DescriptorView& query_descriptors) const {
  const double share =
      vision::view_agreement(query_keypoints, query_descriptors, keypoints_of(result.match),
                             descriptors_of(result.match), result.inliers);
  if (trail != nullptr) trail->checks.back().view_agreement = share;
  return share;
}

void LoopDetector::Impl::examine_view(LoopResult& result, Span<Keypoint> query_keypoints,
                                      const DescriptorView& query_descriptors,
                                      const FeatureVector& query_nodes,
                                      bool before_temporal_consistency) const {
  if (!result.detection() || params.geometric_check == GeometricCheck::kNone) return;
  const auto strong = [&] {
    return result.accepted_by == LoopEvidence::kStrongFit ||
           result.accepted_by == LoopEvidence::kStrongFitAlone;
  };
  // Without min_uncorroborated_inliers every fit stands alone (the paper).
  const bool asks_explained_views =
      params.min_uncorroborated_inliers > 0 && params.min_uncorroborated_view_agreement > 0;
  std::vector<detail::Candidate> others;
  if (params.localise_in_island) others = other_island_candidates(result);
  if (!(asks_explained_views && strong()) && others.empty()) return;
  double agreement = measure_view_agreement(result, query_keypoints, query_descriptors);
  if (agreement < kViewExplained && !others.empty())
    agreement = localise_in_island(result, query_keypoints, query_descriptors, query_nodes,
                                   before_temporal_consistency, std::move(others), agreement);
  if (asks_explained_views && strong() && agreement < params.min_uncorroborated_view_agreement)
    corroborate_unexplained_view(result, query_keypoints, query_descriptors, query_nodes,
                                 before_temporal_consistency);
}

double LoopDetector::Impl::localise_in_island(LoopResult& result, Span<Keypoint> query_keypoints,
                                              const DescriptorView& query_descriptors,
                                              const FeatureVector& query_nodes,
                                              bool before_temporal_consistency,
                                              std::vector<detail::Candidate> others,
                                              double accepted_agreement) const {
  others.resize(std::min(others.size(), static_cast<std::size_t>(params.max_localisation_checks)));
  LoopResult best = result;
  double best_agreement = accepted_agreement;
  for (const detail::Candidate& c : others) {
    LoopResult attempt = with_match(result, c);
    verify(attempt, query_keypoints, query_descriptors, query_nodes, before_temporal_consistency,
           best.inliers.size());
    if (!attempt.detection() || attempt.inliers.size() <= best.inliers.size()) continue;
    const double agreement = measure_view_agreement(attempt, query_keypoints, query_descriptors);
    if (agreement <= accepted_agreement) continue;
    best = std::move(attempt);
    best_agreement = agreement;
  }
  if (best.match == result.match) return accepted_agreement;
  best.localised = true;
  best.localised_from = result.match;
  result = std::move(best);
  return best_agreement;
}

// The accepted strong fit explains too little of the views to stand alone:
// corroborated, or no loop. The trail's check of the match (the last one
// accepted) records the outcome.
void LoopDetector::Impl::corroborate_unexplained_view(LoopResult& result,
                                                      Span<Keypoint> query_keypoints,
                                                      const DescriptorView& query_descriptors,
                                                      const FeatureVector& query_nodes,
                                                      bool before_temporal_consistency) const {
  TrailCheck* check = trail != nullptr ? trail->accepted_check(result.match) : nullptr;
  result.corroboration = {};
  result.corroboration.needed = true;
  result.corroboration.view_unexplained = true;
  corroborate(result, query_keypoints, query_descriptors, query_nodes);
  if (check != nullptr) check->corroboration = result.corroboration;
  if (result.corroboration.corroborated) {
    result.accepted_by = detail::corroborating_evidence(result.corroboration);
    return;
  }
  result.status = before_temporal_consistency ? LoopStatus::kNoTemporalConsistency
                                              : LoopStatus::kNoGeometricConsistency;
  result.accepted_by = LoopEvidence::kNone;
}

void LoopDetector::Impl::record_islands() {
  // Runs of every length: the trail shows the short ones the detector dropped.
  std::vector<detail::Candidate> all = candidates;
  std::vector<detail::Island> runs;
  detail::compute_islands(all, params.max_intra_island_gap, 1, runs);
  for (const detail::Island& i : runs)
    trail->islands.push_back({i.first, i.last, i.score, i.best_entry, i.best_score,
                              i.length() >= params.min_matches_per_island});
}

void LoopDetector::Impl::record_temporal(const detail::Island& chosen,
                                         const detail::TemporalWindow::State& before,
                                         EntryId position, int chain_after) {
  for (std::size_t i = 0; i < trail->islands.size(); ++i)
    if (trail->islands[i].first == chosen.first) trail->chosen_island = static_cast<int>(i);
  trail->temporal_tested = true;
  TrailTemporal& t = trail->temporal;
  t.chain_before = before.consistent;
  t.previous_query = before.last_query;
  t.query = position;
  t.previous_first = before.last_first;
  t.previous_last = before.last_last;
  // As TemporalWindow::update measures it.
  const auto as_signed = [](EntryId e) { return static_cast<long long>(e); };
  t.island_gap = std::max(as_signed(before.last_first) - as_signed(chosen.last),
                          as_signed(chosen.first) - as_signed(before.last_last));
  t.chain_after = chain_after;
}

void LoopDetector::Impl::insert(BowVector& bow, const FeatureVector& nodes,
                                Span<Keypoint> image_keypoints, const DescriptorView& descriptors) {
  database.add(bow, nodes);
  FrameFeatures& kept = frames.emplace_back();
  if (keeps_features()) {
    kept.keypoints.assign(image_keypoints.begin(), image_keypoints.end());
    if (!descriptors.empty())
      kept.descriptors.assign(descriptors.data,
                              descriptors.data + descriptors.rows * descriptors.code_size);
  }
  if (!bow.empty() || !params.skip_featureless_frames) previous_bow = std::move(bow);
  if (!descriptors.empty()) ++featured_frames;
}

LoopResult LoopDetector::process(Span<Keypoint> keypoints, const DescriptorView& descriptors) {
  return impl_->run(keypoints, descriptors);
}

LoopResult LoopDetector::process(const Features& features, LoopDecisionTrail& trail) {
  return process(Span<Keypoint>{features.keypoints.data(), features.keypoints.size()},
                 features.descriptors.view(), trail);
}

LoopResult LoopDetector::process(Span<Keypoint> keypoints, const DescriptorView& descriptors,
                                 LoopDecisionTrail& trail) {
  trail = {};
  impl_->trail = &trail;
  // The trail is this call's only, even when it throws.
  struct Detach {
    Impl& d;
    ~Detach() { d.trail = nullptr; }
  } detach{*impl_};
  LoopResult result = impl_->run(keypoints, descriptors);
  trail.query = result.query;
  trail.status = result.status;
  trail.features = result.features;
  trail.match = result.has_candidate ? static_cast<long long>(result.match) : -1;
  return result;
}

TrailCheck LoopDetector::check_pair(EntryId query, EntryId match) const {
  const Impl& d = *impl_;
  d.check_remembered(query);
  d.check_remembered(match);
  const Impl::FrameFeatures& f = d.frames[query];
  const FeatureVector nodes = d.params.geometric_check == GeometricCheck::kDirectIndex
                                  ? d.database.feature_vector(query)
                                  : FeatureVector{};
  return d.geometric_check({f.keypoints.data(), f.keypoints.size()}, d.descriptors_of(query), nodes,
                           match);
}

LoopResult LoopDetector::Impl::run(Span<Keypoint> keypoints, const DescriptorView& descriptors) {
  Impl& d = *this;
  d.check_input(keypoints, descriptors);
  LoopResult result;
  Clock::time_point clock = Clock::now();
  BowVector bow;
  FeatureVector nodes;
  d.transform(descriptors, bow, nodes);
  result.times.transform_ms = milliseconds_since(clock);

  result.query = d.database.next_entry_id();
  result.features = keypoints.size();
  result.status = LoopStatus::kNoDatabaseResults;
  if (static_cast<long long>(result.query) > d.params.dislocal) {
    const std::vector<QueryResult> found = d.query(bow, result);
    result.times.query_ms = milliseconds_since(clock);
    if (d.passes_normalisation(found, result)) {
      d.select_island(found, result);
      result.times.islands_ms = milliseconds_since(clock);
      if (result.status == LoopStatus::kNoGeometricConsistency) {
        d.verify_island(result, keypoints, descriptors, nodes);
        d.examine_view(result, keypoints, descriptors, nodes, false);
        result.times.verification_ms = milliseconds_since(clock);
      } else if (result.status == LoopStatus::kNoTemporalConsistency &&
                 d.params.strong_fits_skip_temporal_check &&
                 d.params.min_uncorroborated_inliers > 0 &&
                 d.params.geometric_check != GeometricCheck::kNone) {
        LoopResult strong = result;
        d.verify(strong, keypoints, descriptors, nodes, true);
        d.examine_view(strong, keypoints, descriptors, nodes, true);
        if (strong.detection()) result = std::move(strong);
        result.times.verification_ms = milliseconds_since(clock);
      }
    }
  }

  if (result.detection()) {
    d.has_previous_loop = true;
    d.previous_loop_query = result.query;
    d.previous_loop_match = result.match;
  }
  d.insert(bow, nodes, keypoints, descriptors);
  result.times.insertion_ms = milliseconds_since(clock);
  return result;
}

std::size_t LoopDetector::size() const noexcept {
  return impl_->frames.size();
}
const LoopDetectorParams& LoopDetector::params() const noexcept {
  return impl_->params;
}
const Database& LoopDetector::database() const noexcept {
  return impl_->database;
}
const OnlineVocabulary* LoopDetector::online_vocabulary() const noexcept {
  return impl_->online ? &*impl_->online : nullptr;
}

void LoopDetector::Impl::check_remembered(EntryId frame) const {
  if (frame >= frames.size()) throw InvalidArgument("no image " + std::to_string(frame));
  if (!database.contains(frame))
    throw InvalidArgument("image " + std::to_string(frame) + " was forgotten");
}

Span<Keypoint> LoopDetector::keypoints(EntryId entry) const {
  impl_->check_remembered(entry);
  const std::vector<Keypoint>& kept = impl_->frames[entry].keypoints;
  return {kept.data(), kept.size()};
}

DescriptorView LoopDetector::descriptors(EntryId entry) const {
  impl_->check_remembered(entry);
  return impl_->descriptors_of(entry);
}

void LoopDetector::set_label(EntryId entry, std::string label) {
  impl_->check_remembered(entry);
  impl_->database.set_label(entry, std::move(label));
}

std::string LoopDetector::label(EntryId entry) const {
  impl_->check_remembered(entry);
  return impl_->database.label(entry);
}

// The frame's database entry is its id (process() adds every image), so the
// database's removed entries are the forgotten frames: one record of them,
// saved with the database.
void LoopDetector::forget(EntryId frame) {
  Impl& d = *impl_;
  if (frame >= d.frames.size())
    throw InvalidArgument("loop detector: cannot forget image " + std::to_string(frame) + ": " +
                          std::to_string(d.frames.size()) + " images processed");
  if (!d.database.contains(frame)) return;
  d.database.remove(frame);
  d.frames[frame] = {};
}

bool LoopDetector::is_forgotten(EntryId frame) const {
  if (frame >= size())
    throw InvalidArgument("loop detector: no image " + std::to_string(frame) + " (" +
                          std::to_string(size()) + " images processed)");
  return !impl_->database.contains(frame);
}

std::size_t LoopDetector::forgotten_count() const {
  return size() - impl_->database.size();
}

std::size_t LoopDetector::memory_usage() const {
  const Impl& d = *impl_;
  std::size_t bytes = d.database.memory_usage() +
                      d.frames.capacity() * sizeof(Impl::FrameFeatures) +
                      d.previous_bow.size() * sizeof(BowEntry) +
                      d.candidates.capacity() * sizeof(detail::Candidate) +
                      d.islands.capacity() * sizeof(detail::Island);
  for (const Impl::FrameFeatures& f : d.frames)
    bytes += f.keypoints.capacity() * sizeof(Keypoint) + f.descriptors.capacity();
  if (d.online) bytes += d.online->stats().memory_bytes;
  return bytes;
}

void LoopDetector::clear() {
  Impl& d = *impl_;
  d.database.clear();
  d.window.clear();
  d.previous_bow.clear();
  d.featured_frames = 0;
  d.has_previous_loop = false;
  d.previous_loop_query = d.previous_loop_match = 0;
  std::vector<Impl::FrameFeatures>().swap(d.frames);
  if (d.online) {
    // Copied first: emplace destroys the old vocabulary, and its options with it.
    const OnlineVocabularyOptions options = d.online->options();
    d.online.emplace(d.online->code_size(), options);
  }
}

}  // namespace binbow::loop
