// Geometric verification of a loop candidate: putative correspondences
// between two images' binary descriptors, then a fundamental matrix by RANSAC
// (the last stage of the paper's loop detector, Section V-D).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "binbow/bow_vector.h"
#include "binbow/descriptors.h"
#include "binbow/span.h"
#include "binbow/vision/features.h"

namespace binbow::vision {

// Feature `first` of one image corresponds to feature `second` of the other
// (indices of rows of their descriptor matrices / keypoint vectors).
struct Correspondence {
  std::uint32_t first = 0;
  std::uint32_t second = 0;

  friend bool operator==(const Correspondence& a, const Correspondence& b) {
    return a.first == b.first && a.second == b.second;
  }
};

// Putative correspondences: feature i of `first` is matched to its nearest
// feature j of `second` when
//   - d(i, j) ≤ max_distance_fraction × the descriptor's bits, and
//   - d(i, j) ≤ max_neighbor_ratio × d(i, second nearest), strictly below it
//     (Lowe's ratio test). A feature with a single candidate has no second
//     neighbour: it passes only with accept_single_candidate (DLoopDetector
//     accepts it; binbow does not by default, since nothing then shows the
//     match is distinctive, and in repetitive scenes such matches are enough
//     for a spurious fundamental matrix).
// Each feature of `second` keeps at most one partner: the nearest of the
// features that chose it. With `mutual`, the pair must also pass the same
// test the other way (j's nearest feature of `first`, among the features it
// is compared with, is i): a match that is distinctive in one image only is
// often repeated structure in the other. Sorted by `first`.
struct MatchOptions {
  double max_neighbor_ratio = 0.6;
  double max_distance_fraction = 1.0;  // 1: no absolute limit
  bool accept_single_candidate = false;
  bool mutual = false;
};

// Every feature of `first` against every feature of `second`.
std::vector<Correspondence> match_exhaustive(const DescriptorView& first,
                                             const DescriptorView& second,
                                             const MatchOptions& options = {});

// Through the direct index: only features under the same vocabulary node
// (FeatureVector built at the same level for both images) are compared —
// DLoopDetector's GEOM_DI. Much faster than exhaustive matching, but pairs
// whose descriptors descend to different nodes are missed.
std::vector<Correspondence> match_direct_index(const DescriptorView& first,
                                               const FeatureVector& first_nodes,
                                               const DescriptorView& second,
                                               const FeatureVector& second_nodes,
                                               const MatchOptions& options = {});

// The robust estimator of the fundamental matrix (OpenCV's cv::findFundamentalMat methods).
enum class FundamentalEstimator : std::uint8_t {
  kRansac,        // cv::FM_RANSAC (the paper, DLoopDetector)
  kUsacMagsac,    // cv::USAC_MAGSAC (MAGSAC++)
  kUsacAccurate,  // cv::USAC_ACCURATE (GC-RANSAC with local optimisation)
};

// "ransac", "usac-magsac", "usac-accurate".
const char* to_string(FundamentalEstimator estimator);
// Accepts the names above ('_' for '-' too); throws InvalidArgument listing them.
FundamentalEstimator parse_fundamental_estimator(const std::string& name);

// Cells per side of the grid inlier_spread() counts.
inline constexpr int kSpreadGridCells = 4;

// What the inliers of a fit show about the geometry of the two views
// (fit_evidence()).
enum class FitEvidence : std::uint8_t {
  kNone,         // no fit: too few correspondences, or the estimator found none
  kFundamental,  // the inliers determine the fundamental matrix
  // They fit a whole family of fundamental matrices (a plane seen twice, a
  // camera that only rotated) but determine a homography, which they follow.
  kHomography,
  // They determine neither: too few distinct points, points near one line,
  // points on one small patch, a critical configuration. Some fundamental
  // matrix fits such points whatever the two views are, so the fit is no
  // evidence that they show one place.
  kDegenerate,
};

// "none", "fundamental", "homography", "degenerate".
const char* to_string(FitEvidence evidence);

// Whether a fit's inliers determine its geometry, and the numbers that say so.
//
// The inliers are first reduced to distinct points (distinct_inliers()).
// A model is tested only by more points than it needs: 8 for a fundamental
// matrix (7 points fit one exactly, so a 7-point fit is no test at all), 5
// for a homography (4). Coordinates are normalised over each image's
// keypoints (all of them, Hartley's way), so that a geometry is judged over
// the whole view, not over the part of it the inliers cover.
// With 8 or more points, their 8-point system gives the best fundamental
// matrix (its smallest singular vector) and the best one orthogonal to it
// (the second smallest); the alternatives are the two matrices halfway
// between them (45° from the best). When either alternative, a different
// epipolar geometry of the view, also puts at least kAmbiguousShare of the
// points within `tolerance` pixels of their epipolar lines (both ways), the
// points cannot tell it from the best: the fundamental matrix is not
// determined. Nor is it when the points lie near one line or in one small
// patch (as below), which a probe 45° away can miss. This is what points near a line, on one small
// patch or on a plane give, each within the measurement tolerance, whatever their number, and also
// two views from nearly one place (a small baseline: nearly a homography). The points then still
// prove one place if the homography most of them follow (RANSAC, deterministic) maps at least 5 of
// them within tolerance × √2 pixels (point to point, both ways; the others are parallax), and those
// points determine it: in neither image do kAmbiguousShare of them lie
// within that tolerance of one line (a line's points leave a homography
// free off the line), and in neither image does their bounding box fit in
// one cell of the kSpreadGridCells × kSpreadGridCells grid over the image's
// keypoints, both ways (a patch that small is a texture, not a view). Otherwise the fit
// is degenerate.
inline constexpr double kAmbiguousShare = 0.8;
struct FitDeterminacy {
  FitEvidence evidence = FitEvidence::kNone;
  std::size_t points = 0;  // distinct inliers examined
  // Points within tolerance of the alternative fundamental matrix that fits
  // more of them (every point with fewer than 8).
  std::size_t alternative_fundamental_fits = 0;
  // Whether that probe found the fundamental matrix determined (8 points or
  // more, fewer than kAmbiguousShare of them fitting an alternative), before
  // the line and patch tests; when not, the homography is tried.
  bool fundamental_determined = false;
  // Points the homography maps within tolerance (0 when the fundamental
  // matrix is determined or with fewer than 5 points).
  std::size_t homography_fits = 0;
  // Whether the points carrying the evidence (all of them for a fundamental
  // matrix, the homography's for a homography) lie within tolerance × √2 of
  // one line, or in one cell of the kSpreadGridCells grid, in either image:
  // either makes the fit degenerate.
  bool on_a_line = false;
  bool on_a_patch = false;
};
// kNone without inliers. Throws InvalidArgument if a correspondence indexes
// past a keypoint vector or tolerance is not positive.
FitDeterminacy fit_determinacy(Span<Keypoint> first, Span<Keypoint> second,
                               const std::vector<Correspondence>& inliers, double tolerance);

struct FundamentalCheckParams {
  FundamentalEstimator estimator = FundamentalEstimator::kRansac;
  int min_inliers = 12;                 // also the minimum number of correspondences tried
  double max_reprojection_error = 2.0;  // pixels, point to epipolar line (RANSAC threshold)
  double confidence = 0.99;             // RANSAC success probability
  int max_iterations = 500;             // RANSAC iterations
  // Consistent also needs inliers / correspondences ≥ this [0, 1]: a model
  // that explains a small part of many correspondences is likely chance.
  double min_inlier_ratio = 0;
  // ... and inlier_spread() ≥ this [0, 1]: support clustered on one patch
  // (a door, a poster repeated along a corridor) constrains the epipolar
  // geometry badly and is what repeated structure produces.
  double min_inlier_spread = 0;
  // Consistent also needs inliers that determine the geometry
  // (fit_determinacy(): evidence kFundamental or kHomography). A degenerate
  // fit is accepted by no count of inliers.
  bool reject_degenerate = true;
};

struct FundamentalCheckResult {
  bool consistent = false;                         // every test of the params passed
  cv::Matx33d fundamental = cv::Matx33d::zeros();  // maps first-image points to lines in second
  std::vector<Correspondence> inliers;  // the correspondences RANSAC kept, in input order
  std::size_t correspondences = 0;      // correspondences given to the estimator
  double inlier_ratio = 0;              // inliers / correspondences
  double inlier_spread = 0;             // inlier_spread() of the inliers
  // distinct_inliers() of the inliers: what min_distinct_inliers compares.
  std::size_t distinct_inliers = 0;
  // inlier_thickness() of the inliers: what min_inlier_thickness compares.
  double inlier_thickness = 0;
  // fit_determinacy() of the inliers at max_reprojection_error (evidence
  // kNone when no fit was made).
  FitDeterminacy determinacy;
};

// Inliers that are different points: an inlier whose keypoint lies within
// kDistinctInlierRadius pixels of an earlier inlier's, in either image,
// is not counted. ORB and multi-scale detectors describe one corner at
// several pyramid levels, and the copies match together: 12 inliers can be
// 6 points, which any fundamental matrix (7 degrees of freedom) fits.
inline constexpr float kDistinctInlierRadius = 3.0F;
std::size_t distinct_inliers(Span<Keypoint> first, Span<Keypoint> second,
                             const std::vector<Correspondence>& inliers);

// How far `inliers` are from lying on a line: sqrt(λ_min / λ_max) of the
// covariance of their keypoints' coordinates, the smaller of the two images
// (0: collinear or fewer than 2 inliers; 1: no preferred direction).
// Points near a line (a skirting board, the edge of a shelf) leave the
// epipolar geometry undetermined: a fundamental matrix through them exists
// whatever the two views are.
double inlier_thickness(Span<Keypoint> first, Span<Keypoint> second,
                        const std::vector<Correspondence>& inliers);

// How widely `inliers` cover both images: each image's keypoints' bounding
// box is cut into kSpreadGridCells × kSpreadGridCells cells, and the spread is
// the fraction of cells holding an inlier, the smaller of the two images
// (0 without inliers; a degenerate box counts as one cell).
double inlier_spread(Span<Keypoint> first, Span<Keypoint> second,
                     const std::vector<Correspondence>& inliers);

// Fits a fundamental matrix x_secondᵀ F x_first = 0 to the correspondences with
// the chosen estimator, then judges its inliers (fit_determinacy()). Fewer than max(8, min_inliers)
// correspondences: not consistent, no fit attempted. Deterministic (OpenCV seeds its RANSAC, and
// its USAC estimators start from a fixed random state).
// Throws InvalidArgument if a correspondence indexes past a keypoint vector.
FundamentalCheckResult check_fundamental(Span<Keypoint> first, Span<Keypoint> second,
                                         const std::vector<Correspondence>& correspondences,
                                         const FundamentalCheckParams& params = {});

// How much of the two views a fit explains. The homography that most of the
// inliers follow (RANSAC) maps every feature of one image into the other; of
// those that land within the other image's keypoints' bounding box, the
// share that finds there, within kReappearanceRadius pixels, a feature whose
// descriptor differs in at most kReappearanceBits of its bits. The smaller
// share of the two directions; 0 with fewer than 4 distinct inliers or
// without such a homography.
//
// Repeated structure (lamps, doors, alarms along a corridor) fits two views
// a few metres apart: the repeated objects are the inliers, and the rest of
// each view does not reappear where the fit puts it. A view from the same
// place shows much of itself again. The homography is exact for views from
// one place and approximate with parallax, so shares compare fits of one
// query with neighbouring images of one place, not fits of unrelated pairs.
inline constexpr double kReappearanceRadius = 6.0;  // pixels
inline constexpr double kReappearanceBits = 0.25;   // of the descriptor's bits
double view_agreement(Span<Keypoint> first, const DescriptorView& first_descriptors,
                      Span<Keypoint> second, const DescriptorView& second_descriptors,
                      const std::vector<Correspondence>& inliers);

}  // namespace binbow::vision
