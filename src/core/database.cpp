// The image database: posting lists, packed direct index, queries through the
// inverted index. The .bbdb format lives in database_file.cpp.
#include "binbow/database.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <mutex>
#include <new>
#include <utility>

#include "binbow/error.h"
#include "core/database_impl.h"
#include "core/scoring.h"

namespace binbow {

namespace detail {

// Chunks are arrays of unsigned char: their storage implicitly holds the
// EntryId and float arrays the lists write into it.
unsigned char* PostingArena::allocate(std::uint32_t capacity) {
  const auto size_class = static_cast<unsigned>(__builtin_ctz(capacity));
  if (unsigned char* block = free_lists_[size_class]) {
    std::memcpy(&free_lists_[size_class], block, sizeof(unsigned char*));
    return block;
  }
  if (bump_left_ < capacity) {
    const std::size_t postings = std::max<std::size_t>(kChunkPostings, capacity);
    chunks_.emplace_back(new unsigned char[postings * 8]);  // left uninitialised
    chunk_bytes_ += postings * 8;
    bump_ = chunks_.back().get();
    bump_left_ = postings;
  }
  unsigned char* block = bump_;
  bump_ += std::size_t{capacity} * 8;
  bump_left_ -= capacity;
  return block;
}

void PostingArena::release(unsigned char* block, std::uint32_t capacity) noexcept {
  const auto size_class = static_cast<unsigned>(__builtin_ctz(capacity));
  std::memcpy(block, &free_lists_[size_class], sizeof(unsigned char*));
  free_lists_[size_class] = block;
}

void PostingArena::clear() noexcept {
  chunks_.clear();
  std::fill(std::begin(free_lists_), std::end(free_lists_), nullptr);
  bump_ = nullptr;
  bump_left_ = 0;
  chunk_bytes_ = 0;
}

void PostingList::push_back(EntryId entry, float weight, PostingArena& arena) {
  if (size_ == capacity_) {
    const std::uint32_t capacity = capacity_ == 0 ? 1 : capacity_ * 2;
    unsigned char* block = arena.allocate(capacity);
    auto* new_ids = reinterpret_cast<EntryId*>(block);
    if (size_ > 0) {
      auto* new_weights = reinterpret_cast<float*>(new_ids + capacity);
      for (std::uint32_t i = 0; i < size_; ++i) {
        new_ids[i] = ids()[i];
        new_weights[i] = weights()[i];
      }
      arena.release(block_, capacity_);
    }
    block_ = block;
    capacity_ = capacity;
  }
  auto* id_array = reinterpret_cast<EntryId*>(block_);
  id_array[size_] = entry;
  reinterpret_cast<float*>(id_array + capacity_)[size_] = weight;
  ++size_;
}

PackedFeatureVector::PackedFeatureVector(const FeatureVector& features)
    : node_count_(static_cast<std::uint32_t>(features.size())),
      feature_count_(static_cast<std::uint32_t>(features.feature_count())) {
  const auto& indices = features.feature_indices();
  bool partition = node_count_ <= 0x10000;
  if (partition) {
    std::vector<bool> seen(feature_count_, false);
    for (std::uint32_t index : indices) {
      if (index >= feature_count_ || seen[index]) {
        partition = false;
        break;
      }
      seen[index] = true;
    }
  }
  const bool wide =
      feature_count_ > 0xFFFF ||
      std::any_of(indices.begin(), indices.end(), [](std::uint32_t i) { return i > 0xFFFF; });
  if (partition)
    layout_ = node_count_ <= 0x100 ? Layout::kPartition8 : Layout::kPartition16;
  else
    layout_ = wide ? Layout::kRows32 : Layout::kRows16;
  const std::size_t nodes_bytes = std::size_t{node_count_} * 4;
  if (partition) {
    const std::size_t width = layout_ == Layout::kPartition8 ? 1 : 2;
    bytes_.resize(nodes_bytes + std::size_t{feature_count_} * width);
    if (node_count_ > 0) std::memcpy(bytes_.data(), features.nodes().data(), nodes_bytes);
    std::uint8_t* slots = bytes_.data() + nodes_bytes;
    for (std::size_t node = 0; node < node_count_; ++node) {
      for (std::uint32_t index : features.features(node)) {
        const auto slot = static_cast<std::uint16_t>(node);
        std::memcpy(slots + std::size_t{index} * width, &slot, width);  // little-endian
      }
    }
    return;
  }
  const std::size_t width = layout_ == Layout::kRows32 ? 4 : 2;
  bytes_.resize(nodes_bytes + std::size_t{node_count_} * width +
                std::size_t{feature_count_} * width);
  std::uint8_t* out = bytes_.data();
  if (node_count_ > 0) std::memcpy(out, features.nodes().data(), nodes_bytes);
  out += nodes_bytes;
  const auto put = [&](std::uint32_t v) {
    std::memcpy(out, &v, width);  // little-endian: the low bytes
    out += width;
  };
  for (std::size_t i = 1; i <= node_count_; ++i) put(features.offsets()[i]);
  for (std::uint32_t index : indices) put(index);
}

std::uint32_t PackedFeatureVector::value(std::size_t byte_offset,
                                         std::size_t width) const noexcept {
  std::uint32_t v = 0;
  std::memcpy(&v, bytes_.data() + byte_offset, width);  // little-endian
  return v;
}

FeatureVector PackedFeatureVector::unpack() const {
  std::vector<NodeId> nodes(node_count_);
  const std::size_t nodes_bytes = std::size_t{node_count_} * 4;
  if (node_count_ > 0) std::memcpy(nodes.data(), bytes_.data(), nodes_bytes);
  std::vector<std::uint32_t> offsets(std::size_t{node_count_} + 1, 0);
  std::vector<std::uint32_t> indices(feature_count_);
  if (layout_ == Layout::kPartition8 || layout_ == Layout::kPartition16) {
    // Counting sort of the features by node; increasing index within a node.
    const std::size_t width = layout_ == Layout::kPartition8 ? 1 : 2;
    for (std::size_t f = 0; f < feature_count_; ++f)
      ++offsets[value(nodes_bytes + f * width, width) + 1];
    for (std::size_t i = 0; i < node_count_; ++i) offsets[i + 1] += offsets[i];
    std::vector<std::uint32_t> next(offsets.begin(), offsets.end() - 1);
    for (std::uint32_t f = 0; f < feature_count_; ++f)
      indices[next[value(nodes_bytes + f * width, width)]++] = f;
  } else {
    const std::size_t width = layout_ == Layout::kRows32 ? 4 : 2;
    std::size_t at = nodes_bytes;
    for (std::size_t i = 1; i <= node_count_; ++i, at += width) offsets[i] = value(at, width);
    for (auto& index : indices) {
      index = value(at, width);
      at += width;
    }
  }
  return FeatureVector::from_arrays(std::move(nodes), std::move(offsets), std::move(indices));
}

}  // namespace detail

namespace {

struct Accumulator {
  double sum = 0;
  std::uint32_t shared = 0;
};

// Per-thread buffers reused by every query: the dense score array (all zero
// between queries), the ids touched by the current query, the candidates.
struct QueryScratch {
  std::vector<Accumulator> accumulators;
  std::vector<EntryId> touched;
  std::vector<QueryResult> candidates;
};

thread_local QueryScratch scratch;

// Every term is computed and summed exactly as Vocabulary::score does, in the
// same order (increasing word id), so scores agree to the last bit.
struct IndexView {
  const std::uint32_t* main_offsets;  // null when the main tier is empty
  const EntryId* main_ids;
  const float* main_weights;
  const std::uint32_t* slot_of_word;
  const detail::PostingList* lists;
};

// Adds the terms of one posting run; ids increasing, so `last_entry` cuts it.
template <Scoring kScoring>
inline void accumulate_run(const EntryId* ids, const float* weights, std::uint32_t count, double v,
                           EntryId last_entry, Accumulator* accumulators, EntryId* touched,
                           std::size_t& touched_count) {
  if (count > 0 && ids[count - 1] > last_entry)
    count = static_cast<std::uint32_t>(std::upper_bound(ids, ids + count, last_entry) - ids);
  for (std::uint32_t i = 0; i < count; ++i) {
    Accumulator& accumulator = accumulators[ids[i]];
    touched[touched_count] = ids[i];
    touched_count += accumulator.shared == 0;
    ++accumulator.shared;
    accumulator.sum += detail::score_term(kScoring, v, weights[i]);
  }
}

// Every term is computed and summed exactly as Vocabulary::score does, in the
// same order (increasing word id), so scores agree to the last bit. Posting
// lists are scattered in memory: the lists of words a few steps ahead are
// prefetched so that their cache misses overlap.
template <Scoring kScoring>
std::size_t accumulate(IndexView index, const BowVector& bow, EntryId last_entry,
                       Accumulator* accumulators, EntryId* touched) {
  constexpr std::size_t kAhead = 8;
  std::size_t touched_count = 0;
  const std::size_t n = bow.size();
  const BowEntry* query = bow.begin();
  for (std::size_t q = 0; q < n; ++q) {
    if (q + 2 * kAhead < n) {
      const WordId far = query[q + 2 * kAhead].word;
      if (index.main_offsets != nullptr) __builtin_prefetch(index.main_offsets + far);
      __builtin_prefetch(index.slot_of_word + far);
    }
    if (q + kAhead < n) {
      const WordId near = query[q + kAhead].word;
      if (index.main_offsets != nullptr) {
        const std::uint32_t begin = index.main_offsets[near];
        __builtin_prefetch(index.main_ids + begin);
        __builtin_prefetch(index.main_weights + begin);
      }
      const std::uint32_t slot = index.slot_of_word[near];
      if (slot != 0) {
        __builtin_prefetch(index.lists[slot - 1].ids());
        __builtin_prefetch(index.lists[slot - 1].weights());
      }
    }
    const WordId word = query[q].word;
    const double v = query[q].value;
    if (index.main_offsets != nullptr) {
      const std::uint32_t begin = index.main_offsets[word];
      accumulate_run<kScoring>(index.main_ids + begin, index.main_weights + begin,
                               index.main_offsets[word + 1] - begin, v, last_entry, accumulators,
                               touched, touched_count);
    }
    const std::uint32_t slot = index.slot_of_word[word];
    if (slot != 0) {
      const detail::PostingList& list = index.lists[slot - 1];
      accumulate_run<kScoring>(list.ids(), list.weights(), list.size(), v, last_entry, accumulators,
                               touched, touched_count);
    }
  }
  return touched_count;
}

std::size_t accumulate(Scoring scoring, IndexView impl, const BowVector& bow, EntryId last_entry,
                       Accumulator* accumulators, EntryId* touched) {
  switch (scoring) {
    case Scoring::kL1:
      return accumulate<Scoring::kL1>(impl, bow, last_entry, accumulators, touched);
    case Scoring::kL2:
      return accumulate<Scoring::kL2>(impl, bow, last_entry, accumulators, touched);
    case Scoring::kChiSquare:
      return accumulate<Scoring::kChiSquare>(impl, bow, last_entry, accumulators, touched);
    case Scoring::kKL:
      return accumulate<Scoring::kKL>(impl, bow, last_entry, accumulators, touched);
    case Scoring::kBhattacharyya:
      return accumulate<Scoring::kBhattacharyya>(impl, bow, last_entry, accumulators, touched);
    case Scoring::kDotProduct:
      return accumulate<Scoring::kDotProduct>(impl, bow, last_entry, accumulators, touched);
  }
  return 0;
}

// Orders best first, then by entry id. A NaN score (only from vectors with
// negative values) ranks last, so the order stays a strict weak ordering.
struct BetterResult {
  bool lower_is_better;

