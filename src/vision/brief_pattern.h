// BRIEF test patterns: the point pairs compared by each descriptor bit.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace binbow::vision {

// Test i compares the pixels at (x1[i], y1[i]) and (x2[i], y2[i]), offsets from
// the keypoint; the four vectors have the same length, a multiple of 8.
struct BriefPattern {
  std::vector<int> x1, y1, x2, y2;

  std::size_t tests() const { return x1.size(); }
  // Largest |offset| over all coordinates (half the described patch).
  int radius() const;

  // The smallest and largest offsets of the tests, per axis: every test of a
  // keypoint (x, y) lies inside a w × h image exactly when
  // x + min_x ≥ 0, x + max_x < w, y + min_y ≥ 0 and y + max_y < h.
  // DLoopDetector's pattern: x from −24 to +24, y from −23 to +24.
  struct Extent {
    int min_x = 0, min_y = 0, max_x = 0, max_y = 0;
  };
  Extent extent() const;
};

// The largest |offset| a pattern may use; keeps hostile files from asking for
// absurd patches.
inline constexpr int kMaxBriefPatternRadius = 64;

// Pattern files are read whole before OpenCV parses them: this bounds the
// file and its decompressed text (a 256-test pattern takes about 8 KiB).
inline constexpr std::uint64_t kMaxBriefPatternFileBytes = std::uint64_t{4} << 20;

// DLoopDetector's / VINS' brief_pattern.yml, built in.
const BriefPattern& default_brief_pattern();
// Reads a pattern file as OpenCV's FileStorage writes it (YAML, read by
// binbow's flat YAML parser; JSON; XML, through OpenCV; optionally .gz) with the
// integer sequences x1 y1 x2 y2. Throws FileError naming the file for anything
// missing, unequal, not a multiple of 8, or outside ±kMaxBriefPatternRadius,
// for a file that is not a regular file, larger than
// kMaxBriefPatternFileBytes (compressed or not) or nested deeper than
// kMaxStorageNesting.
BriefPattern load_brief_pattern(const std::string& path);

}  // namespace binbow::vision
