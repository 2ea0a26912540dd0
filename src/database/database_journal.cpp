#include "database/database_journal.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <mutex>
#include <shared_mutex>
#include <utility>

#include "binbow/database.h"
#include "binbow/error.h"
#include "core/crc32c.h"
#include "core/file_io.h"
#include "core/little_endian.h"
#include "core/output_path.h"
#include "core/sectioned_file.h"
#include "core/warnings.h"
#include "database/database_impl.h"
#include "database/database_lock.h"

namespace binbow {
namespace detail {

namespace {

constexpr char kJournalMagic[8] = {'B', 'B', 'D', 'B', 'J', 'R', 'N', 'L'};
constexpr std::uint32_t kJournalVersion = 2;
constexpr std::uint8_t kChangesRecord = 1;
constexpr std::uint8_t kSealedRecord = 2;
constexpr std::size_t kSealingRecordSize = kJournalRecordHeaderSize + 13;
// A sectioned file's header says how many sections its table has; binbow's
// formats have a dozen, so more than this is no base.
constexpr std::uint32_t kMaxSections = 1024;

std::string errno_text() {
  return std::strerror(errno);
}

// The id of a sectioned file of `size` bytes whose first bytes `read`
// copies (false if it cannot).
template <class Read>
bool base_id(std::uint64_t size, const Read& read, BaseId& id) {
  std::uint8_t header[kSectionedHeaderSize];
  if (size < kSectionedHeaderSize || !read(header, kSectionedHeaderSize)) return false;
  const auto count = load_le<std::uint32_t>(header + 48);
  if (load_le<std::uint32_t>(header + 12) != kSectionedHeaderSize || count > kMaxSections)
    return false;
  const std::size_t head_size = kSectionedHeaderSize + count * kSectionEntrySize + 4;
  if (size < head_size) return false;
  std::vector<std::uint8_t> head(head_size);
  if (!read(head.data(), head_size)) return false;
  // The header and the table without their own CRCs: a block followed by
  // its CRC32C has the same CRC whatever it holds. The table holds every
  // section's CRC, so the id follows the whole content.
  id.size = size;
  id.checksum = crc32c(head.data(), kSectionedHeaderSize - 4);
  id.checksum = crc32c(head.data() + kSectionedHeaderSize, count * kSectionEntrySize, id.checksum);
  return true;
}

bool descriptor_base_id(int fd, BaseId& id) {
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return false;
  return base_id(
      static_cast<std::uint64_t>(st.st_size),
      [fd](std::uint8_t* out, std::size_t n) {
        return ::pread(fd, out, n, 0) == static_cast<ssize_t>(n);
      },
      id);
}

void put_varint(std::vector<std::uint8_t>& out, std::uint64_t value) {
  while (value >= 0x80) {
    out.push_back(static_cast<std::uint8_t>(value | 0x80));
    value >>= 7;
  }
  out.push_back(static_cast<std::uint8_t>(value));
}

void put_bytes(std::vector<std::uint8_t>& out, const void* data, std::size_t size) {
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  out.insert(out.end(), bytes, bytes + size);
}

std::vector<std::uint8_t> journal_header(const BaseId& base) {
  std::vector<std::uint8_t> header(kJournalHeaderSize, 0);
  std::memcpy(header.data(), kJournalMagic, 8);
  store_le<std::uint32_t>(header.data() + 8, kJournalVersion);
  store_le<std::uint32_t>(header.data() + 12, kJournalHeaderSize);
  store_le<std::uint64_t>(header.data() + 16, base.size);
  store_le<std::uint32_t>(header.data() + 24, base.checksum);
  store_le<std::uint32_t>(header.data() + 28, crc32c(header.data(), 28));
  return header;
}

std::vector<std::uint8_t> framed(const std::vector<std::uint8_t>& payload, const BaseId& base) {
  std::vector<std::uint8_t> record(kJournalRecordHeaderSize);
  store_le<std::uint64_t>(record.data(), payload.size());
  store_le<std::uint32_t>(record.data() + 8, crc32c(payload.data(), payload.size()));
  store_le<std::uint32_t>(record.data() + 12, record_header_crc(record.data(), base));
  put_bytes(record, payload.data(), payload.size());
  return record;
}

// A record of the journal of `base` naming `sealed`, the new base.
std::vector<std::uint8_t> sealing_record(const BaseId& base, const BaseId& sealed) {
  std::vector<std::uint8_t> payload{kSealedRecord};
  put_le<std::uint64_t>(payload, sealed.size);
  put_le<std::uint32_t>(payload, sealed.checksum);
  return framed(payload, base);
}

std::string hex(std::uint32_t value) {
  char text[16];
  std::snprintf(text, sizeof text, "%08x", value);
  return text;
}

std::string describe(const BaseId& base) {
  return std::to_string(base.size) + " bytes, checksum " + hex(base.checksum);
}

bool all_zero(const std::uint8_t* begin, const std::uint8_t* end) {
  return std::all_of(begin, end, [](std::uint8_t b) { return b == 0; });
}

// Reads one record's payload, failing with the record's offset.
class PayloadReader {
 public:
  PayloadReader(const JournalScan::Record& record, const std::string& name)
      : at_(record.payload), end_(record.payload + record.size), record_(record), name_(name) {}

