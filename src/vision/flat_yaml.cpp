#include "vision/flat_yaml.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <vector>

#include "binbow/error.h"

namespace binbow::vision {
namespace {

using Json = nlohmann::json;

struct Line {
  std::size_t number = 0;  // 1-based
  std::size_t indent = 0;
  std::string_view content;  // without indentation, comment and trailing blanks
};

bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r';
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

class Parser {
 public:
  Parser(std::string_view text, const std::string& path) : path_(path) { split(text); }

  Json parse() {
    Json object = Json::object();
    std::size_t i = 0;
    while (i < lines_.size()) {
      const Line& line = lines_[i];
      if (line.indent != 0) fail(line, "an indented line outside a sequence");
      const std::size_t colon = key_end(line);
      const std::string key(trim(line.content.substr(0, colon)));
      if (key.empty()) fail(line, "an empty key");
      if (object.contains(key)) fail(line, "the key \"" + key + "\" a second time");
      std::string_view value = trim(line.content.substr(colon + 1));
      ++i;
      if (value.empty()) {
        object[key] = block_sequence(i, line, key);
      } else if (value.front() == '[') {
        object[key] = flow_sequence(value, i, line, key);
      } else {
        object[key] = scalar(value, line, key);
      }
    }
    return object;
  }

 private:
  [[noreturn]] void fail(const Line& line, const std::string& what) const {
    throw FileError(path_, "line " + std::to_string(line.number) + ": " + what +
                               " (binbow reads a flat mapping of scalars and sequences)");
  }

  // Lines with content; the comment of each removed (outside quotes).
  void split(std::string_view text) {
    std::size_t number = 0;
    while (!text.empty()) {
      const std::size_t end = text.find('\n');
      std::string_view raw = text.substr(0, end);
      text.remove_prefix(end == std::string_view::npos ? text.size() : end + 1);
      ++number;
      Line line{number, 0, {}};
      while (line.indent < raw.size() && raw[line.indent] == ' ') ++line.indent;
      std::string_view content = raw.substr(line.indent);
      char quote = 0;
      for (std::size_t k = 0; k < content.size(); ++k) {
        const char c = content[k];
        if (quote != 0) {
          if (c == quote) quote = 0;
        } else if (c == '"' || c == '\'') {
          quote = c;
        } else if (c == '#' && (k == 0 || is_blank(content[k - 1]))) {
          content = content.substr(0, k);
          break;
        }
      }
      line.content = trim(content);
      if (line.content.empty()) continue;
      if (lines_.empty() && line.indent == 0 && line.content.substr(0, 5) == "%YAML") continue;
      if (line.indent == 0 && line.content == "---") continue;
      if (line.content == "...") break;
      lines_.push_back(line);
    }
  }

  // The position of the colon ending the key of a "key: value" line.
  std::size_t key_end(const Line& line) const {
    const std::string_view c = line.content;
    if (!c.empty() && (c.front() == '-' || c.front() == '[' || c.front() == '{'))
      fail(line, "a sequence or mapping where a key was expected");
    for (std::size_t k = 0; k < c.size(); ++k) {
      if (c[k] == ':' && (k + 1 == c.size() || c[k + 1] == ' ')) return k;
      if (c[k] == '"' || c[k] == '\'' || c[k] == '{' || c[k] == '[') break;
    }
    fail(line, "a line that is not \"key: value\"");
  }

  // "- value" lines after `key_line`, at any indentation.
  Json block_sequence(std::size_t& i, const Line& key_line, const std::string& key) const {
    Json array = Json::array();
    while (i < lines_.size() && !lines_[i].content.empty() && lines_[i].content.front() == '-' &&
           (lines_[i].content.size() == 1 || lines_[i].content[1] == ' ')) {
      const std::string_view item = trim(lines_[i].content.substr(1));
      const bool nested = item.empty() || item.front() == '[' || item.front() == '{' ||
                          (item.front() == '-' && (item.size() == 1 || item[1] == ' '));
      if (nested) fail(lines_[i], "a nested or empty sequence element");
      array.push_back(scalar(item, lines_[i], key));
      ++i;
    }
    if (array.empty()) fail(key_line, "a key with no value");
    return array;
  }

  // "[a, b, ...]", possibly continued on the lines after `line`.
  Json flow_sequence(std::string_view value, std::size_t& i, const Line& line,
                     const std::string& key) const {
    std::string text(value.substr(1));
    while (text.find(']') == std::string::npos) {
      if (i == lines_.size()) fail(line, "a '[' that is never closed");
      text += ' ';
      text += lines_[i++].content;
    }
    const std::size_t close = text.find(']');
    if (text.find_first_of("[{") < close) fail(line, "a nested sequence or mapping");
    if (!trim(std::string_view(text).substr(close + 1)).empty())
      fail(line, "text after a sequence's ']'");
    Json array = Json::array();
    std::string_view items = trim(std::string_view(text).substr(0, close));
    while (!items.empty()) {
      const std::size_t comma = items.find(',');
      const std::string_view item = trim(items.substr(0, comma));
      if (item.empty() || item.front() == '[' || item.front() == '{')
        fail(line, "a nested or empty sequence element");
      array.push_back(scalar(item, line, key));
      if (comma == std::string_view::npos) break;
      items = trim(items.substr(comma + 1));
      if (items.empty()) fail(line, "a ',' before the ']'");
    }
    return array;
  }

  // A value of `key`, named in errors.
  Json scalar(std::string_view token, const Line& line, const std::string& key) const {
    if (token.front() == '"' || token.front() == '\'') {
      if (token.size() < 2 || token.back() != token.front() ||
          token.substr(1, token.size() - 2).find(token.front()) != std::string_view::npos)
        fail(line, "a badly quoted string");
      return std::string(token.substr(1, token.size() - 2));
    }
    if (token.front() == '[' || token.front() == '{' || token.front() == '&' ||
        token.front() == '*' || token.front() == '!' || token.front() == '|' ||
        token.front() == '>')
      fail(line, "a value that is not a scalar");
    const std::string text(token);
    char* end = nullptr;
    errno = 0;
    const long long integer = std::strtoll(text.c_str(), &end, 10);
    if (end == text.c_str() + text.size() && errno == 0) return integer;
    std::string lower;
    for (char c : text) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (lower == "true" || lower == "false") return lower == "true";
    if (lower == ".inf" || lower == "+.inf" || lower == "-.inf" || lower == ".nan")
      fail(line, "\"" + key + "\" is a non-finite number (" + text + ")");
    const double real = std::strtod(text.c_str(), &end);
    if (end == text.c_str() + text.size()) {
      if (!std::isfinite(real)) fail(line, "\"" + key + "\" is a non-finite number (" + text + ")");
      return real;
    }
    return text;
  }

  const std::string& path_;
  std::vector<Line> lines_;
};

}  // namespace

nlohmann::json parse_flat_yaml(std::string_view text, const std::string& path) {
  return Parser(text, path).parse();
}

}  // namespace binbow::vision
