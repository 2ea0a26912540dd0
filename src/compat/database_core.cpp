// TemplatedDatabase's implementation over binbow::Database.
#include <atomic>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "binbow/database.h"
#include "binbow/error.h"
#include "compat/core_impl.h"

namespace DBoW2 {
namespace binbow_detail {

namespace {

// DBoW2's CHI_SQUARE and BHATTACHARYYA queries drop entries sharing fewer
// words with the query than this (its MIN_COMMON_WORDS).
constexpr std::uint32_t kMinCommonWords = 5;

// select_vins_query_rule()'s choice: set by static initialisers, read by
// queries on any thread.
std::atomic<bool> vins_query_rule_selected{false};

binbow::BowVector to_binbow(const BowVector& v) {
  std::vector<binbow::BowEntry> entries;
  entries.reserve(v.size());
  for (const auto& entry : v) entries.push_back({entry.first, static_cast<float>(entry.second)});
  return binbow::BowVector(std::move(entries));
}

binbow::FeatureVector to_binbow(const FeatureVector& fv) {
  std::vector<binbow::NodeId> nodes;
  std::vector<std::uint32_t> offsets(1, 0);
  std::vector<std::uint32_t> features;
  for (const auto& node : fv) {
    nodes.push_back(node.first);
    features.insert(features.end(), node.second.begin(), node.second.end());
    offsets.push_back(static_cast<std::uint32_t>(features.size()));
  }
  return binbow::FeatureVector::from_arrays(std::move(nodes), std::move(offsets),
                                            std::move(features));
}

FeatureVector from_binbow(const binbow::FeatureVector& fv) {
  FeatureVector out;
  for (std::size_t i = 0; i < fv.size(); ++i) {
    const auto features = fv.features(i);
    out.insert(out.end(),
               FeatureVector::value_type(
                   fv.node(i), std::vector<unsigned int>(features.begin(), features.end())));
  }
  return out;
}

// Ids outside the vocabulary are std::out_of_range throughout the DBoW2
// layer (docs/dbow2-compat.md), as TemplatedVocabulary's getters have them;
// binbow's database would report them as InvalidArgument.
void check_words(const BowVector& v, const binbow::Vocabulary& vocabulary) {
  if (!v.empty() && v.rbegin()->first >= vocabulary.word_count())
    throw std::out_of_range("word " + std::to_string(v.rbegin()->first) +
                            " does not exist (the vocabulary has " +
                            std::to_string(vocabulary.word_count()) + " words)");
}

void check_nodes(const FeatureVector& fv, const binbow::Vocabulary& vocabulary) {
  if (!fv.empty() && fv.rbegin()->first >= vocabulary.node_count())
    throw std::out_of_range("node " + std::to_string(fv.rbegin()->first) +
                            " does not exist (the vocabulary has " +
                            std::to_string(vocabulary.node_count()) + " nodes)");
}

}  // namespace

struct DatabaseCore::Impl {
  bool use_di = true;
  int di_levels = 0;
  ScoringType scoring = L1_NORM;
  // VINS's query rule: -1 until set_vins_query_rule(), then 0 or 1.
  int vins_query_rule = -1;
  std::unique_ptr<binbow::Database> database;  // null until a non-empty vocabulary is set
  // retrieveFeatures() returns references: the entries' converted feature
  // vectors live here until the entry goes.
  mutable std::map<EntryId, FeatureVector> features;