  [[noreturn]] void fail(const std::string& problem) const {
    throw FileError(name_, "record at offset " + std::to_string(record_.offset) + ": " + problem);
  }
  bool done() const { return at_ == end_; }
  std::size_t left() const { return static_cast<std::size_t>(end_ - at_); }
  std::uint8_t byte() {
    if (at_ == end_) fail("cut short");
    return *at_++;
  }
  std::uint64_t varint(std::uint64_t max, const char* what) {
    std::uint64_t value = 0;
    for (unsigned shift = 0;; shift += 7) {
      if (at_ == end_) fail(std::string("cut short in ") + what);
      const std::uint8_t b = *at_++;
      if (shift == 63 && b > 1) fail(std::string(what) + " overflows");
      value |= std::uint64_t{b & 0x7Fu} << shift;
      if ((b & 0x80) == 0) break;
      if (shift == 63) fail(std::string(what) + " overflows");
    }
    if (value > max) fail(std::string(what) + " " + std::to_string(value) + " is out of range");
    return value;
  }
  // A count of items of at least `item_bytes` bytes each that must fit in
  // what is left, so that nothing is allocated beyond the file's size.
  std::size_t count(std::size_t item_bytes, const char* what) {
    const std::uint64_t n = varint(std::numeric_limits<std::uint32_t>::max(), what);
    if (n > left() / item_bytes)
      fail(std::string(what) + " " + std::to_string(n) + " runs past the record");
    return static_cast<std::size_t>(n);
  }
  const std::uint8_t* bytes(std::size_t n) {
    if (n > left()) fail("cut short");
    const std::uint8_t* at = at_;
    at_ += n;
    return at;
  }