  double key(double score) const {
    if (std::isnan(score)) return lower_is_better ? INFINITY : -INFINITY;
    return score;
  }
  bool operator()(const QueryResult& a, const QueryResult& b) const {
    const double ka = key(a.score);
    const double kb = key(b.score);
    if (ka != kb) return lower_is_better ? ka < kb : ka > kb;
    return a.entry < b.entry;
  }
};

void check_bow(const BowVector& bow, const Vocabulary& vocabulary, const char* what) {
  if (!bow.empty() && bow[bow.size() - 1].word >= vocabulary.word_count())
    throw InvalidArgument(
        std::string(what) + ": word id " + std::to_string(bow[bow.size() - 1].word) +
        " is outside the vocabulary (" + std::to_string(vocabulary.word_count()) + " words)");
  for (const BowEntry& entry : bow)
    if (!std::isfinite(entry.value))
      throw InvalidArgument(std::string(what) + ": word " + std::to_string(entry.word) +
                            " has a non-finite value");
}

std::string no_entry_message(EntryId entry, EntryId next) {
  if (entry >= next)
    return "entry " + std::to_string(entry) + " does not exist (the database has ids below " +
           std::to_string(next) + ")";
  return "entry " + std::to_string(entry) + " was removed";
}

}  // namespace

Database::Impl::Impl(Vocabulary vocabulary_in, DatabaseOptions options_in)
    : vocabulary(std::move(vocabulary_in)), options(options_in) {
  if (vocabulary.empty()) throw InvalidArgument("Database: the vocabulary is empty");
  slot_of_word.assign(vocabulary.word_count(), 0);
}

EntryId Database::Impl::append(const BowVector& bow, const FeatureVector& features) {
  if (alive.size() >= kAllEntries)
    throw InvalidArgument("Database: no entry id left (" + std::to_string(alive.size()) +
                          " entries added)");
  const auto entry = static_cast<EntryId>(alive.size());
  try {
    alive.push_back(0);
    word_counts.push_back(static_cast<std::uint32_t>(bow.size()));
    if (options.direct_index) direct.emplace_back(features);
    if (!labels.empty()) labels.emplace_back();
    if (lists.capacity() < lists.size() + bow.size())
      lists.reserve(
          std::max(lists.size() + bow.size(), std::min(lists.capacity() * 2, slot_of_word.size())));
    // As in queries: prefetch the lists of words a few steps ahead.
    constexpr std::size_t kAhead = 8;
    const BowEntry* words = bow.begin();
    const std::size_t n = bow.size();
    for (std::size_t i = 0; i < n; ++i) {
      if (i + 2 * kAhead < n) __builtin_prefetch(slot_of_word.data() + words[i + 2 * kAhead].word);
      if (i + kAhead < n) {
        const std::uint32_t ahead = slot_of_word[words[i + kAhead].word];
        if (ahead != 0) lists[ahead - 1].prefetch_end();
      }
      std::uint32_t& slot = slot_of_word[words[i].word];
      if (slot == 0) {
        lists.emplace_back();  // no reallocation: reserved above
        slot = static_cast<std::uint32_t>(lists.size());
      }
      lists[slot - 1].push_back(entry, words[i].value, arena);
    }
  } catch (...) {
    for (const BowEntry& word : bow) {
      const std::uint32_t slot = slot_of_word[word.word];
      if (slot == 0) continue;
      detail::PostingList& list = lists[slot - 1];
      if (list.size() > 0 && list.ids()[list.size() - 1] == entry) list.pop_back();
    }
    alive.resize(entry);
    word_counts.resize(entry);
    if (direct.size() > entry) direct.resize(entry);
    if (labels.size() > entry) labels.resize(entry);
    throw;
  }
  alive[entry] = 1;
  ++live_entries;
  postings += bow.size();
  tail_postings += bow.size();
  return entry;
}

void Database::Impl::merge_if_worthwhile() {
  constexpr std::size_t kMinimumTail = 1 << 16;
  if (tail_postings <= std::max(kMinimumTail, postings / 4) && dead_postings * 3 <= postings)
    return;
  try {
    merge();
  } catch (...) {
    // Out of memory for the merged copy: the two tiers stay valid as they
    // are, and the add or remove that got here has succeeded.
  }
}

void Database::Impl::merge() {
  const std::size_t words = slot_of_word.size();
  std::size_t live = 0;
  std::vector<std::uint32_t> offsets(words + 1, 0);
  const bool drop_dead = dead_postings > 0;  // else the copies are plain memcpy
  const auto live_count = [&](const EntryId* ids, std::uint32_t count) {
    if (!drop_dead) return count;
    std::uint32_t kept = 0;
    for (std::uint32_t i = 0; i < count; ++i) kept += alive[ids[i]];
    return kept;
  };
  for (std::size_t w = 0; w < words; ++w) {
    std::uint32_t count = 0;
    if (!main_offsets.empty())
      count += live_count(main_ids.data() + main_offsets[w], main_offsets[w + 1] - main_offsets[w]);
    if (slot_of_word[w] != 0) {
      const detail::PostingList& list = lists[slot_of_word[w] - 1];
      count += live_count(list.ids(), list.size());
    }
    live += count;
    if (live > std::numeric_limits<std::uint32_t>::max())
      throw InvalidArgument("Database: more than 2^32 postings");
    offsets[w + 1] = static_cast<std::uint32_t>(live);
  }
  std::vector<EntryId> ids(live);
  std::vector<float> weights(live);
  std::size_t at = 0;
  const auto copy_live = [&](const EntryId* from_ids, const float* from_weights,
                             std::uint32_t count) {
    if (!drop_dead) {  // runs are short: a loop beats a call to memcpy
      EntryId* to_ids = ids.data() + at;
      float* to_weights = weights.data() + at;
      for (std::uint32_t i = 0; i < count; ++i) {
        to_ids[i] = from_ids[i];
        to_weights[i] = from_weights[i];
      }
      at += count;
      return;
    }
    for (std::uint32_t i = 0; i < count; ++i) {
      if (alive[from_ids[i]] == 0) continue;
      ids[at] = from_ids[i];
      weights[at] = from_weights[i];
      ++at;
    }
  };
  for (std::size_t w = 0; w < words; ++w) {
    if (!main_offsets.empty()) {
      const std::uint32_t begin = main_offsets[w];
      copy_live(main_ids.data() + begin, main_weights.data() + begin, main_offsets[w + 1] - begin);
    }
    if (slot_of_word[w] != 0) {
      const detail::PostingList& list = lists[slot_of_word[w] - 1];
      copy_live(list.ids(), list.weights(), list.size());
    }
  }
  // Nothing below can throw: the index changes all at once.
  main_offsets.swap(offsets);
  main_ids.swap(ids);
  main_weights.swap(weights);
  std::fill(slot_of_word.begin(), slot_of_word.end(), 0);
  std::vector<detail::PostingList>().swap(lists);
  arena.clear();
  tail_postings = 0;
  postings = live;
  dead_postings = 0;
}

Database::Database(Vocabulary vocabulary, DatabaseOptions options)
    : impl_(std::make_unique<Impl>(std::move(vocabulary), options)) {}
Database::Database(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Database::Database(Database&&) noexcept = default;
Database& Database::operator=(Database&&) noexcept = default;
Database::~Database() = default;

EntryId Database::add(const DescriptorView& descriptors) {
  BowVector bow;
  FeatureVector features;
  if (impl_->options.direct_index)
    impl_->vocabulary.transform(descriptors, bow, features, impl_->options.direct_index_levels_up);
  else
    impl_->vocabulary.transform(descriptors, bow);
  std::unique_lock lock(impl_->mutex);
  const EntryId entry = impl_->append(bow, features);
  impl_->merge_if_worthwhile();
  return entry;
}

EntryId Database::add(const BowVector& bow, const FeatureVector& features) {
  check_bow(bow, impl_->vocabulary, "Database::add");
  if (impl_->options.direct_index && !features.empty() &&
      features.node(features.size() - 1) >= impl_->vocabulary.node_count())
    throw InvalidArgument("Database::add: feature vector node " +
                          std::to_string(features.node(features.size() - 1)) +
                          " is outside the vocabulary (" +
                          std::to_string(impl_->vocabulary.node_count()) + " nodes)");
  std::unique_lock lock(impl_->mutex);
  const EntryId entry = impl_->append(bow, features);
  impl_->merge_if_worthwhile();
  return entry;
}

std::vector<QueryResult> Database::query(const BowVector& bow, std::size_t max_results,
                                         EntryId max_entry_id) const {
  check_bow(bow, impl_->vocabulary, "Database::query");
  std::vector<QueryResult> results;
  if (bow.empty() || max_results == 0) return results;
  const Scoring scoring = impl_->vocabulary.scoring();
  const double base = detail::score_base(scoring, bow);

  std::shared_lock lock(impl_->mutex);
  const std::size_t entry_count = impl_->alive.size();
  if (entry_count == 0) return results;
  QueryScratch& buffers = scratch;
  if (buffers.accumulators.size() < entry_count) buffers.accumulators.resize(entry_count);
  // accumulate() may write one element past the last new id.
  if (buffers.touched.size() < entry_count + 1) buffers.touched.resize(entry_count + 1);
  const EntryId last_entry = std::min<EntryId>(max_entry_id, static_cast<EntryId>(entry_count - 1));
  const IndexView index{impl_->main_offsets.empty() ? nullptr : impl_->main_offsets.data(),
                        impl_->main_ids.data(), impl_->main_weights.data(),
                        impl_->slot_of_word.data(), impl_->lists.data()};
  const std::size_t touched = accumulate(scoring, index, bow, last_entry,
                                         buffers.accumulators.data(), buffers.touched.data());

  // Collecting candidates also zeroes the accumulators for the next query;
  // reserve first so nothing can throw with dirty accumulators.
  std::vector<QueryResult>& candidates = buffers.candidates;
  candidates.clear();
  try {
    candidates.reserve(touched);
  } catch (...) {
    for (std::size_t i = 0; i < touched; ++i) buffers.accumulators[buffers.touched[i]] = {};
    throw;
  }
  for (std::size_t i = 0; i < touched; ++i) {
    const EntryId entry = buffers.touched[i];
    Accumulator& accumulator = buffers.accumulators[entry];
    if (impl_->alive[entry] != 0)
      candidates.push_back(
          {entry, detail::finish_score(scoring, accumulator.sum, base), accumulator.shared});
    accumulator = {};
  }
  lock.unlock();

  const BetterResult better{scoring == Scoring::kKL};
  if (candidates.size() > max_results) {
    std::nth_element(candidates.begin(),
                     candidates.begin() + static_cast<std::ptrdiff_t>(max_results),
                     candidates.end(), better);
    candidates.resize(max_results);
  }
  std::sort(candidates.begin(), candidates.end(), better);
  results.assign(candidates.begin(), candidates.end());
  return results;
}

void Database::remove(EntryId entry) {
  std::unique_lock lock(impl_->mutex);
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::remove: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  impl_->alive[entry] = 0;
  --impl_->live_entries;
  impl_->dead_postings += impl_->word_counts[entry];
  if (!impl_->direct.empty()) impl_->direct[entry] = {};
  if (!impl_->labels.empty()) std::string().swap(impl_->labels[entry]);
  impl_->merge_if_worthwhile();
}

bool Database::contains(EntryId entry) const {
  std::shared_lock lock(impl_->mutex);
  return impl_->is_live(entry);
}

FeatureVector Database::feature_vector(EntryId entry) const {
  std::shared_lock lock(impl_->mutex);
  if (!impl_->options.direct_index)
    throw InvalidArgument("Database::feature_vector: this database keeps no direct index");
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::feature_vector: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  return impl_->direct[entry].unpack();
}

void Database::set_label(EntryId entry, std::string label) {
  std::unique_lock lock(impl_->mutex);
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::set_label: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  if (impl_->labels.size() < impl_->alive.size()) impl_->labels.resize(impl_->alive.size());
  impl_->labels[entry] = std::move(label);
}

std::string Database::label(EntryId entry) const {
  std::shared_lock lock(impl_->mutex);
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::label: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  return impl_->labels.empty() ? std::string() : impl_->labels[entry];
}

std::size_t Database::size() const {
  std::shared_lock lock(impl_->mutex);
  return impl_->live_entries;
}

EntryId Database::next_entry_id() const {
  std::shared_lock lock(impl_->mutex);
  return static_cast<EntryId>(impl_->alive.size());
}

void Database::clear() {
  std::unique_lock lock(impl_->mutex);
  std::vector<std::uint32_t>().swap(impl_->main_offsets);
  std::vector<EntryId>().swap(impl_->main_ids);
  std::vector<float>().swap(impl_->main_weights);
  std::fill(impl_->slot_of_word.begin(), impl_->slot_of_word.end(), 0);
  std::vector<detail::PostingList>().swap(impl_->lists);
  impl_->arena.clear();
  impl_->tail_postings = 0;
  std::vector<std::uint8_t>().swap(impl_->alive);
  std::vector<std::uint32_t>().swap(impl_->word_counts);
  std::vector<detail::PackedFeatureVector>().swap(impl_->direct);
  std::vector<std::string>().swap(impl_->labels);
  impl_->live_entries = 0;
  impl_->postings = 0;
  impl_->dead_postings = 0;
}

std::size_t Database::memory_usage() const {
  std::shared_lock lock(impl_->mutex);
  const Impl& impl = *impl_;
  std::size_t bytes = impl.main_offsets.capacity() * sizeof(std::uint32_t) +
                      impl.main_ids.capacity() * sizeof(EntryId) +
                      impl.main_weights.capacity() * sizeof(float) +
                      impl.slot_of_word.capacity() * sizeof(std::uint32_t) +
                      impl.lists.capacity() * sizeof(detail::PostingList) + impl.alive.capacity() +
                      impl.word_counts.capacity() * sizeof(std::uint32_t) +
                      impl.direct.capacity() * sizeof(detail::PackedFeatureVector) +
                      impl.labels.capacity() * sizeof(std::string);
  bytes += impl.arena.memory_usage();
  for (const auto& features : impl.direct) bytes += features.memory_usage();
  for (const auto& label : impl.labels)
    if (label.capacity() > 15) bytes += label.capacity() + 1;  // beyond the small-string buffer
  return bytes;
}

const Vocabulary& Database::vocabulary() const noexcept {
  return impl_->vocabulary;
}
const DatabaseOptions& Database::options() const noexcept {
  return impl_->options;
}

}  // namespace binbow
