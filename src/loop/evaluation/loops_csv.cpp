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
#include "core/regular_file.h"

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

namespace {

std::string column_name(const std::string& field) {
  const std::size_t first = field.find_first_not_of(" \t");
  const std::size_t last = field.find_last_not_of(" \t");
  std::string name = first == std::string::npos ? "" : field.substr(first, last - first + 1);
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return name;
}

// Where each value of a row is: binbow's six columns, or any header naming a
// query and a match column (e.g. "query,match" of another tool's output).
struct Columns {
  std::size_t count = 0;
  std::size_t query = 0, match = 0;
  static constexpr std::size_t kAbsent = static_cast<std::size_t>(-1);
  std::size_t query_file = kAbsent, match_file = kAbsent, score = kAbsent, inliers = kAbsent;
};

Columns columns_of_header(const std::string& path, const std::vector<std::string>& header) {
  Columns columns;
  columns.count = header.size();
  std::size_t query = Columns::kAbsent, match = Columns::kAbsent;
  const auto place = [&](std::size_t& where, std::size_t i, const std::string& name) {
    if (where != Columns::kAbsent)
      throw FileError(path, "line 1: the header names the column \"" + name + "\" twice");
    where = i;
  };
  for (std::size_t i = 0; i < header.size(); ++i) {
    const std::string name = column_name(header[i]);
    if (name == "query_index" || name == "query")
      place(query, i, name);
    else if (name == "match_index" || name == "match")
      place(match, i, name);
    else if (name == "query_file")
      place(columns.query_file, i, name);
    else if (name == "match_file")
      place(columns.match_file, i, name);
    else if (name == "score")
      place(columns.score, i, name);
    else if (name == "inliers")
      place(columns.inliers, i, name);
  }
  if (query == Columns::kAbsent || match == Columns::kAbsent)
    throw FileError(path,
                    "line 1: expected a header naming a query and a match column: binbow's "
                    "query_index,match_index,query_file,match_file,score,inliers, or any CSV "
                    "whose header has columns named query and match (0-based frame indices)");
  columns.query = query;
  columns.match = match;
  return columns;
}

}  // namespace

std::vector<Detection> read_detections_csv(const std::string& path) {
  const std::string text = binbow::detail::read_regular_file(path, kMaxTextBytes);
  std::size_t pos = 0, line = 0;
  std::vector<std::string> fields;
  bool malformed = false;
  if (!next_record(text, pos, fields, malformed) || malformed)
    throw FileError(path, "line 1: expected a header naming a query and a match column");
  const Columns columns = columns_of_header(path, fields);
  ++line;
  std::vector<Detection> detections;
  // One row per line at most: reserving once avoids the doubling's spare half.
  detections.reserve(static_cast<std::size_t>(std::count(
                         text.begin() + static_cast<std::ptrdiff_t>(pos), text.end(), '\n')) +
                     1);
  while (next_record(text, pos, fields, malformed)) {
    ++line;
    if (fields.size() == 1 && column_name(fields[0]).empty()) continue;
    const std::string where = "line " + std::to_string(line) + ": ";
    if (malformed || fields.size() != columns.count)
      throw FileError(path, where + "expected " + std::to_string(columns.count) +
                                " comma-separated fields, as the header has");
    const auto index = [&](std::size_t column) -> std::size_t {
      const std::string s = column_name(fields[column]);
      if (s.empty() || s.size() > 12 || !std::all_of(s.begin(), s.end(), [](char c) {
            return std::isdigit(static_cast<unsigned char>(c)) != 0;
          }))
        throw FileError(path, where + "\"" + fields[column] + "\" is not a non-negative index");
      return std::strtoull(s.c_str(), nullptr, 10);
    };
    Detection d;
    d.query = index(columns.query);
    d.match = index(columns.match);
    if (columns.query_file != Columns::kAbsent) d.query_file = fields[columns.query_file];
    if (columns.match_file != Columns::kAbsent) d.match_file = fields[columns.match_file];
    if (columns.score != Columns::kAbsent) {
      const std::string score = column_name(fields[columns.score]);
      char* end = nullptr;
      d.score = std::strtod(score.c_str(), &end);
      if (score.empty() || end != score.c_str() + score.size() || !std::isfinite(d.score))
        throw FileError(path,
                        where + "score \"" + fields[columns.score] + "\" is not a finite number");
    }
    // A loop closes with an earlier frame only.
    if (d.match >= d.query)
      throw FileError(path, where + "match " + std::to_string(d.match) +
                                " is not earlier than query " + std::to_string(d.query) +
                                " (a loop closes with an earlier frame)");
    if (columns.inliers != Columns::kAbsent) d.inliers = index(columns.inliers);
    detections.push_back(std::move(d));
  }
  detections.shrink_to_fit();
  return detections;
}

}  // namespace binbow::loop
