// Writing a .bbdb file: serialize() and save(), streamed section by section
// (the format: bbdb_format.h).
#include <sys/stat.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/error.h"
#include "core/crc32c.h"
#include "core/file_io.h"
#include "core/little_endian.h"
#include "core/sectioned_file.h"
#include "database/bbdb_format.h"
#include "database/database_impl.h"
#include "database/database_journal.h"
#include "database/database_lock.h"

namespace binbow {

using namespace detail::bbdb;

namespace {

// Writes the .bbdb sections of `impl` in order, streaming: nothing the size
// of the index is held besides it (the vocabulary section, when included, is
// serialised whole). The caller holds the database's lock. (A template only
// because Database::Impl is private to the class.)
template <class Impl>
void write_database(const Impl& impl, bool include_vocabulary, detail::SectionedFileWriter& out) {
  // A loaded file's bytes are written again only once checked: a save never
  // gives damaged postings fresh checksums.
  impl.wait_for_file();
  include_vocabulary = include_vocabulary && !impl.over_word_ids;
  const auto next_id = static_cast<EntryId>(impl.alive.size());
  if (include_vocabulary) {
    const std::vector<std::uint8_t> vocabulary = impl.vocabulary.serialize();
    out.append(vocabulary.data(), vocabulary.size());
  }
  out.next_section();
  const std::string description = impl.vocabulary.description();
  if (!impl.over_word_ids) out.append(description.data(), description.size());
  out.next_section();
  out.append(impl.alive.data(), impl.alive.size());
  out.next_section();

  // The index in parts of kSegmentSpan ids: each part gathers, row by row,
  // the live postings of the segments (and the tail) that overlap it.
  const std::unique_ptr<detail::Segment> tail = impl.tail_as_segment();
  std::vector<const detail::Segment*> sources;
  for (const auto& segment : impl.segments) sources.push_back(segment.get());
  if (tail) sources.push_back(tail.get());
  const std::size_t span = detail::kSegmentSpan;
  const std::size_t part_count = (std::size_t{next_id} + span - 1) / span;
  // The sources overlapping part k: [source_begin[k], source_begin[k + 1]).
  std::vector<std::size_t> source_begin(part_count + 1, 0);
  for (std::size_t k = 0, s = 0; k <= part_count; ++k) {
    while (s < sources.size() && sources[s]->end_entry <= k * span) ++s;
    source_begin[k] = s;
  }
  // Calls visit(relative_entry, PostingValue) for the live postings of the
  // row in part k, in entry order (relative to the part's first id).
  const auto for_each_posting = [&](std::size_t k, std::uint32_t row, const auto& visit) {
    const auto part_begin = static_cast<EntryId>(k * span);
    const auto part_end = static_cast<EntryId>(std::min<std::size_t>(next_id, (k + 1) * span));
    for (std::size_t s = source_begin[k]; s < sources.size(); ++s) {
      const detail::Segment& source = *sources[s];
      if (source.first_entry >= part_end) break;
      const bool check_alive = source.dead_postings > 0;
      detail::for_each_posting(source.row_begin(row), source.row_end(row),
                               [&](std::uint32_t relative, detail::PostingValue value) {
                                 const EntryId entry = source.first_entry + relative;
                                 if (entry < part_begin || entry >= part_end) return;
                                 if (check_alive && impl.alive[entry] == 0) return;
                                 visit(entry - part_begin, value);
                               });
    }
  };

  struct PartRow {
    std::uint32_t row;
    WordId word;
    std::uint32_t postings;
    std::uint32_t bytes;
  };
  std::vector<std::vector<PartRow>> part_rows(part_count);
  std::vector<std::uint32_t> part_postings(part_count, 0);
  std::uint64_t posting_count = 0;
  std::uint64_t largest_word_end = 0;  // 1 + the largest word with a posting
  for (std::size_t k = 0; k < part_count; ++k) {
    if (source_begin[k] == sources.size()) break;
    detail::RowOrder::for_each_row(impl.word_capacity, [&](std::uint32_t row, WordId word) {
      std::uint32_t gaps = 0, postings = 0, last = detail::kRowStart;
      bool counts = true;  // as RowWriter decides
      for_each_posting(k, row, [&](std::uint32_t relative, detail::PostingValue value) {
        gaps |= relative - last - 1;
        last = relative;
        counts = counts && value.count != 0;
        ++postings;
      });
      if (postings == 0) return;
      part_rows[k].push_back(
          {row, word, postings,
           static_cast<std::uint32_t>(detail::row_bytes(postings, gaps, counts))});
      part_postings[k] += postings;
      largest_word_end = std::max<std::uint64_t>(largest_word_end, std::uint64_t{word} + 1);
    });
    posting_count += part_postings[k];
  }
  for (std::size_t k = 0; k < part_count; ++k) {
    out.append_le<std::uint32_t>(static_cast<std::uint32_t>(part_rows[k].size()));
    out.append_le<std::uint32_t>(part_postings[k]);
  }
  out.next_section();
  for (const auto& rows : part_rows)
    for (const PartRow& row : rows) {
      out.append_le<std::uint32_t>(row.word);
      out.append_le<std::uint32_t>(row.bytes);
    }
  out.next_section();
  std::vector<std::uint8_t> row_bytes;
  for (std::size_t k = 0; k < part_count; ++k) {
    const detail::SegmentWeights weights = impl.segment_weights(static_cast<EntryId>(k * span));
    for (const PartRow& row : part_rows[k]) {
      row_bytes.resize(detail::kRowHeaderBytes +
                       std::size_t{row.postings} * detail::kWriterSlotBytes);
      detail::RowWriter writer(row_bytes.data(), weights, row.word);
      std::uint32_t last = detail::kRowStart;
      for_each_posting(k, row.row, [&](std::uint32_t relative, detail::PostingValue value) {
        writer.put(relative - last - 1, value);
        last = relative;
      });
      writer.finish();  // row.bytes long: the same postings were sized above
      out.append(row_bytes.data(), row.bytes);
    }
  }
  out.next_section();
  for (EntryId entry = 0; entry < next_id; ++entry)
    out.append_le<double>(impl.alive[entry] != 0 ? impl.divisors[entry] : 0.0);
  out.next_section();

  if (impl.options.direct_index) {
    // The entries of a loaded file keep their encodings, as the file has them.
    const detail::LoadedDirectIndex& loaded = impl.loaded_direct;
    for (EntryId entry = 0; entry < next_id; ++entry) {
      const bool alive = impl.alive[entry] != 0;
      if (alive && entry < loaded.entries()) {
        out.append_le<std::uint32_t>(loaded.size_field(entry, 0));
        out.append_le<std::uint32_t>(loaded.size_field(entry, 1));
        out.append_le<std::uint32_t>(loaded.size_field(entry, 2));
        continue;
      }
      const detail::PackedFeatureVector& features = impl.direct[entry];
      out.append_le<std::uint32_t>(alive ? features.node_count() : 0);
      out.append_le<std::uint32_t>(alive ? features.feature_count() : 0);
      out.append_le<std::uint32_t>(alive ? static_cast<std::uint32_t>(features.encoded_size()) : 0);
    }
    out.next_section();
    std::vector<std::uint8_t> encoded;
    for (EntryId entry = 0; entry < next_id; ++entry) {
      if (impl.alive[entry] == 0) continue;
      if (entry < loaded.entries()) {
        out.append(loaded.encoding(entry), loaded.encoded_size(entry));
        continue;
      }
      encoded.resize(impl.direct[entry].encoded_size());
      impl.direct[entry].encode(encoded.data());
      out.append(encoded.data(), encoded.size());
    }
  } else {
    out.next_section();
  }
  out.next_section();

  if (!impl.labels.empty()) {
    for (EntryId entry = 0; entry < next_id; ++entry)
      out.append_le<std::uint32_t>(static_cast<std::uint32_t>(impl.labels[entry].size()));
    out.next_section();
    for (EntryId entry = 0; entry < next_id; ++entry)
      out.append(impl.labels[entry].data(), impl.labels[entry].size());
  } else {
    out.next_section();
  }

  out.finish(kMagic, kVersion, [&](std::uint8_t* h) {
    detail::store_le<std::uint32_t>(h + 16, next_id);
    detail::store_le<std::uint32_t>(h + 20, static_cast<std::uint32_t>(impl.live_entries));
    detail::store_le<std::uint32_t>(h + 24, (impl.options.direct_index ? kFlagDirectIndex : 0) |
                                                (include_vocabulary ? kFlagVocabulary : 0) |
                                                (impl.over_word_ids ? kFlagOverWordIds : 0));
    detail::store_le<std::uint32_t>(h + 28, impl.options.direct_index_levels_up);
    detail::store_le<std::uint64_t>(h + 40, posting_count);
    if (!impl.over_word_ids) {
      detail::store_le<std::uint32_t>(h + 32, impl.vocabulary.checksum());
      return;
    }
    detail::store_le<std::uint32_t>(h + 36, static_cast<std::uint32_t>(impl.scoring));
    // Within what the postings justify (largest_capacity), which the
    // capacity exceeds only when the entries with the largest words were
    // removed: the index keeps its shape, and a reader can bound it.
    detail::store_le<std::uint64_t>(
        h + 52, std::min<std::uint64_t>(impl.word_capacity, largest_capacity(largest_word_end)));
  });
}

}  // namespace

std::vector<std::uint8_t> Database::serialize(bool include_vocabulary) const {
  std::shared_lock lock(impl_->mutex);
  std::vector<std::uint8_t> bytes;
  detail::SectionedFileWriter out(kSectionCount, detail::SectionedFileWriter::into(bytes));
  write_database(*impl_, include_vocabulary, out);
  return bytes;
}

// Streams the file: the memory a save needs does not grow with the database.
void Database::save(const std::string& given_path, bool include_vocabulary) const {
  const detail::SaveTarget target(given_path);
  const std::string& path = target.path;
  std::shared_lock lock(impl_->mutex);
  std::lock_guard<std::mutex> saving(impl_->journal.mutex);
  impl_->journal.save_base(path, [&](std::FILE* file) {
    // Sections follow one another after the space kept for the header, which
    // comes last: only the first section and the header need a seek. The
    // disk writes each 8 MiB while the next ones are produced.
    constexpr std::size_t kWritebackBytes = std::size_t{8} << 20;
    std::size_t position = 0, written_back = 0;
    detail::SectionedFileWriter out(
        kSectionCount, [&](std::size_t offset, const std::uint8_t* data, std::size_t size) {
          if (offset != position && std::fseek(file, static_cast<long>(offset), SEEK_SET) != 0)
            throw FileError(path, "cannot seek to write the header");
          detail::write_all(file, data, size, path);
          position = offset + size;
          if (position >= written_back + kWritebackBytes) {
            detail::start_writeback(file, written_back, position - written_back);
            written_back = position;
          }
        });
    write_database(*impl_, include_vocabulary, out);
  });
}

}  // namespace binbow
