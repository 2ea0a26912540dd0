#include "binbow/loop/explanation.h"

#include <algorithm>
#include <cstdio>
#include <unordered_set>

#include "binbow/error.h"

namespace binbow::loop {
namespace {

std::string number(double value, const char* pattern = "%.3g") {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, pattern, value);
  return buffer;
}

std::string entry_range(EntryId first, EntryId last) {
  return first == last ? std::to_string(first) : std::to_string(first) + "–" + std::to_string(last);
}

std::string island_text(const TrailIsland& island) {
  return entry_range(island.first, island.last) + " (H " + number(island.score) + ")";
}

// "31–35": the ground-truth matches of the query, as a range.
std::string matches_text(const std::vector<std::uint32_t>& matches) {
  if (matches.empty()) return "none";
  return entry_range(matches[0], matches[matches.size() - 1]) +
         (matches.size() > 2 ? " (" + std::to_string(matches.size()) + " images)" : "");
}

}  // namespace

std::vector<CheckMeasure> check_measures(const TrailCheck& check,
                                         const LoopDetectorParams& params) {
  const double correspondences = static_cast<double>(check.correspondences.size());
  // Before temporal consistency only a strong fit counts, and a localisation
  // check must beat the accepted fit: the check asks for that many inliers.
  const bool rival = check.rival_inliers > 0;
  const bool strong_only =
      check.before_temporal_consistency && params.min_uncorroborated_inliers > params.min_inliers;
  const double min_inliers = check.inliers_asked(params);
  const std::string parameter = rival         ? "the accepted fit's inliers + 1"
                                : strong_only ? "min_uncorroborated_inliers"
                                              : "min_inliers";
  const std::string note = rival         ? "localisation"
                           : strong_only ? "before temporal consistency"
                                         : "";
  std::vector<CheckMeasure> measures;
  // check_fundamental fits nothing below max(8, min_inliers) correspondences.
  const double needed = std::max(8.0, min_inliers);
  measures.push_back({"correspondences", correspondences,
                      min_inliers >= 8 ? parameter : "max(8, " + parameter + ")", needed,
                      correspondences >= needed, true, note});
  const auto inliers = static_cast<double>(check.fit.inliers.size());
  measures.push_back(
      {"inliers", inliers, parameter, min_inliers, inliers >= min_inliers, true, note});
  if (params.min_inlier_ratio > 0)
    measures.push_back({"inlier ratio", check.fit.inlier_ratio, "min_inlier_ratio",
                        params.min_inlier_ratio, check.fit.inlier_ratio >= params.min_inlier_ratio,
                        false, ""});
  if (params.min_inlier_spread > 0)
    measures.push_back({"inlier spread", check.fit.inlier_spread, "min_inlier_spread",
                        params.min_inlier_spread,
                        check.fit.inlier_spread >= params.min_inlier_spread, false, ""});
  const vision::FitDeterminacy& d = check.fit.determinacy;
  if (params.reject_degenerate_fits && d.points > 0) {
    const auto share = [&d](std::size_t fits) {
      return static_cast<double>(fits) / static_cast<double>(d.points);
    };
    const std::string of = "of " + std::to_string(d.points) + " distinct points";
    const bool fundamental = d.evidence == vision::FitEvidence::kFundamental;
    const std::string narrow = d.on_a_line    ? ", near one line"
                               : d.on_a_patch ? ", within one cell of a 4 × 4 grid"
                                              : "";
    measures.push_back({"share fitting another fundamental matrix",
                        share(d.alternative_fundamental_fits), "reject_degenerate_fits",
                        vision::kAmbiguousShare, fundamental, false,
                        of + (d.fundamental_determined ? narrow : "")});
    if (!d.fundamental_determined)
      measures.push_back({"points following a homography", static_cast<double>(d.homography_fits),
                          "reject_degenerate_fits", 5,
                          d.evidence == vision::FitEvidence::kHomography, true,
                          of + (d.homography_fits < 5 ? ""
                                : narrow.empty()      ? ", which determine it"
                                                      : narrow)});
  }
  // Fewer inliers, or a fit explaining less of the views, pass only when
  // corroborated (by the latest loop or a neighbour).
  const double alone = params.min_uncorroborated_inliers;
  if (alone > 0 && !check.before_temporal_consistency && check.fit.consistent &&
      (check.corroboration.needed || inliers >= alone))
    measures.push_back({"inliers alone", inliers, "min_uncorroborated_inliers", alone,
                        inliers >= alone || check.corroboration.corroborated, true, ""});
  if (check.corroboration.view_unexplained)
    measures.push_back(
        {"view agreement alone", check.view_agreement, "min_uncorroborated_view_agreement",
         params.min_uncorroborated_view_agreement, check.corroboration.corroborated, false, ""});
  return measures;
}

