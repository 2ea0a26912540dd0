// An image database over a vocabulary: inverted index (word → entries and
// their weights) for fast similarity queries, and optionally a direct index
// (entry → FeatureVector) for finding correspondences between two images.
//
// Concurrency: any number of threads may call the const methods (query,
// feature_vector, ...) at the same time; add, remove, clear and load need
// exclusive access. The class enforces this with an internal reader-writer
// lock, so mixing them from several threads is safe, writers simply wait.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "binbow/bow_vector.h"
#include "binbow/descriptors.h"
#include "binbow/types.h"
#include "binbow/vocabulary.h"

namespace binbow {

struct QueryResult {
  EntryId entry = 0;
  double score = 0;                 // the vocabulary's score(query, entry)
  std::uint32_t shared_words = 0;   // words present in both vectors
};

struct DatabaseOptions {
  // Keep each entry's FeatureVector (direct index) at `direct_index_levels_up`
  // levels above the leaves. DLoopDetector uses 2 with the paper's defaults.
  bool direct_index = true;
  unsigned direct_index_levels_up = 4;
};

inline constexpr EntryId kAllEntries = std::numeric_limits<EntryId>::max();

class Database {
 public:
  explicit Database(Vocabulary vocabulary, DatabaseOptions options = {});
  Database(Database&&) noexcept;
  Database& operator=(Database&&) noexcept;
  ~Database();

  // Transforms the descriptors and adds the image. Returns its entry id: ids
  // are dense and increasing (0, 1, 2, ...), never reused after remove().
  EntryId add(const DescriptorView& descriptors);
  // Adds an image already transformed with this database's vocabulary.
  EntryId add(const BowVector& bow, const FeatureVector& features = {});

  // The `max_results` entries most similar to `bow`, best first; ties are
  // ordered by increasing entry id. Only entries with id ≤ `max_entry_id` are
  // considered. Entries sharing no word with the query are not returned.
  std::vector<QueryResult> query(const BowVector& bow, std::size_t max_results,
                                 EntryId max_entry_id = kAllEntries) const;

  // Removes an entry; throws InvalidArgument if it does not exist.
  void remove(EntryId entry);
  bool contains(EntryId entry) const;
  // The direct index of an entry; throws InvalidArgument if the entry does
  // not exist or the database keeps no direct index.
  FeatureVector feature_vector(EntryId entry) const;

  std::size_t size() const;      // live entries
  EntryId next_entry_id() const; // the id the next add() returns
  void clear();                  // removes every entry; ids restart at 0

  const Vocabulary& vocabulary() const noexcept;
  const DatabaseOptions& options() const noexcept;

  // binbow's database format (.bbdb). Atomic save. With `include_vocabulary`,
  // the file is self-contained; otherwise it records the vocabulary's checksum
  // and load() must be given the same vocabulary.
  void save(const std::string& path, bool include_vocabulary = true) const;
  // Throws FileError (damaged file, or a vocabulary that does not match).
  static Database load(const std::string& path);
  static Database load(const std::string& path, Vocabulary vocabulary);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace binbow
