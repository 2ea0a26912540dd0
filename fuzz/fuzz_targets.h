// The work of each libFuzzer target, shared with the regression test that
// replays fuzz/corpus/<target>/* through the normal build
// (tests/formats/fuzz_corpus_test.cpp). Each function returns for a valid
// file, throws binbow::FileError for an invalid one, and throws
// std::logic_error when an accepted file breaks an invariant (a bug).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "binbow/formats.h"
#include "binbow/vocabulary.h"
#include "formats/codecs.h"
#include "formats/container.h"

namespace binbow::fuzz {

// Every descriptor reaches a word; writing the vocabulary back in `format`
// and reading it again gives the same vocabulary.
inline void check_accepted(const Vocabulary& vocabulary, VocabularyFormat format,
                           detail::DescriptorText text = detail::DescriptorText::kBytes) {
  const std::vector<std::uint8_t> probe(vocabulary.code_size(), 0xA5);
  if (vocabulary.quantize(probe.data()) >= vocabulary.word_count())
    throw std::logic_error("quantize returned a word outside the vocabulary");
  if (format == VocabularyFormat::kBinbow) return;
  const VocabularyTree tree = vocabulary.to_tree();
  std::vector<std::uint8_t> bytes;
  switch (format) {
    case VocabularyFormat::kOrbSlamText:
      bytes = detail::format_orbslam_text(tree);
      break;
    case VocabularyFormat::kOrbSlamBinary:
      bytes = detail::format_orbslam_binary(tree);
      break;
    case VocabularyFormat::kDbow2Yaml:
      bytes = detail::format_dbow2_yaml(tree, text);
      break;
    case VocabularyFormat::kDbow3:
      bytes = detail::format_dbow3_binary(tree);
      break;
    case VocabularyFormat::kFbow:
      bytes = detail::format_fbow(tree);
      break;
    default:
      return;
  }
  const Vocabulary again = detail::vocabulary_from_parsed(
      detail::parse_vocabulary_bytes(format, bytes.data(), bytes.size(), "rewritten"), "rewritten");
  if (again.checksum() != vocabulary.checksum())
    throw std::logic_error("writing and reading back changed the vocabulary");
}

inline void load_tree_format(VocabularyFormat format, const std::uint8_t* data, std::size_t size) {
  const detail::ParsedVocabulary parsed =
      detail::parse_vocabulary_bytes(format, data, size, "fuzz");
  check_accepted(detail::vocabulary_from_parsed(parsed, "fuzz"), format, parsed.descriptor_text);
}

// DBoW2 YAML, also through gzip and tar.gz (the container code is fuzzed here).
inline void load_dbow2_yaml(const std::uint8_t* data, std::size_t size) {
  std::size_t contained_size = 0;
  detail::contained_head(data, size, contained_size);
  const detail::ContainedFile file = detail::open_contained(data, size, "fuzz");
  load_tree_format(VocabularyFormat::kDbow2Yaml, file.data, file.size);
}

inline void load_bbw(const std::uint8_t* data, std::size_t size) {
  // Without checksums only the structural checks stand between the bytes and
  // the tree walk: exercise both.
  LoadOptions options;
  options.verify_checksums = size > 0 && (data[size - 1] & 1);
  check_accepted(Vocabulary::deserialize(data, size, "fuzz", options), VocabularyFormat::kBinbow);
}

// Target names (fuzz_<name>, fuzz/corpus/<name>/) and their functions.
struct Target {
  const char* name;
  void (*run)(const std::uint8_t*, std::size_t);
};
inline const Target kTargets[] = {
    {"orbslam_text", [](const std::uint8_t* d,
                        std::size_t n) { load_tree_format(VocabularyFormat::kOrbSlamText, d, n); }},
    {"orbslam_binary",
     [](const std::uint8_t* d, std::size_t n) {
       load_tree_format(VocabularyFormat::kOrbSlamBinary, d, n);
     }},
    {"dbow2_yaml", load_dbow2_yaml},
    {"dbow3", [](const std::uint8_t* d,
                 std::size_t n) { load_tree_format(VocabularyFormat::kDbow3, d, n); }},
    {"fbow",
     [](const std::uint8_t* d, std::size_t n) { load_tree_format(VocabularyFormat::kFbow, d, n); }},
    {"bbw", load_bbw},
};

// The body of LLVMFuzzerTestOneInput for target `name`.
inline int run_target(const char* name, const std::uint8_t* data, std::size_t size) {
  for (const Target& target : kTargets) {
    if (std::string(target.name) != name) continue;
    try {
      target.run(data, size);
    } catch (const FileError&) {
    }
    return 0;
  }
  throw std::logic_error(std::string("unknown fuzz target ") + name);
}

}  // namespace binbow::fuzz