std::string to_string(const CheckMeasure& m) {
  const char* pattern = m.whole ? "%.0f" : "%.3g";
  const std::string value = number(m.value, pattern);
  const std::string what = m.whole ? value + " " + m.name : m.name + " " + value;
  return what + (m.note.empty() ? "" : " (" + m.note + ")") +
         (m.value >= m.threshold ? " ≥ " : " < ") + m.parameter + " " +
         number(m.threshold, pattern);
}

std::string describe_check(const TrailCheck& check, const LoopDetectorParams& params) {
  std::string text = std::to_string(check.correspondences.size()) + " correspondences";
  if (check.exhaustive_fallback_used)
    text += " (exhaustive matching, after " + std::to_string(check.direct_index_correspondences) +
            " by the direct index)";
  else if (check.direct_index_correspondences >= 0)
    text += " (direct index)";
  else
    text += " (exhaustive matching)";
  const std::vector<CheckMeasure> measures = check_measures(check, params);
  std::string failed, passed;
  for (const CheckMeasure& m : measures) {
    // Below the correspondences needed, nothing was fitted: no inliers to compare.
    if (&m != &measures.front() && !measures.front().passed) break;
    std::string& list = m.passed ? passed : failed;
    list += (list.empty() ? "" : ", ") + to_string(m);
  }
  if (measures.front().passed) text += ", " + std::to_string(check.fit.inliers.size()) + " inliers";
  if (check.view_agreement >= 0) text += ", view agreement " + number(check.view_agreement);
  if (check.fit.consistent && check.corroboration.needed) {
    const LoopCorroboration& c = check.corroboration;
    const std::string weak = c.view_unexplained
                                 ? "view agreement " + number(check.view_agreement) +
                                       " < min_uncorroborated_view_agreement " +
                                       number(params.min_uncorroborated_view_agreement)
                                 : std::to_string(check.fit.inliers.size()) +
                                       " inliers < min_uncorroborated_inliers " +
                                       std::to_string(params.min_uncorroborated_inliers);
    const std::string near =
        "within corroboration_distance " + std::to_string(params.corroboration_distance);
    const std::string pace = "at the revisit's pace: corroboration_horizon " +
                             std::to_string(params.corroboration_horizon) +
                             ", corroboration_pace_tolerance " +
                             number(params.corroboration_pace_tolerance);
    std::string by;
    if (c.has_previous_loop)
      by = "the latest loop was " + std::to_string(c.previous_loop_query) + " → " +
           std::to_string(c.previous_loop_match) + " (" +
           (c.previous_loop_at_pace                  ? pace
            : c.corroborated && !c.neighbour_checked ? near
                                                     : "neither " + near + " nor " + pace) +
           ")";
    else
      by = "no earlier loop";
    if (check.corroboration.neighbour_checked)
      by += "; the best neighbour of the match, " +
            std::to_string(check.corroboration.corroborating_neighbour) + ", has " +
            std::to_string(check.corroboration.neighbour_inliers) + " inliers, " +
            std::to_string(check.corroboration.neighbour_shared_inliers) +
            " on query features the match's inliers use";
    if (check.corroboration.corroborated)
      return text + ": accepted (" + passed + "; " + weak + ", corroborated: " + by + ")";
    return text + ": rejected: " + weak + " and not corroborated (" + by + ")";
  }
  if (check.fit.consistent) return text + ": accepted (" + passed + ")";
  if (failed.empty()) return text + ": rejected by the estimator (no consistent model)";
  return text + ": rejected: " + failed;
}

