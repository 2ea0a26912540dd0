#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <sstream>
#include <string>

#include "binbow/error.h"
#include "core/regular_file.h"
#include "loop/evaluation/ground_truth_readers.h"

namespace binbow::loop::detail {
namespace {

constexpr std::size_t kMaxFrames = kMaxGroundTruthFrames;
constexpr std::size_t kMaxTextBytes = std::size_t{1} << 31;

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

int detect_index_base(const std::string& text) {
  std::istringstream lines(text);
  std::string line;
  bool zero_seen = false;
  while (std::getline(lines, line)) {
    const std::size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos) continue;
    if (line[start] == '#') {
      const std::string l = lower(line);
      if (l.find("1-based") != std::string::npos) return 1;
      if (l.find("0-based") != std::string::npos) return 0;
      continue;
    }
    for (std::size_t i = start; i < line.size(); ++i) {
      const bool boundary_before = i == 0 || !std::isdigit(static_cast<unsigned char>(line[i - 1]));
      const bool boundary_after =
          i + 1 == line.size() || !std::isdigit(static_cast<unsigned char>(line[i + 1]));
      if (line[i] == '0' && boundary_before && boundary_after) zero_seen = true;
    }
  }
  return zero_seen ? 0 : -1;
}

}  // namespace

LoadedGroundTruth read_ground_truth_pairs(const std::string& path,
                                          const GroundTruthOptions& options) {
  const std::string text = binbow::detail::read_regular_file(path, kMaxTextBytes);
  int base = options.pairs_index_base;
  if (base != 0 && base != 1) {
    base = detect_index_base(text);
    if (base < 0)
      throw FileError(path,
                      "cannot tell whether the pairs are 0-based or 1-based: "
                      "add a comment line saying \"0-based\" or \"1-based\", or give the base");
  }
  LoadedGroundTruth loaded;
  // Without the run's frame count, the largest index says how many there are.
  RunCollector runs(options.frames > 0 ? options.frames : kMaxFrames);
  std::size_t frames = 0, line_number = 0;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    ++line_number;
    const std::size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    for (char& c : line)
      if (c == ',' || c == ';' || c == '\t' || c == '\r') c = ' ';
    std::istringstream fields(line);
    std::string a, b, extra;
    fields >> a >> b;
    const auto parse = [&](const std::string& s) -> std::size_t {
      if (s.empty() || s.size() > 12 || !std::all_of(s.begin(), s.end(), [](char c) {
            return std::isdigit(static_cast<unsigned char>(c)) != 0;
          }))
        throw FileError(path, "line " + std::to_string(line_number) +
                                  ": expected two non-negative indices \"query match\"");
      const std::size_t v = std::strtoull(s.c_str(), nullptr, 10);
      if (v < static_cast<std::size_t>(base) || v - base >= kMaxFrames)
        throw FileError(path, "line " + std::to_string(line_number) + ": index " + s +
                                  " out of range for " + std::to_string(base) + "-based pairs");
      return v - base;
    };
    const std::size_t query = parse(a), match = parse(b);
    if (fields >> extra)
      throw FileError(path, "line " + std::to_string(line_number) + ": more than two fields");
    runs.add(query, match);
    frames = std::max({frames, query + 1, match + 1});
  }
  loaded.frames = options.frames > 0 ? options.frames : frames;
  loaded.runs = runs.take();
  return loaded;
}

}  // namespace binbow::loop::detail