 private:
  const std::uint8_t* at_;
  const std::uint8_t* end_;
  const JournalScan::Record& record_;
  const std::string& name_;
};

constexpr std::uint64_t kMaxU32 = std::numeric_limits<std::uint32_t>::max();

// Strictly increasing ids stored as steps; false if one overflows 32 bits.
template <class T>
std::vector<T> read_steps(PayloadReader& in, std::size_t n, const char* what) {
  std::vector<T> ids(n);
  std::uint64_t id = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t step = in.varint(kMaxU32, what);
    if (i > 0 && step == 0) in.fail(std::string(what) + "s are not in increasing order");
    id += step;
    if (id > kMaxU32) in.fail(std::string(what) + " beyond 32 bits");
    ids[i] = static_cast<T>(id);
  }
  return ids;
}

void read_add(PayloadReader& in, JournalChange& change) {
  change.entry = static_cast<EntryId>(in.varint(kMaxU32, "entry id"));
  const std::size_t label_size = in.count(1, "label length");
  const std::uint8_t* label = in.bytes(label_size);
  change.label.assign(reinterpret_cast<const char*>(label), label_size);
  const std::size_t words = in.count(5, "word count");
  const std::vector<WordId> ids = read_steps<WordId>(in, words, "word");
  const std::uint8_t* weights = in.bytes(words * 4);
  std::vector<BowEntry> entries(words);
  for (std::size_t i = 0; i < words; ++i) {
    entries[i] = {ids[i], load_le<float>(weights + 4 * i)};
    if (!std::isfinite(entries[i].value))
      in.fail("the weight of word " + std::to_string(ids[i]) + " is not finite");
  }
  change.bow = BowVector(std::move(entries));
  const std::size_t nodes = in.count(2, "node count");
  std::vector<NodeId> node_ids = read_steps<NodeId>(in, nodes, "node");
  std::vector<std::uint32_t> offsets(nodes + 1, 0);
  for (std::size_t i = 0; i < nodes; ++i) {
    const std::uint64_t n = in.varint(kMaxU32, "feature count");
    if (n > in.left() || offsets[i] + n > kMaxU32) in.fail("feature count runs past the record");
    offsets[i + 1] = static_cast<std::uint32_t>(offsets[i] + n);
  }
  if (offsets[nodes] > in.left()) in.fail("feature indices run past the record");
  std::vector<std::uint32_t> features(offsets[nodes]);
  for (std::uint32_t& feature : features)
    feature = static_cast<std::uint32_t>(in.varint(kMaxU32, "feature index"));
  try {
    change.features =
        FeatureVector::from_arrays(std::move(node_ids), std::move(offsets), std::move(features));
  } catch (const InvalidArgument& e) {
    in.fail(std::string("inconsistent feature vector: ") + e.what());
  }
}

void sync_directory_of(const std::string& path) {
  const std::string parent = std::filesystem::path(path).parent_path().string();
  const int fd = ::open(parent.empty() ? "." : parent.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw FileError(path, "cannot open its directory to flush it: " + errno_text());
  const bool synced = ::fsync(fd) == 0 || errno == EINVAL;
  const std::string why = errno_text();
  ::close(fd);
  if (!synced) throw FileError(path, "cannot flush its directory to disk: " + why);
}

// Removes the file at `path` for good (missing already is fine).
void remove_durably(const std::string& path) {
  if (::unlink(path.c_str()) != 0) {
    if (errno == ENOENT) return;
    throw FileError(path, "cannot remove: " + errno_text());
  }
  sync_directory_of(path);
}

// The journal open for writing at `end`, its header checked against
// `header`: invalid if it is missing or not the expected journal.
class OpenJournal {
 public:
  OpenJournal(const std::string& path, const std::vector<std::uint8_t>& header, std::uint64_t end)
      : path_(path) {
    fd_ = ::open(path.c_str(), O_RDWR | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
    if (fd_ < 0) return;
    struct stat st {};
    std::vector<std::uint8_t> found(header.size());
    if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode) ||
        static_cast<std::uint64_t>(st.st_size) < end ||
        ::pread(fd_, found.data(), found.size(), 0) != static_cast<ssize_t>(found.size()) ||
        found != header) {
      ::close(fd_);
      fd_ = -1;
    }
  }
  OpenJournal(const OpenJournal&) = delete;
  OpenJournal& operator=(const OpenJournal&) = delete;
  ~OpenJournal() {
    if (fd_ >= 0) ::close(fd_);
  }
  bool valid() const { return fd_ >= 0; }

  // Writes `bytes` at `end` (cutting what follows) and flushes them to disk:
  // the commit. On failure the file is cut back to `end` and FileError thrown.
  void append(std::uint64_t end, const std::vector<std::uint8_t>& bytes) {
    const auto offset = static_cast<off_t>(end);
    bool written = ::ftruncate(fd_, offset) == 0;
    for (std::size_t done = 0; written && done < bytes.size();) {
      const ssize_t n = ::pwrite(fd_, bytes.data() + done, bytes.size() - done,
                                 offset + static_cast<off_t>(done));
      if (n < 0 && errno == EINTR) continue;
      written = n > 0;
      if (written) done += static_cast<std::size_t>(n);
    }
    if (written && ::fdatasync(fd_) == 0) return;
    const std::string why = errno_text();
    (void)::ftruncate(fd_, offset);
    throw FileError(path_, "cannot append to the journal: " + why);
  }

 private:
  std::string path_;
  int fd_ = -1;
};

std::string key_of(const std::string& path) {
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::absolute(path, error);
  return error ? path : absolute.lexically_normal().string();
}

}  // namespace

std::uint32_t record_header_crc(const std::uint8_t* head, const BaseId& base) {
  std::uint8_t id[12];
  store_le<std::uint64_t>(id, base.size);
  store_le<std::uint32_t>(id + 8, base.checksum);
  return crc32c(id, sizeof id, crc32c(head, 12));
}

bool base_id_of(const std::uint8_t* data, std::size_t size, BaseId& id) {
  return base_id(
      size,
      [data](std::uint8_t* out, std::size_t n) {
        std::memcpy(out, data, n);
        return true;
      },
      id);
}

bool read_base_id(const std::string& path, BaseId& id) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return false;
  const bool found = descriptor_base_id(fd, id);
  ::close(fd);
  return found;
}

