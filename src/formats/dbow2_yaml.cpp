// DBoW2 YAML vocabularies, the files TemplatedVocabulary::save writes through
// OpenCV's FileStorage (and DBoW3's YAML, whose descriptors read "dbw3 0 32 ...",
// or "0 32 ..." without the "dbw3" in files of early DBoW3 versions).
//
//   %YAML:1.0
//   ---
//   vocabulary:
//      k: 10
//      L: 6
//      scoringType: 0
//      weightingType: 0
//      nodes:
//         - { nodeId:1, parentId:0, weight:0.,
//             descriptor:"0010...1" }       (FBrief: bits, most significant first)
//         - { nodeId:2, parentId:0, weight:0., descriptor:"12 255 3 ... " }  (FORB)
//      words:
//         - { wordId:0, nodeId:6 }
//
// This is a dedicated single-pass parser for that subset of YAML, not a YAML
// library: it is linear (DBoW2's own loader through cv::FileNode is
// quadratic), has no dependency, and is small enough to fuzz exhaustively.
// Whitespace, line wrapping and key order are free; anything else is an
// error naming the line.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <string_view>

#include "binbow/error.h"
#include "formats/codecs.h"
#include "formats/text_numbers.h"
#include "formats/tree_checks.h"

namespace binbow::detail {

namespace {

class Scanner {
 public:
  Scanner(const char* begin, const char* end, const std::string& name)
      : begin_(begin), p_(begin), end_(end), name_(name) {}

  [[noreturn]] void fail(const std::string& problem) const {
    const std::size_t line = 1 + static_cast<std::size_t>(std::count(begin_, p_, '\n'));
    throw FileError(name_, "line " + std::to_string(line) + ": " + problem);
  }

  // Skips blanks, newlines and comments.
  void skip_space() {
    while (p_ < end_) {
      if (is_blank(*p_) || *p_ == '\n') {
        ++p_;
      } else if (*p_ == '#') {
        while (p_ < end_ && *p_ != '\n') ++p_;
      } else {
        break;
      }
    }
  }
  void skip_line() {
    while (p_ < end_ && *p_ != '\n') ++p_;
  }
  bool at_end() {
    skip_space();
    return p_ == end_;
  }
  char peek() {
    skip_space();
    return p_ < end_ ? *p_ : '\0';
  }
  bool starts_with(std::string_view text) const {
    return static_cast<std::size_t>(end_ - p_) >= text.size() &&
           std::memcmp(p_, text.data(), text.size()) == 0;
  }
  bool consume(char c) {
    if (peek() != c) return false;
    ++p_;
    return true;
  }
  void expect(char c, const char* context) {
    if (!consume(c)) fail(std::string("expected '") + c + "' " + context);
  }
  std::size_t column() const {
    const char* line = p_;
    while (line > begin_ && line[-1] != '\n') --line;
    return static_cast<std::size_t>(p_ - line);
  }
  std::string_view identifier() {
    skip_space();
    const char* start = p_;
    while (p_ < end_ && (std::isalnum(static_cast<unsigned char>(*p_)) || *p_ == '_')) ++p_;
    if (p_ == start) fail("expected a key");
    return {start, static_cast<std::size_t>(p_ - start)};
  }
  // A quoted string (no escapes: DBoW2 never writes any) or a plain scalar,
  // which ends at a blank, a newline, ',' or '}'.
  std::string_view value() {
    skip_space();
    if (p_ < end_ && (*p_ == '"' || *p_ == '\'')) {
      const char quote = *p_++;
      const char* start = p_;
      while (p_ < end_ && *p_ != quote) {
        if (*p_ == '\\') fail("escape sequences are not used by DBoW2 files");
        ++p_;
      }
      if (p_ == end_) fail("unterminated string");
      return {start, static_cast<std::size_t>(p_++ - start)};
    }
    const char* start = p_;
    while (p_ < end_ && !is_blank(*p_) && *p_ != '\n' && *p_ != ',' && *p_ != '}') ++p_;
    if (p_ == start) fail("expected a value");
    return {start, static_cast<std::size_t>(p_ - start)};
  }

  template <class T>
  T number(std::string_view key) {
    const std::string_view text = value();
    T result{};
    const auto [next, ec] = std::from_chars(text.data(), text.data() + text.size(), result);
    if (ec != std::errc() || next != text.data() + text.size())
      fail("`" + std::string(key) + "` must be a number in range, not '" +
           std::string(text.substr(0, 40)) + "'");
    return result;
  }

