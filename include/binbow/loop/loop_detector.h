// The paper's loop detector (Gálvez-López & Tardós 2012, Section V;
// DLoopDetector): every image of a sequence is turned into a BoW vector,
// queried against the earlier images, and a loop is reported when
//   1. the normalised similarity η = s(v_t, v_j) / s(v_t, v_{t−Δt}) of the
//      candidates reaches α (frames whose s(v_t, v_{t−Δt}) is too small to
//      normalise by are skipped),
//   2. the candidates, grouped into islands of nearby entries, give a best
//      island (highest H = Σ η) that
//   3. agrees with the islands of the k previous queries (temporal
//      consistency), and
//   4. the best entry of that island and the query have a fundamental matrix
//      with enough RANSAC inliers (geometric consistency; binbow's default
//      estimator is MAGSAC++, see LoopDetectorParams), and a weak one (fewer
//      than min_uncorroborated_inliers, or one that explains little of the
//      two views) follows a loop near the same match or is confirmed by a
//      neighbour of the match.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/descriptors.h"
#include "binbow/loop/corroboration.h"
#include "binbow/loop/decision_trail.h"
#include "binbow/online_vocabulary.h"
#include "binbow/span.h"
#include "binbow/types.h"
#include "binbow/vision/features.h"
#include "binbow/vision/geometric_check.h"
#include "binbow/vocabulary.h"

namespace binbow::loop {

// How candidate correspondences for the fundamental matrix are found.
enum class GeometricCheck : std::uint8_t {
  kDirectIndex,  // features under the same vocabulary node at `direct_index_levels` (paper)
  kExhaustive,   // every feature against every feature
  kNone,         // no geometric check: temporally consistent candidates are loops
};

// "direct-index", "exhaustive", "none".
const char* to_string(GeometricCheck check);
// Accepts the names above ('_' for '-' too); throws InvalidArgument listing them.
GeometricCheck parse_geometric_check(const std::string& name);

// Limits of LoopDetectorParams, checked by validate() (and so by load(),
// from_json() and the LoopDetector constructor). The upper bounds bound the
// work a parameter file can ask for: per frame, at most 2 ×
// max_verified_entries RANSAC runs (the direct index, then the exhaustive
// fallback) and max_localisation_checks more (the direct index only) of at
// most max_ransac_iterations iterations each. See also docs/limits.md.
inline constexpr double kMaxFrequency = 10000;       // Hz
inline constexpr double kMaxScoreThreshold = 1000;   // alpha, min_normalisation_score
inline constexpr int kMaxFrameDistance = 1'000'000;  // every frame-count parameter
inline constexpr int kMaxConsistentQueries = 1000;   // k
inline constexpr int kMaxDirectIndexLevels = 16;     // direct_index_levels
inline constexpr int kMaxVerifiedEntries = 10;       // max_verified_entries
inline constexpr int kMaxLocalisationChecks = 50;    // max_localisation_checks
// A fit whose vision::view_agreement() reaches this explains most of both
// views: localise_in_island leaves such a loop where it is, and it is the
// default of min_uncorroborated_view_agreement.
inline constexpr double kViewExplained = 0.5;
inline constexpr int kMaxMinInliers = 10'000;         // min_inliers
inline constexpr double kMinReprojectionError = 0.1;  // pixels
inline constexpr double kMaxReprojectionError = 100;  // pixels
inline constexpr int kMaxRansacIterations = 5000;     // max_ransac_iterations
inline constexpr std::size_t kMaxLoopParamsFileBytes = std::size_t{1} << 20;  // load()

// Every parameter of the detector, with its valid range in brackets. The
// defaults are the paper's (and DLoopDetector's) at a frequency of 1 Hz,
// except binbow's measured departures, each switchable back:
// accept_single_candidate, exhaustive_fallback, skip_featureless_frames,
// fundamental_estimator, reject_degenerate_fits, min_uncorroborated_inliers,
// min_uncorroborated_view_agreement, strong_fits_skip_temporal_check and
// localise_in_island (docs/loop-detection.md has their effect).
// The DLoopDetector rules: {"accept_single_candidate": true,
// "exhaustive_fallback": false, "skip_featureless_frames": false,
// "fundamental_estimator": "ransac", "reject_degenerate_fits": false,
// "min_uncorroborated_inliers": 0, "strong_fits_skip_temporal_check": false,
// "localise_in_island": false} (min_uncorroborated_view_agreement applies
// only with min_uncorroborated_inliers: without it every fit stands alone).
// for_frequency() scales the frame-count parameters to another image rate as
// DLoopDetector does. Every number must be finite.
struct LoopDetectorParams {
  // Images per second the parameters below were derived for (informative).
  // (0, 10000]
  double frequency = 1;