const char* to_string(ExplainedStage stage) {
  switch (stage) {
    case ExplainedStage::kFound:
      return "found";
    case ExplainedStage::kNoGroundTruth:
      return "no ground-truth loop";
    case ExplainedStage::kNoFeatures:
      return "no features";
    case ExplainedStage::kInsideDislocal:
      return "inside dislocal";
    case ExplainedStage::kNoDatabaseResults:
      return "no database results";
    case ExplainedStage::kLowNormalisationScore:
      return "low normalisation score";
    case ExplainedStage::kNotAmongResults:
      return "not among the database results";
    case ExplainedStage::kBelowAlpha:
      return "below alpha";
    case ExplainedStage::kIslandTooShort:
      return "island too short";
    case ExplainedStage::kIslandNotChosen:
      return "island not chosen";
    case ExplainedStage::kTemporalConsistency:
      return "temporal consistency";
    case ExplainedStage::kOtherEntryVerified:
      return "another entry verified";
    case ExplainedStage::kWrongLoopAccepted:
      return "wrong loop accepted";
    case ExplainedStage::kGeometricCheck:
      return "geometric check";
  }
  return "unknown";
}

namespace {

// Builds the explanation stage by stage; each stage adds its step, and the
// first stage that loses the ground-truth match sets the stage and reason.
class Explainer {
 public:
  Explainer(const LoopDecisionTrail& trail, const GroundTruth& truth,
            const LoopDetectorParams& params, const LoopDetector* detector)
      : t_(trail), truth_(truth), p_(params), detector_(detector) {
    if (t_.query < truth_.frames()) matches_ = truth_.earlier_matches(t_.query);
  }

  LoopExplanation run() {
    e_.query = t_.query;
    const bool detected = t_.status == LoopStatus::kLoopDetected;
    if (detected) e_.detected_match = t_.match;
    const bool detected_true = detected && is_true(static_cast<EntryId>(t_.match));
    e_.false_loop = detected && !detected_true;
    e_.missed = !matches_.empty() && !detected_true;
    step("query " + std::to_string(t_.query) + ": " + std::to_string(t_.features) +
         " features; ground-truth matches: " + matches_text(matches_));
    explain_stages();
    if (e_.missed) recheck();
    if (detected_true) lost(ExplainedStage::kFound, "the loop was found");
    if (matches_.empty())
      lost(ExplainedStage::kNoGroundTruth, "the query has no ground-truth loop");
    if (e_.false_loop) {
      const TrailCheck* accepted = accepted_check();
      const bool alone = accepted != nullptr && accepted->before_temporal_consistency;
      std::string why = "false loop with " + std::to_string(t_.match) + " (η " +
                        number(accepted != nullptr ? accepted->normalised_score : 0) +
                        ", temporal consistency " + std::to_string(t_.temporal.chain_after - 1) +
                        (alone ? " < k " : " ≥ k ") + std::to_string(p_.k) +
                        (alone ? ", skipped by a strong fit" : "") +
                        ") accepted by the geometric check: ";
      if (accepted != nullptr)
        why += describe_check(*accepted, p_);
      else
        why = "false loop with " + std::to_string(t_.match) +
              " accepted without a geometric check (geometric_check none)";
      e_.reason = e_.stage == ExplainedStage::kNoGroundTruth ? why : why + "; " + e_.reason;
      if (accepted != nullptr)
        draw(*accepted, false);
      else
        e_.drawn_match = t_.match;
    }
    if (e_.drawn_match < 0 && e_.true_match < 0 && e_.missed) {
      // Nothing was checked: show the query beside a ground-truth match still.
      e_.true_match = matches_[0];
      for (const std::uint32_t j : matches_)
        if (static_cast<long long>(j) + p_.dislocal < static_cast<long long>(t_.query))
          e_.true_match = j;
    }
    if (e_.drawn_match < 0 && e_.true_match >= 0) e_.drawn_match = e_.true_match;
    return std::move(e_);
  }

 private:
  bool is_true(EntryId entry) const { return truth_.is_loop(t_.query, entry); }
  void step(std::string text) { e_.steps.push_back(std::move(text)); }
  // The first stage that loses the ground-truth match wins.
  void lost(ExplainedStage stage, std::string reason) {
    if (decided_) return;
    decided_ = true;
    e_.stage = stage;
    e_.reason = std::move(reason);
  }

