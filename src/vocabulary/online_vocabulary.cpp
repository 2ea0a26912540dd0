#include "binbow/online_vocabulary.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

#include "binbow/error.h"
#include "core/kernels.h"
#include "vocabulary/kmedians.h"
#include "vocabulary/online_vocabulary_impl.h"
#include "vocabulary/vocabulary_block.h"

namespace binbow {

namespace {

// Halving the counters at this total keeps them in a byte; the majority then
// weighs recent descriptors a little more than very old ones.
constexpr std::uint32_t kCounterLimit = 255;

void check_options(std::size_t code_size, const OnlineVocabularyOptions& o) {
  const auto fail = [](const std::string& problem) {
    throw InvalidArgument("OnlineVocabulary: " + problem);
  };
  if (code_size == 0 || code_size > detail::bbw::kMaxCodeSize)
    fail("descriptor size " + std::to_string(code_size) + " bytes is out of range 1..1024");
  if (!(o.new_word_distance >= 0.0 && o.new_word_distance <= 1.0))
    fail("new_word_distance must be a fraction of the descriptor's bits in [0, 1]");
  if (o.purge_after_images >= 0x80000000u) fail("purge_after_images must be below 2^31");
  if (o.trees < 1 || o.trees > 16) fail("trees must be in 1..16, got " + std::to_string(o.trees));
  if (o.branching < 2 || o.branching > 64)
    fail("branching must be in 2..64, got " + std::to_string(o.branching));
  if (o.leaf_size < 1 || o.leaf_size > 4096)
    fail("leaf_size must be in 1..4096, got " + std::to_string(o.leaf_size));
  if (o.max_checks < 1 || o.max_checks >= 0x80000000u) fail("max_checks must be in 1..2^31-1");
  if (static_cast<unsigned>(o.scoring) > 5) fail("unknown scoring type");
  if (!detail::valid_descriptor_name(o.descriptor))
    fail("descriptor name \"" + o.descriptor + "\" is not " + detail::kDescriptorNameRule);
}

bool bit_of(const std::uint8_t* descriptor, std::size_t bit) {
  return (descriptor[bit / 8] >> (bit % 8)) & 1u;
}

// A branch not yet explored by a search, as one integer ordered as the
// search takes branches: closest centre first, then by tree, then by node.
// Keys are unique, so the order never depends on where a branch sits in the
// list. Distances fit 14 bits (descriptors have at most 8192), trees 4,
// nodes 32.
using Branch = std::uint64_t;
Branch make_branch(std::uint32_t distance, std::uint32_t tree, std::uint32_t node) {
  return (std::uint64_t{distance} << 36) | (std::uint64_t{tree} << 32) | node;
}
std::uint32_t branch_tree(Branch branch) {
  return static_cast<std::uint32_t>(branch >> 32) & 0xFu;
}
std::uint32_t branch_node(Branch branch) {
  return static_cast<std::uint32_t>(branch);
}

std::uint32_t branch_distance(Branch branch) {
  return static_cast<std::uint32_t>(branch >> 36);
}

// The branches of one search, taken smallest key first: a bucket per
// distance, each unordered (it holds a few branches; the smallest is looked
// for when one is taken).
class BranchQueue {
 public:
  // Empty, for distances up to `bits`.
  void reset(std::size_t bits) {
    if (buckets_.size() < bits + 1) buckets_.resize(bits + 1);
    for (std::size_t d = lowest_; d <= highest_ && d < buckets_.size(); ++d) buckets_[d].clear();
    lowest_ = buckets_.size();
    highest_ = 0;
  }
  void push(Branch branch) {
    const std::uint32_t d = branch_distance(branch);
    buckets_[d].push_back(branch);
    lowest_ = std::min<std::size_t>(lowest_, d);
    highest_ = std::max<std::size_t>(highest_, d);
  }
  bool pop(Branch& branch) {
    while (lowest_ <= highest_ && buckets_[lowest_].empty()) ++lowest_;
    if (lowest_ > highest_) return false;
    std::vector<Branch>& bucket = buckets_[lowest_];
    const auto smallest = std::min_element(bucket.begin(), bucket.end());
    branch = *smallest;
    *smallest = bucket.back();
    bucket.pop_back();
    return true;
  }

