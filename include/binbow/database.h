// An image database over a vocabulary: inverted index (word → entries and
// their weights) for fast similarity queries, and optionally a direct index
// (entry → FeatureVector) for finding correspondences between two images.
//
// Scores: a query touches only the entries that share at least one word with
// the query vector, and every result's score equals, to the last bit, what
// vocabulary().score(query, entry_bow) returns (the same terms, summed in the
// same order of increasing word id). "Best" is the highest score, except for
// Scoring::kKL, a divergence, where it is the lowest (as in DBoW2).
//
// Index layout: new entries go to a tail of growable lists, one per group
// of words (at most 65,536 groups, so that adding stays in cache); when the
// tail holds about two postings per vocabulary word it becomes a segment of
// compact rows by word (each posting the gap from the row's previous entry,
// 1 byte in common rows and 2 in rows with a gap of 256 or more, then its
// weight: a fixed stride per row, which queries read without a branch per
// posting), and every 8 segments of one size merge into one while it spans at
// most 65,536 entry ids (so that a query's sums for a segment stay in
// cache). add() is
// O(words of the image) amortised; a query costs O(postings of the query's
// words), plus one row lookup per query word and segment. A query thread
// scores one segment (or the tail) at a time, so it keeps 768 KiB of sums
// and counts, whatever the database's size; a query on several threads
// (QueryOptions::threads) hands the segments out between them.
//
// Removal: remove() marks the entry dead at once (it never appears in a
// result again); its postings are dropped when the tail becomes a segment,
// or when a segment's dead postings exceed a third of it (the segment is
// compacted in place), so remove() is O(1) amortised over the entries added.
//
// Concurrency: any number of threads may call the const methods (query,
// feature_vector, ...) at the same time; add, remove, clear and set_label need
// exclusive access. The class enforces this with an internal reader-writer
// lock, so mixing them from several threads is safe: a writer waits for the
// calls already running, and calls that arrive after it wait for the writer,
// so writers make progress under any query load.
// Moving or destroying a Database while another thread uses it is not.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "binbow/bow_vector.h"
#include "binbow/descriptors.h"
#include "binbow/types.h"
#include "binbow/vocabulary.h"

namespace binbow {

struct QueryResult {
  EntryId entry = 0;
  double score = 0;                // the vocabulary's score(query, entry)
  std::uint32_t shared_words = 0;  // words present in both vectors (whatever their values)