std::string journal_path_of(const std::string& database_path) {
  return database_path + ".journal";
}

std::uint64_t journal_limit(std::uint64_t base_size) {
  return std::max<std::uint64_t>(base_size / 4, std::uint64_t{1} << 20);
}

JournalScan scan_journal(const std::uint8_t* data, std::size_t size, const std::string& name) {
  if (size < kJournalHeaderSize)
    throw FileError(name, "truncated: " + std::to_string(size) + " bytes, shorter than the " +
                              std::to_string(kJournalHeaderSize) +
                              "-byte header of a database journal");
  if (std::memcmp(data, kJournalMagic, 8) != 0)
    throw FileError(name, "not a binbow database journal: wrong magic bytes");
  const auto version = load_le<std::uint32_t>(data + 8);
  if (version != kJournalVersion)
    throw FileError(name, "unsupported journal version " + std::to_string(version) +
                              " (this binbow reads version 2)" +
                              (version < kJournalVersion
                                   ? ": written by a development build of binbow before 0.2.0, "
                                     "whose journals could not tell their base from another "
                                     "save of the same size; compact it with that binbow "
                                     "(binbow db add --compact, or Database::save), or remove it"
                                   : ": written by a newer binbow?"));
  if (load_le<std::uint32_t>(data + 28) != crc32c(data, 28))
    throw FileError(name, "header checksum mismatch: the journal is corrupted");
  if (load_le<std::uint32_t>(data + 12) != kJournalHeaderSize)
    throw FileError(name, "unexpected journal header size");
  JournalScan scan;
  scan.base.size = load_le<std::uint64_t>(data + 16);
  scan.base.checksum = load_le<std::uint32_t>(data + 24);
  // Saves never let a journal grow past its limit (then a sealing record);
  // a longer one, whatever its tail holds, is damage, refused before its
  // bytes are read.
  const std::uint64_t most = journal_limit(scan.base.size) + kSealingRecordSize;
  if (size > most)
    throw FileError(name, "the journal is " + std::to_string(size) + " bytes, more than the " +
                              std::to_string(most) + " a journal of its " +
                              std::to_string(scan.base.size) +
                              "-byte base can hold: it is damaged (remove it to load the "
                              "database as its last full save, or restore both from a backup)");
  std::size_t at = kJournalHeaderSize;
  const auto torn_from = [&](std::size_t offset) {
    scan.valid_end = offset;
    scan.torn_bytes = size - offset;
    return scan;
  };
  while (at < size) {
    // Appends write in order and only the last may be cut short: a damaged
    // record is torn if nothing but zeros follows where it went wrong.
    if (size - at < kJournalRecordHeaderSize) return torn_from(at);
    const std::uint8_t* head = data + at;
    if (load_le<std::uint32_t>(head + 12) != record_header_crc(head, scan.base)) {
      if (all_zero(head + kJournalRecordHeaderSize, data + size)) return torn_from(at);
      throw FileError(name, "damaged record header at offset " + std::to_string(at));
    }
    const auto length = load_le<std::uint64_t>(head);
    const std::size_t body = at + kJournalRecordHeaderSize;
    if (length > size - body) return torn_from(at);
    const std::uint8_t* payload = data + body;
    const std::size_t end = body + static_cast<std::size_t>(length);
    if (load_le<std::uint32_t>(head + 8) != crc32c(payload, static_cast<std::size_t>(length))) {
      if (all_zero(data + end, data + size)) return torn_from(at);
      throw FileError(name, "damaged record at offset " + std::to_string(at) +
                                ": checksum mismatch (records follow it)");
    }
    scan.records.push_back({at, payload, static_cast<std::size_t>(length)});
    at = end;
  }
  scan.valid_end = size;
  return scan;
}

