// The image database's public API. Its index: the tail (database_tail.cpp)
// and segments (database_segments.cpp); queries in database_query.cpp, the
// .bbdb format in bbdb_format.h, incremental saves in database_journal.cpp.
#include "binbow/database.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <mutex>
#include <new>
#include <shared_mutex>
#include <utility>

#include "binbow/error.h"
#include "database/database_impl.h"

namespace binbow {

namespace {

void check_direct_index_levels(const DatabaseOptions& options) {
  if (options.direct_index_levels_up > kMaxDirectIndexLevelsUp)
    throw InvalidArgument("Database: direct_index_levels_up is " +
                          std::to_string(options.direct_index_levels_up) + ", at most " +
                          std::to_string(kMaxDirectIndexLevelsUp) + " can be saved");
}

// Over word ids, the rows start with this many words and double as needed.

std::string no_entry_message(EntryId entry, EntryId next) {
  if (entry >= next)
    return "entry " + std::to_string(entry) + " does not exist (the database has ids below " +
           std::to_string(next) + ")";
  return "entry " + std::to_string(entry) + " was removed";
}

// An add under the database's lock: the entry, its journal record, its label,
// then a frozen tail if it is full. (A template only because Database::Impl is
// private to the class.)
template <class Impl>
EntryId append_entry(Impl& impl, const BowVector& bow, const FeatureVector& features,
                     std::string label) {
  const EntryId entry = impl.append(bow, features);
  impl.journal.record_add(entry, bow, impl.options.direct_index ? features : FeatureVector(),
                          label);
  if (!label.empty()) impl.store_label(entry, std::move(label));
  impl.freeze_tail_if_full();
  return entry;
}

}  // namespace

Database::Impl::Impl(Vocabulary vocabulary_in, DatabaseOptions options_in)
    : vocabulary(std::move(vocabulary_in)), options(options_in) {
  if (vocabulary.empty()) throw InvalidArgument("Database: the vocabulary is empty");
  check_direct_index_levels(options);
  scoring = vocabulary.scoring();
  lay_out(vocabulary.word_count());
}

Database::Impl::Impl(Scoring scoring_in, DatabaseOptions options_in)
    : options(options_in), scoring(scoring_in), over_word_ids(true) {
  check_direct_index_levels(options);
  lay_out(detail::kInitialWordCapacity);
}

Database::Database(Vocabulary vocabulary, DatabaseOptions options)
    : impl_(std::make_unique<Impl>(std::move(vocabulary), options)) {}
Database::Database(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Database Database::over_word_ids(Scoring scoring, DatabaseOptions options) {
  return Database(std::make_unique<Impl>(scoring, options));
}
Database::Database(Database&&) noexcept = default;
Database& Database::operator=(Database&&) noexcept = default;
Database::~Database() = default;

void Database::Impl::store_label(EntryId entry, std::string label) {
  if (labels.size() < alive.size()) labels.resize(alive.size());
  labels[entry] = std::move(label);
}

EntryId Database::add(const DescriptorView& descriptors, std::string label) {
  if (impl_->over_word_ids)
    throw InvalidArgument(
        "Database::add: a database over word ids has no vocabulary to transform descriptors");
  BowVector bow;
  FeatureVector features;
  if (impl_->options.direct_index)
    impl_->vocabulary.transform(descriptors, bow, features, impl_->options.direct_index_levels_up);
  else
    impl_->vocabulary.transform(descriptors, bow);
  std::unique_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  return append_entry(*impl_, bow, features, std::move(label));
}

EntryId Database::add(const BowVector& bow, const FeatureVector& features, std::string label) {
  if (impl_->over_word_ids) {
    std::unique_lock lock(impl_->mutex);
    impl_->throw_if_damaged();
    if (!bow.empty()) impl_->grow_words(std::size_t{bow[bow.size() - 1].word} + 1);
    return append_entry(*impl_, bow, features, std::move(label));
  }
  // append checks the values.
  detail::check_bow_words(bow, impl_->vocabulary, "Database::add");
  if (impl_->options.direct_index && !features.empty() &&
      features.node(features.size() - 1) >= impl_->vocabulary.node_count())
    throw InvalidArgument("Database::add: feature vector node " +
                          std::to_string(features.node(features.size() - 1)) +
                          " is outside the vocabulary (" +
                          std::to_string(impl_->vocabulary.node_count()) + " nodes)");
  std::unique_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  return append_entry(*impl_, bow, features, std::move(label));
}

void Database::remove(EntryId entry) {
  std::unique_lock lock(impl_->mutex);
  // The entry's postings are counted by the file's check.
  impl_->merge_file_check();
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::remove: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  impl_->alive[entry] = 0;
  --impl_->live_entries;
  impl_->journal.record_remove(entry);
  // An entry without postings has nothing to drop, and may lie where no
  // segment is left (one whose postings were all removed is dropped).
  const std::size_t segment =
      impl_->word_counts[entry] == 0 ? impl_->segments.size() : impl_->segment_of(entry);
  if (segment == impl_->segments.size()) {
    impl_->tail_dead_postings += impl_->word_counts[entry];
  } else {
    detail::Segment& thinned = *impl_->segments[segment];
    thinned.dead_postings += impl_->word_counts[entry];
    if (thinned.dead_postings * 3 > thinned.postings()) impl_->compact(segment);
  }
  if (!impl_->direct.empty()) impl_->direct[entry] = {};
  if (impl_->forward_built) impl_->forward.drop(entry);
  if (!impl_->labels.empty()) std::string().swap(impl_->labels[entry]);
}

bool Database::contains(EntryId entry) const {
  std::shared_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  return impl_->is_live(entry);
}

FeatureVector Database::feature_vector(EntryId entry) const {
  std::shared_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  if (!impl_->options.direct_index)
    throw InvalidArgument("Database::feature_vector: this database keeps no direct index");
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::feature_vector: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  if (entry >= impl_->loaded_direct.entries()) return impl_->direct[entry].unpack();
  try {
    return impl_->loaded_direct.decode(entry).unpack();
  } catch (const InvalidArgument& e) {
    // Only in a damaged file, whose check has not ended yet.
    throw FileError(
        impl_->loaded_direct.name,
        "the direct index of entry " + std::to_string(entry) + " is damaged (" + e.what() + ")");
  }
}

void Database::set_label(EntryId entry, std::string label) {
  std::unique_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::set_label: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  impl_->journal.record_label(entry, label);
  impl_->store_label(entry, std::move(label));
}

std::string Database::label(EntryId entry) const {
  std::shared_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  if (!impl_->is_live(entry))
    throw InvalidArgument("Database::label: " +
                          no_entry_message(entry, static_cast<EntryId>(impl_->alive.size())));
  return impl_->labels.empty() ? std::string() : impl_->labels[entry];
}

std::size_t Database::size() const {
  std::shared_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  return impl_->live_entries;
}

EntryId Database::next_entry_id() const {
  std::shared_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  return static_cast<EntryId>(impl_->alive.size());
}

void Database::clear() {
  std::unique_lock lock(impl_->mutex);
  impl_->throw_if_damaged();
  impl_->journal.record_clear();
  impl_->file_check.reset();  // stops it: nothing of the file is left
  impl_->file_check_merged = true;
  impl_->loaded_direct = {};
  std::vector<std::unique_ptr<detail::Segment>>().swap(impl_->segments);
  std::fill(impl_->tail_lists.begin(), impl_->tail_lists.end(), detail::TailList{});
  std::fill(impl_->first_block_logs.begin(), impl_->first_block_logs.end(), detail::kFirstBlockLog);
  impl_->arena.clear();
  impl_->tail_postings = 0;
  impl_->tail_dead_postings = 0;
  impl_->tail_first_entry = 0;
  std::vector<std::uint8_t>().swap(impl_->alive);
  std::vector<std::uint32_t>().swap(impl_->word_counts);
  std::vector<double>().swap(impl_->divisors);
  std::vector<detail::PackedFeatureVector>().swap(impl_->direct);
  std::vector<std::string>().swap(impl_->labels);
  impl_->live_entries = 0;
  impl_->values = {};
  impl_->forward.clear();
}

std::size_t Database::memory_usage() const {
  std::shared_lock lock(impl_->mutex);
  const Impl& impl = *impl_;
  std::size_t bytes = impl.segments.capacity() * sizeof(impl.segments[0]) +
                      impl.tail_lists.capacity() * sizeof(detail::TailList) +
                      impl.first_block_logs.capacity() + impl.alive.capacity() +
                      impl.word_counts.capacity() * sizeof(std::uint32_t) +
                      impl.divisors.capacity() * sizeof(double) +
                      impl.direct.capacity() * sizeof(detail::PackedFeatureVector) +
                      impl.loaded_direct.offsets.capacity() * sizeof(std::uint64_t) +
                      impl.labels.capacity() * sizeof(std::string);
  // A loaded database's rows and direct index are the file's pages, counted
  // too: what the index occupies in memory once read (see Database::load).
  for (const auto& segment : impl.segments)
    bytes += sizeof(*segment) + segment->offsets.capacity() * sizeof(std::uint32_t) +
             segment->bytes.size();
  if (!impl.loaded_direct.offsets.empty())
    bytes += static_cast<std::size_t>(impl.loaded_direct.offsets.back());
  bytes += impl.arena.memory_usage();
  if (impl.forward_built) bytes += impl.forward.memory_usage();
  bytes += impl.journal.memory_usage();
  for (const auto& features : impl.direct) bytes += features.memory_usage();
  for (const auto& label : impl.labels)
    if (label.capacity() > 15) bytes += label.capacity() + 1;  // beyond the small-string buffer
  return bytes;
}

const Vocabulary& Database::vocabulary() const noexcept {
  return impl_->vocabulary;
}
Scoring Database::scoring() const noexcept {
  return impl_->scoring;
}
const DatabaseOptions& Database::options() const noexcept {
  return impl_->options;
}

}  // namespace binbow
