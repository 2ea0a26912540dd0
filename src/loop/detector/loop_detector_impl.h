// The state behind binbow::loop::LoopDetector, shared by its logic
// (loop_detector.cpp) and its state file (loop_detector_file.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "binbow/loop/loop_detector.h"
#include "loop/detector/islands.h"

namespace binbow::loop {

namespace detail {
// The database a detector with these parameters keeps: a direct index for
// GeometricCheck::kDirectIndex, at direct_index_levels.
DatabaseOptions database_options(const LoopDetectorParams& params);
// Correspondences of `second` whose query feature (their `first`) lies within
// vision::kDistinctInlierRadius of a query feature of `first`'s.
std::size_t shared_query_features(Span<vision::Keypoint> query_keypoints,
                                  const std::vector<vision::Correspondence>& first,
                                  const std::vector<vision::Correspondence>& second);
// What accepted a weak fit that `c` corroborated.
LoopEvidence corroborating_evidence(const LoopCorroboration& c);
}  // namespace detail

struct LoopDetector::Impl {
  Impl(Database database_in, const LoopDetectorParams& p, std::size_t code_size_in)
      : params(p),
        database(std::move(database_in)),
        window(p.max_distance_between_islands, p.max_distance_between_queries),
        code_size(code_size_in) {}

  LoopDetectorParams params;
  Database database;
  // With an online vocabulary: its words, and the scratch of add_image().
  std::optional<OnlineVocabulary> online;
  OnlineImageWords image_words;
  detail::TemporalWindow window;
  BowVector previous_bow;
  // Images with features so far: the time axis of the temporal window when
  // featureless frames are skipped.
  EntryId featured_frames = 0;
  // The latest loop detected (query, match), which corroborates the next
  // weak ones (LoopDetectorParams::min_uncorroborated_inliers).
  bool has_previous_loop = false;
  EntryId previous_loop_query = 0, previous_loop_match = 0;
  // One per image processed (empty with GeometricCheck::kNone, and once
  // forgotten): arrays of their own, so that forget() frees them at once.
  struct FrameFeatures {
    std::vector<vision::Keypoint> keypoints;
    std::vector<std::uint8_t> descriptors;  // keypoints.size() rows of code_size bytes
  };
  std::vector<FrameFeatures> frames;
  std::size_t code_size = 0;
  // Scratch reused across frames.
  std::vector<detail::Candidate> candidates;
  std::vector<detail::Island> islands;
  // Set by process(..., trail) for that call only: where each stage records
  // what it saw. Null otherwise, and then nothing is recorded.
  LoopDecisionTrail* trail = nullptr;

  bool keeps_features() const { return params.geometric_check != GeometricCheck::kNone; }
  Span<vision::Keypoint> keypoints_of(EntryId frame) const {
    return {frames[frame].keypoints.data(), frames[frame].keypoints.size()};
  }
  DescriptorView descriptors_of(EntryId frame) const {
    const FrameFeatures& f = frames[frame];
    return {f.descriptors.data(), f.keypoints.size(), code_size};
  }
  // InvalidArgument unless `frame` was processed and not forgotten.
  void check_remembered(EntryId frame) const;
  // η's divisor: s(v_t, v_{t−Δt}), or 1 when the raw score is compared with α.
  double normalisation_factor(const LoopResult& result) const {
    return params.use_normalised_score ? result.normalisation_score : 1;
  }