  // --- Normalised similarity score (paper Section V-A)
  bool use_normalised_score = true;  // η instead of the raw score
  double alpha = 0.3;                // α: minimum η (or raw score) of a candidate [0, 1000]
  // Frames with s(v_t, v_{t−Δt}) below this are skipped (status
  // kLowNormalisationScore): η would divide by a meaningless score. [0, 1000]
  double min_normalisation_score = 0.005;
  // binbow's addition, on by default: an image without features (blurred,
  // dark, blank) is invisible to the temporal rules. It is not the previous
  // image v_{t−Δt} that η divides by (the latest image with features is),
  // and it does not count in max_distance_between_queries. With false
  // (DLoopDetector), the frame after a featureless one is skipped (its
  // normalisation score is 0) and the temporal chain restarts, costing the
  // k frames after it. See docs/loop-detection.md.
  bool skip_featureless_frames = true;

  // --- Database query
  int dislocal = 20;        // candidates of image t are entries j < t − dislocal (20 f) [0, 1e6]
  int max_db_results = 50;  // candidates taken from each query (50 f) [1, 1e6]
  // Query the database in fast mode (QueryMode::kFast): the same exact
  // scores, but read from the candidates that the query's rarest words
  // find, for databases of many images that share most words. Off by
  // default. Fast mode reads the whole index until skipping words saves
  // more postings than its candidates hold words (~1M postings per query,
  // ~20,000 images of 1000 features that share most words): smaller maps
  // get the same loops either way.
  bool fast_queries = false;

  // --- Islands (Section V-B)
  // Entries j < j' join the same island when j' − j < gap (3 f). [1, 1e6]
  int max_intra_island_gap = 3;
  int min_matches_per_island = 1;  // minimum island length, last − first + 1 (f) [1, 1e6]

  // --- Temporal consistency (Section V-C)
  int k = 3;  // consistent previous queries needed [0, 1000]
  // Islands of consecutive queries this far apart still agree (3 f). [0, 1e6]
  int max_distance_between_islands = 3;
  int max_distance_between_queries = 2;  // queries further apart break the chain (2 f) [1, 1e6]

