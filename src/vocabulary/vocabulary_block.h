// The in-memory form of a vocabulary: the bytes of a .bbw file (mapped from
// disk or built in memory) plus pointers to its sections. See docs/formats.md
// for the layout.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "binbow/types.h"
#include "binbow/vocabulary.h"
#include "core/file_io.h"
#include "core/kernels.h"

namespace binbow::detail {

namespace bbw {
inline constexpr char kMagic[8] = {'B', 'B', 'W', 'V', 'O', 'C', 'A', 'B'};
inline constexpr std::uint32_t kVersion = 1;
inline constexpr std::size_t kHeaderSize = 64;
inline constexpr std::size_t kSectionEntrySize = 24;
inline constexpr std::size_t kAlignment = 64;
enum SectionId : std::uint32_t {
  kDescriptors = 1,  // node_count × code_size bytes
  kLinks = 2,        // node_count × u32: first child, or word | kLeafBit
  kChildCounts = 3,  // node_count × u8
  kWordWeights = 4,  // word_count × f32
};
inline constexpr std::uint32_t kSectionCount = 4;
inline constexpr std::size_t kMaxCodeSize = 1024;
inline constexpr std::uint32_t kMaxBranching = 255;
inline constexpr std::uint32_t kMaxLevels = 32;
inline constexpr std::size_t kDescriptorNameOffset = 52;  // in the header
inline constexpr std::size_t kMaxDescriptorName = 8;
}  // namespace bbw

// Whether `name` can be stored as a vocabulary's descriptor name (empty:
// unknown); kDescriptorNameRule says what is allowed, for error messages.
bool valid_descriptor_name(const std::string& name) noexcept;
inline constexpr char kDescriptorNameRule[] = "a name of up to 8 characters a-z 0-9 _ -";

struct VocabularyBlock {
  // Exactly one of these holds the bytes.
  std::vector<std::uint8_t> owned;
  std::unique_ptr<MappedFile> mapped;

  const std::uint8_t* bytes = nullptr;
  std::size_t size = 0;

  std::size_t code_size = 0;
  std::uint32_t branching = 0;
  std::uint32_t levels = 0;
  Weighting weighting = Weighting::kTfIdf;
  Scoring scoring = Scoring::kL1;
  std::string descriptor;
  std::size_t node_count = 0;
  std::size_t word_count = 0;
  std::uint32_t section_crcs[bbw::kSectionCount] = {};

  TreeView tree;
  const float* word_weights = nullptr;
};

// Parses and validates .bbw bytes already stored in block->owned or
// block->mapped; `name` names the source in errors (FileError).
void parse_block(VocabularyBlock& block, const std::string& name, const LoadOptions& options);

// Lays out a .bbw image from its parts (sections already in final form).
std::vector<std::uint8_t> encode_block(std::size_t code_size, std::uint32_t branching,
                                       std::uint32_t levels, Weighting weighting, Scoring scoring,
                                       const std::string& descriptor, std::size_t node_count,
                                       std::size_t word_count, const std::uint8_t* descriptors,
                                       const std::uint32_t* links, const std::uint8_t* child_counts,
                                       const float* word_weights);

// CRC32C identity of the content under a given scoring type.
std::uint32_t content_checksum(const VocabularyBlock& block, Scoring scoring);

}  // namespace binbow::detail