  // The stages of Section V, in order; each sets result.status when the frame stops there.
  void check_input(Span<vision::Keypoint> image_keypoints, const DescriptorView& descriptors) const;
  // Adds the image to the online vocabulary, if there is one.
  void transform(const DescriptorView& descriptors, BowVector& bow, FeatureVector& nodes);
  std::vector<QueryResult> query(const BowVector& bow, LoopResult& result) const;
  bool passes_normalisation(const std::vector<QueryResult>& found, LoopResult& result) const;
  void select_island(const std::vector<QueryResult>& found, LoopResult& result);
  std::vector<detail::Candidate> other_island_candidates(const LoopResult& result) const;
  LoopResult with_match(const LoopResult& result, const detail::Candidate& candidate) const;
  // For a loop `result` accepted by verify() with before_temporal_consistency:
  // its fit's view agreement, when localisation or
  // min_uncorroborated_view_agreement asks for it; localise_in_island; then
  // corroborate_unexplained_view for a strong fit that explains too little.
  void examine_view(LoopResult& result, Span<vision::Keypoint> query_keypoints,
                    const DescriptorView& query_descriptors, const FeatureVector& query_nodes,
                    bool before_temporal_consistency) const;
  // vision::view_agreement() of result's fit, recorded in the trail's last check.
  double measure_view_agreement(const LoopResult& result, Span<vision::Keypoint> query_keypoints,
                                const DescriptorView& query_descriptors) const;
  // LoopDetectorParams::localise_in_island over `others` (the island's other
  // candidates, best η first) for a loop whose fit has accepted_agreement;
  // returns the agreement of the fit it ends with.
  double localise_in_island(LoopResult& result, Span<vision::Keypoint> query_keypoints,
                            const DescriptorView& query_descriptors,
                            const FeatureVector& query_nodes, bool before_temporal_consistency,
                            std::vector<detail::Candidate> others, double accepted_agreement) const;
  // LoopDetectorParams::min_uncorroborated_view_agreement.
  void corroborate_unexplained_view(LoopResult& result, Span<vision::Keypoint> query_keypoints,
                                    const DescriptorView& query_descriptors,
                                    const FeatureVector& query_nodes,
                                    bool before_temporal_consistency) const;
  void verify_island(LoopResult& result, Span<vision::Keypoint> query_keypoints,
                     const DescriptorView& query_descriptors, const FeatureVector& query_nodes);
  // before_temporal_consistency: only a strong fit (min_uncorroborated_inliers) is a loop.
  // rival_inliers > 0 (localisation): only a fit with more inliers counts, and
  // the direct index alone is tried.
  void verify(LoopResult& result, Span<vision::Keypoint> query_keypoints,
              const DescriptorView& query_descriptors, const FeatureVector& query_nodes,
              bool before_temporal_consistency = false, std::size_t rival_inliers = 0) const;
  // Stage 6 for one pair: correspondences, then the fundamental matrix.
  // strong_fit_only: only a fit of min_uncorroborated_inliers inliers counts,
  // so a direct-index fit with fewer is retried by exhaustive matching as an
  // inconsistent one is. rival_inliers: as verify()'s.
  TrailCheck geometric_check(Span<vision::Keypoint> query_keypoints,
                             const DescriptorView& query_descriptors,
                             const FeatureVector& query_nodes, EntryId match,
                             bool strong_fit_only = false, std::size_t rival_inliers = 0) const;
  LoopResult run(Span<vision::Keypoint> keypoints, const DescriptorView& descriptors);
  // Record in `trail` the islands of `candidates` (short ones too), and the
  // temporal test of the chosen island (the window's state before it).
  void record_islands();
  void record_temporal(const detail::Island& chosen, const detail::TemporalWindow::State& before,
                       EntryId position, int chain_after);
  // Sets c's latest-loop fields, and corroborated when that loop corroborates
  // the weak loop query → match (LoopDetectorParams::min_uncorroborated_inliers).
  void corroborate_by_previous_loop(LoopCorroboration& c, EntryId query, EntryId match) const;
  // Sets result's corroboration fields (LoopDetectorParams::min_uncorroborated_inliers).
  void corroborate(LoopResult& result, Span<vision::Keypoint> query_keypoints,
                   const DescriptorView& query_descriptors, const FeatureVector& query_nodes) const;
  void insert(BowVector& bow, const FeatureVector& nodes, Span<vision::Keypoint> image_keypoints,
              const DescriptorView& descriptors);
};

}  // namespace binbow::loop