  // --- Geometric check (Section V-D)
  GeometricCheck geometric_check = GeometricCheck::kDirectIndex;
  int direct_index_levels = 2;  // l: direct index this many levels above the words [0, 16]
  // binbow's addition, on by default: when the direct index yields no
  // consistent fundamental matrix, retry once with exhaustive matching. The
  // direct index is an accelerator whose recall depends on how well the
  // vocabulary fits the images (a descriptor and its true partner often fall
  // under different nodes when it does not); RANSAC still guards precision,
  // and the extra cost is one exhaustive match for the single candidate that
  // passed every other test. See docs/loop-detection.md.
  bool exhaustive_fallback = true;
  // Entries of the best island checked, best η first, until one is
  // geometrically consistent. 1 (the paper): only the island's best entry.
  // More raise BRIEF recall but let false loops through (see
  // docs/loop-detection.md). [1, 10]
  int max_verified_entries = 1;
  double max_neighbor_ratio = 0.6;  // nearest-neighbour ratio test of correspondences (0, 1]
  // Largest Hamming distance of a correspondence, as a fraction of the
  // descriptor's bits. binbow's addition (see exhaustive_fallback's note).
  // [0, 1]
  double max_match_distance = 1.0;
  // Accept a correspondence whose feature has a single candidate under its
  // direct-index node (no second neighbour for the ratio test), as
  // DLoopDetector does. Off by default: see MatchOptions.
  bool accept_single_candidate = false;
  // binbow's addition: a correspondence must pass the ratio test both ways
  // (MatchOptions::mutual).
  bool mutual_matching = false;
  // The robust estimator. binbow's default is MAGSAC++ (OpenCV's USAC):
  // its local optimisation finds the full inlier set where plain RANSAC
  // (the paper, "ransac") stops at a partial one below min_inliers.
  vision::FundamentalEstimator fundamental_estimator = vision::FundamentalEstimator::kUsacMagsac;
  int min_inliers = 12;                 // minimum RANSAC inliers of the fundamental matrix [8, 1e4]
  double max_reprojection_error = 2.0;  // pixels, RANSAC threshold [0.1, 100]
  double ransac_confidence = 0.99;      // (0, 1)
  int max_ransac_iterations = 500;      // [1, 5000]
  // binbow's additions (FundamentalCheckParams): minimum inliers /
  // correspondences, and minimum inlier_spread() over both images. [0, 1]
  double min_inlier_ratio = 0;
  double min_inlier_spread = 0;
  // binbow's addition, on by default: a fit whose inliers do not determine
  // its geometry (vision::fit_determinacy(): too few distinct points, points
  // near a line or on one small patch) accepts no loop, whatever its count
  // of inliers (FundamentalCheckParams::reject_degenerate).
  bool reject_degenerate_fits = true;
  // binbow's addition, on by default: a loop whose fundamental matrix has
  // fewer inliers than this must be corroborated, by the loop before it or
  // else by a second place: the match's neighbour (match − 1 or match + 1)
  // also passes the geometric check with the query. The loop before it
  // corroborates when it is near (detected at most corroboration_distance
  // queries earlier, with its match at most corroboration_distance entries
  // from this match), or when the revisit kept its pace since (detected at
  // most corroboration_horizon queries earlier, and its match is as many
  // entries from this match as its query is queries from this query, either
  // way, give or take corroboration_pace_tolerance of that many): a camera
  // that lost the place for a few frames (dim or blank images) and finds
  // it again where its pace puts it. A camera that is really back at a
  // place keeps recognising it and sees what the neighbouring frames saw,
  // where a chance fit of a dozen matches of repeated or distant structure
  // (what re-encoded, noisy or rescaled frames of another place give) comes
  // alone, with one image, or jumps entries away from the loop before it.
  // Loops with at least this many inliers stand alone. 0: off (the paper).
  // [0, 1e4]
  int min_uncorroborated_inliers = 16;
  // binbow's addition, on by default: a fit of min_uncorroborated_inliers
  // inliers or more stands alone only when it also explains this share of
  // both views (vision::view_agreement(), after localise_in_island). One that
  // explains less, before or after the temporal test, is a loop only when a
  // second image agrees: the latest loop is near it or at the revisit's pace
  // (as for a weak fit), or a neighbour of the match (match − 1 or match + 1)
  // passes the geometric check with the query, on any of its features. Along
  // a corridor of repeated doors and lamps, the image at the next door along
  // can fit a dozen or two of the query's features, as many as a true
  // revisit, but nothing else of either view; when the images of the
  // query's own spot cannot show more (occluded, blurred), localisation has
  // nothing to move such a fit to. That alignment of repeated objects holds
  // from one viewpoint, where a place really seen again is seen from the
  // frames beside the match too (revisits under blur and noise often
  // explain less than half of the view, and their neighbours fit). 0: off;
  // off too when min_uncorroborated_inliers is 0. [0, 1]
  double min_uncorroborated_view_agreement = kViewExplained;
  // binbow's addition, on by default: when the temporal test fails, the best
  // island's best entry is checked anyway, and a fit with at least
  // min_uncorroborated_inliers inliers (non-degenerate) is a loop on its
  // own, or with a second image when it explains little of the views
  // (min_uncorroborated_view_agreement). Temporal consistency is
  // corroboration by the next queries; a fit that needs no corroboration
  // needs none of them either, and a revisit of a few frames cannot wait for
  // k + 1 of them. Weaker fits still need the temporal test. Off when
  // min_uncorroborated_inliers is 0.
  bool strong_fits_skip_temporal_check = true;
  // binbow's addition, on by default: a loop whose fit explains less than
  // most of the two views (vision::view_agreement() below kViewExplained)
  // is checked against the other candidates of its island too (the
  // max_localisation_checks best η), and moves to the one that is also
  // accepted with more inliers and a larger view_agreement() (the most
  // inliers of such). The island's best η is the place; which of its
  // images was taken from where the camera is now is a question for the
  // geometry. Along a corridor of repeated lamps and doors, the image a few
  // metres back shares the most words with the query and fits a dozen of
  // its repeated objects, which explain little of either view, while the
  // image from the same spot fits many more features and shows much of the
  // view again. These checks match through the direct index only (no
  // exhaustive fallback), and run RANSAC only with more correspondences
  // than the accepted fit has inliers.
  bool localise_in_island = true;
  int max_localisation_checks = 8;  // [1, 50]
  int corroboration_distance = 4;   // frames (4 f) [1, 1e6]
  int corroboration_horizon = 10;   // frames (10 f) [1, 1e6]
  // Fraction of the queries since the loop before it. [0, 1]
  double corroboration_pace_tolerance = 0.25;

