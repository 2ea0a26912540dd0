#include "loop/evaluation/ground_truth_runs.h"

#include <algorithm>
#include <utility>

namespace binbow::detail {

void RunCollector::add(std::size_t a, std::size_t b) {
  if (a == b || a >= frames_ || b >= frames_) return;
  if (b < a)
    add_below(static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b));
  else
    add_above(static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b));
}

void RunCollector::add_line(std::size_t a, std::size_t b_first, std::size_t b_end) {
  if (a >= frames_) return;
  b_end = std::min(b_end, frames_);
  // Left of the diagonal: one run of `a`.
  const std::size_t below_end = std::min(b_end, a);
  if (b_first < below_end) {
    add_below(static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b_first));
    runs_[last_below_].end = static_cast<std::uint32_t>(below_end);
  }
  for (std::size_t b = std::max(b_first, a + 1); b < b_end; ++b)
    add_above(static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b));
}

void RunCollector::add_below(std::uint32_t later, std::uint32_t earlier) {
  if (last_below_ < runs_.size() && runs_[last_below_].later == later &&
      runs_[last_below_].end == earlier) {
    ++runs_[last_below_].end;
    return;
  }
  last_below_ = runs_.size();
  runs_.push_back({later, earlier, earlier + 1});
}

void RunCollector::add_above(std::uint32_t earlier, std::uint32_t later) {
  if (earlier != line_) {
    // Only the runs the previous line reached can go on into this one.
    if (line_ != SIZE_MAX && earlier == line_ + 1)
      previous_line_.swap(current_line_);
    else
      previous_line_.clear();
    current_line_.clear();
    cursor_ = 0;
    line_ = earlier;
    line_in_order_ = true;
  } else if (later <= last_later_in_line_) {
    line_in_order_ = false;
  }
  last_later_in_line_ = later;
  if (line_in_order_) {
    while (cursor_ < previous_line_.size() && runs_[previous_line_[cursor_]].later < later)
      ++cursor_;
    if (cursor_ < previous_line_.size()) {
      LaterRun& run = runs_[previous_line_[cursor_]];
      if (run.later == later && run.end == earlier) {
        ++run.end;
        current_line_.push_back(previous_line_[cursor_]);
        return;
      }
    }
    current_line_.push_back(runs_.size());
  }
  runs_.push_back({later, earlier, earlier + 1});
}

std::vector<LaterRun> RunCollector::take() {
  std::vector<LaterRun> runs = std::move(runs_);
  *this = RunCollector(frames_);
  const auto before = [](const LaterRun& x, const LaterRun& y) {
    return x.later != y.later ? x.later < y.later : x.first < y.first;
  };
  if (!std::is_sorted(runs.begin(), runs.end(), before))
    std::sort(runs.begin(), runs.end(), before);
  std::size_t kept = 0;
  for (const LaterRun& run : runs) {
    if (kept > 0 && runs[kept - 1].later == run.later && run.first <= runs[kept - 1].end) {
      runs[kept - 1].end = std::max(runs[kept - 1].end, run.end);
      continue;
    }
    runs[kept++] = run;
  }
  runs.resize(kept);
  runs.shrink_to_fit();
  return runs;
}

}  // namespace binbow::detail