  binbow::Database& require_database() const {
    if (!database) throw std::logic_error("DBoW2::TemplatedDatabase: the vocabulary is empty");
    return *database;
  }
};

DatabaseCore::DatabaseCore(bool use_di, int di_levels) : impl_(new Impl) {
  if (di_levels < 0)
    throw std::invalid_argument("di_levels must be at least 0, not " + std::to_string(di_levels));
  impl_->use_di = use_di;
  impl_->di_levels = di_levels;
}

DatabaseCore::DatabaseCore(const DatabaseCore& other) : impl_(new Impl) {
  *this = other;
}

DatabaseCore& DatabaseCore::operator=(const DatabaseCore& other) {
  if (this == &other) return *this;
  std::unique_ptr<Impl> copy(new Impl);
  copy->use_di = other.impl_->use_di;
  copy->di_levels = other.impl_->di_levels;
  copy->scoring = other.impl_->scoring;
  copy->vins_query_rule = other.impl_->vins_query_rule;
  if (other.impl_->database) {
    const binbow::Database& source = *other.impl_->database;
    const std::vector<std::uint8_t> bytes = source.serialize(false);
    copy->database.reset(new binbow::Database(binbow::Database::deserialize(
        bytes.data(), bytes.size(), "database copy", source.vocabulary())));
  }
  impl_ = std::move(copy);
  return *this;
}

DatabaseCore::~DatabaseCore() = default;

void DatabaseCore::set_vocabulary(const VocabularyCore& vocabulary, bool use_di, int di_levels) {
  if (di_levels < 0)
    throw std::invalid_argument("di_levels must be at least 0, not " + std::to_string(di_levels));
  std::unique_ptr<binbow::Database> database;
  const binbow::Vocabulary current = vocabulary.impl_->current();
  if (!current.empty()) {
    binbow::DatabaseOptions options;
    options.direct_index = use_di;
    options.direct_index_levels_up = static_cast<unsigned>(di_levels);
    try {
      database.reset(new binbow::Database(current, options));
    } catch (const binbow::InvalidArgument& e) {
      throw std::invalid_argument(e.what());
    }
  }
  impl_->database = std::move(database);
  impl_->use_di = use_di;
  impl_->di_levels = di_levels;
  impl_->scoring = vocabulary.scoring();
  impl_->features.clear();
}

bool DatabaseCore::using_direct_index() const {
  return impl_->use_di;
}
int DatabaseCore::direct_index_levels() const {
  return impl_->di_levels;
}

EntryId DatabaseCore::add(const BowVector& v, const FeatureVector& fv) {
  binbow::Database& database = impl_->require_database();
  check_words(v, database.vocabulary());
  if (impl_->use_di) check_nodes(fv, database.vocabulary());
  return database.add(to_binbow(v), impl_->use_di ? to_binbow(fv) : binbow::FeatureVector());
}

void DatabaseCore::erase(EntryId id) {
  impl_->require_database().remove(id);
  impl_->features.erase(id);
}

void DatabaseCore::clear() {
  if (impl_->database) impl_->database->clear();
  impl_->features.clear();
}

unsigned int DatabaseCore::size() const {
  return impl_->database ? impl_->database->next_entry_id() : 0;
}

void DatabaseCore::query(const BowVector& v, QueryResults& ret, int max_results, int max_id) const {
  ret.clear();
  if (!impl_->database) return;
  const binbow::Database& database = *impl_->database;
  check_words(v, database.vocabulary());
  const ScoringType scoring = impl_->scoring;
  const EntryId entries = database.next_entry_id();
  // VINS's fork (its queryL1) also scores the newest entry when max_id
  // leaves it out: the entries it skips are then those from max_id (or 0)
  // up to the newest.
  const bool newest_too = vins_query_rule() && scoring == L1_NORM && max_id != -1 && entries > 0 &&
                          static_cast<long long>(entries) - 1 >= max_id;
  const EntryId newest = entries - 1;
  const EntryId first_skipped = max_id > 0 ? static_cast<EntryId>(max_id) : 0;
  if (max_id != -1 && max_id <= 0 && !newest_too) return;
  const bool needs_common_words = scoring == CHI_SQUARE || scoring == BHATTACHARYYA;
  // The common-words rule is applied after the query, so those queries ask
  // for every candidate before keeping the best max_results; the newest
  // entry's rule asks for as many more as it skips.
  std::size_t wanted = max_results > 0 && !needs_common_words
                           ? static_cast<std::size_t>(max_results)
                           : static_cast<std::size_t>(entries);
  if (newest_too) wanted += newest - first_skipped;
  const binbow::EntryId last =
      max_id == -1 || newest_too ? binbow::kAllEntries : static_cast<EntryId>(max_id - 1);
  for (const binbow::QueryResult& found : database.query(to_binbow(v), wanted, last)) {
    if (newest_too && found.entry >= first_skipped && found.entry != newest) continue;
    if (needs_common_words && found.shared_words < kMinCommonWords) continue;
    Result result(found.entry, found.score);
    result.nWords = static_cast<int>(found.shared_words);
    if (scoring == CHI_SQUARE) result.chiScore = found.score;
    if (scoring == BHATTACHARYYA) result.bhatScore = found.score;
    ret.push_back(result);
    if (max_results > 0 && ret.size() == static_cast<std::size_t>(max_results)) break;
  }
}

void DatabaseCore::set_vins_query_rule(bool on) {
  impl_->vins_query_rule = on ? 1 : 0;
}

bool DatabaseCore::vins_query_rule() const {
  return impl_->vins_query_rule == -1 ? vins_query_rule_selected.load()
                                      : impl_->vins_query_rule == 1;
}

bool select_vins_query_rule() {
  vins_query_rule_selected.store(true);
  return true;
}

const FeatureVector& DatabaseCore::features(EntryId id) const {
  if (!impl_->use_di)
    throw std::runtime_error("DBoW2::TemplatedDatabase: the database keeps no direct index");
  auto found = impl_->features.find(id);
  if (found == impl_->features.end())
    found =
        impl_->features
            .insert(std::make_pair(id, from_binbow(impl_->require_database().feature_vector(id))))
            .first;
  return found->second;
}

void DatabaseCore::save(const std::string& filename) const {
  try {
    impl_->require_database().save(filename, true);
  } catch (const binbow::Error&) {
    rethrow_naming(filename);
  }
}

void DatabaseCore::load(const std::string& filename, VocabularyCore& vocabulary) {
  try {
    // DBoW2's load either fails or leaves a usable database: the whole file
    // is checked before it returns, rather than in the background, where
    // damage would surface as an exception from a later query, add or erase.
    binbow::DatabaseLoadOptions options;
    options.verification = binbow::Verification::kBeforeReturn;
    std::unique_ptr<binbow::Database> database(
        new binbow::Database(binbow::Database::load(filename, options)));
    VocabularyCore loaded(10, 5, TF_IDF, L1_NORM);
    loaded.impl_->assign(database->vocabulary());
    loaded.impl_->scoring = static_cast<ScoringType>(database->scoring());
    vocabulary = loaded;
    impl_->use_di = database->options().direct_index;
    impl_->di_levels = static_cast<int>(database->options().direct_index_levels_up);
    impl_->scoring = loaded.scoring();
    impl_->database = std::move(database);
    impl_->features.clear();
  } catch (const binbow::Error&) {
    rethrow_naming(filename);
  }
}

}  // namespace binbow_detail
}  // namespace DBoW2