void read_record(const JournalScan::Record& record, const std::string& name,
                 const std::function<void(JournalChange&)>& apply,
                 const std::function<void(const BaseId&)>& sealed) {
  PayloadReader in(record, name);
  const std::uint8_t kind = in.byte();
  if (kind == kSealedRecord) {
    if (in.left() != 12) in.fail("a sealing record of " + std::to_string(in.left()) + " bytes");
    const std::uint8_t* at = in.bytes(12);
    sealed({load_le<std::uint64_t>(at), load_le<std::uint32_t>(at + 8)});
    return;
  }
  if (kind != kChangesRecord) in.fail("unknown record kind " + std::to_string(kind));
  while (!in.done()) {
    JournalChange change;
    const std::uint8_t type = in.byte();
    change.type = static_cast<Change>(type);
    switch (change.type) {
      case Change::kAdd:
        try {
          read_add(in, change);
        } catch (const InvalidArgument& e) {
          in.fail(e.what());
        }
        break;
      case Change::kRemove:
        change.entry = static_cast<EntryId>(in.varint(kMaxU32, "entry id"));
        break;
      case Change::kLabel: {
        change.entry = static_cast<EntryId>(in.varint(kMaxU32, "entry id"));
        const std::size_t size = in.count(1, "label length");
        change.label.assign(reinterpret_cast<const char*>(in.bytes(size)), size);
        break;
      }
      case Change::kClear:
        break;
      default:
        in.fail("unknown change type " + std::to_string(type));
    }
    try {
      apply(change);
    } catch (const InvalidArgument& e) {
      in.fail(e.what());
    }
  }
}

void DatabaseJournal::start_change(Change type) noexcept {
  if (pending_.empty()) pending_.push_back(kChangesRecord);
  pending_.push_back(static_cast<std::uint8_t>(type));
}

void DatabaseJournal::give_up() noexcept {
  needs_full_save_ = true;
  std::vector<std::uint8_t>().swap(pending_);
}

void DatabaseJournal::record_add(EntryId entry, const BowVector& bow, const FeatureVector& features,
                                 const std::string& label) noexcept {
  if (key_.empty() || needs_full_save_) return;
  try {
    start_change(Change::kAdd);
    put_varint(pending_, entry);
    put_varint(pending_, label.size());
    put_bytes(pending_, label.data(), label.size());
    put_varint(pending_, bow.size());
    WordId previous = 0;
    for (const BowEntry& e : bow) {
      put_varint(pending_, e.word - previous);
      previous = e.word;
    }
    const std::size_t weights = pending_.size();
    pending_.resize(weights + 4 * bow.size());
    for (std::size_t i = 0; i < bow.size(); ++i)
      store_le<float>(pending_.data() + weights + 4 * i, bow[i].value);
    put_varint(pending_, features.size());
    NodeId previous_node = 0;
    for (const NodeId node : features.nodes()) {
      put_varint(pending_, node - previous_node);
      previous_node = node;
    }
    for (std::size_t i = 0; i < features.size(); ++i)
      put_varint(pending_, features.offsets()[i + 1] - features.offsets()[i]);
    for (const std::uint32_t feature : features.feature_indices()) put_varint(pending_, feature);
    // Changes past what the journal may hold are saved by a full save: the
    // memory they would keep is not worth it.
    if (pending_.size() > journal_limit(base_.size)) give_up();
  } catch (...) {
    give_up();
  }
}

void DatabaseJournal::record_remove(EntryId entry) noexcept {
  if (key_.empty() || needs_full_save_) return;
  try {
    start_change(Change::kRemove);
    put_varint(pending_, entry);
  } catch (...) {
    give_up();
  }
}

void DatabaseJournal::record_label(EntryId entry, const std::string& label) noexcept {
  if (key_.empty() || needs_full_save_) return;
  try {
    start_change(Change::kLabel);
    put_varint(pending_, entry);
    put_varint(pending_, label.size());
    put_bytes(pending_, label.data(), label.size());
  } catch (...) {
    give_up();
  }
}