 private:
  const char* begin_;
  const char* p_;
  const char* end_;
  const std::string& name_;
};

struct NodeEntry {
  std::uint32_t id = 0;
  std::uint32_t parent = 0;
  float weight = 0;
};

enum class DescriptorKind { kUnknown, kBits, kBytes, kDbow3 };

// OpenCV's depth codes: only CV_8U (0) holds binary descriptors.
std::string unsupported_opencv_type(int type) {
  const bool floating = type == 5 || type == 6 || type == 7;  // CV_32F, CV_64F, CV_16F
  return std::string(floating ? "float descriptors" : "descriptors") + " (OpenCV type " +
         std::to_string(type) +
         ") are not supported: binbow handles binary descriptors (CV_8U, type 0) only";
}

class DescriptorDecoder {
 public:
  explicit DescriptorDecoder(Scanner& scanner) : scanner_(scanner) {}

  std::size_t code_size() const { return code_size_; }
  DescriptorKind kind() const { return kind_; }

  // Early DBoW3 versions wrote "<OpenCV type> <cols> v0 ... v{cols-1}" with
  // no "dbw3": read as bytes, every descriptor then starts with the same
  // "0 <code_size - 2>". True when every decoded descriptor did (a chance
  // match of the first two bytes of every node of a DBoW2 file is negligible).
  bool opencv_header_everywhere() const {
    return kind_ == DescriptorKind::kBytes && code_size_ > 2 && every_opencv_header_;
  }

  // Appends the decoded bytes of one descriptor string to `out`.
  void decode(std::string_view text, std::vector<std::uint8_t>& out) {
    const DescriptorKind kind = classify(text);
    if (kind_ == DescriptorKind::kUnknown) kind_ = kind;
    if (kind != kind_) scanner_.fail("descriptor spelled differently from the first node's");
    const std::size_t at = out.size();
    if (kind == DescriptorKind::kBits) {
      if (text.size() % 8 != 0)
        scanner_.fail("a bit-string descriptor of " + std::to_string(text.size()) +
                      " bits is not a whole number of bytes");
      set_code_size(text.size() / 8);
      out.resize(at + code_size_, 0);
      // FBrief writes bitset::to_string(): character k is bit (bits - 1 - k).
      const std::size_t bits = text.size();
      std::uint8_t* bytes = out.data() + at;
      for (std::size_t k = 0; k < bits; ++k) {
        const unsigned value = static_cast<unsigned>(text[k]) - '0';
        if (value > 1)
          scanner_.fail("a bit-string descriptor holds a character other than 0 and 1");
        const std::size_t bit = bits - 1 - k;
        bytes[bit / 8] |= static_cast<std::uint8_t>(value << (bit % 8));
      }
      return;
    }
    const char* p = text.data();
    const char* end = p + text.size();
    std::size_t count = 0;
    if (kind == DescriptorKind::kDbow3) {
      // "dbw3 <OpenCV type> <cols> v0 v1 ...": only CV_8U (type 0) is binary.
      p += 4;
      int type = -1;
      std::size_t cols = 0;
      if (!parse_token(p, end, type) || !parse_token(p, end, cols))
        scanner_.fail("malformed DBoW3 descriptor header (expected `dbw3 type cols`)");
      if (type != 0) scanner_.fail(unsupported_opencv_type(type));
      if (cols == 0 || cols > kMaxCodeSize)
        scanner_.fail("DBoW3 descriptor of " + std::to_string(cols) + " bytes");
      set_code_size(cols);
    }
    out.resize(at + (code_size_ ? code_size_ : 0));
    for (p = skip_blanks(p, end); p < end; p = skip_blanks(p, end)) {
      unsigned byte = 0;
      if (!parse_token(p, end, byte) || byte > 255) {
        if (kind == DescriptorKind::kBytes && count >= 2) report_opencv_type(text);
        scanner_.fail("descriptor byte " + std::to_string(count) + " is not an integer in 0..255");
      }
      if (code_size_ != 0 && count >= code_size_)
        scanner_.fail("descriptor has more than " + std::to_string(code_size_) + " bytes");
      if (code_size_ == 0) out.push_back(0);
      out[at + count++] = static_cast<std::uint8_t>(byte);
      if (code_size_ == 0 && count > kMaxCodeSize)
        scanner_.fail("descriptor longer than " + std::to_string(kMaxCodeSize) + " bytes");
    }
    if (count == 0) scanner_.fail("empty descriptor");
    set_code_size(count);
    if (kind == DescriptorKind::kBytes)
      every_opencv_header_ =
          every_opencv_header_ && count > 2 && out[at] == 0 && out[at + 1] + 2u == count;
  }

