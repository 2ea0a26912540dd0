// ORB-SLAM2/3 text vocabulary (ORBvoc.txt), as written by ORB-SLAM's
// TemplatedVocabulary::saveToTextFile:
//   line 1:      "k L  scoring weighting"
//   line i + 1:  "parent is_leaf d0 d1 ... d31  weight" for node i = 1, 2, ...
// Node ids are line numbers, word ids number the leaves in line order.
//
// The whole file is parsed in place with std::from_chars, the node lines
// split between threads; every field is validated before use.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <thread>

#include "binbow/error.h"
#include "formats/codecs.h"
#include "formats/text_numbers.h"
#include "formats/tree_checks.h"

namespace binbow::detail {

namespace {

constexpr std::size_t kParallelThreshold = 1 << 20;  // bytes; below, one thread is faster

struct LineError {
  std::size_t line = SIZE_MAX;  // 1-based line number in the file
  std::string problem;
};

const char* find_newline(const char* p, const char* end) {
  const void* hit = std::memchr(p, '\n', static_cast<std::size_t>(end - p));
  return hit != nullptr ? static_cast<const char*>(hit) : end;
}

std::size_t count_newlines(const char* p, const char* end) {
  std::size_t count = 0;
  while ((p = find_newline(p, end)) < end) {
    ++count;
    ++p;
  }
  return count;
}

std::size_t count_tokens(const char* p, const char* end) {
  std::size_t count = 0;
  for (p = skip_blanks(p, end); p < end; p = skip_blanks(p, end)) {
    ++count;
    while (p < end && !is_blank(*p)) ++p;
  }
  return count;
}

struct Header {
  std::uint64_t branching = 0, levels = 0, scoring = 0, weighting = 0;
};

Header parse_header(const char* p, const char* end, const std::string& name) {
  Header h;
  const char* cursor = p;
  if (!parse_token(cursor, end, h.branching) || !parse_token(cursor, end, h.levels) ||
      !parse_token(cursor, end, h.scoring) || !parse_token(cursor, end, h.weighting) ||
      skip_blanks(cursor, end) != end)
    throw FileError(name,
                    "line 1: expected the ORB-SLAM header `k L scoring weighting` (four "
                    "non-negative integers)");
  auto signed_value = [](std::uint64_t v) {
    return static_cast<std::int64_t>(std::min<std::uint64_t>(v, INT64_MAX));
  };
  check_header_values(name, "line 1", signed_value(h.branching), signed_value(h.levels),
                      signed_value(h.scoring), signed_value(h.weighting));
  return h;
}

// Parses the node lines in [begin, end) (whole lines, the last one possibly
// without '\n') into nodes first_node, first_node + 1, ...
void parse_node_lines(const char* begin, const char* end, std::size_t first_node,
                      VocabularyTree& tree, std::vector<std::uint8_t>& leaf_flags,
                      LineError& error) {
  const std::size_t code_size = tree.code_size;
  std::size_t node = first_node;
  for (const char* line = begin; line < end; ++node) {
    const char* line_end = find_newline(line, end);
    const char* p = line;
    const auto fail = [&](const std::string& problem) {
      error.line = node + 1;
      error.problem = problem;
    };
    std::uint32_t parent = 0;
    std::uint32_t leaf = 0;
    if (!parse_token(p, line_end, parent)) {
      if (skip_blanks(line, line_end) == line_end)
        fail("empty line where node " + std::to_string(node) + " was expected");
      else
        fail("expected the parent id (a non-negative integer)");
      return;
    }
    if (!parse_token(p, line_end, leaf) || leaf > 1) {
      fail("expected the leaf flag (0 or 1) after the parent id");
      return;
    }
    std::uint8_t* descriptor = tree.descriptors.data() + node * code_size;
    for (std::size_t i = 0; i < code_size; ++i) {
      // The hot loop: 1-3 digit numbers, parsed inline.
      p = skip_blanks(p, line_end);
      unsigned value = p < line_end ? static_cast<unsigned>(*p) - '0' : 10u;
      bool valid = value <= 9;
      for (++p; valid && p < line_end && !is_blank(*p); ++p) {
        const unsigned digit = static_cast<unsigned>(*p) - '0';
        value = value * 10 + digit;
        valid = digit <= 9 && value <= 255;
      }
      if (!valid) {
        fail("descriptor byte " + std::to_string(i) + " of " + std::to_string(code_size) +
             " is missing or not an integer in 0..255");
        return;
      }
      descriptor[i] = static_cast<std::uint8_t>(value);
    }
    float weight = 0;
    if (!parse_token(p, line_end, weight) || !std::isfinite(weight)) {
      fail("expected a finite weight after the " + std::to_string(code_size) + " descriptor bytes");
      return;
    }
    if (skip_blanks(p, line_end) != line_end) {
      fail("more than " + std::to_string(code_size + 3) +
           " fields (parent, leaf flag, descriptor bytes, weight)");
      return;
    }
    tree.parent[node] = parent;
    leaf_flags[node] = static_cast<std::uint8_t>(leaf);
    tree.weights[node] = weight;
    line = line_end < end ? line_end + 1 : end;
  }
}

}  // namespace

ParsedVocabulary parse_orbslam_text(const std::uint8_t* data, std::size_t size,
                                    const std::string& name, unsigned threads) {
  const char* const text = reinterpret_cast<const char*>(data);
  const char* const text_end = text + size;
  if (size == 0) throw FileError(name, "file is empty");
  const char* header_end = find_newline(text, text_end);
  const Header header = parse_header(text, header_end, name);

  // Trailing blank lines are tolerated; blank lines elsewhere are errors.
  const char* body = header_end < text_end ? header_end + 1 : text_end;
  const char* body_end = text_end;
  while (body_end > body && (is_blank(body_end[-1]) || body_end[-1] == '\n')) --body_end;
  if (body == body_end) throw FileError(name, "no node lines after the header");

  const char* first_line_end = find_newline(body, body_end);
  const std::size_t fields = count_tokens(body, first_line_end);
  if (fields < 4)
    throw FileError(name, "line 2: expected `parent is_leaf descriptor-bytes... weight`, found " +
                              std::to_string(fields) + " fields");
  const std::size_t code_size = fields - 3;
  if (code_size > kMaxCodeSize)
    throw FileError(name, "line 2: descriptors of " + std::to_string(code_size) +
                              " bytes are longer than the supported " +
                              std::to_string(kMaxCodeSize));

  // Split the body into one range of whole lines per thread and count lines.
  const std::size_t body_size = static_cast<std::size_t>(body_end - body);
  const unsigned parts = body_size < kParallelThreshold ? 1 : std::max(1u, threads);
  std::vector<const char*> bounds(parts + 1, body_end);
  bounds[0] = body;
  for (unsigned t = 1; t < parts; ++t) {
    const char* at = std::max(bounds[t - 1], body + body_size * t / parts);
    const char* newline = find_newline(at, body_end);
    bounds[t] = newline < body_end ? newline + 1 : body_end;
  }
  std::vector<std::size_t> first_node(parts + 1, 1);
  for (unsigned t = 0; t < parts; ++t) {
    const bool last = bounds[t + 1] == body_end && bounds[t] < body_end;
    first_node[t + 1] = first_node[t] + count_newlines(bounds[t], bounds[t + 1]) + (last ? 1 : 0);
  }
  const std::size_t node_count = first_node[parts];

  // Every valid line has code_size + 3 fields: at least 2 (code_size + 3)
  // bytes with its separator. Checking that before allocating keeps memory
  // proportional to the file even for a file of empty lines.
  const std::size_t min_line = 2 * (code_size + 3);
  if ((node_count - 1) > (body_size + 1) / min_line) {
    std::size_t line_number = 2;
    for (const char* line = body; line < body_end; ++line_number) {
      const char* line_end = find_newline(line, body_end);
      if (count_tokens(line, line_end) != code_size + 3)
        throw FileError(name, "line " + std::to_string(line_number) + ": expected " +
                                  std::to_string(code_size + 3) + " fields, found " +
                                  std::to_string(count_tokens(line, line_end)));
      line = line_end + 1;
    }
    throw FileError(name,
                    "fewer bytes than its " + std::to_string(node_count - 1) + " node lines need");
  }

  ParsedVocabulary parsed;
  VocabularyTree& tree = parsed.tree;
  tree.code_size = code_size;
  tree.branching = static_cast<std::uint32_t>(header.branching);
  tree.levels = static_cast<std::uint32_t>(header.levels);
  tree.scoring = scoring_from_code(static_cast<int>(header.scoring));
  tree.weighting = weighting_from_code(static_cast<int>(header.weighting));
  tree.parent.assign(node_count, 0);
  tree.descriptors.assign(node_count * code_size, 0);
  tree.weights.assign(node_count, 0.0f);
  std::vector<std::uint8_t> leaf_flags(node_count, 0);

  std::vector<LineError> errors(parts);
  std::vector<std::thread> workers;
  for (unsigned t = 1; t < parts; ++t)
    workers.emplace_back(parse_node_lines, bounds[t], bounds[t + 1], first_node[t], std::ref(tree),
                         std::ref(leaf_flags), std::ref(errors[t]));
  parse_node_lines(bounds[0], bounds[1], first_node[0], tree, leaf_flags, errors[0]);
  for (std::thread& worker : workers) worker.join();
  for (const LineError& error : errors)  // ranges are in file order: the first is the earliest
    if (error.line != SIZE_MAX)
      throw FileError(name, "line " + std::to_string(error.line) + ": " + error.problem);

  check_listed_tree(tree, leaf_flags, name, "line", 1);
  return parsed;
}

std::vector<std::uint8_t> format_orbslam_text(const VocabularyTree& tree) {
  const ChildLists children = child_lists(tree);
  const std::size_t nodes = tree.node_count();
  const std::size_t code_size = tree.code_size;
  // Lines are written through a raw pointer into a buffer sized for the
  // longest possible line: this writer runs at memory speed.
  const std::size_t max_line = 10 + 3 + code_size * 4 + 1 + 20 + 1;
  std::vector<std::uint8_t> out(64 + nodes * max_line);
  char* p = reinterpret_cast<char*>(out.data());
  char* const limit = p + out.size();
  const auto put_number = [&](auto value) { p = std::to_chars(p, limit, value).ptr; };
  put_number(tree.branching);
  *p++ = ' ';
  put_number(tree.levels);
  // ORB-SLAM writes two spaces before the scoring type; kept for identical files.
  *p++ = ' ';
  *p++ = ' ';
  put_number(static_cast<unsigned>(tree.scoring));
  *p++ = ' ';
  put_number(static_cast<unsigned>(tree.weighting));
  *p++ = '\n';
  for (std::size_t node = 1; node < nodes; ++node) {
    const bool leaf = children.first[node] == children.first[node + 1];
    put_number(tree.parent[node]);
    std::memcpy(p, leaf ? " 1 " : " 0 ", 3);
    p += 3;
    const std::uint8_t* descriptor = tree.descriptors.data() + node * code_size;
    for (std::size_t i = 0; i < code_size; ++i) {
      put_number(static_cast<unsigned>(descriptor[i]));
      *p++ = ' ';
    }
    *p++ = ' ';  // ORB-SLAM's descriptor string ends with a space, then " " weight
    if (leaf)
      put_number(tree.weights[node]);
    else
      *p++ = '0';
    *p++ = '\n';
  }
  out.resize(static_cast<std::size_t>(p - reinterpret_cast<char*>(out.data())));
  return out;
}

}  // namespace binbow::detail