void DatabaseJournal::record_clear() noexcept {
  if (key_.empty() || needs_full_save_) return;
  try {
    start_change(Change::kClear);
  } catch (...) {
    give_up();
  }
}

void DatabaseJournal::attach(const std::string& path, const BaseId& base, std::uint64_t journal_end,
                             std::uint64_t records, bool sealed) {
  key_ = key_of(path);
  base_ = base;
  journal_end_ = journal_end;
  records_ = records;
  needs_full_save_ = sealed;
  std::vector<std::uint8_t>().swap(pending_);
}

bool DatabaseJournal::seal(const std::string& path, const std::string& key, const BaseId& id) {
  const std::string journal = journal_path_of(path);
  struct stat st {};
  if (::lstat(journal.c_str(), &st) != 0) {
    if (errno == ENOENT) return false;
    throw FileError(journal, "cannot stat: " + errno_text());
  }
  BaseId current;
  const bool has_base = read_base_id(path, current);
  // Where the journal's intact records end, if it extends the base there.
  std::uint64_t end = 0;
  if (has_base && key == key_ && current == base_ && journal_end_ > 0 &&
      OpenJournal(journal, journal_header(base_), journal_end_).valid()) {
    end = journal_end_;
  } else if (has_base && S_ISREG(st.st_mode)) {
    try {
      const MappedFile file(journal);
      const JournalScan scan = scan_journal(file.data(), file.size(), journal);
      if (scan.base == current) end = scan.valid_end;
    } catch (const FileError&) {
    }
  }
  if (end == 0) {
    remove_durably(journal);
    return false;
  }
  OpenJournal open(journal, journal_header(current), end);
  if (!open.valid()) throw FileError(journal, "cannot open the journal to seal it");
  const std::vector<std::uint8_t> record = sealing_record(current, id);
  open.append(end, record);
  // This database's own record, not another writer's.
  if (key == key_ && current == base_) journal_end_ = end + record.size();
  return true;
}

bool DatabaseJournal::changed_on_disk(const std::string& path) const {
  BaseId current;
  if (!read_base_id(path, current)) return false;  // gone: a save makes it again
  if (current != base_) return true;
  const int fd =
      ::open(journal_path_of(path).c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
  if (fd < 0) return false;  // removed: what this database holds is saved whole
  struct stat st {};
  std::vector<std::uint8_t> header(kJournalHeaderSize);
  bool changed = false;
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) &&
      ::pread(fd, header.data(), header.size(), 0) == static_cast<ssize_t>(header.size()) &&
      header == journal_header(base_)) {
    // Another writer's commit is an intact record where this database's
    // journal ends; anything else there is an append that never completed.
    const std::uint64_t end = journal_end_ == 0 ? kJournalHeaderSize : journal_end_;
    const auto size = static_cast<std::uint64_t>(st.st_size);
    std::uint8_t head[kJournalRecordHeaderSize];
    if (size < end) {
      changed = true;
    } else if (size - end >= kJournalRecordHeaderSize &&
               ::pread(fd, head, sizeof head, static_cast<off_t>(end)) ==
                   static_cast<ssize_t>(sizeof head) &&
               load_le<std::uint32_t>(head + 12) == record_header_crc(head, base_)) {
      const auto length = load_le<std::uint64_t>(head);
      std::vector<std::uint8_t> payload;
      if (length <= size - end - kJournalRecordHeaderSize) {
        payload.resize(static_cast<std::size_t>(length));
        changed = ::pread(fd, payload.data(), payload.size(),
                          static_cast<off_t>(end + kJournalRecordHeaderSize)) ==
                      static_cast<ssize_t>(payload.size()) &&
                  load_le<std::uint32_t>(head + 8) == crc32c(payload.data(), payload.size());
      }
    }
  }
  ::close(fd);
  return changed;
}

void DatabaseJournal::refuse_if_changed(const std::string& path) const {
  if (key_ == key_of(path) && changed_on_disk(path))
    throw WriteConflict(path,
                        "another writer saved the database since it was loaded or saved here: "
                        "nothing was written (load it again and redo the changes, or hold a "
                        "DatabaseLock from before the load until after the save)");
}

