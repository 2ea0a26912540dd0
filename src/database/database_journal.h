// The journal of a .bbdb database: "<database>.journal", beside it. An
// incremental save appends what changed since the last save or load (entries
// added with their BoW and feature vectors and labels, entries removed,
// labels set, clear) as one record and flushes it with fdatasync: that is its
// commit. Loading replays the journal over the base file; a full save writes a
// new base and removes the journal. Layout, little-endian:
//   header (32 bytes): magic "BBDBJRNL", u32 version (2), u32 header size
//     (32), the base it extends (u64 file size, u32 checksum: see BaseId), u32
//     CRC32C of bytes 0..27
//   records, back to back: u64 payload length, u32 CRC32C of the payload,
//     u32 CRC32C of these 12 bytes continued over the base id (u64 size,
//     u32 checksum), so that a record is valid only in a journal of its
//     base; then the payload: u8 kind, then
//     kind 1 (changes): changes until the payload's end, each a u8 type:
//       1 add: entry id, label length, label bytes, word count, the words
//         as steps from the previous one (the first from 0), their weights
//         (f32 each), node count, the nodes as steps, per node its feature
//         count, then the feature indices
//       2 remove: entry id   3 set label: entry id, length, bytes   4 clear
//     (every integer but the weights is an unsigned LEB128 varint)
//     kind 2 (sealed): the base (u64 size, u32 checksum) that a full save
//       wrote with every change of this journal in it.
// docs/database-files.md describes the protocol and what a crash leaves.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include "binbow/bow_vector.h"
#include "binbow/database.h"
#include "binbow/types.h"

namespace binbow::detail {

inline constexpr std::size_t kJournalHeaderSize = 32;
inline constexpr std::size_t kJournalRecordHeaderSize = 16;

// Which base file a journal extends: the base's size and the CRC32C of its
// header and section table without their own CRCs (the table holds every
// section's CRC): a different save has a different id, unless the two saves
// hold the same bytes, over which the journal's changes replay alike.
struct BaseId {
  std::uint64_t size = 0;
  std::uint32_t checksum = 0;
  friend bool operator==(const BaseId& a, const BaseId& b) {
    return a.size == b.size && a.checksum == b.checksum;
  }
  friend bool operator!=(const BaseId& a, const BaseId& b) { return !(a == b); }
};

// The CRC32C a record header `head` (12 bytes: length, payload CRC) has in
// a journal of `base`.
std::uint32_t record_header_crc(const std::uint8_t* head, const BaseId& base);

// The id of a sectioned file image (false if too short to hold its header
// and table).
bool base_id_of(const std::uint8_t* data, std::size_t size, BaseId& id);
// The same, reading only the head of the file at `path` (false if it cannot
// be read or is no sectioned file).
bool read_base_id(const std::string& path, BaseId& id);

std::string journal_path_of(const std::string& database_path);

// The changes of one record, in order.
enum class Change : std::uint8_t { kAdd = 1, kRemove = 2, kLabel = 3, kClear = 4 };
struct JournalChange {
  Change type = Change::kClear;
  EntryId entry = 0;
  std::string label;
  BowVector bow;
  FeatureVector features;
};

// A journal's records as the file holds them, checked (header and record
// CRCs) but not decoded.
struct JournalScan {
  struct Record {
    std::size_t offset = 0;  // of its header in the file
    const std::uint8_t* payload = nullptr;
    std::size_t size = 0;
  };
  BaseId base;
  std::vector<Record> records;
  std::size_t valid_end = 0;   // the end of the last intact record
  std::size_t torn_bytes = 0;  // after it: an append that never completed
};

// Throws FileError naming `name` for a damaged header, or a damaged record
// followed by anything but zeros (an append that never completed may leave
// its prefix, then zeros: that tail is dropped and counted as torn).
JournalScan scan_journal(const std::uint8_t* data, std::size_t size, const std::string& name);
// Calls `apply` for each change of a record, decoded and checked (sorted
// words, finite weights, a valid FeatureVector); `sealed` gets the base a
// sealing record names. Throws FileError naming `name` and the record's
// offset; an exception from `apply` (InvalidArgument) is reported so too.
void read_record(const JournalScan::Record& record, const std::string& name,
                 const std::function<void(JournalChange&)>& apply,
                 const std::function<void(const BaseId&)>& sealed);

// Replays a journal (scanned) over `database`, just read from the base
// `base`; `files_size` is the base's and the journal's bytes, which bound
// the word ids of a database over word ids. A journal that a full save of
// this base superseded is not applied; one of another base is refused
// (FileError naming `name`).
struct JournalReplay {
  std::uint64_t records = 0;  // of changes, applied
  bool sealed = false;        // a sealing record follows the base's changes
  bool superseded = false;
};
JournalReplay replay_journal(Database& database, const JournalScan& scan, const BaseId& base,
                             const std::string& name, std::uint64_t files_size);

// What a database remembers of the file it was last saved to or loaded
// from, and the changes made since (recorded only while it is tied to a
// file). The Database's lock protects it: changes are recorded under the
// exclusive lock, saves run under the shared lock and `mutex`.
class DatabaseJournal {
 public:
  void record_add(EntryId entry, const BowVector& bow, const FeatureVector& features,
                  const std::string& label) noexcept;
  void record_remove(EntryId entry) noexcept;
  void record_label(EntryId entry, const std::string& label) noexcept;
  void record_clear() noexcept;
  std::size_t memory_usage() const noexcept { return pending_.capacity(); }