  void explain_stages() {
    if (t_.features == 0) lost(ExplainedStage::kNoFeatures, "the query image has no features");
    const long long newest = static_cast<long long>(t_.query) - p_.dislocal - 1;
    std::size_t old_enough = 0;
    for (const std::uint32_t j : matches_) old_enough += static_cast<long long>(j) <= newest;
    if (!matches_.empty() && old_enough == 0)
      lost(ExplainedStage::kInsideDislocal,
           "every ground-truth match (" + matches_text(matches_) + ") is within dislocal " +
               std::to_string(p_.dislocal) + " of the query: candidates are entries ≤ " +
               (newest < 0 ? std::string("none") : std::to_string(newest)));
    if (!t_.queried) {
      step("no database query: candidates are entries < query − dislocal " +
           std::to_string(p_.dislocal) + ", and there are none");
      lost(ExplainedStage::kNoDatabaseResults,
           "no image is older than dislocal " + std::to_string(p_.dislocal));
      return;
    }
    explain_results();
  }

  void explain_results() {
    const auto& c = t_.candidates;
    if (c.empty()) {
      step("database: no earlier image (entries ≤ " + std::to_string(t_.newest_candidate) +
           ") shares a word with the query");
      lost(ExplainedStage::kNoDatabaseResults, "no earlier image shares a word with the query");
      return;
    }
    std::string best;
    for (std::size_t i = 0; i < c.size() && i < 3; ++i)
      best += (i ? ", " : "") + std::to_string(c[i].entry) + " η " + number(c[i].normalised_score);
    step("database: " + std::to_string(c.size()) + " results (max_db_results " +
         std::to_string(p_.max_db_results) + ", entries ≤ " + std::to_string(t_.newest_candidate) +
         "), best " + best);
    if (p_.use_normalised_score) {
      const bool low = t_.status == LoopStatus::kLowNormalisationScore;
      step("normalisation: s(v_t, v_t−Δt) = " + number(t_.normalisation_score) +
           (low ? " < " : " ≥ ") + "min_normalisation_score " + number(p_.min_normalisation_score) +
           (low ? ": the frame is skipped" : ""));
      if (low) {
        lost(ExplainedStage::kLowNormalisationScore,
             "normalisation score s(v_t, v_t−Δt) " + number(t_.normalisation_score) +
                 " < min_normalisation_score " + number(p_.min_normalisation_score) +
                 ": the frame was skipped");
        return;
      }
    } else {
      step("scores compared with α unnormalised (use_normalised_score false)");
    }
    std::size_t above = 0;
    for (const TrailCandidate& r : c) above += r.normalised_score >= p_.alpha;
    step(std::to_string(above) + " of " + std::to_string(c.size()) + " results reach α " +
         number(p_.alpha) + (above == 0 ? ": no candidate above alpha" : ""));
    // The ground-truth match with the highest η among the results.
    const TrailCandidate* truth_candidate = nullptr;
    std::size_t rank = 0;
    for (std::size_t i = 0; i < c.size(); ++i)
      if (is_true(c[i].entry) && truth_candidate == nullptr) {
        truth_candidate = &c[i];
        rank = i + 1;
      }
    if (!matches_.empty()) {
      if (truth_candidate == nullptr) {
        step("no ground-truth match among the " + std::to_string(c.size()) +
             " results (the last one has η " + number(c.back().normalised_score) + ")");
        lost(ExplainedStage::kNotAmongResults, "no ground-truth match (" + matches_text(matches_) +
                                                   ") among the " + std::to_string(c.size()) +
                                                   " database results (max_db_results " +
                                                   std::to_string(p_.max_db_results) + ")");
      } else {
        e_.true_match = truth_candidate->entry;
        const bool reaches = truth_candidate->normalised_score >= p_.alpha;
        const std::string eta = "η " + number(truth_candidate->normalised_score) +
                                (reaches ? " ≥ α " : " < α ") + number(p_.alpha);
        step("ground-truth match " + std::to_string(truth_candidate->entry) + ": result " +
             std::to_string(rank) + " of " + std::to_string(c.size()) + ", " + eta);
        if (!reaches)
          lost(ExplainedStage::kBelowAlpha,
               "ground-truth match " + std::to_string(truth_candidate->entry) + ": " + eta +
                   (above == 0 ? " (no candidate above alpha)" : ""));
      }
    }
    if (above == 0) {
      lost(ExplainedStage::kBelowAlpha, "no candidate above alpha " + number(p_.alpha));
      return;
    }
    explain_islands();
  }