  // The defaults with frame-count parameters scaled to `frequency` Hz
  // (dislocal 20 f, max_db_results 50 f, gaps 3 f, min_matches_per_island f,
  // max_distance_between_queries 2 f, corroboration_distance 4 f,
  // corroboration_horizon 10 f; at least 1 each where it matters).
  static LoopDetectorParams for_frequency(double frequency);

  // Reads a JSON file (content starting with '{', or a .json name) or a YAML
  // file (a flat mapping, as OpenCV writes it; see docs/limits.md), at most
  // kMaxLoopParamsFileBytes and nested at most 64 levels. Keys are the field names above;
  // keys absent keep their value in `defaults`. A "frequency" key first scales
  // the frame-count parameters to it (as for_frequency), the other keys then
  // override. geometric_check takes the to_string() names. JSON and YAML
  // values go through one validation: unknown keys, wrong types, non-finite
  // numbers (YAML's .inf, .nan) and values out of range are FileErrors naming
  // the file and the key. Anything but a regular file (a FIFO, a device) is
  // refused before reading.
  static LoopDetectorParams load(const std::string& path, const LoopDetectorParams& defaults);
  static LoopDetectorParams load(const std::string& path);  // defaults: the paper's
  // Same from JSON text; `name` is used in error messages.
  static LoopDetectorParams from_json(const std::string& text, const std::string& name,
                                      const LoopDetectorParams& defaults);
  static LoopDetectorParams from_json(const std::string& text, const std::string& name = "<json>");
  // Every field as a JSON object (the format load() reads), pretty-printed.
  std::string to_json() const;

