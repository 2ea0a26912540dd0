// binbow's vocabulary format (.bbw): header, section table, aligned sections,
// every part protected by a CRC32C, explicit little-endian, mapped in place.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "binbow/error.h"
#include "binbow/vocabulary.h"
#include "core/crc32c.h"
#include "core/little_endian.h"
#include "vocabulary/vocabulary_block.h"
#include "vocabulary/word_weights.h"

namespace binbow::detail {

namespace {

std::size_t align_up(std::size_t n) {
  return (n + bbw::kAlignment - 1) / bbw::kAlignment * bbw::kAlignment;
}

struct SectionLayout {
  std::uint32_t id;
  std::size_t size;
};

std::string describe_size(std::size_t n) {
  return std::to_string(n) + " bytes";
}

}  // namespace

bool valid_descriptor_name(const std::string& name) noexcept {
  if (name.size() > bbw::kMaxDescriptorName) return false;
  for (const char c : name)
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-')) return false;
  return true;
}

std::vector<std::uint8_t> encode_block(std::size_t code_size, std::uint32_t branching,
                                       std::uint32_t levels, Weighting weighting, Scoring scoring,
                                       const std::string& descriptor, std::size_t node_count,
                                       std::size_t word_count, const std::uint8_t* descriptors,
                                       const std::uint32_t* links, const std::uint8_t* child_counts,
                                       const float* word_weights) {
  const void* sources[bbw::kSectionCount] = {descriptors, links, child_counts, word_weights};
  const SectionLayout sections[bbw::kSectionCount] = {
      {bbw::kDescriptors, node_count * code_size},
      {bbw::kLinks, node_count * sizeof(std::uint32_t)},
      {bbw::kChildCounts, node_count},
      {bbw::kWordWeights, word_count * sizeof(float)},
  };
  std::size_t offsets[bbw::kSectionCount];
  std::size_t end = align_up(bbw::kHeaderSize + bbw::kSectionCount * bbw::kSectionEntrySize + 4);
  for (std::size_t i = 0; i < bbw::kSectionCount; ++i) {
    offsets[i] = align_up(end);
    end = offsets[i] + sections[i].size;
  }
  std::vector<std::uint8_t> out(end, 0);
  std::uint32_t crcs[bbw::kSectionCount];
  for (std::size_t i = 0; i < bbw::kSectionCount; ++i) {
    if (sections[i].size > 0) std::memcpy(out.data() + offsets[i], sources[i], sections[i].size);
    crcs[i] = crc32c(out.data() + offsets[i], sections[i].size);
  }

  std::uint8_t* h = out.data();
  std::memcpy(h, bbw::kMagic, 8);
  store_le<std::uint32_t>(h + 8, bbw::kVersion);
  store_le<std::uint32_t>(h + 12, bbw::kHeaderSize);
  store_le<std::uint32_t>(h + 16, static_cast<std::uint32_t>(code_size));
  store_le<std::uint32_t>(h + 20, branching);
  store_le<std::uint32_t>(h + 24, levels);
  h[28] = static_cast<std::uint8_t>(weighting);
  h[29] = static_cast<std::uint8_t>(scoring);
  store_le<std::uint64_t>(h + 32, node_count);
  store_le<std::uint64_t>(h + 40, word_count);
  store_le<std::uint32_t>(h + 48, bbw::kSectionCount);
  std::memcpy(h + bbw::kDescriptorNameOffset, descriptor.data(), descriptor.size());
  store_le<std::uint32_t>(h + 60, crc32c(h, 60));

  std::uint8_t* table = out.data() + bbw::kHeaderSize;
  for (std::size_t i = 0; i < bbw::kSectionCount; ++i) {
    std::uint8_t* e = table + i * bbw::kSectionEntrySize;
    store_le<std::uint32_t>(e, sections[i].id);
    store_le<std::uint32_t>(e + 4, crcs[i]);
    store_le<std::uint64_t>(e + 8, offsets[i]);
    store_le<std::uint64_t>(e + 16, sections[i].size);
  }
  const std::size_t table_size = bbw::kSectionCount * bbw::kSectionEntrySize;
  store_le<std::uint32_t>(table + table_size, crc32c(table, table_size));
  return out;
}

void parse_block(VocabularyBlock& block, const std::string& name, const LoadOptions& options) {
  const std::uint8_t* data = block.mapped ? block.mapped->data() : block.owned.data();
  const std::size_t size = block.mapped ? block.mapped->size() : block.owned.size();
  auto fail = [&](const std::string& problem) -> void { throw FileError(name, problem); };

  if (size < bbw::kHeaderSize)
    fail("truncated: " + describe_size(size) + ", shorter than the " +
         std::to_string(bbw::kHeaderSize) + "-byte header of a .bbw vocabulary");
  if (std::memcmp(data, bbw::kMagic, 8) != 0)
    fail(
        "not a binbow vocabulary (.bbw): wrong magic bytes; use `binbow convert` for other "
        "formats");
  const auto version = load_le<std::uint32_t>(data + 8);
  if (version != bbw::kVersion)
    fail("unsupported .bbw format version " + std::to_string(version) +
         " (this binbow reads version " + std::to_string(bbw::kVersion) +
         "); re-create the file with this binbow version");
  if (load_le<std::uint32_t>(data + 60) != crc32c(data, 60))
    fail("header checksum mismatch: the file is corrupted");
  if (load_le<std::uint32_t>(data + 12) != bbw::kHeaderSize) fail("unexpected header size");

  const auto code_size = load_le<std::uint32_t>(data + 16);
  const auto branching = load_le<std::uint32_t>(data + 20);
  const auto levels = load_le<std::uint32_t>(data + 24);
  const auto node_count = load_le<std::uint64_t>(data + 32);
  const auto word_count = load_le<std::uint64_t>(data + 40);
  const auto section_count = load_le<std::uint32_t>(data + 48);
  if (code_size == 0 || code_size > bbw::kMaxCodeSize)
    fail("descriptor size " + std::to_string(code_size) + " bytes is out of range 1.." +
         std::to_string(bbw::kMaxCodeSize));
  if (branching == 0 || branching > bbw::kMaxBranching)
    fail("branching factor " + std::to_string(branching) + " is out of range 1..255");
  if (levels == 0 || levels > bbw::kMaxLevels)
    fail("depth " + std::to_string(levels) + " is out of range 1..32");
  if (data[28] > 3) fail("unknown weighting code " + std::to_string(data[28]));
  if (data[29] > 5) fail("unknown scoring code " + std::to_string(data[29]));
  if (node_count < 2 || node_count >= kLeafBit || node_count > size / code_size)
    fail("node count " + std::to_string(node_count) + " does not fit a file of " +
         describe_size(size));
  if (word_count == 0 || word_count >= node_count)
    fail("word count " + std::to_string(word_count) + " does not fit " +
         std::to_string(node_count) + " nodes");
  const char* name_field = reinterpret_cast<const char*>(data + bbw::kDescriptorNameOffset);
  const std::string descriptor(name_field,
                               std::find(name_field, name_field + bbw::kMaxDescriptorName, '\0'));
  if (!valid_descriptor_name(descriptor) ||
      std::any_of(name_field + descriptor.size(), name_field + bbw::kMaxDescriptorName,
                  [](char c) { return c != 0; }))
    fail(std::string("the descriptor name field is not ") + kDescriptorNameRule);
  if (section_count != bbw::kSectionCount)
    fail("expected " + std::to_string(bbw::kSectionCount) + " sections, the header says " +
         std::to_string(section_count));

  const std::size_t table_size = bbw::kSectionCount * bbw::kSectionEntrySize;
  if (size < bbw::kHeaderSize + table_size + 4) fail("truncated inside the section table");
  const std::uint8_t* table = data + bbw::kHeaderSize;
  if (load_le<std::uint32_t>(table + table_size) != crc32c(table, table_size))
    fail("section table checksum mismatch: the file is corrupted");

  const std::size_t expected_sizes[bbw::kSectionCount] = {node_count * code_size, node_count * 4,
                                                          node_count, word_count * 4};
  const char* const names[bbw::kSectionCount] = {"descriptors", "links", "child counts",
                                                 "word weights"};
  const std::uint8_t* section_data[bbw::kSectionCount];
  // Sections lie where the writer puts them, and the padding before each is
  // zero: with the CRCs, every byte of the file is checked.
  std::size_t previous_end = bbw::kHeaderSize + table_size + 4;
  for (std::size_t i = 0; i < bbw::kSectionCount; ++i) {
    const std::uint8_t* e = table + i * bbw::kSectionEntrySize;
    const auto id = load_le<std::uint32_t>(e);
    const auto crc = load_le<std::uint32_t>(e + 4);
    const auto offset = load_le<std::uint64_t>(e + 8);
    const auto length = load_le<std::uint64_t>(e + 16);
    if (id != i + 1) fail("unexpected section id " + std::to_string(id));
    if (length != expected_sizes[i])
      fail(std::string("section '") + names[i] + "' has " + describe_size(length) + ", expected " +
           describe_size(expected_sizes[i]));
    if (offset % bbw::kAlignment != 0 || offset > size || length > size - offset)
      fail(std::string("section '") + names[i] + "' lies outside the file (truncated?)");
    if (offset != align_up(previous_end))
      fail(std::string("section '") + names[i] + "' is not where the layout puts it");
    if (std::any_of(data + previous_end, data + offset, [](std::uint8_t b) { return b != 0; }))
      fail(std::string("nonzero padding before section '") + names[i] + "': the file is corrupted");
    previous_end = offset + length;
    if (options.verify_checksums && crc32c(data + offset, length) != crc)
      fail(std::string("checksum mismatch in section '") + names[i] + "': the file is corrupted");
    block.section_crcs[i] = crc;
    section_data[i] = data + offset;
    if (i + 1 == bbw::kSectionCount && offset + length != size)
      fail(size < offset + length ? "truncated" : "unexpected bytes after the last section");
  }

  block.bytes = data;
  block.size = size;
  block.code_size = code_size;
  block.branching = branching;
  block.levels = levels;
  block.descriptor = descriptor;
  block.weighting = static_cast<Weighting>(data[28]);
  block.scoring = static_cast<Scoring>(data[29]);
  block.node_count = node_count;
  block.word_count = word_count;
  block.tree.descriptors = section_data[0];
  block.tree.links = reinterpret_cast<const std::uint32_t*>(section_data[1]);
  block.tree.child_counts = section_data[2];
  block.tree.code_size = code_size;
  block.word_weights = reinterpret_cast<const float*>(section_data[3]);
  const std::string weights_problem = word_weights_problem(
      word_count,
      [&](std::size_t word) { return load_le<float>(section_data[3] + word * sizeof(float)); },
      "word");
  if (!weights_problem.empty()) fail(weights_problem);

  // Structure: every link stays inside the tree and points forward (so no
  // cycle), every node but the root has exactly one parent, depth ≤ levels,
  // every word belongs to exactly one leaf. Later code relies on this.
  const std::uint32_t* links = block.tree.links;
  const std::uint8_t* counts = block.tree.child_counts;
  std::vector<std::uint8_t> depth(node_count, 0);  // depth + 1 once the node has a parent
  std::vector<bool> word_seen(word_count, false);
  if (counts[0] == 0) fail("the root has no children: the vocabulary has no words");
  depth[0] = 1;
  for (std::size_t n = 0; n < node_count; ++n) {
    if (depth[n] == 0)
      fail("node " + std::to_string(n) + " has no parent (the tree is inconsistent)");
    const std::uint32_t count = counts[n];
    if (count == 0) {
      const std::uint32_t word = links[n] & ~kLeafBit;
      if ((links[n] & kLeafBit) == 0 || word >= word_count || word_seen[word])
        fail("leaf node " + std::to_string(n) + " has an invalid or duplicate word id");
      word_seen[word] = true;
      continue;
    }
    if (count > branching)
      fail("node " + std::to_string(n) + " has " + std::to_string(count) +
           " children, more than the branching factor " + std::to_string(branching));
    const std::uint64_t first = links[n];
    if (first <= n || first + count > node_count)
      fail("node " + std::to_string(n) + " links to children outside the tree");
    if (depth[n] > levels)
      fail("node " + std::to_string(n) + " has children below the declared depth " +
           std::to_string(levels));
    for (std::uint64_t c = first; c < first + count; ++c) {
      if (depth[c] != 0) fail("node " + std::to_string(c) + " has two parents");
      depth[c] = static_cast<std::uint8_t>(depth[n] + 1);
    }
  }
  // Each leaf marked a distinct word and there are word_count leaves only if
  // every word was seen; count the leaves instead of scanning the bitmap.
  std::size_t leaves = 0;
  for (std::size_t n = 0; n < node_count; ++n) leaves += counts[n] == 0;
  if (leaves != word_count)
    fail(std::to_string(word_count) + " words declared but the tree has " + std::to_string(leaves) +
         " leaves");
}

std::uint32_t content_checksum(const VocabularyBlock& block, Scoring scoring) {
  std::uint8_t head[24];
  store_le<std::uint32_t>(head, static_cast<std::uint32_t>(block.code_size));
  store_le<std::uint32_t>(head + 4, block.branching);
  store_le<std::uint32_t>(head + 8, block.levels);
  head[12] = static_cast<std::uint8_t>(block.weighting);
  head[13] = static_cast<std::uint8_t>(scoring);
  head[14] = head[15] = 0;
  store_le<std::uint64_t>(head + 16, block.node_count);
  std::uint32_t crc = crc32c(head, sizeof head);
  return crc32c(block.section_crcs, sizeof block.section_crcs, crc);
}

}  // namespace binbow::detail