  void explain_islands() {
    std::string list;
    for (std::size_t i = 0; i < t_.islands.size() && i < 6; ++i) {
      const TrailIsland& island = t_.islands[i];
      list += (i ? ", " : "") + island_text(island) +
              (static_cast<int>(i) == t_.chosen_island ? " chosen"
               : island.long_enough                    ? ""
                                                       : " too short");
    }
    if (t_.islands.size() > 6) list += ", …";
    step("islands (max_intra_island_gap " + std::to_string(p_.max_intra_island_gap) + "): " + list);
    const TrailIsland* chosen = t_.chosen_island >= 0 ? &t_.islands[t_.chosen_island] : nullptr;
    const TrailIsland* own = nullptr;  // the ground-truth match's island
    if (e_.true_match >= 0)
      for (const TrailIsland& island : t_.islands)
        if (island.first <= e_.true_match && e_.true_match <= island.last) own = &island;
    const std::string match = "ground-truth match " + std::to_string(e_.true_match);
    if (own != nullptr && !own->long_enough)
      lost(ExplainedStage::kIslandTooShort,
           match + ": its island " + entry_range(own->first, own->last) + " spans " +
               std::to_string(own->last - own->first + 1) + " < min_matches_per_island " +
               std::to_string(p_.min_matches_per_island));
    if (chosen == nullptr) {
      lost(ExplainedStage::kIslandTooShort,
           "no island spans min_matches_per_island " + std::to_string(p_.min_matches_per_island));
      return;
    }
    if (own != nullptr && own != chosen)
      lost(ExplainedStage::kIslandNotChosen,
           match + ": its island " + island_text(*own) +
               (own->score < chosen->score ? " scores below the chosen island "
                                           : " ties with the earlier chosen island ") +
               island_text(*chosen));
    if (own == nullptr && e_.true_match >= 0)
      lost(ExplainedStage::kIslandNotChosen, match + " is in no island");
    if (own == nullptr && e_.true_match < 0 && !matches_.empty())
      lost(ExplainedStage::kIslandNotChosen,
           "the chosen island " + island_text(*chosen) + " holds no ground-truth match");
    explain_temporal(*chosen);
  }

  void explain_temporal(const TrailIsland& chosen) {
    if (!t_.temporal_tested) return;
    const TrailTemporal& tc = t_.temporal;
    std::string chain;
    if (tc.chain_before == 0) {
      chain = "no chain before this query";
    } else if (static_cast<long long>(tc.query) - static_cast<long long>(tc.previous_query) >
               p_.max_distance_between_queries) {
      chain = "chain restarted: the previous query with an island is " +
              std::to_string(tc.query - tc.previous_query) +
              " images back > max_distance_between_queries " +
              std::to_string(p_.max_distance_between_queries);
    } else if (tc.island_gap > p_.max_distance_between_islands) {
      chain = "chain restarted: island " + entry_range(chosen.first, chosen.last) + " is " +
              std::to_string(tc.island_gap) + " entries from the previous query's island " +
              entry_range(tc.previous_first, tc.previous_last) +
              " > max_distance_between_islands " + std::to_string(p_.max_distance_between_islands);
    } else {
      chain = "chain continued from the previous query's island " +
              entry_range(tc.previous_first, tc.previous_last);
    }
    const int before = tc.chain_after - 1;
    const bool passes = tc.chain_after > p_.k;
    const std::string sentence = "temporal consistency " + std::to_string(before) +
                                 (passes ? " ≥ k " : " < k ") + std::to_string(p_.k) +
                                 " (consistent queries before this one; " + chain + ")";
    step(sentence);
    if (!passes) {
      const TrailCheck* early = t_.checks.empty() ? nullptr : &t_.checks.front();
      if (early != nullptr && early->accepted()) {
        step("a fit of min_uncorroborated_inliers " +
             std::to_string(p_.min_uncorroborated_inliers) +
             " inliers or more is a loop without temporal consistency "
             "(strong_fits_skip_temporal_check)");
        explain_checks();
        return;
      }
      lost(ExplainedStage::kTemporalConsistency,
           early == nullptr
               ? sentence
               : sentence + "; the strong-fit check of " + std::to_string(early->entry) +
                     " before it: " + describe_check(*early, p_));
      return;
    }
    explain_checks();
  }

  // The check that accepted the loop (or the wrong candidate); null without one.
  const TrailCheck* accepted_check() const {
    return t_.match < 0 ? nullptr : t_.accepted_check(static_cast<EntryId>(t_.match));
  }

