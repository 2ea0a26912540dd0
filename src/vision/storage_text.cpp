#include "vision/storage_text.h"

#include <algorithm>
#include <cctype>
#include <vector>

#include <opencv2/core/persistence.hpp>

#include "binbow/error.h"
#include "core/regular_file.h"
#include "formats/gzip.h"

namespace binbow::vision {
namespace {

// Skips to just after `terminator`, or to the end.
std::size_t skip_past(std::string_view text, std::size_t at, std::string_view terminator) {
  const std::size_t found = text.find(terminator, at);
  return found == std::string_view::npos ? text.size() : found + terminator.size();
}

// Open elements: <a> opens, </a> closes, <a/>, <?...?>, <!--...-->, <!...>
// and <![CDATA[...]]> do neither.
std::size_t xml_depth_bound(std::string_view text) {
  std::size_t depth = 0, deepest = 0;
  std::size_t at = 0;
  while ((at = text.find('<', at)) != std::string_view::npos) {
    const std::string_view rest = text.substr(at);
    if (rest.compare(0, 4, "<!--") == 0) {
      at = skip_past(text, at + 4, "-->");
    } else if (rest.compare(0, 9, "<![CDATA[") == 0) {
      at = skip_past(text, at + 9, "]]>");
    } else if (rest.compare(0, 2, "<?") == 0) {
      at = skip_past(text, at + 2, "?>");
    } else {
      const bool closing = rest.compare(0, 2, "</") == 0;
      const bool declaration = rest.compare(0, 2, "<!") == 0;
      // The tag ends at the first '>' outside quoted attribute values.
      std::size_t end = at + 1;
      char quote = 0;
      for (; end < text.size(); ++end) {
        if (quote != 0) {
          if (text[end] == quote) quote = 0;
        } else if (text[end] == '"' || text[end] == '\'') {
          quote = text[end];
        } else if (text[end] == '>') {
          break;
        }
      }
      const bool self_closing = end < text.size() && text[end - 1] == '/';
      if (closing) {
        depth -= depth > 0 ? 1 : 0;
      } else if (!declaration && !self_closing) {
        deepest = std::max(deepest, ++depth);
      }
      at = end;
    }
  }
  return deepest;
}

bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r';
}

// YAML and JSON, line by line. Block nesting is bounded by the number of
// distinct indentations open (a stack of columns) plus the "- " and "? "
// entries that open a level on the line itself ("- - - x"); flow nesting by
// the brackets open. Quoted scalars are skipped (only when a quote starts a
// scalar, and never past the line end: a misread quote can then only make
// the bound larger, never smaller).
std::size_t yaml_depth_bound(std::string_view text) {
  std::vector<std::size_t> indents;
  std::size_t flow = 0, deepest = 0;
  std::size_t line_start = 0;
  while (line_start < text.size()) {
    std::size_t line_end = text.find('\n', line_start);
    if (line_end == std::string_view::npos) line_end = text.size();
    const std::string_view line = text.substr(line_start, line_end - line_start);
    line_start = line_end + 1;

    std::size_t at = 0;
    while (at < line.size() && is_blank(line[at])) ++at;
    if (at == line.size() || line[at] == '#') continue;
    if (flow == 0) {
      if (at == 0 &&
          (line[0] == '%' || line.compare(0, 3, "---") == 0 || line.compare(0, 3, "...") == 0)) {
        continue;  // directives and document markers
      }
      while (!indents.empty() && indents.back() > at) indents.pop_back();
      if (indents.empty() || indents.back() < at) indents.push_back(at);
      // "- " and "? " entries open a level each; their content's column is
      // where the block continues on the next lines.
      while (at < line.size() && (line[at] == '-' || line[at] == '?') &&
             (at + 1 == line.size() || is_blank(line[at + 1]))) {
        ++at;
        while (at < line.size() && is_blank(line[at])) ++at;
        indents.push_back(at);
      }
    }
    char previous = 0;  // last non-blank character before `at` on this line
    for (; at < line.size(); ++at) {
      const char c = line[at];
      if ((c == '"' || c == '\'') &&
          (previous == 0 || std::string_view(":,[{-?").find(previous) != std::string_view::npos)) {
        std::size_t end = at + 1;
        while (end < line.size() && line[end] != c) end += (c == '"' && line[end] == '\\') ? 2 : 1;
        if (end >= line.size()) break;  // unterminated on this line: the rest is skipped
        at = end;
      } else if (c == '[' || c == '{') {
        ++flow;
      } else if ((c == ']' || c == '}') && flow > 0) {
        --flow;
      }
      deepest = std::max(deepest, indents.size() + flow);
      if (!is_blank(c)) previous = c;
    }
    deepest = std::max(deepest, indents.size() + flow);
  }
  return deepest;
}

bool ends_with(const std::string& s, const char* suffix) {
  const std::size_t n = std::char_traits<char>::length(suffix);
  return s.size() >= n &&
         std::equal(s.end() - static_cast<std::ptrdiff_t>(n), s.end(), suffix, [](char a, char b) {
           return std::tolower(static_cast<unsigned char>(a)) == b;
         });
}

}  // namespace

std::size_t nesting_depth_bound(std::string_view text) {
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  if (first != std::string_view::npos && text[first] == '<') return xml_depth_bound(text);
  return yaml_depth_bound(text);
}

void check_storage_text(std::string_view text, const std::string& path) {
  // OpenCV's parsers take a NUL for the end of the text, then read on past it
  // (a crash in its XML reader): text files have none.
  if (const std::size_t nul = text.find('\0'); nul != std::string_view::npos)
    throw FileError(path, "a NUL byte at byte " + std::to_string(nul) + ": not a text file");
  const std::size_t depth = nesting_depth_bound(text);
  if (depth > kMaxStorageNesting) {
    throw FileError(path, "nested " + std::to_string(depth) +
                              " levels deep, more than the limit of " +
                              std::to_string(kMaxStorageNesting));
  }
}

int storage_format(std::string_view text, const std::string& path) {
  std::string name = path;
  if (ends_with(name, ".gz")) name.resize(name.size() - 3);
  if (ends_with(name, ".xml")) return cv::FileStorage::FORMAT_XML;
  if (ends_with(name, ".json")) return cv::FileStorage::FORMAT_JSON;
  if (ends_with(name, ".yml") || ends_with(name, ".yaml")) return cv::FileStorage::FORMAT_YAML;
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  if (first != std::string_view::npos && text[first] == '<') return cv::FileStorage::FORMAT_XML;
  if (first != std::string_view::npos && text[first] == '{') return cv::FileStorage::FORMAT_JSON;
  return cv::FileStorage::FORMAT_YAML;
}

std::string read_storage_text(const std::string& path, std::uint64_t max_bytes) {
  std::string text = binbow::detail::read_regular_file(path, max_bytes);
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(text.data());
  if (detail::is_gzip(bytes, text.size())) {
    const std::vector<std::uint8_t> inflated =
        detail::gunzip(bytes, text.size(), path, static_cast<std::size_t>(max_bytes));
    text.assign(inflated.begin(), inflated.end());
  }
  check_storage_text(text, path);
  return text;
}

}  // namespace binbow::vision