  friend bool operator==(const QueryResult& a, const QueryResult& b) {
    return a.entry == b.entry && a.score == b.score && a.shared_words == b.shared_words;
  }
};

// The largest DatabaseOptions::direct_index_levels_up: what a .bbdb file can
// record (deeper than any vocabulary: levels above the root mean the root).
inline constexpr unsigned kMaxDirectIndexLevelsUp = 255;

struct DatabaseOptions {
  // Keep each entry's FeatureVector (direct index) at `direct_index_levels_up`
  // levels above the leaves. DLoopDetector uses 2 with the paper's defaults.
  // [0, kMaxDirectIndexLevelsUp]
  bool direct_index = true;
  unsigned direct_index_levels_up = 4;
};

inline constexpr EntryId kAllEntries = std::numeric_limits<EntryId>::max();

// How a query finds its best entries. Either way every reported score (and
// shared_words) is exact: what vocabulary().score(query, entry) returns, to
// the last bit.
enum class QueryMode {
  // Reads every posting of the query's words: the best entries, always.
  kExact,
  // Reads the postings of the query's rarest words only (an eighth of the
  // exact query's postings, at least ~1M, the words that tell images apart,
  // heavy ones first), keeps the 1000 entries that score best on them as
  // candidates (QueryOptions tunes both numbers), then computes the exact
  // score of every candidate from a copy of its BoW vector. An entry can
  // only be missing, never ranked by a wrong score. The first fast query
  // makes that copy of every entry, compact: about 2 bytes per word (~2 KiB
  // per ORB-1000 image, 30% more memory_usage()) for vectors that
  // Vocabulary::transform made, whose weights it computes again from word
  // counts bit for bit, 6 bytes per word for others (over word ids); add,
  // remove and clear keep it up to date. Indexes where skipping words would
  // save fewer postings than the candidates hold words (under ~2M postings
  // per query) are read whole, as kExact does. Worth it when a query reads
  // millions of postings (large databases of images that share most words;
  // docs/benchmarks.md has the speed and agreement).
  kFast,
};

struct QueryOptions {
  QueryMode mode = QueryMode::kExact;
  // Threads one query may use (0: one per core); the index's parts are
  // shared between them, and the result does not depend on their number,
  // to the last bit. A database too small to gain from it (under ~4M
  // postings per thread) uses fewer. Servers answering many queries at
  // once get more from threads = 1 per query.
  unsigned threads = 0;
  // kFast only, like an approximate index's probe count: speed for agreement
  // with kExact. A query reads the postings of its rarest words, an eighth
  // of its postings but at least fast_min_postings (at least one word), and
  // its best candidates on them get their exact score: fast_candidates, or
  // more for a large database (and at least max_results), leaving out those
  // whose sum on the rare words is below 0.6 of the max_results-th best's,
  // unless the candidates cover every entry searched. A query whose other
  // words hold fewer postings than the candidates hold words reads every
  // posting, as kExact does. More of either finds more of the exact best,
  // slower (a candidate's rescoring costs ~2.5 µs for an ORB-1000 image).
  //
  // With more entries, more of them are near-copies of the query's best,
  // and more candidates are needed: fast_candidate_share of the entries
  // searched where that is more than fast_candidates, or by default (unset)
  // a share that grows with the entries searched, N / 125 * (N / 10^6)^0.3
  // candidates (1000 at 200,000, 3250 at 500,000, 8000 at 1,000,000). On
  // tuning queries of ORB-1000 images the candidates that kept the exact top
  // 10 for 99% of them grew about so, as N^1.3: 800-1000 at 200,000 (800
  // kept 98.99%, 1000 all), 2500-3000 at 500,000 (98.99%, 99.7%; 3249 all),
  // 6000-8000 at 1,000,000 (98.3%, 99.7%; docs/benchmarks.md). A share set
  // here applies as it is: fast_candidate_share = 1 makes every entry a
  // candidate. fast_min_postings = 0 leaves the eighth alone.
  std::size_t fast_candidates = 1000;
  std::optional<double> fast_candidate_share = std::nullopt;
  std::uint64_t fast_min_postings = std::uint64_t{1} << 20;

  // The candidates a fast query rescores at most when it searches
  // `entries` entries (fewer are rescored when some are far behind), as
  // set above: candidates_for(200'000) is 1000 with the defaults.
  std::size_t candidates_for(std::size_t entries) const;

  // Throws InvalidArgument for what query() refuses, with its message: an
  // unknown mode, fast_candidates = 0, a share outside [0, 1]. For callers
  // that check options before any work (the CLI, ShardedDatabase).
  void check() const;
};

// One writer at a time for a database file (docs/database-files.md): an
// advisory lock (flock) on "<path>.lock", a file made beside the database
// (links followed) and left there. Every save takes it for its duration,
// without waiting: a save while another writer holds it throws
// WriteConflict. A program that loads a database shared with other
// processes, changes it and saves it holds one from before load() until
// after the save, so that no other writer changes the file in between
// (binbow db add and db remove do); without it, a save that would
// overwrite a change made since the load throws WriteConflict too.
// Readers (load) take no lock: saves never show them a half-written file.
// Within a process the lock belongs to the thread that took it, which may
// take it again (its saves do); another thread waits like another process.
class DatabaseLock {
 public:
  // Waits up to `wait_seconds` (0: not at all) for the other writer to
  // finish. Throws WriteConflict naming `path` and the holder's process id
  // when it does not, FileError when the lock file cannot be made.
  explicit DatabaseLock(const std::string& path, double wait_seconds = 0);
  DatabaseLock(DatabaseLock&& other) noexcept;
  DatabaseLock(const DatabaseLock&) = delete;
  DatabaseLock& operator=(const DatabaseLock&) = delete;
  DatabaseLock& operator=(DatabaseLock&&) = delete;
  ~DatabaseLock();