 private:
  // Bit strings have no blank in their first 9 characters, byte lists do
  // (decode then checks every character).
  static DescriptorKind classify(std::string_view text) {
    if (text.rfind("dbw3", 0) == 0) return DescriptorKind::kDbow3;
    if (text.size() < 8) return DescriptorKind::kBytes;
    for (std::size_t k = 0; k < std::min<std::size_t>(text.size(), 9); ++k)
      if (text[k] != '0' && text[k] != '1') return DescriptorKind::kBytes;
    return DescriptorKind::kBits;
  }
  // A descriptor that is not all bytes but starts like an early DBoW3 one,
  // "<type> <cols>" then exactly cols values, is of another OpenCV type.
  void report_opencv_type(std::string_view text) const {
    const char* p = text.data();
    const char* end = p + text.size();
    int type = 0;
    std::size_t cols = 0;
    if (!parse_token(p, end, type) || !parse_token(p, end, cols) || type < 1 || type > 7) return;
    std::size_t values = 0;
    for (p = skip_blanks(p, end); p < end; p = skip_blanks(p, end), ++values)
      while (p < end && !is_blank(*p)) ++p;
    if (values == cols) scanner_.fail(unsupported_opencv_type(type));
  }
  void set_code_size(std::size_t size) {
    if (size > kMaxCodeSize)
      scanner_.fail("descriptor of " + std::to_string(size) + " bytes is longer than " +
                    std::to_string(kMaxCodeSize));
    if (code_size_ == 0) code_size_ = size;
    if (size != code_size_)
      scanner_.fail("descriptor of " + std::to_string(size) + " bytes where the first had " +
                    std::to_string(code_size_));
  }