  void explain_checks() {
    if (p_.geometric_check == GeometricCheck::kNone) {
      step("no geometric check (geometric_check none): the island's best entry is the loop");
      return;
    }
    const TrailCheck* truth_check = nullptr;
    for (const TrailCheck& c : t_.checks) {
      step("geometric check of " + std::to_string(c.entry) + " (η " + number(c.normalised_score) +
           (is_true(c.entry) ? ", a ground-truth match" : ", not a ground-truth match") +
           "): " + describe_check(c, p_));
      if (is_true(c.entry) && truth_check == nullptr) truth_check = &c;
    }
    if (matches_.empty()) return;
    if (truth_check != nullptr) {
      e_.true_match = truth_check->entry;
      if (!truth_check->accepted()) {
        lost(ExplainedStage::kGeometricCheck, "geometric check of ground-truth match " +
                                                  std::to_string(truth_check->entry) + ": " +
                                                  describe_check(*truth_check, p_));
        draw(*truth_check, false);
      }
      return;
    }
    if (t_.checks.empty()) return;
    if (const TrailCheck* accepted = accepted_check())
      lost(ExplainedStage::kWrongLoopAccepted,
           "entry " + std::to_string(accepted->entry) +
               " of the chosen island (not a ground-truth match) passed the geometric check");
    else
      lost(ExplainedStage::kOtherEntryVerified,
           "the island's entry " + std::to_string(t_.checks.front().entry) +
               " (not a ground-truth match) was checked and failed; no ground-truth match was "
               "checked (max_verified_entries " +
               std::to_string(p_.max_verified_entries) + ")");
  }

  // A ground-truth match the detector never checked geometrically is
  // checked now, with the detector's parameters: would the check have let
  // it through?
  void recheck() {
    if (detector_ == nullptr || e_.has_check || t_.features == 0 ||
        p_.geometric_check == GeometricCheck::kNone || t_.query >= detector_->size() ||
        detector_->is_forgotten(t_.query))
      return;
    for (const TrailCheck& c : t_.checks)
      if (is_true(c.entry)) return;
    const long long newest = static_cast<long long>(t_.query) - p_.dislocal - 1;
    std::vector<EntryId> tried;
    if (e_.true_match >= 0) {
      tried.push_back(static_cast<EntryId>(e_.true_match));
    } else {
      // No ground-truth match among the results: up to five, spread over them.
      std::vector<EntryId> eligible;
      for (const std::uint32_t j : matches_)
        if (static_cast<long long>(j) <= newest) eligible.push_back(j);
      const std::size_t n = std::min<std::size_t>(5, eligible.size());
      for (std::size_t i = 0; i < n; ++i) tried.push_back(eligible[i * eligible.size() / n]);
    }
    bool any = false;
    TrailCheck best;
    for (const EntryId j : tried) {
      if (j >= detector_->size() || detector_->is_forgotten(j)) continue;
      TrailCheck c = detector_->check_pair(t_.query, j);
      if (!any || c.fit.inliers.size() > best.fit.inliers.size()) best = std::move(c);
      any = true;
    }
    if (!any) return;
    if (e_.true_match < 0) e_.true_match = best.entry;
    for (const TrailCandidate& c : t_.candidates)
      if (c.entry == best.entry) best.normalised_score = c.normalised_score;
    step("had ground-truth match " + std::to_string(best.entry) +
         " been checked (run for this explanation, same parameters): " + describe_check(best, p_));
    draw(best, true);
  }

  void draw(const TrailCheck& check, bool rerun) {
    e_.has_check = true;
    e_.check_rerun = rerun;
    e_.measures = check_measures(check, p_);
    e_.check_correspondences = check.correspondences.size();
    e_.check_inliers = check.fit.inliers.size();
    e_.drawn_match = check.entry;
    if (detector_ == nullptr || t_.query >= detector_->size() || check.entry >= detector_->size() ||
        detector_->is_forgotten(t_.query) || detector_->is_forgotten(check.entry))
      return;
    const Span<vision::Keypoint> q = detector_->keypoints(t_.query);
    const Span<vision::Keypoint> m = detector_->keypoints(check.entry);
    std::unordered_set<std::uint64_t> inliers;
    const auto key = [](const vision::Correspondence& c) {
      return (std::uint64_t{c.first} << 32) | c.second;
    };
    for (const vision::Correspondence& c : check.fit.inliers) inliers.insert(key(c));
    std::vector<ExplainedCorrespondence> in, out;
    for (const vision::Correspondence& c : check.correspondences) {
      if (c.first >= q.size() || c.second >= m.size()) continue;
      ExplainedCorrespondence d{{q[c.first].x, q[c.first].y, m[c.second].x, m[c.second].y},
                                inliers.count(key(c)) > 0};
      (d.inlier ? in : out).push_back(d);
    }
    // Inliers and rejected ones share the budget; what one leaves unused goes to the other.
    const auto take = [&](const std::vector<ExplainedCorrespondence>& from, std::size_t n) {
      n = std::min(n, from.size());
      for (std::size_t i = 0; i < n; ++i) e_.correspondences.push_back(from[i * from.size() / n]);
    };
    e_.correspondences.clear();
    const std::size_t budget = kExplainedCorrespondences;
    const std::size_t rejected = std::min(out.size(), budget - std::min(in.size(), budget / 2));
    take(in, budget - rejected);
    take(out, rejected);
  }