namespace binbow {

Vocabulary Vocabulary::load(const std::string& path, const LoadOptions& options) {
  auto block = std::make_shared<detail::VocabularyBlock>();
  block->mapped = std::make_unique<detail::MappedFile>(path, options.verify_checksums);
  detail::parse_block(*block, path, options);
  return Vocabulary(std::move(block));
}

Vocabulary Vocabulary::deserialize(const std::uint8_t* data, std::size_t size,
                                   const std::string& name, const LoadOptions& options) {
  auto block = std::make_shared<detail::VocabularyBlock>();
  block->owned.assign(data, data + size);
  detail::parse_block(*block, name, options);
  return Vocabulary(std::move(block));
}

std::vector<std::uint8_t> Vocabulary::serialize() const {
  if (empty()) throw InvalidArgument("cannot serialize an empty vocabulary");
  std::vector<std::uint8_t> out(block_->bytes, block_->bytes + block_->size);
  if (scoring_ != block_->scoring) {
    out[29] = static_cast<std::uint8_t>(scoring_);
    detail::store_le<std::uint32_t>(out.data() + 60, detail::crc32c(out.data(), 60));
  }
  return out;
}

Vocabulary Vocabulary::with_descriptor(const std::string& descriptor) const {
  if (!detail::valid_descriptor_name(descriptor))
    throw InvalidArgument("descriptor name \"" + descriptor + "\" is not " +
                          detail::kDescriptorNameRule);
  auto block = std::make_shared<detail::VocabularyBlock>();
  block->owned = serialize();
  std::uint8_t* header = block->owned.data();
  std::uint8_t* name_field = header + detail::bbw::kDescriptorNameOffset;
  std::fill_n(name_field, detail::bbw::kMaxDescriptorName, std::uint8_t{0});
  std::copy(descriptor.begin(), descriptor.end(), name_field);
  detail::store_le<std::uint32_t>(header + 60, detail::crc32c(header, 60));
  detail::parse_block(*block, "vocabulary", LoadOptions{false});
  return Vocabulary(std::move(block));
}

void Vocabulary::save(const std::string& path) const {
  const std::vector<std::uint8_t> bytes = serialize();
  detail::write_file_atomically(path, bytes.data(), bytes.size());
}

}  // namespace binbow