 private:
  std::vector<std::vector<Branch>> buckets_;
  std::size_t lowest_ = 0;   // no branch below it
  std::size_t highest_ = 0;  // nor above it
};

void check_code_size(const DescriptorView& descriptors, std::size_t code_size) {
  if (descriptors.rows > 0 && descriptors.code_size != code_size)
    throw InvalidArgument("descriptors have " + std::to_string(descriptors.code_size) +
                          " bytes but the online vocabulary's words have " +
                          std::to_string(code_size) + " (wrong descriptor type?)");
}

}  // namespace

OnlineVocabulary::Impl::Impl(std::size_t code_size_, OnlineVocabularyOptions options_)
    : code_size(code_size_), bits(code_size_ * 8), options(std::move(options_)) {
  check_options(code_size, options);
  new_word_bits =
      static_cast<std::uint32_t>(std::floor(options.new_word_distance * static_cast<double>(bits)));
  trees.resize(options.trees);
  for (detail::WordTree& tree : trees) {
    tree.nodes.resize(1);
    tree.centres.assign(code_size, 0);
  }
}

void OnlineVocabulary::Impl::nearest(const std::uint8_t* query, std::uint32_t& best_slot,
                                     std::uint32_t& best_distance) const {
  best_slot = detail::kNoSlot;
  best_distance = kNoWord;
  WordId best_word = kNoWord;
  // One kernel call per leaf or set of children, not one per row: the call
  // through the kernel table cost as much as the distance itself.
  const auto distances = detail::kernels().distances;
  thread_local std::vector<std::uint32_t> found;
  const auto consider = [&](const std::uint32_t* slots, std::size_t count) {
    found.resize(std::max(found.size(), count));
    distances(query, descriptors.data(), slots, count, code_size, found.data());
    // The smallest distance first (a loop without branches), then the words
    // at it: most leaves hold nothing nearer than the best so far.
    std::uint32_t nearest = kNoWord;
    for (std::size_t i = 0; i < count; ++i) nearest = std::min(nearest, found[i]);
    if (nearest > best_distance) return;
    for (std::size_t i = 0; i < count; ++i) {
      if (found[i] != nearest) continue;
      const std::uint32_t slot = slots != nullptr ? slots[i] : static_cast<std::uint32_t>(i);
      if (nearest < best_distance || info[slot].id < best_word) {
        best_distance = nearest;
        best_slot = slot;
        best_word = info[slot].id;
      }
    }
  };
  if (options.exact) {
    consider(nullptr, word_count());
    return;
  }

  // Branches not taken, in buckets by distance to their centre (distances
  // are small integers): a search pushes hundreds of branches and takes a
  // few dozen, so a push must cost nothing. A linear scan per branch taken
  // was most of the search's time; a binary heap's pushes still cost half.
  thread_local BranchQueue branches;
  branches.reset(bits);
  std::size_t checks = 0;
  std::uint32_t child_distances[64];  // branching ≤ 64
  const auto descend = [&](std::uint32_t t, std::uint32_t n) {
    const detail::WordTree& tree = trees[t];
    while (tree.nodes[n].child_count != 0) {
      const detail::WordTree::Node& node = tree.nodes[n];
      distances(query, tree.centres.data() + std::size_t{node.first_child} * code_size, nullptr,
                node.child_count, code_size, child_distances);
      std::uint32_t nearest = 0;
      for (std::uint32_t c = 1; c < node.child_count; ++c)
        if (child_distances[c] < child_distances[nearest]) nearest = c;
      for (std::uint32_t c = 0; c < node.child_count; ++c)
        if (c != nearest) branches.push(make_branch(child_distances[c], t, node.first_child + c));
      n = node.first_child + nearest;
    }
    consider(tree.nodes[n].slots.data(), tree.nodes[n].slots.size());
    checks += tree.nodes[n].slots.size();
  };
  for (std::uint32_t t = 0; t < trees.size(); ++t) descend(t, 0);
  Branch branch;
  while (checks < options.max_checks && branches.pop(branch))
    descend(branch_tree(branch), branch_node(branch));
}

std::uint32_t OnlineVocabulary::Impl::create_word(const std::uint8_t* descriptor,
                                                  std::uint32_t image) {
  const WordId word = next_word_id++;
  const auto slot = static_cast<std::uint32_t>(word_count());
  descriptors.insert(descriptors.end(), descriptor, descriptor + code_size);
  info.push_back({word, 1, 1, image, image});
  counter_block.push_back(detail::kNoSlot);
  leaves.resize(leaves.size() + trees.size(), 0);
  slot_of.emplace(word, slot);
  for (std::size_t t = 0; t < trees.size(); ++t) insert_into_tree(t, slot);
  if (options.purge_after_images > 0) purge_queue.push_back(word);
  return slot;
}

bool OnlineVocabulary::Impl::join_word(std::uint32_t slot, const std::uint8_t* descriptor,
                                       std::uint32_t image) {
  OnlineWordInfo& word_info = info[slot];
  if (word_info.last_image != image) {
    ++word_info.images;
    word_info.last_image = image;
  }
  if (word_info.observations < 0xFFFFFFFFu) ++word_info.observations;

  std::uint8_t* current = descriptors.data() + std::size_t{slot} * code_size;
  std::uint32_t& block = counter_block[slot];
  if (block == detail::kNoSlot) {
    // The word's first descriptor is its only vote so far.
    if (!free_blocks.empty()) {
      block = free_blocks.back();
      free_blocks.pop_back();
    } else {
      block = static_cast<std::uint32_t>(counter_totals.size());
      counter_totals.push_back(0);
      counters.resize(counters.size() + bits);
    }
    std::uint8_t* ones = counters.data() + std::size_t{block} * bits;
    for (std::size_t b = 0; b < bits; ++b) ones[b] = bit_of(current, b);
    counter_totals[block] = 1;
  }
  std::uint8_t* ones = counters.data() + std::size_t{block} * bits;
  const std::uint32_t total = ++counter_totals[block];
  // A byte at a time, its eight bits without branches: this runs for most
  // descriptors of every image.
  bool changed = false;
  for (std::size_t byte = 0; byte < code_size; ++byte) {
    std::uint8_t* byte_ones = ones + 8 * byte;
    const std::uint32_t votes = descriptor[byte];
    std::uint32_t set = 0;
    std::uint32_t clear = 0;
    for (std::uint32_t k = 0; k < 8; ++k) {
      byte_ones[k] = static_cast<std::uint8_t>(byte_ones[k] + ((votes >> k) & 1u));
      const std::uint32_t twice = 2u * byte_ones[k];
      set |= std::uint32_t{twice > total} << k;
      clear |= std::uint32_t{twice < total} << k;
    }
    const std::uint8_t before = current[byte];
    current[byte] = static_cast<std::uint8_t>((before | set) & ~clear);
    changed |= current[byte] != before;
  }
  if (total == kCounterLimit) {
    for (std::size_t b = 0; b < bits; ++b) ones[b] = static_cast<std::uint8_t>(ones[b] / 2);
    counter_totals[block] = static_cast<std::uint8_t>(total / 2);
  }
  return changed;
}

void OnlineVocabulary::Impl::purge(std::uint32_t slot) {
  const std::size_t tree_count = trees.size();
  const auto replace_in_leaves = [&](std::uint32_t from, std::uint32_t to) {
    for (std::size_t t = 0; t < tree_count; ++t) {
      std::vector<std::uint32_t>& slots = trees[t].nodes[leaves[from * tree_count + t]].slots;
      const auto at = std::find(slots.begin(), slots.end(), from);
      if (to == detail::kNoSlot)
        slots.erase(at);
      else
        *at = to;
    }
  };
  replace_in_leaves(slot, detail::kNoSlot);
  if (counter_block[slot] != detail::kNoSlot) free_blocks.push_back(counter_block[slot]);
  slot_of.erase(info[slot].id);

  // The last slot moves into the hole.
  const auto last = static_cast<std::uint32_t>(word_count() - 1);
  if (slot != last) {
    replace_in_leaves(last, slot);
    std::memcpy(descriptors.data() + std::size_t{slot} * code_size, slot_descriptor(last),
                code_size);
    info[slot] = info[last];
    counter_block[slot] = counter_block[last];
    std::copy_n(leaves.begin() + std::size_t{last} * tree_count, tree_count,
                leaves.begin() + std::size_t{slot} * tree_count);
    slot_of[info[slot].id] = slot;
  }
  descriptors.resize(descriptors.size() - code_size);
  info.pop_back();
  counter_block.pop_back();
  leaves.resize(leaves.size() - tree_count);
  ++purged_words;
}

void OnlineVocabulary::Impl::purge_expired(std::vector<WordId>& purged) {
  const std::uint32_t current = images - 1;
  while (!purge_queue.empty()) {
    const WordId word = purge_queue.front();
    const std::uint32_t slot = find_slot(word);
    if (slot != detail::kNoSlot &&
        info[slot].first_image + std::uint64_t{options.purge_after_images} > current)
      break;
    purge_queue.pop_front();
    if (slot != detail::kNoSlot && info[slot].images == 1) {
      purge(slot);
      purged.push_back(word);
    }
  }
}

namespace {
// The child of inner node `node` whose centre is nearest (lowest on ties).
std::uint32_t nearest_child(const detail::WordTree& tree, std::uint32_t node,
                            const std::uint8_t* descriptor, std::size_t code_size) {
  const std::uint32_t first = tree.nodes[node].first_child;
  std::uint32_t index = 0;
  detail::kernels().nearest(descriptor, 1, tree.centres.data() + std::size_t{first} * code_size,
                            tree.nodes[node].child_count, code_size, &index, nullptr);
  return first + index;
}
}  // namespace

void OnlineVocabulary::Impl::insert_into_tree(std::size_t t, std::uint32_t slot) {
  detail::WordTree& tree = trees[t];
  std::uint32_t n = 0;
  while (tree.nodes[n].child_count != 0)
    n = nearest_child(tree, n, slot_descriptor(slot), code_size);
  tree.nodes[n].slots.push_back(slot);
  leaves[std::size_t{slot} * trees.size() + t] = n;
  if (tree.nodes[n].slots.size() > options.leaf_size) split_leaf(t, n);
}

void OnlineVocabulary::Impl::reinsert_into_tree(std::size_t t, std::uint32_t slot) {
  detail::WordTree& tree = trees[t];
  std::uint32_t& leaf = leaves[std::size_t{slot} * trees.size() + t];
  std::uint32_t n = 0;
  while (tree.nodes[n].child_count != 0)
    n = nearest_child(tree, n, slot_descriptor(slot), code_size);
  if (n == leaf) return;
  std::vector<std::uint32_t>& old_slots = tree.nodes[leaf].slots;
  old_slots.erase(std::find(old_slots.begin(), old_slots.end(), slot));
  tree.nodes[n].slots.push_back(slot);
  leaf = n;
  if (tree.nodes[n].slots.size() > options.leaf_size) split_leaf(t, n);
}

void OnlineVocabulary::Impl::split_leaf(std::size_t t, std::uint32_t overfull) {
  detail::WordTree& tree = trees[t];
  // A list, not recursion: an unlucky draw can make a tree deep.
  std::vector<std::uint32_t> pending{overfull};
  while (!pending.empty()) {
    const std::uint32_t leaf = pending.back();
    pending.pop_back();
    std::vector<std::uint32_t> slots = std::move(tree.nodes[leaf].slots);
    tree.nodes[leaf].slots.clear();

    // Up to `branching` centres drawn at random among the words, with
    // distinct descriptors, so every word's own centre is unique and every
    // child gets at least its centre's word: each child is smaller than the
    // leaf.
    detail::SplitMix64 random(detail::child_seed(options.seed, random_draws++));
    std::vector<std::uint32_t> pool = slots;
    std::vector<const std::uint8_t*> centres;
    for (std::size_t remaining = pool.size();
         remaining > 0 && centres.size() < options.branching;) {
      const std::size_t pick = random.below(remaining);
      std::swap(pool[pick], pool[--remaining]);
      const std::uint8_t* candidate = slot_descriptor(pool[remaining]);
      if (std::none_of(centres.begin(), centres.end(), [&](const std::uint8_t* centre) {
            return std::memcmp(centre, candidate, code_size) == 0;
          }))
        centres.push_back(candidate);
    }
    if (centres.size() < 2) {  // all equal: nothing to split on, the leaf stays big
      tree.nodes[leaf].slots = std::move(slots);
      continue;
    }

    const auto first = static_cast<std::uint32_t>(tree.nodes.size());
    const auto count = static_cast<std::uint32_t>(centres.size());
    tree.nodes.resize(tree.nodes.size() + count);
    tree.nodes[leaf].first_child = first;
    tree.nodes[leaf].child_count = count;
    tree.centres.resize(tree.nodes.size() * code_size);
    for (std::uint32_t c = 0; c < count; ++c)
      std::memcpy(tree.centres.data() + std::size_t{first + c} * code_size, centres[c], code_size);
    for (const std::uint32_t slot : slots) {
      const std::uint32_t child = nearest_child(tree, leaf, slot_descriptor(slot), code_size);
      tree.nodes[child].slots.push_back(slot);
      leaves[std::size_t{slot} * trees.size() + t] = child;
    }
    // Pushed in reverse: children split in order, depth first.
    for (std::uint32_t c = first + count; c-- > first;)
      if (tree.nodes[c].slots.size() > options.leaf_size) pending.push_back(c);
  }
}

void OnlineVocabulary::Impl::rebuild_tree(std::size_t t) {
  detail::WordTree& tree = trees[t];
  tree.nodes.assign(1, {});
  tree.centres.assign(code_size, 0);
  tree.nodes[0].slots.resize(word_count());
  for (std::uint32_t slot = 0; slot < word_count(); ++slot) {
    tree.nodes[0].slots[slot] = slot;
    leaves[std::size_t{slot} * trees.size() + t] = 0;
  }
  if (word_count() > options.leaf_size) split_leaf(t, 0);
  tree.built_words = word_count();
  ++tree_rebuilds;
}

void OnlineVocabulary::Impl::rebuild_grown_trees() {
  for (std::size_t t = 0; t < trees.size(); ++t) {
    const std::size_t built = std::max<std::size_t>(trees[t].built_words, options.leaf_size);
    if (word_count() > 2 * built) rebuild_tree(t);
  }
}

void OnlineVocabulary::Impl::restore_purge_queue() {
  purge_queue.clear();
  if (options.purge_after_images > 0) {
    // The words created in the last purge_after_images images, oldest first,
    // as add_image left them.
    std::vector<WordId> recent;
    for (const OnlineWordInfo& word : info)
      if (word.first_image + std::uint64_t{options.purge_after_images} + 1 > images)
        recent.push_back(word.id);
    std::sort(recent.begin(), recent.end());
    purge_queue.assign(recent.begin(), recent.end());
  }
}

void OnlineVocabulary::Impl::rebuild_trees_after_load() {
  // The rebuilds draw from a range add_image never reaches, and leave the
  // counters as saved: every load of the file continues the same way.
  const std::uint64_t saved_draws = random_draws;
  const std::size_t saved_rebuilds = tree_rebuilds;
  random_draws = saved_draws | (std::uint64_t{1} << 63);
  for (std::size_t t = 0; t < trees.size(); ++t) rebuild_tree(t);
  random_draws = saved_draws;
  tree_rebuilds = saved_rebuilds;
}

std::size_t OnlineVocabulary::Impl::memory_usage() const {
  // A hash node holds the pair and a next pointer; buckets are pointers.
  const std::size_t map_bytes =
      slot_of.size() * (sizeof(std::pair<WordId, std::uint32_t>) + sizeof(void*)) +
      slot_of.bucket_count() * sizeof(void*);
  std::size_t bytes = descriptors.capacity() + info.capacity() * sizeof(OnlineWordInfo) +
                      (counter_block.capacity() + leaves.capacity() + free_blocks.capacity()) *
                          sizeof(std::uint32_t) +
                      counters.capacity() + counter_totals.capacity() +
                      purge_queue.size() * sizeof(WordId) + map_bytes;
  for (const detail::WordTree& tree : trees) {
    bytes += tree.nodes.capacity() * sizeof(detail::WordTree::Node) + tree.centres.capacity();
    for (const detail::WordTree::Node& node : tree.nodes)
      bytes += node.slots.capacity() * sizeof(std::uint32_t);
  }
  return bytes;
}

OnlineVocabulary::OnlineVocabulary(std::size_t code_size, OnlineVocabularyOptions options)
    : impl_(std::make_unique<Impl>(code_size, std::move(options))) {}
OnlineVocabulary::OnlineVocabulary(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OnlineVocabulary::OnlineVocabulary(const OnlineVocabulary& other)
    : impl_(std::make_unique<Impl>(*other.impl_)) {}
OnlineVocabulary& OnlineVocabulary::operator=(const OnlineVocabulary& other) {
  if (this != &other) impl_ = std::make_unique<Impl>(*other.impl_);
  return *this;
}
OnlineVocabulary::OnlineVocabulary(OnlineVocabulary&&) noexcept = default;
OnlineVocabulary& OnlineVocabulary::operator=(OnlineVocabulary&&) noexcept = default;
OnlineVocabulary::~OnlineVocabulary() = default;

OnlineImageWords OnlineVocabulary::add_image(const DescriptorView& descriptors) {
  OnlineImageWords result;
  add_image(descriptors, result);
  return result;
}

void OnlineVocabulary::add_image(const DescriptorView& descriptors, OnlineImageWords& result) {
  Impl& impl = *impl_;
  check_code_size(descriptors, impl.code_size);
  if (impl.images == 0xFFFFFFFFu)
    throw InvalidArgument("OnlineVocabulary: 2^32 - 1 images added, no more can be counted");
  // Checked before anything changes, though the image may need fewer.
  if (descriptors.rows > kNoWord - impl.next_word_id)
    throw InvalidArgument("OnlineVocabulary: " + std::to_string(descriptors.rows) +
                          " descriptors could need more word ids than the " +
                          std::to_string(kNoWord - impl.next_word_id) + " left");
  result.words.resize(descriptors.rows);
  result.purged.clear();
  result.new_words = 0;
  const std::uint32_t image = impl.images++;
  for (std::size_t i = 0; i < descriptors.rows; ++i) {
    const std::uint8_t* descriptor = descriptors.row(i);
    std::uint32_t slot;
    std::uint32_t distance;
    impl.nearest(descriptor, slot, distance);
    if (slot == detail::kNoSlot || distance > impl.new_word_bits) {
      slot = impl.create_word(descriptor, image);
      ++result.new_words;
    } else if (impl.join_word(slot, descriptor, image)) {
      // The word moved: its leaves may no longer be the nearest.
      for (std::size_t t = 0; t < impl.trees.size(); ++t) impl.reinsert_into_tree(t, slot);
    }
    result.words[i] = impl.info[slot].id;
  }
  if (impl.options.purge_after_images > 0) impl.purge_expired(result.purged);
  impl.rebuild_grown_trees();
}

void OnlineVocabulary::nearest_words(const DescriptorView& descriptors, WordId* words,
                                     std::uint32_t* distances) const {
  check_code_size(descriptors, impl_->code_size);
  for (std::size_t i = 0; i < descriptors.rows; ++i) {
    std::uint32_t slot;
    impl_->nearest(descriptors.row(i), slot, distances[i]);
    words[i] = slot == detail::kNoSlot ? kNoWord : impl_->info[slot].id;
  }
}

void OnlineVocabulary::transform(const DescriptorView& descriptors, BowVector& bow,
                                 FeatureVector* features) const {
  check_code_size(descriptors, impl_->code_size);
  thread_local std::vector<WordId> words;
  words.resize(descriptors.rows);
  for (std::size_t i = 0; i < descriptors.rows; ++i) {
    std::uint32_t slot;
    std::uint32_t distance;
    impl_->nearest(descriptors.row(i), slot, distance);
    const bool known = slot != detail::kNoSlot && distance <= impl_->new_word_bits;
    words[i] = known ? impl_->info[slot].id : kNoWord;
  }
  weigh(words.data(), words.size(), bow, features);
}

void OnlineVocabulary::weigh(const WordId* words, std::size_t count, BowVector& bow,
                             FeatureVector* features) const {
  const Impl& impl = *impl_;
  // (word, feature) pairs of the features whose word has a positive weight,
  // sorted by word then feature.
  thread_local std::vector<std::pair<WordId, std::uint32_t>> pairs;
  pairs.clear();
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t slot = impl.find_slot(words[i]);
    if (slot == detail::kNoSlot || impl.info[slot].images >= impl.images) continue;  // idf 0
    pairs.emplace_back(words[i], static_cast<std::uint32_t>(i));
  }
  std::sort(pairs.begin(), pairs.end());

  std::vector<BowEntry> entries;
  std::vector<double> values;
  std::vector<NodeId> nodes;
  std::vector<std::uint32_t> offsets{0};
  std::vector<std::uint32_t> feature_ids;
  for (std::size_t i = 0; i < pairs.size();) {
    const WordId word = pairs[i].first;
    std::size_t j = i;
    for (; j < pairs.size() && pairs[j].first == word; ++j) feature_ids.push_back(pairs[j].second);
    nodes.push_back(word);
    offsets.push_back(static_cast<std::uint32_t>(j));
    entries.push_back({word, 0.0f});
    const double weight = idf(word);
    values.push_back(weight * static_cast<double>(j - i));
    i = j;
  }
  // Normalised as Vocabulary::transform normalises tf-idf vectors.
  const Scoring scoring = impl.options.scoring;
  if (scoring != Scoring::kDotProduct) {
    double norm = 0;
    for (const double v : values) norm += scoring == Scoring::kL2 ? v * v : std::fabs(v);
    if (scoring == Scoring::kL2) norm = std::sqrt(norm);
    if (norm > 0)
      for (double& v : values) v /= norm;
  } else if (!values.empty()) {
    const double distinct = static_cast<double>(values.size());
    for (double& v : values) v /= distinct;
  }
  for (std::size_t i = 0; i < values.size(); ++i) entries[i].value = static_cast<float>(values[i]);
  bow = BowVector(std::move(entries));
  if (features != nullptr) {
    *features =
        FeatureVector::from_arrays(std::move(nodes), std::move(offsets), std::move(feature_ids));
  }
}

std::size_t OnlineVocabulary::code_size() const noexcept {
  return impl_->code_size;
}
const OnlineVocabularyOptions& OnlineVocabulary::options() const noexcept {
  return impl_->options;
}
std::size_t OnlineVocabulary::word_count() const noexcept {
  return impl_->word_count();
}
std::size_t OnlineVocabulary::image_count() const noexcept {
  return impl_->images;
}
WordId OnlineVocabulary::next_word_id() const noexcept {
  return impl_->next_word_id;
}
bool OnlineVocabulary::contains(WordId word) const noexcept {
  return impl_->find_slot(word) != detail::kNoSlot;
}

OnlineVocabularyStats OnlineVocabulary::stats() const {
  OnlineVocabularyStats stats;
  stats.images = impl_->images;
  stats.words = impl_->word_count();
  stats.next_word_id = impl_->next_word_id;
  stats.purged_words = impl_->purged_words;
  stats.tree_rebuilds = impl_->tree_rebuilds;
  stats.memory_bytes = impl_->memory_usage();
  return stats;
}

namespace {
void check_word(const OnlineVocabulary& vocabulary, WordId word) {
  if (!vocabulary.contains(word))
    throw InvalidArgument(
        "word " + std::to_string(word) +
        (word < vocabulary.next_word_id()
             ? " was purged"
             : " does not exist (" + std::to_string(vocabulary.next_word_id()) + " ids created)"));
}
}  // namespace

const std::uint8_t* OnlineVocabulary::word_descriptor(WordId word) const {
  check_word(*this, word);
  return impl_->slot_descriptor(impl_->find_slot(word));
}

OnlineWordInfo OnlineVocabulary::word_info(WordId word) const {
  check_word(*this, word);
  return impl_->info[impl_->find_slot(word)];
}

double OnlineVocabulary::idf(WordId word) const {
  check_word(*this, word);
  return std::log(static_cast<double>(impl_->images) /
                  static_cast<double>(impl_->info[impl_->find_slot(word)].images));
}

std::vector<WordId> OnlineVocabulary::words() const {
  std::vector<WordId> ids;
  ids.reserve(impl_->word_count());
  for (const OnlineWordInfo& word : impl_->info) ids.push_back(word.id);
  std::sort(ids.begin(), ids.end());
  return ids;
}

Vocabulary OnlineVocabulary::to_vocabulary(const BuildOptions& options) const {
  const Impl& impl = *impl_;
  if (impl.word_count() == 0)
    throw InvalidArgument("OnlineVocabulary::to_vocabulary: the vocabulary has no words");
  BuildOptions build = options;
  if (build.descriptor.empty()) build.descriptor = impl.options.descriptor;
  const bool idf_weights =
      options.weighting == Weighting::kTfIdf || options.weighting == Weighting::kIdf;
  // The tree over the words as one "image"; the weights come from the
  // images the online vocabulary has seen, not from this clustering.
  if (idf_weights) build.weighting = Weighting::kTf;
  const DescriptorView words{impl.descriptors.data(), impl.word_count(), impl.code_size};
  Vocabulary tree_only = Vocabulary::build({words}, build);
  if (!idf_weights) return tree_only;

  std::vector<WordId> leaf_of_word(impl.word_count());
  tree_only.quantize(words, leaf_of_word.data());
  std::vector<std::uint64_t> leaf_images(tree_only.word_count(), 0);
  for (std::size_t slot = 0; slot < impl.word_count(); ++slot)
    leaf_images[leaf_of_word[slot]] += impl.info[slot].images;
  VocabularyTree tree = tree_only.to_tree();
  tree.weighting = options.weighting;
  const std::vector<NodeId> leaf_nodes = tree_only.word_nodes();
  const double n = impl.images;
  bool any_positive = false;
  for (std::size_t leaf = 0; leaf < leaf_nodes.size(); ++leaf) {
    const double images = std::min<double>(static_cast<double>(leaf_images[leaf]), n);
    const double weight = images == 0 ? 0.0 : std::log(n / images);
    tree.weights[leaf_nodes[leaf]] = static_cast<float>(weight);
    any_positive |= weight > 0;
  }
  if (!any_positive)
    throw InvalidArgument(
        "OnlineVocabulary::to_vocabulary: every word is in every image seen, so every IDF weight "
        "is 0 and every BoW vector would be empty; add more images first");
  return Vocabulary::from_tree(tree);
}

}  // namespace binbow