  // "<path>.lock".
  static std::string lock_path(const std::string& path);

 private:
  std::string key_;
};

// How Database::load checks a file (docs/database-files.md).
enum class Verification {
  // load() checks the header, the section table and the small sections, and
  // lays the index out over the mapped file, then returns: the large
  // sections (the postings and the direct index) are checked by a thread of
  // their own (one to two seconds per GB), while the database already answers.
  // Until that check ends a query reads bytes not verified yet: safe (never
  // outside the file or the query's buffers), but a damaged file may give
  // wrong results meanwhile. Damage found makes every later call throw
  // FileError naming the file and the section. Calls that need the checked
  // postings (remove, save, serialize, the first fast query) wait for it.
  kBackground,
  // Everything is checked before load() returns, as deserialize() does:
  // the whole file is read once (one to two seconds per GB more to open).
  kBeforeReturn,
};

struct DatabaseLoadOptions {
  Verification verification = Verification::kBackground;
};

// What the header of a .bbdb file says (Database::inspect).
struct DatabaseFileInfo {
  std::uint32_t version = 0;
  std::size_t entries = 0;  // live entries
  EntryId next_entry_id = 0;
  bool direct_index = false;
  unsigned direct_index_levels_up = 0;
  bool vocabulary_included = false;
  std::uint32_t vocabulary_checksum = 0;
  std::string vocabulary_description;  // Vocabulary::description() at save time
};

// What the journal beside a .bbdb file holds (Database::inspect_journal).
struct DatabaseJournalInfo {
  bool present = false;     // a journal file exists beside the database
  bool superseded = false;  // a full save made it obsolete: load() ignores it
  std::uint64_t bytes = 0;
  std::size_t saves = 0;  // incremental saves it holds (its intact records)
  std::size_t added = 0, removed = 0, labels_set = 0, cleared = 0;  // changes in them
  // The database once the journal is replayed (the base's when none applies).
  std::size_t entries = 0;
  EntryId next_entry_id = 0;
  // After the last intact record: an append that never completed (the
  // process died during an incremental save), which load() drops.
  std::uint64_t torn_bytes = 0;
};

class Database {
 public:
  // An empty database. Throws InvalidArgument if the vocabulary is empty or
  // options.direct_index_levels_up > kMaxDirectIndexLevelsUp (such a
  // database could be saved but never loaded).
  explicit Database(Vocabulary vocabulary, DatabaseOptions options = {});
  // An empty database over word ids assigned elsewhere (an OnlineVocabulary's
  // words), with no vocabulary: BoW vectors may name any word id, and the
  // index grows its rows as larger ids arrive (doubling, so the re-layout is
  // amortised over the postings). Scores use `scoring`. Differences from a
  // database over a vocabulary: add(descriptors) throws InvalidArgument;
  // save() and serialize() record the scoring and the index's word-id
  // capacity instead of a vocabulary (include_vocabulary is ignored), and
  // load() without a vocabulary restores it (ids much sparser than the
  // postings, beyond 2^16 + 4 per byte of the file, are refused as
  // hostile); vocabulary() is empty; a query's words that no
  // entry has yet are simply not found; the direct index keeps the nodes as
  // given (the words themselves, for OnlineVocabulary::weigh). A word that
  // the caller stops using (a purged online word) keeps its postings, which
  // no later query names: they cost memory, never a score. Meant for dense
  // ids such as OnlineVocabulary's: rows cost 4 bytes per id up to the
  // largest one, in each segment of the index.
  static Database over_word_ids(Scoring scoring, DatabaseOptions options = {});
  Database(Database&&) noexcept;
  Database& operator=(Database&&) noexcept;
  ~Database();

