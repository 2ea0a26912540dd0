#include "vision/brief_pattern.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "binbow/error.h"
#include "vision/flat_yaml.h"
#include "vision/storage_text.h"

namespace binbow::vision {

int BriefPattern::radius() const {
  int radius = 0;
  for (const std::vector<int>* coordinates : {&x1, &y1, &x2, &y2}) {
    for (int value : *coordinates) radius = std::max(radius, std::abs(value));
  }
  return radius;
}

BriefPattern::Extent BriefPattern::extent() const {
  Extent e;
  for (const std::vector<int>* xs : {&x1, &x2}) {
    for (int x : *xs) {
      e.min_x = std::min(e.min_x, x);
      e.max_x = std::max(e.max_x, x);
    }
  }
  for (const std::vector<int>* ys : {&y1, &y2}) {
    for (int y : *ys) {
      e.min_y = std::min(e.min_y, y);
      e.max_y = std::max(e.max_y, y);
    }
  }
  return e;
}

namespace {

int checked_offset(int value, const char* key, const std::string& path) {
  if (std::abs(value) > kMaxBriefPatternRadius) {
    throw FileError(path, std::string("BRIEF pattern '") + key + "' has offset " +
                              std::to_string(value) + ", beyond ±" +
                              std::to_string(kMaxBriefPatternRadius));
  }
  return value;
}

// One coordinate sequence of an OpenCV FileStorage pattern (XML).
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
    values.push_back(checked_offset(static_cast<int>(element), key, path));
  }
  return values;
}

// The same from a YAML or JSON pattern, read as JSON.
std::vector<int> read_coordinates(const nlohmann::json& object, const char* key,
                                  const std::string& path) {
  const auto node = object.find(key);
  if (node == object.end() || !node->is_array())
    throw FileError(path, std::string("BRIEF pattern has no sequence '") + key + "'");
  std::vector<int> values;
  values.reserve(node->size());
  for (const nlohmann::json& element : *node) {
    // No dump() of the value: a string of invalid UTF-8 would throw there.
    const bool in_range =
        element.is_number_unsigned()
            ? element.get<std::uint64_t>() <= static_cast<std::uint64_t>(kMaxBriefPatternRadius)
            : element.is_number_integer() &&
                  std::abs(element.get<std::int64_t>()) <= kMaxBriefPatternRadius;
    if (!in_range)
      throw FileError(path, std::string("BRIEF pattern '") + key +
                                "' holds a value that is not an integer within ±" +
                                std::to_string(kMaxBriefPatternRadius));
    values.push_back(element.get<int>());
  }
  return values;
}

BriefPattern read_pattern(const nlohmann::json& object, const std::string& path) {
  if (!object.is_object()) throw FileError(path, "a BRIEF pattern must be a mapping");
  return {read_coordinates(object, "x1", path), read_coordinates(object, "y1", path),
          read_coordinates(object, "x2", path), read_coordinates(object, "y2", path)};
}

}  // namespace

BriefPattern load_brief_pattern(const std::string& path) {
  const std::string text = read_storage_text(path, kMaxBriefPatternFileBytes);
  BriefPattern pattern;
  const int format = storage_format(text, path);
  if (format == cv::FileStorage::FORMAT_YAML) {
    // Parsed here: OpenCV's YAML parser hangs on some malformed files.
    pattern = read_pattern(parse_flat_yaml(text, path), path);
  } else if (format == cv::FileStorage::FORMAT_JSON) {
    try {
      pattern = read_pattern(nlohmann::json::parse(text), path);
    } catch (const nlohmann::json::exception& e) {
      throw FileError(path, std::string("invalid JSON: ") + e.what());
    }
  } else {
    try {
      cv::FileStorage storage(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | format);
      if (!storage.isOpened()) throw FileError(path, "cannot open BRIEF pattern");
      pattern.x1 = read_coordinates(storage, "x1", path);
      pattern.y1 = read_coordinates(storage, "y1", path);
      pattern.x2 = read_coordinates(storage, "x2", path);
      pattern.y2 = read_coordinates(storage, "y2", path);
    } catch (const cv::Exception& e) {
      throw FileError(path, "cannot parse BRIEF pattern: " + e.msg);
    }
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
