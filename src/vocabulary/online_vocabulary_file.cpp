// The online vocabulary's state file (.bbov). Layout, all little-endian:
//   header (64 bytes, CRC32C in its last 4), section table (24 bytes per
//   section: id, CRC32C, offset, length; then the table's CRC32C), then the
//   sections back to back in id order up to the end of the file, so that
//   every byte is covered by a CRC. Sections, always present:
//   0 options   1 word ids (u32 per live word, in slot order)
//   2 word counts (u32 images, observations, first image, last image per word)
//   3 word descriptors (code_size bytes per word)
//   4 majority counters (one count byte per bit, for each word with two
//     observations or more, in slot order)   5 counter totals (u8 per such word)
//   6 trees (u32 node count, u32 live words at the last rebuild, per tree)
//   7 tree nodes (u32 first child, u32 child count, u32 leaf words, per node
//     of every tree in order)   8 tree centres (code_size bytes per node but
//     the roots)   9 leaf words (u32 slots of every leaf, in node order)
// Version 2 stores the search trees as they are, so that a loaded vocabulary
// searches (and grows) exactly as the saved one would have; version 1 (no
// sections 6..9) still loads, its trees rebuilt from the words.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "binbow/online_vocabulary.h"
#include "core/crc32c.h"
#include "core/file_io.h"
#include "core/little_endian.h"
#include "core/sectioned_file.h"
#include "vocabulary/online_vocabulary_impl.h"