  // Transforms the descriptors and adds the image. Returns its entry id: ids
  // are dense and increasing (0, 1, 2, ...), never reused after remove().
  // A non-empty `label` is set in the same step (see set_label), so no other
  // thread sees the entry without it. Throws InvalidArgument if the code
  // size differs from the vocabulary's.
  EntryId add(const DescriptorView& descriptors, std::string label = {});
  // Adds an image already transformed with this database's vocabulary. The
  // feature vector is kept only if the database has a direct index. Throws
  // InvalidArgument for a word or node id outside the vocabulary, or a
  // non-finite value; nothing is added then.
  EntryId add(const BowVector& bow, const FeatureVector& features = {}, std::string label = {});

  // The `max_results` entries most similar to `bow`, best first; ties are
  // ordered by increasing entry id. Only entries with id ≤ `max_entry_id` are
  // considered (inclusive; DBoW2's max_id excludes it: pass max_id − 1). Entries sharing no word
  // with the query are not returned, so an empty `bow` or `max_results` = 0 give an empty result.
  // Throws InvalidArgument for a word id outside the vocabulary.
  // The same as query(bow, max_results, max_entry_id, QueryOptions{}).
  std::vector<QueryResult> query(const BowVector& bow, std::size_t max_results,
                                 EntryId max_entry_id = kAllEntries) const;
  std::vector<QueryResult> query(const BowVector& bow, std::size_t max_results,
                                 EntryId max_entry_id, const QueryOptions& options) const;
  std::vector<QueryResult> query(const BowVector& bow, std::size_t max_results,
                                 const QueryOptions& options) const {
    return query(bow, max_results, kAllEntries, options);
  }

  // Removes an entry; throws InvalidArgument if it does not exist (never
  // added, or already removed).
  void remove(EntryId entry);
  bool contains(EntryId entry) const;
  // The direct index of an entry; throws InvalidArgument if the entry does
  // not exist or the database keeps no direct index.
  FeatureVector feature_vector(EntryId entry) const;

  // An optional name per entry (the CLI stores image file names), saved with
  // the database. label() is empty for entries without one; both throw
  // InvalidArgument if the entry does not exist.
  void set_label(EntryId entry, std::string label);
  std::string label(EntryId entry) const;

  std::size_t size() const;       // live entries
  EntryId next_entry_id() const;  // the id the next add() returns
  void clear();                   // removes every entry; ids restart at 0
  // Bytes of memory held by the index (posting lists, direct index,
  // per-entry state, labels, changes kept for the next save_incremental),
  // excluding the vocabulary. A loaded database's postings and direct index
  // are counted too, though they are the mapped file's pages (see load()).
  std::size_t memory_usage() const;

  const Vocabulary& vocabulary() const noexcept;  // empty over word ids
  Scoring scoring() const noexcept;
  const DatabaseOptions& options() const noexcept;