  Scanner& scanner_;
  DescriptorKind kind_ = DescriptorKind::kUnknown;
  std::size_t code_size_ = 0;
  bool every_opencv_header_ = true;
};

// Drops the leading "<type> <cols>" bytes of every descriptor of an early
// DBoW3 file; returns the real descriptor size.
std::size_t strip_opencv_headers(std::vector<std::uint8_t>& descriptors, std::size_t code_size) {
  const std::size_t real_size = code_size - 2;
  const std::size_t count = descriptors.size() / code_size;
  for (std::size_t i = 0; i < count; ++i)
    std::memmove(descriptors.data() + i * real_size, descriptors.data() + i * code_size + 2,
                 real_size);
  descriptors.resize(count * real_size);
  return real_size;
}

// Calls `entry` for each item of a block sequence of flow maps
// ("- { key:value, ... }"), or of an empty flow sequence "[]".
template <class Entry>
void parse_sequence_of_maps(Scanner& in, Entry&& entry) {
  if (in.consume('[')) {
    in.expect(']', "(only empty flow sequences are used by DBoW2)");
    return;
  }
  while (in.peek() == '-') {
    in.expect('-', "");
    in.expect('{', "to open a map entry");
    entry();
    in.expect('}', "to close a map entry");
  }
}

// Parses the pairs of one flow map up to (not including) its '}'.
template <class Field>
void parse_map_fields(Scanner& in, Field&& field) {
  if (in.peek() == '}') return;
  do {
    const std::string_view key = in.identifier();
    in.expect(':', "after a key");
    field(key);
  } while (in.consume(','));
}

constexpr std::uint32_t kNone = UINT32_MAX;

}  // namespace

ParsedVocabulary parse_dbow2_yaml(const std::uint8_t* data, std::size_t size,
                                  const std::string& name) {
  const char* text = reinterpret_cast<const char*>(data);
  Scanner in(text, text + size, name);
  if (size == 0) throw FileError(name, "file is empty");
  // Directives ("%YAML:1.0") and the document marker.
  while (in.peek() == '%') in.skip_line();
  if (in.starts_with("---")) in.skip_line();
  if (in.at_end()) in.fail("no `vocabulary` map (empty YAML document)");
  if (in.identifier() != "vocabulary") in.fail("expected the `vocabulary:` map of a DBoW2 file");
  in.expect(':', "after `vocabulary`");

  std::int64_t branching = -1, levels = -1, scoring = -1, weighting = -1;
  std::vector<NodeEntry> nodes;
  std::vector<std::uint8_t> descriptors;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> words;  // (word, node)
  bool have_words = false;
  DescriptorDecoder decoder(in);

  while (!in.at_end() && in.column() > 0) {  // a key at column 0 ends the map
    const std::string_view key = in.identifier();
    in.expect(':', "after a key");
    if (key == "k") {
      branching = in.number<std::int64_t>(key);
    } else if (key == "L") {
      levels = in.number<std::int64_t>(key);
    } else if (key == "scoringType") {
      scoring = in.number<std::int64_t>(key);
    } else if (key == "weightingType") {
      weighting = in.number<std::int64_t>(key);
    } else if (key == "nodes") {
      parse_sequence_of_maps(in, [&] {
        NodeEntry node;
        node.id = node.parent = kNone;
        bool have_weight = false, have_descriptor = false;
        parse_map_fields(in, [&](std::string_view field) {
          if (field == "nodeId") {
            node.id = in.number<std::uint32_t>(field);
          } else if (field == "parentId") {
            node.parent = in.number<std::uint32_t>(field);
          } else if (field == "weight") {
            node.weight = in.number<float>(field);
            if (!std::isfinite(node.weight)) in.fail("weight is not finite");
            have_weight = true;
          } else if (field == "descriptor") {
            if (have_descriptor) in.fail("two descriptors in one node");
            decoder.decode(in.value(), descriptors);
            have_descriptor = true;
          } else {
            in.fail("unknown node field `" + std::string(field) + "`");
          }
        });
        if (node.id == kNone || node.parent == kNone || !have_weight || !have_descriptor)
          in.fail("a node needs nodeId, parentId, weight and descriptor");
        nodes.push_back(node);
      });
    } else if (key == "words") {
      have_words = true;
      parse_sequence_of_maps(in, [&] {
        std::uint32_t word = kNone, node = kNone;
        parse_map_fields(in, [&](std::string_view field) {
          if (field == "wordId")
            word = in.number<std::uint32_t>(field);
          else if (field == "nodeId")
            node = in.number<std::uint32_t>(field);
          else
            in.fail("unknown word field `" + std::string(field) + "`");
        });
        if (word == kNone || node == kNone) in.fail("a word needs wordId and nodeId");
        words.emplace_back(word, node);
      });
    } else {
      in.fail("unknown key `" + std::string(key) + "` in the vocabulary map");
    }
  }

  for (const auto& [value, key] :
       {std::pair{branching, "k"}, std::pair{levels, "L"}, std::pair{scoring, "scoringType"},
        std::pair{weighting, "weightingType"}})
    if (value == -1) throw FileError(name, std::string("the vocabulary map has no `") + key + "`");
  check_header_values(name, "the vocabulary map", branching, levels, scoring, weighting);
  if (nodes.empty()) throw FileError(name, "the vocabulary has no nodes");

  ParsedVocabulary parsed;
  parsed.descriptor_text =
      decoder.kind() == DescriptorKind::kBits ? DescriptorText::kBits : DescriptorText::kBytes;
  VocabularyTree& tree = parsed.tree;
  const std::size_t code_size = decoder.opencv_header_everywhere()
                                    ? strip_opencv_headers(descriptors, decoder.code_size())
                                    : decoder.code_size();
  const std::size_t node_count = nodes.size() + 1;
  tree.code_size = code_size;
  tree.branching = static_cast<std::uint32_t>(branching);
  tree.levels = static_cast<std::uint32_t>(levels);
  tree.scoring = scoring_from_code(static_cast<int>(scoring));
  tree.weighting = weighting_from_code(static_cast<int>(weighting));
  tree.parent.assign(node_count, kNone);
  tree.parent[0] = 0;
  tree.descriptors.assign(node_count * code_size, 0);
  tree.weights.assign(node_count, 0.0f);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const NodeEntry& node = nodes[i];
    if (node.id == 0 || node.id >= node_count)
      throw FileError(name, "node entry " + std::to_string(i + 1) + ": nodeId " +
                                std::to_string(node.id) + " is outside 1.." +
                                std::to_string(node_count - 1) + " (the file lists " +
                                std::to_string(nodes.size()) + " nodes)");
    if (tree.parent[node.id] != kNone)
      throw FileError(name, "nodeId " + std::to_string(node.id) + " appears twice");
    if (node.parent >= node_count || node.parent == node.id)
      throw FileError(name, "node " + std::to_string(node.id) + ": parentId " +
                                std::to_string(node.parent) + " is not another node of the tree");
    tree.parent[node.id] = node.parent;
    tree.weights[node.id] = node.weight;
    std::memcpy(tree.descriptors.data() + node.id * code_size, descriptors.data() + i * code_size,
                code_size);
  }