  // Throws InvalidArgument naming the first field that is not finite or out
  // of its range.
  void validate() const;
};

// Why a frame did or did not close a loop (DLoopDetector's DetectionStatus).
enum class LoopStatus : std::uint8_t {
  kLoopDetected,
  kNoDatabaseResults,       // no earlier image (outside `dislocal`) shares a word
  kLowNormalisationScore,   // s(v_t, v_{t−Δt}) < min_normalisation_score: frame skipped
  kLowScores,               // no candidate reaches α
  kNoIslands,               // no island long enough
  kNoTemporalConsistency,   // best island disagrees with the previous queries' islands
  kNoGeometricConsistency,  // fundamental-matrix check failed
};

// "loop-detected", "no-database-results", "low-normalisation-score",
// "low-scores", "no-islands", "no-temporal-consistency",
// "no-geometric-consistency".
const char* to_string(LoopStatus status);

// Wall-clock time of each stage of one process() call, milliseconds.
struct LoopStageTimes {
  double transform_ms = 0;     // descriptors → BoW vector (and direct index)
  double query_ms = 0;         // database query and η
  double islands_ms = 0;       // islands and temporal consistency
  double verification_ms = 0;  // correspondences and RANSAC
  double insertion_ms = 0;     // adding the image to the database and feature store
};

struct LoopResult {
  LoopStatus status = LoopStatus::kNoDatabaseResults;
  EntryId query = 0;         // entry id of the processed image (= its 0-based index)
  std::size_t features = 0;  // keypoints of the image (0: it can match nothing)
  // The loop when detected; otherwise the best candidate so far (the best
  // entry of the best island, or the best-scoring entry), if any.
  bool has_candidate = false;
  EntryId match = 0;
  double score = 0;                // s(v_t, v_match)
  double normalisation_score = 0;  // s(v_t, v_{t−Δt}), 0 before the first query
  double normalised_score = 0;     // η of the match (= score without normalisation)
  double island_score = 0;         // H of the best island
  EntryId island_first = 0, island_last = 0;
  int consistent_queries = 0;       // queries agreeing so far, this one included
  std::size_t correspondences = 0;  // putative correspondences given to RANSAC
  bool exhaustive_fallback_used = false;
  // RANSAC inliers: first = feature of the query, second = feature of the match.
  std::vector<vision::Correspondence> inliers;
  // The measures of the last geometric check of the match
  // (vision::FundamentalCheckResult; 0 before any check).
  double inlier_ratio = 0;
  double inlier_spread = 0;
  std::size_t distinct_inliers = 0;
  double inlier_thickness = 0;
  LoopCorroboration corroboration;
  // What accepted the loop (kNone unless detection()).
  LoopEvidence accepted_by = LoopEvidence::kNone;
  // Whether localisation (LoopDetectorParams::localise_in_island) moved the
  // loop from localised_from, the island's entry first accepted, to match.
  bool localised = false;
  EntryId localised_from = 0;
  // The fit's evidence (vision::FitDeterminacy::evidence; kNone before any check).
  vision::FitEvidence fit_evidence = vision::FitEvidence::kNone;
  LoopStageTimes times;

  bool detection() const noexcept { return status == LoopStatus::kLoopDetected; }
};

// What the header and the small sections of a .bbld state file say
// (LoopDetector::inspect): enough to choose how to load it.
struct LoopDetectorFileInfo {
  std::uint32_t version = 0;
  // An online vocabulary's state (LoopDetector::load(path)); otherwise a fixed
  // vocabulary's (LoopDetector::load(path, vocabulary)).
  bool online = false;
  std::size_t code_size = 0;  // bytes per descriptor
  // The extractor recorded by the vocabulary ("orb", "brief", ...; "" when
  // the vocabulary does not say).
  std::string descriptor;
  std::size_t frames = 0;  // images processed: the next one gets this entry id
  // Of those, the ones forgotten (LoopDetector::forget; 0 in a version-1 file).
  std::size_t forgotten_frames = 0;
  // The fixed vocabulary the state needs (zeros when online): its checksum()
  // (what load() compares), word_count() and levels().
  std::uint32_t vocabulary_checksum = 0;
  std::size_t vocabulary_words = 0;
  std::uint32_t vocabulary_levels = 0;
  LoopDetectorParams params;
};

class LoopDetector {
 public:
  // Throws InvalidArgument for invalid parameters or an empty vocabulary.
  explicit LoopDetector(Vocabulary vocabulary, LoopDetectorParams params = {});
  // A detector with no pre-trained vocabulary: its words grow from the
  // sequence itself (OnlineVocabulary, for descriptors of `code_size` bytes),
  // and its database is a Database::over_word_ids with the vocabulary
  // options' scoring. Each image is first added to the online vocabulary
  // (its new words exist in no earlier image, so they cannot create
  // candidates), weighed with the IDF of the images so far, then queried and
  // inserted as with a fixed vocabulary; an entry keeps the weights it was
  // inserted with (the first image's words are in every image so far: IDF 0,
  // so it can never be a candidate). The geometric check's direct index
  // pairs features that share an online word, whatever its weight
  // (direct_index_levels does not apply). Throws
  // InvalidArgument for invalid parameters or vocabulary options.
  static LoopDetector online(std::size_t code_size, OnlineVocabularyOptions vocabulary_options = {},
                             LoopDetectorParams params = {});
  LoopDetector(LoopDetector&&) noexcept;
  LoopDetector& operator=(LoopDetector&&) noexcept;
  ~LoopDetector();