  // Saves take `path` with links followed (resolve_output_path) and run
  // under the database's DatabaseLock; both throw WriteConflict when
  // another writer saved `path` since this database was tied to it.
  //
  // A full save: `write` writes the base into a temporary file; then the
  // journal beside `path`, if it extends the base now there, is sealed
  // (truncated to its last intact record, then a sealing record naming the
  // new base is appended and flushed), the temporary replaces the base, and
  // the journal is removed. A journal that extends no base there is removed
  // first (no load would replay it).
  void save_base(const std::string& path, const std::function<void(std::FILE*)>& write);
  // Appends the changes since the last save as one record (or does nothing
  // when there are none), after removing what dead saves left beside
  // `path`; false, with nothing written, when a full save is needed instead
  // (see Database::save_incremental).
  bool append(const std::string& path);
  // Ties the database to `path`, whose base is `base` and whose journal
  // holds `records` intact records ending at `journal_end` (0: no journal);
  // `sealed`: the journal holds a sealing record, so that the next save
  // must be full.
  void attach(const std::string& path, const BaseId& base, std::uint64_t journal_end,
              std::uint64_t records, bool sealed);

  std::mutex mutex;  // serialises saves

 private:
  void start_change(Change type) noexcept;
  void give_up() noexcept;
  // Whether another writer saved `path` since this database was tied to
  // it: its base is another, or its journal has a record past this one's.
  bool changed_on_disk(const std::string& path) const;
  // Throws WriteConflict when the database is tied to `path` and another
  // writer saved there since.
  void refuse_if_changed(const std::string& path) const;
  // Seals the journal of `path` for the new base `id` (see save_base); true
  // if there is one to remove once the base is replaced.
  bool seal(const std::string& path, const std::string& key, const BaseId& id);

  std::string key_;  // the absolute path tied to; empty: none
  BaseId base_;
  std::uint64_t journal_end_ = 0;
  std::uint64_t records_ = 0;
  bool needs_full_save_ = false;
  std::vector<std::uint8_t> pending_;  // a changes payload, or empty
};

// A journal may grow to this many bytes for a base of `base_size` bytes;
// a larger one is compacted into a new base by the next incremental save.
std::uint64_t journal_limit(std::uint64_t base_size);

}  // namespace binbow::detail