namespace binbow {

namespace {

constexpr char kMagic[8] = {'B', 'I', 'N', 'B', 'O', 'W', 'O', 'V'};
constexpr std::uint32_t kVersion = 2;
constexpr std::uint32_t kVersionWithoutTrees = 1;
constexpr std::size_t kHeaderSize = detail::kSectionedHeaderSize;
constexpr std::size_t kOptionsSize = 48;  // before the descriptor name
constexpr std::size_t kMaxDescriptorName = 8;

enum Section : std::uint32_t {
  kOptions = 0,
  kWordIds,
  kWordCounts,
  kDescriptors,
  kCounters,
  kCounterTotals,
  kSectionCountWithoutTrees,
  kTrees = kSectionCountWithoutTrees,
  kTreeNodes,
  kTreeCentres,
  kLeafWords,
  kSectionCount,
};
constexpr const char* kSectionNames[kSectionCount] = {
    "options",        "word ids", "word counts", "descriptors",  "counters",
    "counter totals", "trees",    "tree nodes",  "tree centres", "leaf words"};
constexpr std::size_t kTreeRecordSize = 8;
constexpr std::size_t kNodeRecordSize = 12;

}  // namespace

std::vector<std::uint8_t> OnlineVocabulary::serialize() const {
  const Impl& impl = *impl_;
  const OnlineVocabularyOptions& o = impl.options;
  std::vector<std::uint8_t> sections[kSectionCount];

  std::vector<std::uint8_t>& options = sections[kOptions];
  detail::put_le<double>(options, o.new_word_distance);
  detail::put_le<std::uint32_t>(options, o.purge_after_images);
  detail::put_le<std::uint32_t>(options, o.trees);
  detail::put_le<std::uint32_t>(options, o.branching);
  detail::put_le<std::uint32_t>(options, o.leaf_size);
  detail::put_le<std::uint32_t>(options, o.max_checks);
  options.push_back(o.exact ? 1 : 0);
  options.push_back(static_cast<std::uint8_t>(o.scoring));
  options.resize(options.size() + 2, 0);
  detail::put_le<std::uint64_t>(options, o.seed);
  detail::put_le<std::uint64_t>(options, impl.random_draws);
  options.insert(options.end(), o.descriptor.begin(), o.descriptor.end());

  std::size_t with_counters = 0;
  for (std::size_t slot = 0; slot < impl.word_count(); ++slot) {
    const OnlineWordInfo& word = impl.info[slot];
    detail::put_le<std::uint32_t>(sections[kWordIds], word.id);
    detail::put_le<std::uint32_t>(sections[kWordCounts], word.images);
    detail::put_le<std::uint32_t>(sections[kWordCounts], word.observations);
    detail::put_le<std::uint32_t>(sections[kWordCounts], word.first_image);
    detail::put_le<std::uint32_t>(sections[kWordCounts], word.last_image);
    const std::uint32_t block = impl.counter_block[slot];
    if (block == detail::kNoSlot) continue;
    const std::uint8_t* ones = impl.counters.data() + std::size_t{block} * impl.bits;
    sections[kCounters].insert(sections[kCounters].end(), ones, ones + impl.bits);
    sections[kCounterTotals].push_back(impl.counter_totals[block]);
    ++with_counters;
  }
  sections[kDescriptors] = impl.descriptors;

  for (const detail::WordTree& tree : impl.trees) {
    detail::put_le<std::uint32_t>(sections[kTrees], static_cast<std::uint32_t>(tree.nodes.size()));
    detail::put_le<std::uint32_t>(sections[kTrees], static_cast<std::uint32_t>(tree.built_words));
    for (const detail::WordTree::Node& node : tree.nodes) {
      detail::put_le<std::uint32_t>(sections[kTreeNodes], node.first_child);
      detail::put_le<std::uint32_t>(sections[kTreeNodes], node.child_count);
      detail::put_le<std::uint32_t>(sections[kTreeNodes],
                                    static_cast<std::uint32_t>(node.slots.size()));
      for (const std::uint32_t slot : node.slots)
        detail::put_le<std::uint32_t>(sections[kLeafWords], slot);
    }
    sections[kTreeCentres].insert(
        sections[kTreeCentres].end(),
        tree.centres.begin() + static_cast<std::ptrdiff_t>(impl.code_size), tree.centres.end());
  }

  return detail::write_sectioned_file(
      kMagic, kVersion, sections, kSectionCount, [&](std::uint8_t* h) {
        detail::store_le<std::uint32_t>(h + 16, static_cast<std::uint32_t>(impl.code_size));
        detail::store_le<std::uint32_t>(h + 20, impl.images);
        detail::store_le<std::uint32_t>(h + 24, impl.next_word_id);
        detail::store_le<std::uint32_t>(h + 28, static_cast<std::uint32_t>(impl.word_count()));
        detail::store_le<std::uint32_t>(h + 32, static_cast<std::uint32_t>(with_counters));
        detail::store_le<std::uint64_t>(h + 40, impl.purged_words);
        detail::store_le<std::uint32_t>(h + 52, static_cast<std::uint32_t>(std::min<std::size_t>(
                                                    impl.tree_rebuilds, 0xFFFFFFFFu)));
      });
}

// Every count is checked against the length of the section that holds its
// values before anything is allocated: a hostile header cannot make the
// reader allocate more than the file's own size.
OnlineVocabulary OnlineVocabulary::deserialize(const std::uint8_t* data, std::size_t size,
                                               const std::string& name) {
  const auto fail = [&](const std::string& problem) { throw FileError(name, problem); };
  if (size < kHeaderSize)
    fail("truncated: " + std::to_string(size) + " bytes, shorter than the " +
         std::to_string(kHeaderSize) + "-byte header of an online vocabulary (.bbov)");
  if (std::memcmp(data, kMagic, 8) != 0)
    fail("not a binbow online vocabulary (.bbov): wrong magic bytes");
  const auto version = detail::load_le<std::uint32_t>(data + 8);
  if (version != kVersion && version != kVersionWithoutTrees)
    fail("unsupported .bbov format version " + std::to_string(version) +
         " (this binbow reads versions " + std::to_string(kVersionWithoutTrees) + " and " +
         std::to_string(kVersion) + ")");
  const bool has_trees = version == kVersion;
  const std::uint32_t expected_sections = has_trees ? kSectionCount : kSectionCountWithoutTrees;
  if (detail::load_le<std::uint32_t>(data + 60) != detail::crc32c(data, 60))
    fail("header checksum mismatch: the file is corrupted");
  if (detail::load_le<std::uint32_t>(data + 12) != kHeaderSize) fail("unexpected header size");
  const auto code_size = detail::load_le<std::uint32_t>(data + 16);
  const auto images = detail::load_le<std::uint32_t>(data + 20);
  const auto next_word_id = detail::load_le<std::uint32_t>(data + 24);
  const auto word_count = detail::load_le<std::uint32_t>(data + 28);
  const auto with_counters = detail::load_le<std::uint32_t>(data + 32);
  const auto purged_words = detail::load_le<std::uint64_t>(data + 40);
  const auto section_count = detail::load_le<std::uint32_t>(data + 48);
  const auto tree_rebuilds = detail::load_le<std::uint32_t>(data + 52);
  if (section_count != expected_sections)
    fail("expected " + std::to_string(expected_sections) + " sections, the header says " +
         std::to_string(section_count));
  if (detail::load_le<std::uint32_t>(data + 36) != 0 ||
      detail::load_le<std::uint32_t>(data + 56) != 0)
    fail("reserved header bytes are not zero");
  if (next_word_id == OnlineVocabulary::kNoWord || word_count > next_word_id ||
      purged_words != std::uint64_t{next_word_id} - word_count || with_counters > word_count)
    fail("inconsistent word counts in the header (" + std::to_string(word_count) + " words, " +
         std::to_string(purged_words) + " purged, " + std::to_string(next_word_id) +
         " ids created)");

  const std::vector<detail::Section> table = detail::read_section_table(
      data, size, expected_sections, kSectionNames, [&](const std::string& p) { fail(p); });
  const std::uint8_t* section_data[kSectionCount] = {};
  std::size_t section_size[kSectionCount] = {};
  for (std::uint32_t i = 0; i < expected_sections; ++i) {
    if (!detail::section_intact(table[i]))
      fail(std::string("checksum mismatch in section '") + kSectionNames[i] +
           "': the file is corrupted");
    section_data[i] = table[i].data;
    section_size[i] = table[i].size;
  }

  // Options: a fixed record, then the descriptor name.
  const std::size_t options_size = section_size[kOptions];
  if (options_size < kOptionsSize || options_size > kOptionsSize + kMaxDescriptorName)
    fail("section 'options' has " + std::to_string(options_size) + " bytes, expected " +
         std::to_string(kOptionsSize) + " to " + std::to_string(kOptionsSize + kMaxDescriptorName));
  const std::uint8_t* o = section_data[kOptions];
  OnlineVocabularyOptions options;
  options.new_word_distance = detail::load_le<double>(o);
  options.purge_after_images = detail::load_le<std::uint32_t>(o + 8);
  options.trees = detail::load_le<std::uint32_t>(o + 12);
  options.branching = detail::load_le<std::uint32_t>(o + 16);
  options.leaf_size = detail::load_le<std::uint32_t>(o + 20);
  options.max_checks = detail::load_le<std::uint32_t>(o + 24);
  if (o[28] > 1 || o[29] > 5 || o[30] != 0 || o[31] != 0) fail("invalid options flags");
  options.exact = o[28] != 0;
  options.scoring = static_cast<Scoring>(o[29]);
  options.seed = detail::load_le<std::uint64_t>(o + 32);
  const auto random_draws = detail::load_le<std::uint64_t>(o + 40);
  options.descriptor.assign(reinterpret_cast<const char*>(o + kOptionsSize),
                            options_size - kOptionsSize);
  std::unique_ptr<Impl> impl;
  try {
    impl = std::make_unique<Impl>(code_size, options);
  } catch (const InvalidArgument& e) {
    fail(std::string("invalid options: ") + e.what());
  }

  const auto expect_size = [&](Section s, std::uint64_t expected) {
    if (section_size[s] != expected)
      fail(std::string("section '") + kSectionNames[s] + "' has " +
           std::to_string(section_size[s]) + " bytes, expected " + std::to_string(expected));
  };
  expect_size(kWordIds, std::uint64_t{word_count} * 4);
  expect_size(kWordCounts, std::uint64_t{word_count} * 16);
  expect_size(kDescriptors, std::uint64_t{word_count} * code_size);
  expect_size(kCounters, std::uint64_t{with_counters} * code_size * 8);
  expect_size(kCounterTotals, with_counters);

  impl->images = images;
  impl->next_word_id = next_word_id;
  impl->purged_words = static_cast<std::size_t>(purged_words);
  impl->tree_rebuilds = static_cast<std::size_t>(tree_rebuilds);
  impl->random_draws = random_draws;
  impl->descriptors.assign(section_data[kDescriptors],
                           section_data[kDescriptors] + section_size[kDescriptors]);
  impl->info.resize(word_count);
  impl->counter_block.assign(word_count, detail::kNoSlot);
  impl->leaves.assign(std::size_t{word_count} * options.trees, 0);
  std::uint32_t block = 0;
  for (std::uint32_t slot = 0; slot < word_count; ++slot) {
    OnlineWordInfo& word = impl->info[slot];
    const std::uint8_t* counts = section_data[kWordCounts] + std::size_t{slot} * 16;
    word.id = detail::load_le<std::uint32_t>(section_data[kWordIds] + std::size_t{slot} * 4);
    word.images = detail::load_le<std::uint32_t>(counts);
    word.observations = detail::load_le<std::uint32_t>(counts + 4);
    word.first_image = detail::load_le<std::uint32_t>(counts + 8);
    word.last_image = detail::load_le<std::uint32_t>(counts + 12);
    const std::string what = "word " + std::to_string(word.id);
    if (word.id >= next_word_id) fail(what + " is beyond the ids created");
    if (word.images == 0 || word.observations < word.images || word.last_image >= images ||
        word.first_image > word.last_image || word.images - 1 > word.last_image - word.first_image)
      fail(what + " has inconsistent counts");
    if (options.purge_after_images > 0 && word.images == 1 &&
        word.first_image + std::uint64_t{options.purge_after_images} < images)
      fail(what + " should have been purged");
    if (word.observations < 2) continue;
    if (block == with_counters) fail("more words with counters than the header says");
    // The counters must back the word's descriptor: a bit most descriptors
    // have is set, a bit most lack is clear (a tie allows either).
    const std::uint8_t* ones = section_data[kCounters] + std::size_t{block} * impl->bits;
    const std::uint32_t total = section_data[kCounterTotals][block];
    const std::uint8_t* descriptor = impl->slot_descriptor(slot);
    if (total == 0 || total > 254) fail(what + " has an invalid counter total");
    for (std::size_t b = 0; b < impl->bits; ++b) {
      const bool set = (descriptor[b / 8] >> (b % 8)) & 1u;
      if (ones[b] > total || (2u * ones[b] > total && !set) || (2u * ones[b] < total && set))
        fail(what + "'s descriptor disagrees with its majority counters");
    }
    impl->counter_block[slot] = block++;
  }
  if (block != with_counters) fail("fewer words with counters than the header says");
  impl->counters.assign(section_data[kCounters], section_data[kCounters] + section_size[kCounters]);
  impl->counter_totals.assign(section_data[kCounterTotals],
                              section_data[kCounterTotals] + section_size[kCounterTotals]);
  impl->slot_of.reserve(word_count);
  for (std::uint32_t slot = 0; slot < word_count; ++slot)
    if (!impl->slot_of.emplace(impl->info[slot].id, slot).second)
      fail("word " + std::to_string(impl->info[slot].id) + " appears twice");
  impl->restore_purge_queue();
  if (has_trees) {
    impl->read_trees(section_data + kTrees, section_size + kTrees, fail);
  } else {
    impl->rebuild_trees_after_load();
  }
  return OnlineVocabulary(std::move(impl));
}

// Every count is checked against its section's length before anything is
// allocated. A tree is well formed when every inner node has 2..branching
// children placed after it (so no node is its own ancestor: no cycles, and a
// descent ends within the node count), every node but the root is the child
// of exactly one node, only leaves list words, and every live word is in
// exactly one leaf.
void OnlineVocabulary::Impl::read_trees(const std::uint8_t* const* data, const std::size_t* size,
                                        const std::function<void(const std::string&)>& fail) {
  const auto section_name = [](std::size_t s) { return std::string(kSectionNames[kTrees + s]); };
  const auto expect_size = [&](std::size_t s, std::uint64_t expected) {
    if (size[s] != expected)
      fail("section '" + section_name(s) + "' has " + std::to_string(size[s]) +
           " bytes, expected " + std::to_string(expected));
  };
  const std::size_t tree_count = trees.size();
  const std::size_t live_words = word_count();
  expect_size(0, std::uint64_t{tree_count} * kTreeRecordSize);
  std::uint64_t total_nodes = 0;
  for (std::size_t t = 0; t < tree_count; ++t) {
    const auto nodes = detail::load_le<std::uint32_t>(data[0] + t * kTreeRecordSize);
    const auto built = detail::load_le<std::uint32_t>(data[0] + t * kTreeRecordSize + 4);
    if (nodes == 0) fail("tree " + std::to_string(t) + " has no root");
    if (built > next_word_id)
      fail("tree " + std::to_string(t) + " was built over more words than were ever created");
    total_nodes += nodes;
  }
  expect_size(1, total_nodes * kNodeRecordSize);
  expect_size(2, (total_nodes - tree_count) * code_size);
  expect_size(3, std::uint64_t{tree_count} * live_words * 4);

  std::fill(leaves.begin(), leaves.end(), detail::kNoSlot);
  const std::uint8_t* node_record = data[1];
  const std::uint8_t* centre = data[2];
  const std::uint8_t* leaf_word = data[3];
  for (std::size_t t = 0; t < tree_count; ++t) {
    const std::string what = "tree " + std::to_string(t);
    detail::WordTree& tree = trees[t];
    const auto node_count = detail::load_le<std::uint32_t>(data[0] + t * kTreeRecordSize);
    tree.built_words = detail::load_le<std::uint32_t>(data[0] + t * kTreeRecordSize + 4);
    tree.nodes.assign(node_count, {});
    tree.centres.assign(std::size_t{node_count} * code_size, 0);
    std::memcpy(tree.centres.data() + code_size, centre, (std::size_t{node_count} - 1) * code_size);
    centre += (std::size_t{node_count} - 1) * code_size;
    std::vector<bool> has_parent(node_count, false);
    std::size_t words_in_leaves = 0;
    for (std::uint32_t n = 0; n < node_count; ++n, node_record += kNodeRecordSize) {
      detail::WordTree::Node& node = tree.nodes[n];
      node.first_child = detail::load_le<std::uint32_t>(node_record);
      node.child_count = detail::load_le<std::uint32_t>(node_record + 4);
      const auto leaf_words = detail::load_le<std::uint32_t>(node_record + 8);
      const std::string where = what + " node " + std::to_string(n);
      if (node.child_count == 0) {
        if (node.first_child != 0) fail(where + " is a leaf with a first child");
        if (leaf_words > live_words - words_in_leaves)
          fail(what + " lists more words in its leaves than there are");
        words_in_leaves += leaf_words;
        node.slots.resize(leaf_words);
        for (std::uint32_t& slot : node.slots) {
          slot = detail::load_le<std::uint32_t>(leaf_word);
          leaf_word += 4;
          if (slot >= live_words)
            fail(where + " lists word slot " + std::to_string(slot) + " beyond the " +
                 std::to_string(live_words) + " words");
          std::uint32_t& leaf = leaves[std::size_t{slot} * tree_count + t];
          if (leaf != detail::kNoSlot)
            fail(what + " lists word " + std::to_string(info[slot].id) + " twice");
          leaf = n;
        }
        continue;
      }
      if (leaf_words != 0) fail(where + " is an inner node that lists words");
      if (node.child_count < 2 || node.child_count > options.branching)
        fail(where + " has " + std::to_string(node.child_count) + " children, expected 2 to " +
             std::to_string(options.branching));
      if (node.first_child <= n || std::uint64_t{node.first_child} + node.child_count > node_count)
        fail(where +
             "'s children are out of range (a child index must come after its parent "
             "and within the tree's " +
             std::to_string(node_count) + " nodes)");
      for (std::uint32_t c = node.first_child; c < node.first_child + node.child_count; ++c) {
        if (has_parent[c]) fail(what + " node " + std::to_string(c) + " has two parents");
        has_parent[c] = true;
      }
    }
    for (std::uint32_t n = 1; n < node_count; ++n)
      if (!has_parent[n]) fail(what + " node " + std::to_string(n) + " is not in the tree");
    if (words_in_leaves != live_words)
      fail(what + " is missing " + std::to_string(live_words - words_in_leaves) +
           " word(s) from its leaves");
  }
}

void OnlineVocabulary::save(const std::string& path) const {
  const std::vector<std::uint8_t> bytes = serialize();
  detail::write_file_atomically(path, bytes.data(), bytes.size());
}

OnlineVocabulary OnlineVocabulary::load(const std::string& path) {
  const detail::MappedFile file(path);
  return deserialize(file.data(), file.size(), path);
}

}  // namespace binbow
