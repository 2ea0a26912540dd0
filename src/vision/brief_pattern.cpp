#include "vision/brief_pattern.h"

#include <algorithm>
#include <cstdlib>

#include <opencv2/core.hpp>

#include "binbow/error.h"
#include "vision/storage_text.h"

namespace binbow::vision {

int BriefPattern::radius() const {
  int radius = 0;
  for (const std::vector<int>* coordinates : {&x1, &y1, &x2, &y2}) {
    for (int value : *coordinates) radius = std::max(radius, std::abs(value));
  }
  return radius;
}

namespace {

std::vector<int> read_coordinates(const cv::FileStorage& storage, const char* key,
                                  const std::string& path) {
  const cv::FileNode node = storage[key];
  if (node.empty() || !node.isSeq()) {
    throw FileError(path, std::string("BRIEF pattern has no sequence '") + key + "'");
  }
  std::vector<int> values;
  values.reserve(node.size());
  for (const cv::FileNode& element : node) {
    if (!element.isInt()) {
      throw FileError(path, std::string("BRIEF pattern '") + key + "' holds a non-integer");
    }
    const int value = static_cast<int>(element);
    if (std::abs(value) > kMaxBriefPatternRadius) {
      throw FileError(path, std::string("BRIEF pattern '") + key + "' has offset " +
                                std::to_string(value) + ", beyond ±" +
                                std::to_string(kMaxBriefPatternRadius));
    }
    values.push_back(value);
  }
  return values;
}

}  // namespace

BriefPattern load_brief_pattern(const std::string& path) {
  const std::string text = read_storage_text(path, kMaxBriefPatternFileBytes);
  BriefPattern pattern;
  try {
    cv::FileStorage storage(
        text, cv::FileStorage::READ | cv::FileStorage::MEMORY | storage_format(text, path));
    if (!storage.isOpened()) throw FileError(path, "cannot open BRIEF pattern");
    pattern.x1 = read_coordinates(storage, "x1", path);
    pattern.y1 = read_coordinates(storage, "y1", path);
    pattern.x2 = read_coordinates(storage, "x2", path);
    pattern.y2 = read_coordinates(storage, "y2", path);
  } catch (const cv::Exception& e) {
    throw FileError(path, "cannot parse BRIEF pattern: " + e.msg);
  }
  const std::size_t tests = pattern.x1.size();
  if (pattern.y1.size() != tests || pattern.x2.size() != tests || pattern.y2.size() != tests) {
    throw FileError(path, "BRIEF pattern sequences x1 y1 x2 y2 have different lengths");
  }
  if (tests == 0 || tests % 8 != 0) {
    throw FileError(path, "BRIEF pattern has " + std::to_string(tests) +
                              " tests; need a positive multiple of 8");
  }
  return pattern;
}

}  // namespace binbow::vision