  // binbow's database format (.bbdb): magic, version, little-endian sections
  // with a CRC32C each; saved atomically (temporary file, then rename; missing
  // folders are made). With
  // `include_vocabulary`, the file is self-contained; otherwise it records the
  // vocabulary's checksum and load() must be given the same vocabulary.
  // save() writes format version 3 (the index as memory holds it: about 6 KB
  // per ORB-1000 image with its direct index); load() reads versions 1 to 3.
  void save(const std::string& path, bool include_vocabulary = true) const;
  //
  // save() is a full save: it also folds the journal of an earlier
  // save_incremental() into the new file and removes it, so that a crash at
  // any moment leaves the old or the new database (docs/database-files.md).
  //
  // An incremental save: appends what changed since the last save or load
  // of `path` (entries added, removed, labels set, clear) to the journal
  // beside it, journal_path(path), as one record flushed to disk
  // (fdatasync): it costs what changed, not the database. It is a full save
  // instead when the database was last saved to or loaded from another path
  // (or never), when the file at `path` is not the one it was saved to or
  // loaded from (another process replaced it), or when the journal would
  // grow past a quarter of the file (at least 1 MiB), which keeps loading
  // fast. A process killed during the append leaves the database as it was
  // before it. Between saves, a database tied to a file keeps a copy of its
  // changes (about their journal's size, counted in memory_usage(); past the
  // journal's limit it drops them and the next save is full).
  void save_incremental(const std::string& path, bool include_vocabulary = true) const;
  // The append of save_incremental() alone: true once the changes since the
  // last save or load of `path` are in its journal (also when there were
  // none); false, with nothing written, where save_incremental() would make
  // a full save instead. For a caller that must not see `path` rewritten in
  // place, such as a set of files committed together by a manifest, which
  // then saves the database whole under another name. Takes the writer lock
  // and refuses another writer's changes as every save does (DatabaseLock).
  bool append_journal(const std::string& path) const;
  // "<path>.journal": copy, move or remove it together with the .bbdb file.
  static std::string journal_path(const std::string& path);
  // Throws FileError naming the file and the problem (damaged file, a file
  // without vocabulary, or a vocabulary whose checksum does not match).
  // Loading replays the journal beside the file, if any: the database is
  // then exactly what a full save would have written (entry ids, scores,
  // labels). A journal that extends another save of the file is refused
  // (FileError naming it), a damaged record in it too, except at its end,
  // where it is an incremental save that never completed and is dropped.
  //
  // A version 3 file is memory-mapped, not copied: its postings and direct
  // index stay the file's pages (shared with the page cache; memory_usage()
  // counts them), so opening costs little per entry and nothing per
  // posting, and the first query answers at once. binbow's saves replace a
  // file by renaming a new one over it, which leaves the mapped one intact
  // (saving a loaded database to its own path is fine); a file truncated or
  // rewritten in place by another program while loaded is undefined
  // behaviour (the process may be killed by SIGBUS). Where the file cannot
  // be mapped it is read into memory. Changing a segment of the index
  // (compaction after remove) copies it into memory first.
  static Database load(const std::string& path, const DatabaseLoadOptions& options = {});
  static Database load(const std::string& path, Vocabulary vocabulary,
                       const DatabaseLoadOptions& options = {});
  // Waits until the background check of the file this database was loaded
  // from (Verification::kBackground) has ended. Throws FileError naming the
  // file and the damaged section if the file is not intact; returns at once
  // when there is nothing to wait for.
  void wait_until_verified() const;
  // The exact bytes save() writes, and their parsing; `name` is used in error
  // messages (FileError) in place of a path.
  std::vector<std::uint8_t> serialize(bool include_vocabulary = true) const;
  static Database deserialize(const std::uint8_t* data, std::size_t size, const std::string& name);
  static Database deserialize(const std::uint8_t* data, std::size_t size, const std::string& name,
                              Vocabulary vocabulary);
  // What the header of a .bbdb file says. With `verify` (the default), first
  // checks the whole file: everything load() checks when the file includes
  // its vocabulary (the index is loaded then dropped), every section's CRC
  // otherwise; without it only the header and the description are read.
  // Throws FileError.
  static DatabaseFileInfo inspect(const std::string& path, bool verify = true);
  // The journal beside the .bbdb file at `path`, its records checked.
  // Throws FileError for a damaged journal or one of another save.
  static DatabaseJournalInfo inspect_journal(const std::string& path);

 private:
  struct Impl;
  explicit Database(std::unique_ptr<Impl> impl);
  friend struct DatabaseLoading;
  // Applies the journal beside `path` to the database just read from the
  // base `base`, and ties the database to that file.
  void replay_journal(const std::string& path, const std::uint8_t* base, std::size_t base_size);
  std::unique_ptr<Impl> impl_;
};

}  // namespace binbow
