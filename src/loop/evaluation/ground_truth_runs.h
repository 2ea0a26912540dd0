// Same-place cells collected as runs of consecutive earlier frames, so that a
// ground truth costs memory by its blocks, not by its pairs: the readers of
// dense matrices (images, .mat) and of pairs all feed a RunCollector.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace binbow::detail {

// The earlier frames [first, end) share a place with `later` (end ≤ later).
struct LaterRun {
  std::uint32_t later = 0;
  std::uint32_t first = 0;
  std::uint32_t end = 0;
};

// Takes the cells (a, b) of a symmetric same-place relation in any order:
// cells on the diagonal or with an index ≥ frames are ignored. Cells arriving
// line by line — lines a increasing, and b increasing within a line, as a
// matrix is scanned by rows or by columns — extend the runs they continue on
// both sides of the diagonal, so an all-ones N × N matrix makes N runs, not
// N² / 2. Any other order is still right, only less compact until take().
class RunCollector {
 public:
  explicit RunCollector(std::size_t frames) : frames_(frames) {}

  void add(std::size_t a, std::size_t b);
  // The cells (a, b) for every b in [b_first, b_end): what add() does for
  // each, faster.
  void add_line(std::size_t a, std::size_t b_first, std::size_t b_end);

  // The runs sorted by (later, first), overlapping and adjacent ones merged.
  std::vector<LaterRun> take();

 private:
  // b < a: the run of `a` left of the diagonal.
  void add_below(std::uint32_t later, std::uint32_t earlier);
  // b > a: the run of `b` above the diagonal, continued from line a - 1.
  void add_above(std::uint32_t earlier, std::uint32_t later);

  std::size_t frames_;
  std::vector<LaterRun> runs_;
  std::size_t last_below_ = SIZE_MAX;  // the run add_below() extends
  // Above the diagonal: the runs of the current line (`line_`) and of the one
  // before it, as indices into runs_ sorted by later, and how far the
  // current line has walked the previous line's.
  std::size_t line_ = SIZE_MAX;
  std::uint32_t last_later_in_line_ = 0;
  bool line_in_order_ = true;
  std::vector<std::size_t> previous_line_;
  std::vector<std::size_t> current_line_;
  std::size_t cursor_ = 0;
};

}  // namespace binbow::detail
