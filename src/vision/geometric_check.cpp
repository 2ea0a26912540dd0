#include "binbow/vision/geometric_check.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <string>

#include <opencv2/calib3d.hpp>

#include "binbow/error.h"

namespace binbow::vision {
namespace {

constexpr std::uint32_t kNoPartner = std::numeric_limits<std::uint32_t>::max();

// Distances from one descriptor to `count` rows (row index[j], or j when
// index is null) of a contiguous matrix.
using DistanceRow = void (*)(const std::uint8_t* query, const std::uint8_t* rows,
                             std::size_t code_size, const std::uint32_t* index, std::size_t count,
                             std::uint32_t* out);

void distance_row_any_size(const std::uint8_t* query, const std::uint8_t* rows,
                           std::size_t code_size, const std::uint32_t* index, std::size_t count,
                           std::uint32_t* out) {
  for (std::size_t j = 0; j < count; ++j)
    out[j] =
        hamming_distance(query, rows + (index != nullptr ? index[j] : j) * code_size, code_size);
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
// 256-bit descriptors (ORB, BRIEF) with the popcnt instruction: the query
// stays in registers, no call per pair.
__attribute__((target("popcnt"))) void distance_row_256_popcnt(
    const std::uint8_t* query, const std::uint8_t* rows, std::size_t, const std::uint32_t* index,
    std::size_t count, std::uint32_t* out) {
  std::uint64_t q[4];
  std::memcpy(q, query, 32);
  for (std::size_t j = 0; j < count; ++j) {
    std::uint64_t r[4];
    std::memcpy(r, rows + (index != nullptr ? index[j] : j) * 32, 32);
    out[j] = static_cast<std::uint32_t>(
        __builtin_popcountll(q[0] ^ r[0]) + __builtin_popcountll(q[1] ^ r[1]) +
        __builtin_popcountll(q[2] ^ r[2]) + __builtin_popcountll(q[3] ^ r[3]));
  }
}
#endif

DistanceRow distance_row_for(std::size_t code_size) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  static const bool has_popcnt = __builtin_cpu_supports("popcnt");
  if (code_size == 32 && has_popcnt) return distance_row_256_popcnt;
#endif
  (void)code_size;
  return distance_row_any_size;
}

// Ratio-test matching of index sets of `first` against index sets of
// `second`, keeping one partner per feature of `second` across calls.
class RatioMatcher {
 public:
  RatioMatcher(const DescriptorView& first, const DescriptorView& second,
               const MatchOptions& options)
      : first_(first),
        second_(second),
        max_ratio_(options.max_neighbor_ratio),
        accept_single_(options.accept_single_candidate),
        max_distance_(static_cast<std::uint32_t>(options.max_distance_fraction * 8.0 *
                                                 static_cast<double>(first.code_size))),
        slot_of_second_(second.rows, kNoPartner),
        distance_row_(distance_row_for(first.code_size)) {
    if (first.code_size != second.code_size && !first.empty() && !second.empty())
      throw InvalidArgument("matching descriptors of different sizes (" +
                            std::to_string(first.code_size) + " and " +
                            std::to_string(second.code_size) + " bytes)");
  }

  // Matches features first_index[i] (i < first_count) against
  // second_index[j] (j < second_count); a null index means 0, 1, 2, ...
  void match(const std::uint32_t* first_index, std::size_t first_count,
             const std::uint32_t* second_index, std::size_t second_count) {
    if (second_count == 0) return;
    distances_row_.resize(second_count);
    for (std::size_t i = 0; i < first_count; ++i) {
      const std::uint32_t a =
          first_index != nullptr ? first_index[i] : static_cast<std::uint32_t>(i);
      distance_row_(first_.row(a), second_.data, second_.code_size, second_index, second_count,
                    distances_row_.data());
      std::uint32_t best = kNoPartner, second_best = kNoPartner, best_j = 0;
      for (std::size_t j = 0; j < second_count; ++j) {
        const std::uint32_t d = distances_row_[j];
        if (d < best) {
          second_best = best;
          best = d;
          best_j = static_cast<std::uint32_t>(j);
        } else if (d < second_best) {
          second_best = d;
        }
      }
      const std::uint32_t best_b = second_index != nullptr ? second_index[best_j] : best_j;
      const bool distinctive = second_best == kNoPartner
                                   ? accept_single_
                                   : best < second_best && best <= max_ratio_ * second_best;
      if (!distinctive || best > max_distance_) continue;
      std::uint32_t& slot = slot_of_second_[best_b];
      if (slot == kNoPartner) {
        slot = static_cast<std::uint32_t>(matches_.size());
        matches_.push_back({a, best_b});
        distances_.push_back(best);
      } else if (best < distances_[slot]) {
        matches_[slot].first = a;
        distances_[slot] = best;
      }
    }
  }