  const LoopDecisionTrail& t_;
  const GroundTruth& truth_;
  const LoopDetectorParams& p_;
  const LoopDetector* detector_;
  std::vector<std::uint32_t> matches_;
  LoopExplanation e_;
  bool decided_ = false;
};

}  // namespace

LoopExplanation explain_frame(const LoopDecisionTrail& trail, const GroundTruth& truth,
                              const LoopDetectorParams& params, const LoopDetector* detector) {
  return Explainer(trail, truth, params, detector).run();
}

RunExplanations explain_run(const LoopRun& run, const RunFeatures& features,
                            const Vocabulary& vocabulary, const GroundTruth& truth,
                            std::size_t max_pictured, const SweepProgress& progress) {
  const std::string name = run.path.empty() ? "the run's parameters" : run.path;
  const LoopDetectorParams params = LoopDetectorParams::from_json(run.params_json, name);
  OnlineVocabularyOptions online_options = run.online_options;
  online_options.descriptor = run.descriptor;
  LoopDetector detector =
      run.online_vocabulary
          ? LoopDetector::online(make_run_extractor(run)->code_size(), online_options, params)
          : LoopDetector(vocabulary, params);
  RunExplanations out;
  LoopDecisionTrail trail;
  const std::size_t frames = features.features.size();
  for (std::size_t i = 0; i < frames; ++i) {
    detector.process(features.features[i], trail);
    if (i < run.frames.size() && out.note.empty() &&
        run.frames[i].status != kUnreadableFrameStatus &&
        run.frames[i].status != to_string(trail.status))
      out.note = "re-running detection gave frame " + std::to_string(i) + " the status " +
                 to_string(trail.status) + " where the record says " + run.frames[i].status +
                 "; the explanations describe the re-run";
    const bool detected = trail.status == LoopStatus::kLoopDetected;
    const bool false_loop = detected && (i >= truth.frames() ||
                                         !truth.is_loop(i, static_cast<std::size_t>(trail.match)));
    const bool has_loop = truth.has_loop(i);
    if (false_loop || (has_loop && !(detected && !false_loop))) {
      // Re-checks cost a few RANSAC runs each: bounded for runs with many misses.
      LoopExplanation e = explain_frame(
          trail, truth, params, out.cases.size() < kMaxRecheckedCases ? &detector : nullptr);
      if (out.pictured < max_pictured) {
        ++out.pictured;
        e.query_file = features.names[i];
        const double qs = i < features.scales.size() ? features.scales[i] : 1;
        double ms = 1;
        if (e.drawn_match >= 0 && static_cast<std::size_t>(e.drawn_match) < features.names.size()) {
          const auto match = static_cast<std::size_t>(e.drawn_match);
          e.match_file = features.names[match];
          if (match < features.scales.size()) ms = features.scales[match];
        }
        for (ExplainedCorrespondence& c : e.correspondences) {
          c.points[0] = static_cast<float>(c.points[0] / qs);
          c.points[1] = static_cast<float>(c.points[1] / qs);
          c.points[2] = static_cast<float>(c.points[2] / ms);
          c.points[3] = static_cast<float>(c.points[3] / ms);
        }
      } else {
        e.correspondences.clear();
        e.correspondences.shrink_to_fit();
      }
      out.cases.push_back(std::move(e));
    }
    if (progress) progress("explaining", i + 1, frames);
  }
  return out;
}

}  // namespace binbow::loop