  // Adds the next image of the sequence and looks for a loop with the earlier
  // ones. Keypoint i is described by descriptor row i (their counts must
  // match, and the code size must be the vocabulary's: InvalidArgument).
  // An image without features is added too (it can match nothing).
  LoopResult process(const vision::Features& features);
  LoopResult process(Span<vision::Keypoint> keypoints, const DescriptorView& descriptors);
  // The same, also recording in `trail` (cleared first) every candidate,
  // island, temporal test and geometric check with its numbers: what the
  // report's explanations read. The result is the plain process()'s; only
  // this form pays for the recording (copies of at most max_db_results
  // candidates and of each check's correspondences).
  LoopResult process(const vision::Features& features, LoopDecisionTrail& trail);
  LoopResult process(Span<vision::Keypoint> keypoints, const DescriptorView& descriptors,
                     LoopDecisionTrail& trail);
  // The geometric check (stage 6) of image `query` against image `match`,
  // both processed and remembered, exactly as process() runs it with these
  // parameters (direct index, exhaustive fallback, estimator, thresholds):
  // for a pair the detector never verified, e.g. a ground-truth match that
  // stopped at an earlier stage. normalised_score is left 0. With
  // GeometricCheck::kNone no features are kept: a check without
  // correspondences. InvalidArgument for an image not processed or forgotten.
  TrailCheck check_pair(EntryId query, EntryId match) const;

  // Images processed, forgotten ones included: the next image gets this id.
  std::size_t size() const noexcept;
  const LoopDetectorParams& params() const noexcept;
  const Database& database() const noexcept;
  // The words grown so far by a detector made by online(); nullptr otherwise.
  const OnlineVocabulary* online_vocabulary() const noexcept;
  // Features kept for the geometric check (empty with GeometricCheck::kNone).
  // InvalidArgument for an image not processed or forgotten.
  Span<vision::Keypoint> keypoints(EntryId entry) const;
  DescriptorView descriptors(EntryId entry) const;
  // An optional name per image (SequenceDetector records the frame's file),
  // kept in the database and so saved with the state: after a resume, a loop
  // with an image of an earlier session can still name it. label() is empty
  // for an image without one; both throw InvalidArgument for an image not
  // processed or forgotten.
  void set_label(EntryId entry, std::string label);
  std::string label(EntryId entry) const;

