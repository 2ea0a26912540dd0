#include "binbow/loop/loops_csv.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "core/file_io.h"
#include "vision/regular_file.h"

namespace binbow::loop {
namespace {

constexpr std::size_t kMaxTextBytes = std::size_t{1} << 31;

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string quoted = "\"";
  for (char c : s) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

// Splits one CSV record (RFC 4180) starting at `pos`; advances `pos` past it.
bool next_record(const std::string& text, std::size_t& pos, std::vector<std::string>& fields,
                 bool& malformed) {
  fields.clear();
  malformed = false;
  if (pos >= text.size()) return false;
  std::string field;
  bool quoted = false, in_quotes = false;
  while (pos < text.size()) {
    const char c = text[pos++];
    if (in_quotes) {
      if (c == '"') {
        if (pos < text.size() && text[pos] == '"') {
          field += '"';
          ++pos;
        } else {
          in_quotes = false;
        }
      } else {
        field += c;
      }
    } else if (c == '"') {
      if (!field.empty() || quoted) malformed = true;
      in_quotes = quoted = true;
    } else if (c == ',') {
      fields.push_back(std::move(field));
      field.clear();
      quoted = false;
    } else if (c == '\n') {
      break;
    } else if (c != '\r') {
      if (quoted) malformed = true;
      field += c;
    }
  }
  if (in_quotes) malformed = true;
  fields.push_back(std::move(field));
  return true;
}

}  // namespace

std::string format_detections_csv(const std::vector<Detection>& detections) {
  std::ostringstream out;
  out << "query_index,match_index,query_file,match_file,score,inliers\n";
  char score[64];
  for (const Detection& d : detections) {
    std::snprintf(score, sizeof score, "%.9g", d.score);
    out << d.query << ',' << d.match << ',' << csv_field(d.query_file) << ','
        << csv_field(d.match_file) << ',' << score << ',' << d.inliers << '\n';
  }
  return out.str();
}

void write_detections_csv(const std::string& path, const std::vector<Detection>& detections) {
  const std::string text = format_detections_csv(detections);
  detail::write_file_atomically(path, text.data(), text.size());
}

std::vector<Detection> read_detections_csv(const std::string& path) {
  const std::string text = vision::read_regular_file(path, kMaxTextBytes);
  std::size_t pos = 0, line = 0;
  std::vector<std::string> fields;
  bool malformed = false;
  if (!next_record(text, pos, fields, malformed) ||
      fields != std::vector<std::string>{"query_index", "match_index", "query_file", "match_file",
                                         "score", "inliers"})
    throw FileError(path,
                    "line 1: expected the header "
                    "query_index,match_index,query_file,match_file,score,inliers");
  ++line;
  std::vector<Detection> detections;
  // One row per line at most: reserving once avoids the doubling's spare half.
  detections.reserve(static_cast<std::size_t>(std::count(
                         text.begin() + static_cast<std::ptrdiff_t>(pos), text.end(), '\n')) +
                     1);
  while (next_record(text, pos, fields, malformed)) {
    ++line;
    if (fields.size() == 1 && fields[0].empty()) continue;
    const std::string where = "line " + std::to_string(line) + ": ";
    if (malformed || fields.size() != 6)
      throw FileError(path, where + "expected 6 comma-separated fields");
    const auto index = [&](const std::string& s) -> std::size_t {
      if (s.empty() || s.size() > 12 || !std::all_of(s.begin(), s.end(), [](char c) {
            return std::isdigit(static_cast<unsigned char>(c)) != 0;
          }))
        throw FileError(path, where + "\"" + s + "\" is not a non-negative index");
      return std::strtoull(s.c_str(), nullptr, 10);
    };
    Detection d;
    d.query = index(fields[0]);
    d.match = index(fields[1]);
    d.query_file = fields[2];
    d.match_file = fields[3];
    char* end = nullptr;
    d.score = std::strtod(fields[4].c_str(), &end);
    if (fields[4].empty() || end != fields[4].c_str() + fields[4].size() || !std::isfinite(d.score))
      throw FileError(path, where + "score \"" + fields[4] + "\" is not a finite number");
    // detect-loops closes a loop with an earlier frame only.
    if (d.match >= d.query)
      throw FileError(path, where + "match " + fields[1] + " is not earlier than query " +
                                fields[0] + " (a loop closes with an earlier frame)");
    d.inliers = index(fields[5]);
    detections.push_back(std::move(d));
  }
  detections.shrink_to_fit();
  return detections;
}

}  // namespace binbow::loop