void DatabaseJournal::save_base(const std::string& path,
                                const std::function<void(std::FILE*)>& write) {
  if (is_written_in_place(path)) {
    write_file_atomically(path, write);
    key_.clear();
    std::vector<std::uint8_t>().swap(pending_);
    return;
  }
  refuse_if_changed(path);
  const std::string key = key_of(path);
  StagedFiles staged;
  std::FILE* file = staged.stage(path);
  write(file);
  BaseId id;
  if (std::fflush(file) != 0) throw FileError(path, "cannot write: " + errno_text());
  if (!descriptor_base_id(::fileno(file), id))
    throw FileError(path, "cannot read back the header just written");
  const bool sealed = seal(path, key, id);
  try {
    staged.commit();
  } catch (...) {
    // The journal still extends the old base, which stays; its sealing
    // record must not be followed by more changes.
    if (sealed) needs_full_save_ = true;
    throw;
  }
  // Committed: the journal is sealed for the new base, which loads alone,
  // and the next save replaces a journal that could not be removed.
  attach(path, id, 0, 0, false);
  if (sealed) {
    try {
      remove_durably(journal_path_of(path));
    } catch (const FileError& e) {
      warn(path + ": saved; its superseded journal stays until the next save (" + e.problem() +
           ")");
    }
  }
}

bool DatabaseJournal::append(const std::string& path) {
  if (key_.empty() || needs_full_save_ || key_of(path) != key_ || is_written_in_place(path))
    return false;
  BaseId current;
  if (!read_base_id(path, current)) return false;
  refuse_if_changed(path);
  sweep_leftovers(path);
  if (pending_.empty()) return true;
  const std::vector<std::uint8_t> record = framed(pending_, base_);
  const std::uint64_t start = journal_end_ == 0 ? kJournalHeaderSize : journal_end_;
  if (start + record.size() > journal_limit(base_.size)) return false;
  const std::string journal = journal_path_of(path);
  if (journal_end_ == 0) {
    // A new journal appears whole (it may replace one that a full save
    // superseded): write the header and the first record as one file.
    std::vector<std::uint8_t> bytes = journal_header(base_);
    put_bytes(bytes, record.data(), record.size());
    write_file_atomically(journal, bytes.data(), bytes.size());
  } else {
    OpenJournal open(journal, journal_header(base_), journal_end_);
    if (!open.valid()) return false;
    open.append(journal_end_, record);
  }
  journal_end_ = start + record.size();
  ++records_;
  std::vector<std::uint8_t>().swap(pending_);
  return true;
}

}  // namespace detail

std::string Database::journal_path(const std::string& path) {
  return detail::journal_path_of(path);
}

void Database::save_incremental(const std::string& path, bool include_vocabulary) const {
  // The lock is held across the fallback to a full save, so no writer
  // comes between.
  const detail::SaveTarget target(path);
  {
    std::shared_lock lock(impl_->mutex);
    std::lock_guard<std::mutex> saving(impl_->journal.mutex);
    if (impl_->journal.append(target.path)) return;
  }
  save(target.path, include_vocabulary);
}

bool Database::append_journal(const std::string& path) const {
  const detail::SaveTarget target(path);
  std::shared_lock lock(impl_->mutex);
  std::lock_guard<std::mutex> saving(impl_->journal.mutex);
  return impl_->journal.append(target.path);
}