  std::vector<Correspondence> take() {
    std::sort(matches_.begin(), matches_.end(),
              [](const Correspondence& x, const Correspondence& y) { return x.first < y.first; });
    return std::move(matches_);
  }

 private:
  DescriptorView first_, second_;
  double max_ratio_;
  bool accept_single_;
  std::uint32_t max_distance_;
  std::vector<std::uint32_t> slot_of_second_;
  std::vector<Correspondence> matches_;
  std::vector<std::uint32_t> distances_;
  DistanceRow distance_row_;
  std::vector<std::uint32_t> distances_row_;
};

void check_options(const MatchOptions& options) {
  if (!(options.max_neighbor_ratio > 0 && options.max_neighbor_ratio <= 1))
    throw InvalidArgument("max_neighbor_ratio must be in (0, 1], got " +
                          std::to_string(options.max_neighbor_ratio));
  if (!(options.max_distance_fraction >= 0 && options.max_distance_fraction <= 1))
    throw InvalidArgument("max_distance_fraction must be in [0, 1], got " +
                          std::to_string(options.max_distance_fraction));
}

// The pairs of `forward` (first → second) that `backward` (second → first) also found.
std::vector<Correspondence> mutual_pairs(std::vector<Correspondence> forward,
                                         const std::vector<Correspondence>& backward,
                                         std::size_t second_rows) {
  std::vector<std::uint32_t> partner_of_second(second_rows, kNoPartner);
  for (const Correspondence& c : backward) partner_of_second[c.first] = c.second;
  forward.erase(std::remove_if(forward.begin(), forward.end(),
                               [&](const Correspondence& c) {
                                 return partner_of_second[c.second] != c.first;
                               }),
                forward.end());
  return forward;
}

MatchOptions one_way(MatchOptions options) {
  options.mutual = false;
  return options;
}

}  // namespace

std::vector<Correspondence> match_exhaustive(const DescriptorView& first,
                                             const DescriptorView& second,
                                             const MatchOptions& options) {
  check_options(options);
  if (options.mutual)
    return mutual_pairs(match_exhaustive(first, second, one_way(options)),
                        match_exhaustive(second, first, one_way(options)), second.rows);
  RatioMatcher matcher(first, second, options);
  matcher.match(nullptr, first.rows, nullptr, second.rows);
  return matcher.take();
}

std::vector<Correspondence> match_direct_index(const DescriptorView& first,
                                               const FeatureVector& first_nodes,
                                               const DescriptorView& second,
                                               const FeatureVector& second_nodes,
                                               const MatchOptions& options) {
  check_options(options);
  if (first_nodes.feature_count() > first.rows || second_nodes.feature_count() > second.rows)
    throw InvalidArgument("direct index lists more features than there are descriptors");
  const auto in_range = [](const FeatureVector& nodes, std::size_t rows) {
    for (std::uint32_t f : nodes.feature_indices())
      if (f >= rows) return false;
    return true;
  };
  if (!in_range(first_nodes, first.rows) || !in_range(second_nodes, second.rows))
    throw InvalidArgument("direct index refers to a feature past the descriptors");
  if (options.mutual)
    return mutual_pairs(
        match_direct_index(first, first_nodes, second, second_nodes, one_way(options)),
        match_direct_index(second, second_nodes, first, first_nodes, one_way(options)),
        second.rows);

  RatioMatcher matcher(first, second, options);
  std::size_t i = 0, j = 0;
  while (i < first_nodes.size() && j < second_nodes.size()) {
    const NodeId a = first_nodes.node(i), b = second_nodes.node(j);
    if (a < b) {
      ++i;
    } else if (b < a) {
      ++j;
    } else {
      const Span<std::uint32_t> fa = first_nodes.features(i), fb = second_nodes.features(j);
      matcher.match(fa.data(), fa.size(), fb.data(), fb.size());
      ++i;
      ++j;
    }
  }
  return matcher.take();
}

const char* to_string(FundamentalEstimator estimator) {
  switch (estimator) {
    case FundamentalEstimator::kRansac:
      return "ransac";
    case FundamentalEstimator::kUsacMagsac:
      return "usac-magsac";
    case FundamentalEstimator::kUsacAccurate:
      return "usac-accurate";
  }
  return "?";
}

FundamentalEstimator parse_fundamental_estimator(const std::string& name) {
  std::string n = name;
  std::replace(n.begin(), n.end(), '_', '-');
  std::transform(n.begin(), n.end(), n.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (n == "ransac") return FundamentalEstimator::kRansac;
  if (n == "usac-magsac") return FundamentalEstimator::kUsacMagsac;
  if (n == "usac-accurate") return FundamentalEstimator::kUsacAccurate;
  throw InvalidArgument("unknown fundamental estimator \"" + name +
                        "\" (expected ransac, usac-magsac or usac-accurate)");
}

double inlier_spread(Span<Keypoint> first, Span<Keypoint> second,
                     const std::vector<Correspondence>& inliers) {
  if (inliers.empty()) return 0;
  const auto spread_in = [&inliers](Span<Keypoint> keypoints, bool use_first) {
    float min_x = std::numeric_limits<float>::max(), min_y = min_x;
    float max_x = std::numeric_limits<float>::lowest(), max_y = max_x;
    for (const Keypoint& k : keypoints) {
      min_x = std::min(min_x, k.x);
      max_x = std::max(max_x, k.x);
      min_y = std::min(min_y, k.y);
      max_y = std::max(max_y, k.y);
    }
    const auto cell = [](float value, float low, float high) {
      if (!(high > low)) return 0;
      const int c = static_cast<int>((value - low) / (high - low) * kSpreadGridCells);
      return std::clamp(c, 0, kSpreadGridCells - 1);
    };
    bool occupied[kSpreadGridCells * kSpreadGridCells] = {};
    for (const Correspondence& c : inliers) {
      const std::uint32_t index = use_first ? c.first : c.second;
      if (index >= keypoints.size())
        throw InvalidArgument("correspondence refers to a keypoint past the end");
      const Keypoint& k = keypoints[index];
      occupied[cell(k.y, min_y, max_y) * kSpreadGridCells + cell(k.x, min_x, max_x)] = true;
    }
    const auto cells = std::count(std::begin(occupied), std::end(occupied), true);
    return static_cast<double>(cells) / (kSpreadGridCells * kSpreadGridCells);
  };
  return std::min(spread_in(first, true), spread_in(second, false));
}

double inlier_thickness(Span<Keypoint> first, Span<Keypoint> second,
                        const std::vector<Correspondence>& inliers) {
  if (inliers.size() < 2) return 0;
  const auto thickness_in = [&inliers](Span<Keypoint> keypoints, bool use_first) {
    double mean_x = 0, mean_y = 0;
    for (const Correspondence& c : inliers) {
      const std::uint32_t index = use_first ? c.first : c.second;
      if (index >= keypoints.size())
        throw InvalidArgument("correspondence refers to a keypoint past the end");
      mean_x += keypoints[index].x;
      mean_y += keypoints[index].y;
    }
    const double n = static_cast<double>(inliers.size());
    mean_x /= n;
    mean_y /= n;
    double xx = 0, xy = 0, yy = 0;
    for (const Correspondence& c : inliers) {
      const Keypoint& k = keypoints[use_first ? c.first : c.second];
      const double dx = k.x - mean_x, dy = k.y - mean_y;
      xx += dx * dx;
      xy += dx * dy;
      yy += dy * dy;
    }
    // Eigenvalues of the 2x2 scatter matrix.
    const double half_trace = (xx + yy) / 2;
    const double root = std::sqrt(std::max(0.0, (xx - yy) * (xx - yy) / 4 + xy * xy));
    const double largest = half_trace + root, smallest = std::max(0.0, half_trace - root);
    return largest > 0 ? std::sqrt(smallest / largest) : 0.0;
  };
  return std::min(thickness_in(first, true), thickness_in(second, false));
}

FundamentalCheckResult check_fundamental(Span<Keypoint> first, Span<Keypoint> second,
                                         const std::vector<Correspondence>& correspondences,
                                         const FundamentalCheckParams& params) {
  if (params.min_inliers < 0 || !(params.max_reprojection_error > 0) ||
      !(params.confidence > 0 && params.confidence < 1) || params.max_iterations <= 0 ||
      !(params.min_inlier_ratio >= 0 && params.min_inlier_ratio <= 1) ||
      !(params.min_inlier_spread >= 0 && params.min_inlier_spread <= 1))
    throw InvalidArgument("fundamental check parameters out of range");
  FundamentalCheckResult result;
  result.correspondences = correspondences.size();
  const std::size_t needed = static_cast<std::size_t>(std::max(8, params.min_inliers));
  if (correspondences.size() < needed) return result;

  std::vector<cv::Point2f> points_first, points_second;
  points_first.reserve(correspondences.size());
  points_second.reserve(correspondences.size());
  for (const Correspondence& c : correspondences) {
    if (c.first >= first.size() || c.second >= second.size())
      throw InvalidArgument("correspondence refers to a keypoint past the end");
    points_first.emplace_back(first[c.first].x, first[c.first].y);
    points_second.emplace_back(second[c.second].x, second[c.second].y);
  }
  std::vector<std::uint8_t> mask;
  int method = cv::FM_RANSAC;
  if (params.estimator == FundamentalEstimator::kUsacMagsac) method = cv::USAC_MAGSAC;
  if (params.estimator == FundamentalEstimator::kUsacAccurate) method = cv::USAC_ACCURATE;
  const cv::Mat fundamental =
      cv::findFundamentalMat(points_first, points_second, method, params.max_reprojection_error,
                             params.confidence, params.max_iterations, mask);
  // Several solutions (7-point) come stacked; RANSAC returns one 3x3 or none.
  if (fundamental.rows != 3 || fundamental.cols != 3 || mask.size() != correspondences.size())
    return result;
  for (std::size_t i = 0; i < mask.size(); ++i)
    if (mask[i] != 0) result.inliers.push_back(correspondences[i]);
  fundamental.convertTo(cv::Mat(3, 3, CV_64F, result.fundamental.val), CV_64F);
  result.inlier_ratio =
      static_cast<double>(result.inliers.size()) / static_cast<double>(correspondences.size());
  result.inlier_spread = inlier_spread(first, second, result.inliers);
  result.inlier_thickness = inlier_thickness(first, second, result.inliers);
  result.determinacy =
      fit_determinacy(first, second, result.inliers, params.max_reprojection_error);
  // The distinct points fit_determinacy judged: distinct_inliers() of the inliers.
  result.distinct_inliers = result.determinacy.points;
  const bool determined = result.determinacy.evidence == FitEvidence::kFundamental ||
                          result.determinacy.evidence == FitEvidence::kHomography;
  result.consistent = result.inliers.size() >= static_cast<std::size_t>(params.min_inliers) &&
                      result.inlier_ratio >= params.min_inlier_ratio &&
                      result.inlier_spread >= params.min_inlier_spread &&
                      (determined || !params.reject_degenerate);
  return result;
}

}  // namespace binbow::vision
