// libFuzzer target: the .bbdb reader (Database::deserialize). Every input is
// tried twice: as is (the CRCs reject almost all mutations) and with its CRCs
// recomputed, so that mutations reach the structural checks behind them. An
// accepted database must answer queries, return its direct index and survive
// a save/load round trip unchanged.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "core/crc32c.h"
#include "core/little_endian.h"

namespace {

constexpr std::size_t kHeaderSize = 64;
constexpr std::size_t kSectionEntrySize = 24;

// Rewrites the header, table and section CRCs of a .bbdb image in place,
// where the layout allows it.
void fix_checksums(std::vector<std::uint8_t>& bytes) {
  using binbow::detail::crc32c;
  using binbow::detail::load_le;
  using binbow::detail::store_le;
  if (bytes.size() < kHeaderSize) return;
  std::uint8_t* data = bytes.data();
  const auto sections = load_le<std::uint32_t>(data + 48);
  if (sections > 64) return;
  const std::size_t table_size = sections * kSectionEntrySize;
  if (bytes.size() >= kHeaderSize + table_size + 4) {
    std::uint8_t* table = data + kHeaderSize;
    for (std::uint32_t i = 0; i < sections; ++i) {
      std::uint8_t* e = table + i * kSectionEntrySize;
      const auto offset = load_le<std::uint64_t>(e + 8);
      const auto length = load_le<std::uint64_t>(e + 16);
      if (offset <= bytes.size() && length <= bytes.size() - offset)
        store_le<std::uint32_t>(e + 4, crc32c(data + offset, length));
    }
    store_le<std::uint32_t>(table + table_size, crc32c(table, table_size));
  }
  store_le<std::uint32_t>(data + 60, crc32c(data, 60));
}

void check_accepted(const binbow::Database& database) {
  using namespace binbow;
  const std::size_t words = std::min<std::size_t>(database.vocabulary().word_count(), 16);
  std::vector<BowEntry> entries;
  for (WordId w = 0; w < words; ++w) entries.push_back({w, 1.0f / static_cast<float>(words)});
  const auto results = database.query(BowVector(entries), 5);
  for (const auto& result : results)
    if (!database.contains(result.entry)) throw std::logic_error("query returned a missing entry");
  std::size_t live = 0;
  for (EntryId id = 0; id < database.next_entry_id(); ++id) {
    if (!database.contains(id)) continue;
    ++live;
    if (database.options().direct_index) (void)database.feature_vector(id);
    (void)database.label(id);
  }
  if (live != database.size()) throw std::logic_error("size() disagrees with contains()");
  const std::vector<std::uint8_t> saved = database.serialize();
  const Database again = Database::deserialize(saved.data(), saved.size(), "resaved");
  if (again.serialize() != saved) throw std::logic_error("save/load round trip changed the file");
}

void try_load(const std::uint8_t* data, std::size_t size) {
  try {
    check_accepted(binbow::Database::deserialize(data, size, "fuzz"));
  } catch (const binbow::FileError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try_load(data, size);
  std::vector<std::uint8_t> fixed(data, data + size);
  fix_checksums(fixed);
  try_load(fixed.data(), fixed.size());
  return 0;
}
