// Parsers and writers of the vocabulary formats of other libraries. Each
// parser takes a whole file's bytes and returns the tree as the file states it
// (node order = file order); Vocabulary::from_tree then validates the tree
// shape and renumbers it. Parsers check everything a hostile file could get
// wrong, throw FileError(name, problem), and allocate only what the input size
// justifies (they are the libFuzzer targets' entry points).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "binbow/formats.h"
#include "binbow/vocabulary.h"

namespace binbow::detail {

// How DBoW2 YAML spells a descriptor: DBoW2's FORB writes decimal bytes
// ("12 255 3 ..."), FBrief a 0/1 string of the bits, most significant first.
enum class DescriptorText { kBytes, kBits };

// What a parser found besides the tree.
struct ParsedVocabulary {
  VocabularyTree tree;
  DescriptorText descriptor_text = DescriptorText::kBytes;
  // For formats that store word ids (DBoW2/DBoW3 YAML, DBoW3, fbow): false
  // when the file numbers words differently from binbow's leaf order, in
  // which case binbow's word ids differ from the file's.
  bool word_ids_match = true;
};

// Limits shared by the readers (match the .bbw format's).
inline constexpr std::size_t kMaxCodeSize = 1024;
inline constexpr std::uint32_t kMaxBranching = 255;
inline constexpr std::uint32_t kMaxLevels = 32;
// VINS files hold exactly 256-bit descriptors (four 64-bit words).
inline constexpr std::size_t kVinsCodeSize = 32;

ParsedVocabulary parse_orbslam_text(const std::uint8_t* data, std::size_t size,
                                    const std::string& name, unsigned threads = 2);
ParsedVocabulary parse_orbslam_binary(const std::uint8_t* data, std::size_t size,
                                      const std::string& name);
// Plain (already decompressed) YAML text; DBoW3's YAML variant ("dbw3 ..."
// descriptor strings) is accepted too.
ParsedVocabulary parse_dbow2_yaml(const std::uint8_t* data, std::size_t size,
                                  const std::string& name);
ParsedVocabulary parse_dbow3_binary(const std::uint8_t* data, std::size_t size,
                                    const std::string& name);
ParsedVocabulary parse_fbow(const std::uint8_t* data, std::size_t size, const std::string& name);
ParsedVocabulary parse_vins_binary(const std::uint8_t* data, std::size_t size,
                                   const std::string& name);
// The size of a VINS file with these counts (its only signature).
std::uint64_t vins_binary_size(std::int64_t node_count, std::int64_t word_count);

// Writers take a tree from Vocabulary::to_tree() (DBoW2 node order).
std::vector<std::uint8_t> format_orbslam_text(const VocabularyTree& tree);
std::vector<std::uint8_t> format_orbslam_binary(const VocabularyTree& tree);
std::vector<std::uint8_t> format_dbow2_yaml(const VocabularyTree& tree, DescriptorText text);
std::vector<std::uint8_t> format_dbow3_binary(const VocabularyTree& tree);
std::vector<std::uint8_t> format_fbow(const VocabularyTree& tree);
// Throws InvalidArgument unless tree.code_size is kVinsCodeSize.
std::vector<std::uint8_t> format_vins_binary(const VocabularyTree& tree);

// Vocabulary::from_tree, with its InvalidArgument turned into FileError(name, ...).
Vocabulary vocabulary_from_parsed(const ParsedVocabulary& parsed, const std::string& name);

// The parser of `format` (not kAuto, not kBinbow) on bytes that are already
// decompressed.
ParsedVocabulary parse_vocabulary_bytes(VocabularyFormat format, const std::uint8_t* data,
                                        std::size_t size, const std::string& name);

// Children lists of a tree in CSR form (children in node order), after the
// parents are known to be in range.
struct ChildLists {
  std::vector<std::uint32_t> first;  // node_count + 1 offsets into `child`
  std::vector<NodeId> child;
};
ChildLists child_lists(const VocabularyTree& tree);

}  // namespace binbow::detail