  if (have_words) {
    parsed.word_ids_match = check_word_list(tree, words, name);
  } else {
    std::vector<std::uint8_t> has_children(node_count, 0);
    for (std::size_t node = 1; node < node_count; ++node) has_children[tree.parent[node]] = 1;
    for (std::size_t node = 1; node < node_count; ++node)
      if (has_children[node]) tree.weights[node] = 0.0f;
  }
  return parsed;
}

namespace {

void append_yaml_float(std::vector<std::uint8_t>& out, float value) {
  // OpenCV reads a scalar as a real only with a '.' or an exponent.
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  std::string text(buffer, result.ptr);
  if (text.find_first_of(".ni") == std::string::npos) {
    const std::size_t exponent = text.find('e');
    text.insert(exponent == std::string::npos ? text.size() : exponent, ".");
  }
  append_text(out, text);
}

}  // namespace

std::vector<std::uint8_t> format_dbow2_yaml(const VocabularyTree& tree, DescriptorText text) {
  const ChildLists children = child_lists(tree);
  const std::size_t nodes = tree.node_count();
  const std::size_t code_size = tree.code_size;
  std::vector<std::uint8_t> out;
  out.reserve(256 + nodes * (code_size * (text == DescriptorText::kBits ? 8 : 4) + 80));
  append_text(out, "%YAML:1.0\n---\nvocabulary:\n   k: ");
  append_number(out, tree.branching);
  append_text(out, "\n   L: ");
  append_number(out, tree.levels);
  append_text(out, "\n   scoringType: ");
  append_number(out, static_cast<unsigned>(tree.scoring));
  append_text(out, "\n   weightingType: ");
  append_number(out, static_cast<unsigned>(tree.weighting));
  append_text(out, "\n   nodes:\n");
  // DBoW2 lists nodes parent by parent, taking the next parent from the back
  // of a stack; same order here so that files compare equal.
  std::vector<NodeId> parents{0};
  while (!parents.empty()) {
    const NodeId parent = parents.back();
    parents.pop_back();
    for (std::uint32_t c = children.first[parent]; c < children.first[parent + 1]; ++c) {
      const NodeId node = children.child[c];
      const bool leaf = children.first[node] == children.first[node + 1];
      append_text(out, "      - { nodeId:");
      append_number(out, node);
      append_text(out, ", parentId:");
      append_number(out, parent);
      append_text(out, ", weight:");
      if (leaf)
        append_yaml_float(out, tree.weights[node]);
      else
        append_text(out, "0.");
      append_text(out, ",\n          descriptor:\"");
      const std::uint8_t* descriptor = tree.descriptors.data() + node * code_size;
      if (text == DescriptorText::kBits) {
        const std::size_t bits = code_size * 8;
        for (std::size_t k = 0; k < bits; ++k) {
          const std::size_t bit = bits - 1 - k;
          out.push_back((descriptor[bit / 8] >> (bit % 8)) & 1u ? '1' : '0');
        }
      } else {
        for (std::size_t i = 0; i < code_size; ++i) {
          append_number(out, static_cast<unsigned>(descriptor[i]));
          out.push_back(' ');
        }
      }
      append_text(out, "\" }\n");
      if (!leaf) parents.push_back(node);
    }
  }
  append_text(out, "   words:\n");
  std::uint32_t word = 0;
  for (std::size_t node = 1; node < nodes; ++node) {
    if (children.first[node] != children.first[node + 1]) continue;
    append_text(out, "      - { wordId:");
    append_number(out, word++);
    append_text(out, ", nodeId:");
    append_number(out, static_cast<std::uint32_t>(node));
    append_text(out, " }\n");
  }
  return out;
}

}  // namespace binbow::detail
