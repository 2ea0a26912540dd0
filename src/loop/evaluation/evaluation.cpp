#include "binbow/loop/evaluation.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "binbow/error.h"

namespace binbow::loop {
namespace {

// A true positive that also finds its query: the loop is with an earlier image.
bool finds_query(const Detection& d, const GroundTruth& truth) {
  return d.match < d.query && truth.is_loop(d.query, d.match);
}

void set_ratios(PrecisionRecall& r) {
  r.precision = r.detections == 0 ? 1.0 : double(r.true_positives) / double(r.detections);
  r.recall =
      r.queries_with_loops == 0 ? 0.0 : double(r.queries_found) / double(r.queries_with_loops);
}

}  // namespace

void check_detection_inside(const Detection& d, const GroundTruth& truth) {
  if (d.query >= truth.frames() || d.match >= truth.frames())
    throw InvalidArgument("detection (" + std::to_string(d.query) + ", " + std::to_string(d.match) +
                          ") outside the ground truth's " + std::to_string(truth.frames()) +
                          " frames");
}

PrecisionRecall evaluate_detections(const std::vector<Detection>& detections,
                                    const GroundTruth& truth) {
  PrecisionRecall r;
  r.queries_with_loops = truth.queries_with_loops();
  std::vector<std::size_t> found;  // queries with a true positive, repeated
  for (const Detection& d : detections) {
    check_detection_inside(d, truth);
    ++r.detections;
    if (truth.is_loop(d.query, d.match)) {
      ++r.true_positives;
      if (d.match < d.query) found.push_back(d.query);
    } else {
      ++r.false_positives;
    }
  }
  std::sort(found.begin(), found.end());
  r.queries_found =
      static_cast<std::size_t>(std::unique(found.begin(), found.end()) - found.begin());
  set_ratios(r);
  return r;
}

double recall_at_full_precision(const std::vector<PrCurvePoint>& curve) {
  double best = 0;
  for (const PrCurvePoint& p : curve)
    if (p.result.detections > 0 && p.result.false_positives == 0)
      best = std::max(best, p.result.recall);
  return best;
}

std::vector<PrCurvePoint> pr_curve_by_score(const std::vector<Detection>& detections,
                                            const GroundTruth& truth) {
  for (const Detection& d : detections) {
    check_detection_inside(d, truth);
    if (std::isnan(d.score)) throw InvalidArgument("detection with a NaN score");
  }
  // Detections by decreasing score: lowering the threshold t adds them in this order.
  std::vector<const Detection*> order;
  order.reserve(detections.size());
  for (const Detection& d : detections) order.push_back(&d);
  std::sort(order.begin(), order.end(),
            [](const Detection* a, const Detection* b) { return a->score > b->score; });
  // A query is found at t once its best-scoring detection that finds it is kept.
  std::vector<std::pair<std::size_t, double>> finding;  // (query, score)
  for (const Detection& d : detections)
    if (finds_query(d, truth)) finding.emplace_back(d.query, d.score);
  std::sort(finding.begin(), finding.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first < b.first : a.second > b.second;
  });
  std::vector<double> found_at;  // per found query, the highest t that finds it; decreasing
  for (std::size_t i = 0; i < finding.size(); ++i)
    if (i == 0 || finding[i].first != finding[i - 1].first) found_at.push_back(finding[i].second);
  std::sort(found_at.begin(), found_at.end(), std::greater<>());

  std::vector<PrCurvePoint> curve;
  PrecisionRecall r;
  r.queries_with_loops = truth.queries_with_loops();
  std::size_t next_found = 0;
  for (std::size_t i = 0; i < order.size();) {
    const double t = order[i]->score;
    for (; i < order.size() && order[i]->score == t; ++i) {
      ++r.detections;
      ++(truth.is_loop(order[i]->query, order[i]->match) ? r.true_positives : r.false_positives);
    }
    while (next_found < found_at.size() && found_at[next_found] >= t) ++next_found;
    r.queries_found = next_found;
    set_ratios(r);
    curve.push_back({t, r});
  }
  std::reverse(curve.begin(), curve.end());
  return curve;
}

}  // namespace binbow::loop