namespace detail {

JournalReplay replay_journal(Database& database, const JournalScan& scan, const BaseId& base,
                             const std::string& name, std::uint64_t files_size) {
  const auto no_changes = [](JournalChange&) {};
  JournalReplay replay;
  if (scan.base != base) {
    for (const auto& record : scan.records)
      read_record(record, name, no_changes,
                  [&](const BaseId& sealed) { replay.superseded |= sealed == base; });
    if (!replay.superseded)
      throw FileError(name, "the journal of another save of the database (" + describe(scan.base) +
                                "), not of its base (" + describe(base) +
                                "): load the database it extends, or remove the journal");
    return replay;
  }
  // Word ids far sparser than the files' bytes are refused, as load() does.
  const std::uint64_t word_limit = kInitialWordCapacity + 4 * files_size;
  const bool over_word_ids = database.vocabulary().empty();
  for (const auto& record : scan.records) {
    bool sealing = false;
    read_record(
        record, name,
        [&](JournalChange& change) {
          switch (change.type) {
            case Change::kAdd:
              if (change.entry != database.next_entry_id())
                throw InvalidArgument("adds entry " + std::to_string(change.entry) +
                                      " where the next entry id is " +
                                      std::to_string(database.next_entry_id()));
              if (!change.features.empty() && !database.options().direct_index)
                throw InvalidArgument("a feature vector for a database without a direct index");
              if (over_word_ids && !change.bow.empty() &&
                  change.bow[change.bow.size() - 1].word >= word_limit)
                throw InvalidArgument("word ids up to " +
                                      std::to_string(change.bow[change.bow.size() - 1].word) +
                                      " are too sparse for the files' size");
              database.add(change.bow, change.features, std::move(change.label));
              break;
            case Change::kRemove:
              database.remove(change.entry);
              break;
            case Change::kLabel:
              database.set_label(change.entry, std::move(change.label));
              break;
            case Change::kClear:
              database.clear();
              break;
          }
        },
        [&](const BaseId&) { sealing = true; });
    replay.sealed |= sealing;
    replay.records += sealing ? 0 : 1;
  }
  return replay;
}

}  // namespace detail

void Database::replay_journal(const std::string& path, const std::uint8_t* base,
                              std::size_t base_size) {
  detail::BaseId id;
  if (!detail::base_id_of(base, base_size, id))
    throw FileError(path, "not a sectioned file");  // load() has checked it already
  // The journal is beside the file, wherever a link to it is.
  const std::string file_path = detail::resolve_database_path(path);
  const std::string journal = detail::journal_path_of(file_path);
  struct stat st {};
  if (::stat(journal.c_str(), &st) != 0 && errno == ENOENT) {
    impl_->journal.attach(file_path, id, 0, 0, false);
    return;
  }
  const detail::MappedFile file(journal);
  const detail::JournalScan scan = detail::scan_journal(file.data(), file.size(), journal);
  const detail::JournalReplay replay =
      detail::replay_journal(*this, scan, id, journal, std::uint64_t{base_size} + file.size());
  // A superseded journal is left to the next save, which replaces it.
  impl_->journal.attach(file_path, id, replay.superseded ? 0 : scan.valid_end, replay.records,
                        replay.sealed);
}

DatabaseJournalInfo Database::inspect_journal(const std::string& path) {
  DatabaseJournalInfo info;
  const DatabaseFileInfo base = inspect(path, false);
  info.entries = base.entries;
  info.next_entry_id = base.next_entry_id;
  const std::string journal = detail::journal_path_of(detail::resolve_database_path(path));
  struct stat st {};
  if (::stat(journal.c_str(), &st) != 0 && errno == ENOENT) return info;
  const detail::MappedFile file(journal);
  const detail::JournalScan scan = detail::scan_journal(file.data(), file.size(), journal);
  detail::BaseId id;
  if (!detail::read_base_id(path, id))
    throw FileError(path, "cannot read the header of the database the journal extends");
  info.present = true;
  info.bytes = file.size();
  info.torn_bytes = scan.torn_bytes;
  bool superseded = false;
  // Counted, not checked against the index: load() does that.
  std::size_t entries = info.entries;
  EntryId next_id = info.next_entry_id;
  for (const auto& record : scan.records) {
    bool sealing = false;
    detail::read_record(
        record, journal,
        [&](detail::JournalChange& change) {
          switch (change.type) {
            case detail::Change::kAdd:
              ++info.added;
              ++entries;
              ++next_id;
              break;
            case detail::Change::kRemove:
              ++info.removed;
              --entries;
              break;
            case detail::Change::kLabel:
              ++info.labels_set;
              break;
            case detail::Change::kClear:
              ++info.cleared;
              entries = 0;
              next_id = 0;
              break;
          }
        },
        [&](const detail::BaseId& sealed) {
          sealing = true;
          superseded |= sealed == id;
        });
    info.saves += sealing ? 0 : 1;
  }
  if (scan.base == id) {
    info.entries = entries;
    info.next_entry_id = next_id;
    return info;
  }
  if (!superseded)
    throw FileError(journal, "the journal of another save of the database (" +
                                 detail::describe(scan.base) + "), not of " + path + " (" +
                                 detail::describe(id) + ")");
  info.superseded = true;
  return info;
}

}  // namespace binbow