  // Keyframe culling: forgets one image, as a SLAM system erases a redundant
  // keyframe from its place-recognition database.
  //  - The frame is never proposed again: later queries see the database as
  //    if it had never been in it (their candidates, η, islands and
  //    geometric checks are those of a detector that never had it as a
  //    candidate), so it is no match, no island member, and its features
  //    are never matched.
  //  - Its memory goes: its keypoints and descriptors at once, its database
  //    entry's direct index and label at once, its postings when the
  //    database next compacts (Database::remove; see memory_usage()).
  //  - Ids stay honest: size() still counts it, the next image gets the id
  //    it would have had, ids are never reused; is_forgotten() says which.
  //  - What the image was to the *sequence* stays, since it was seen: if it
  //    is the latest image, it is still the v_{t−Δt} the next frame's η
  //    divides by (the detector keeps that one BoW vector until the next
  //    image replaces it); it still counts on the temporal window's time
  //    axis and, online, in the vocabulary's words and IDF; and the
  //    temporal-consistency chain that earlier queries built is kept even if
  //    the frame lies in its last island (the chain records where the place
  //    was seen, an id range, and a culled keyframe's neighbours still show
  //    it). Earlier results are not revised. Hence forgetting a frame before
  //    it is old enough to be a candidate (t ≤ frame + dislocal) gives the
  //    results of forgetting it right after process().
  //  - Idempotent: forgetting a forgotten frame does nothing (a culling pass
  //    may erase a keyframe twice). A frame never processed (frame ≥ size())
  //    is a caller bug: InvalidArgument, nothing changes.
  //  - save() keeps it forgotten (.bbld version 2).
  // O(1) amortised; exclusive access, as process().
  void forget(EntryId frame);
  // Whether `frame` was forgotten; InvalidArgument for frame ≥ size().
  bool is_forgotten(EntryId frame) const;
  // Images forgotten so far; size() − forgotten_count() can still be matched.
  std::size_t forgotten_count() const;
  // Bytes of heap memory held: the database (Database::memory_usage), the
  // features kept for the geometric check, an online vocabulary (its
  // stats().memory_bytes) and the temporal state.
  std::size_t memory_usage() const;

  // Forgets every image (and the words of an online vocabulary); the next
  // one gets entry id 0.
  void clear();

  // The whole state as a file (.bbld, "binbow loop detector"), so that a
  // session can stop and resume later: a detector loaded from it gives, for
  // the next images, the same LoopResults (statuses, matches, scores,
  // inliers; not the times) as the saved one would have, to the last bit.
  // It holds the parameters, the database (inverted and direct index), the
  // features kept for the geometric check, the temporal state (the previous
  // BoW vector η divides by, the temporal-consistency chain, the count of
  // images with features) and, for a detector made by online(), its
  // OnlineVocabulary. A fixed vocabulary is not embedded: the file records its
  // checksum, word count, levels and code size, and load() must be given the
  // same vocabulary. Layout (docs/loop-detection.md): binbow's sectioned container
  // (magic "BINBOWLD", version, CRC32C of the header, of the section table and
  // of every section, little-endian), sections: parameters (JSON, as
  // LoopDetectorParams::to_json), temporal state, previous BoW vector, the
  // database as .bbdb without vocabulary, the online vocabulary as .bbov,
  // feature counts per image, keypoints, descriptors; forgotten images are
  // the database's removed entries, without features. Saved atomically
  // (temporary file, then rename): a failed save leaves no partial file and
  // the old file, if any, intact. Missing folders are made. Throws FileError.
  // save() writes version 2 (with forgotten images); load() reads versions 1
  // and 2.
  //
  // A resumed detector continues exactly as the uninterrupted one would
  // have, online ones included: the .bbov keeps the vocabulary's search
  // trees as they were (see OnlineVocabulary::save).
  void save(const std::string& path) const;
  std::vector<std::uint8_t> serialize() const;
  // A detector with a fixed vocabulary: `vocabulary` must be the one it was
  // saved with (same checksum), else FileError naming both. A file of an
  // online detector is refused (load it with the other form), as is any
  // damage: every section's CRC, every size checked against its section
  // before allocation, every id and count against the others (FileError
  // naming the file and the problem).
  static LoopDetector load(const std::string& path, Vocabulary vocabulary);
  // A detector made by online(); a file of a fixed-vocabulary detector is
  // refused with a FileError saying which vocabulary it needs.
  static LoopDetector load(const std::string& path);
  // The same from bytes; `name` stands for the path in error messages.
  static LoopDetector deserialize(const std::uint8_t* data, std::size_t size,
                                  const std::string& name, Vocabulary vocabulary);
  static LoopDetector deserialize(const std::uint8_t* data, std::size_t size,
                                  const std::string& name);
  // The header, parameters and kind of a .bbld file, checked (CRCs of what it
  // reads) but without loading the rest. Throws FileError.
  static LoopDetectorFileInfo inspect(const std::string& path);

 private:
  struct Impl;
  explicit LoopDetector(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace binbow::loop
