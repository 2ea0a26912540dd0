// Reading a .bbdb file: deserialize(), load() (then the journal beside it)
// and inspect(), for every format version (the format: bbdb_format.h).
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

std::string hex(std::uint32_t value) {
  char text[16];
  std::snprintf(text, sizeof text, "%08x", value);
  return text;
}
// Moves rows written into RowWriter's slots (a header and kWriterSlotBytes
// per posting; the finished row is shorter) next to each other, and shrinks
// the block.
void squeeze_rows(detail::Segment& segment) noexcept {
  std::uint32_t* offsets = segment.offsets.data();
  std::uint8_t* const bytes = segment.bytes.data();
  std::uint32_t out = 0;
  for (std::size_t r = 0; r + 1 < segment.offsets.size(); ++r) {
    const std::uint32_t begin = offsets[r], slot = offsets[r + 1] - begin;
    offsets[r] = out;
    if (slot == 0) continue;
    const std::uint32_t postings =
        static_cast<std::uint32_t>((slot - detail::kRowHeaderBytes) / detail::kWriterSlotBytes);
    const auto size = static_cast<std::uint32_t>(detail::kRowHeaderBytes +
                                                 postings * detail::header_stride(bytes[begin]));
    std::memmove(bytes + out, bytes + begin, size);
    out += size;
  }
  offsets[segment.offsets.size() - 1] = out;
  segment.bytes.resize(out);
}

// The readers below check every count against the length of the section it
// comes from before anything is allocated, so a hostile file cannot make
// them allocate more than its own size justifies. Each section's CRC is
// checked just before it is read, and `release` is told when the reader is
// done with it (load() then drops its pages from memory), so reading holds
// little more than the database it builds. (Templates only because
// Database::Impl is private to the class.)
constexpr std::size_t kReleaseBytes = std::size_t{64} << 20;  // released a part at a time

// Version 1: posting lists by word over every id, cut into segments of
// kSegmentSpan ids.
template <class Impl>
void read_postings_v1(const Layout& layout, const Release& release, Impl* impl) {
  const Header& header = layout.header();
  const std::size_t word_count = impl->word_capacity;
  const EntryId next_id = header.next_entry_id;
  const std::size_t list_count = layout.count_of(kWords, 4);
  if (list_count > word_count)
    layout.fail("more posting lists (" + std::to_string(list_count) + ") than words (" +
                std::to_string(word_count) + ")");
  const auto words = layout.values<std::uint32_t>(kWords, list_count);
  const auto lengths = layout.values<std::uint32_t>(kListLengths, list_count);
  const std::size_t posting_count = layout.count_of(kPostingIds, 4);
  if (posting_count != header.postings)
    layout.fail("the header counts " + std::to_string(header.postings) + " postings, the index " +
                std::to_string(posting_count));
  const std::uint8_t* ids = layout.array(kPostingIds, posting_count, 4);
  const std::uint8_t* weights = layout.array(kPostingWeights, posting_count, 4);
  if (posting_count > std::numeric_limits<std::uint32_t>::max())
    layout.fail("more postings than this binbow supports (2^32)");
  std::vector<std::uint32_t> rows(list_count);
  std::size_t at = 0;
  for (std::size_t l = 0; l < list_count; ++l) {
    if (words[l] >= word_count || (l > 0 && words[l] <= words[l - 1]))
      layout.fail("posting list words are out of range or not increasing (word " +
                  std::to_string(words[l]) + ")");
    const std::uint32_t length = lengths[l];
    if (length == 0 || length > posting_count - at)
      layout.fail("posting list of word " + std::to_string(words[l]) + " has an invalid length");
    rows[l] = impl->row_order.row(words[l]);
    at += length;
  }
  if (at != posting_count) layout.fail("posting lists do not cover every posting");

  // The postings go to one segment per kSegmentSpan ids (as in a database
  // that was filled by add()): a first pass checks them and sizes each
  // segment's rows, a second encodes them in place. Within a list
  // the entries increase, so each segment's part of a row is one run of it.
  // The sections are released as they are read, a part at a time.
  const auto for_each_list = [&](const auto& visit) {
    std::size_t from = 0, released = 0;
    for (std::size_t l = 0; l < list_count; ++l) {
      visit(l, from);
      from += lengths[l];
      if ((from - released) * 4 >= kReleaseBytes || l + 1 == list_count) {
        release(ids + 4 * released, 4 * (from - released));
        release(weights + 4 * released, 4 * (from - released));
        released = from;
      }
    }
  };
  impl->word_counts.assign(next_id, 0);
  impl->divisors.assign(next_id, 0.0);
  const std::size_t span = detail::kSegmentSpan;
  const std::size_t segment_count = posting_count > 0 ? (next_id + span - 1) / span : 0;
  std::vector<std::unique_ptr<detail::Segment>> segments(segment_count);  // those with postings
  for_each_list([&](std::size_t l, std::size_t from) {
    EntryId previous = 0;
    for (std::size_t i = from; i < from + lengths[l]; ++i) {
      const auto id = detail::load_le<std::uint32_t>(ids + 4 * i);
      if (id >= next_id || impl->alive[id] == 0 || (i > from && id <= previous))
        layout.fail("posting list of word " + std::to_string(words[l]) +
                    " names a missing entry or is not in increasing order");
      const float weight = detail::load_le<float>(weights + 4 * i);
      if (!std::isfinite(weight))
        layout.fail("posting list of word " + std::to_string(words[l]) +
                    " has a non-finite weight");
      impl->values.include(weight);
      ++impl->word_counts[id];
      auto& segment = segments[id / span];
      if (!segment) {
        segment = std::make_unique<detail::Segment>();
        segment->first_entry = static_cast<EntryId>(id / span * span);
        segment->end_entry =
            static_cast<EntryId>(std::min<std::size_t>(next_id, segment->first_entry + span));
        segment->level = detail::kLoadedLevel;
        segment->offsets.assign(word_count + 1, 0);
      }
      // The row's previous posting in this segment, if any, precedes it in the list.
      const bool first_in_row = i == from || previous < segment->first_entry;
      // Room for RowWriter: pass two writes the row, pass three squeezes it.
      segment->offsets[rows[l] + 1] += static_cast<std::uint32_t>(
          (first_in_row ? detail::kRowHeaderBytes : 0) + detail::kWriterSlotBytes);
      ++segment->posting_count;
      previous = id;
    }
  });
  for (auto& segment : segments) {
    if (!segment) continue;
    std::uint32_t* offsets = segment->offsets.data();
    for (std::size_t r = 0; r < word_count; ++r) offsets[r + 1] += offsets[r];
    segment->bytes.resize(offsets[word_count]);
  }
  for_each_list([&](std::size_t l, std::size_t from) {
    std::size_t i = from;
    const std::size_t end = from + lengths[l];
    while (i < end) {
      detail::Segment& segment = *segments[detail::load_le<std::uint32_t>(ids + 4 * i) / span];
      // Weights only: no counts to compute.
      detail::RowWriter row(segment.bytes.data() + segment.offsets[rows[l]], {}, words[l]);
      std::uint32_t last = detail::kRowStart;
      for (; i < end; ++i) {
        const auto id = detail::load_le<std::uint32_t>(ids + 4 * i);
        if (id >= segment.end_entry) break;
        const std::uint32_t relative = id - segment.first_entry;
        row.put(relative - last - 1, {0, detail::load_le<float>(weights + 4 * i)});
        last = relative;
      }
      row.finish();
    }
  });
  for (auto& segment : segments)
    if (segment) {
      squeeze_rows(*segment);
      impl->segments.push_back(std::move(segment));
    }
}

// Version 3: per entry, the divisor of its counts, or 0: finite and
// positive, and only for live entries of a database with a vocabulary.
// Checked at open (8 bytes per entry): check_postings() reads them.
template <class Impl>
void read_divisors(const Layout& layout, Impl* impl) {
  const EntryId next_id = layout.header().next_entry_id;
  const std::uint8_t* data = layout.array(kDivisors, next_id, 8);
  impl->divisors.resize(next_id);
  for (EntryId entry = 0; entry < next_id; ++entry) {
    const auto divisor = detail::load_le<double>(data + 8 * std::size_t{entry});
    if (divisor != 0 && (!std::isfinite(divisor) || !(divisor > 0) || impl->alive[entry] == 0 ||
                         impl->over_word_ids))
      layout.fail("entry " + std::to_string(entry) + " has an invalid divisor (" +
                  std::to_string(divisor) + ")");
    impl->divisors[entry] = divisor;
  }
}

// Versions 2 and 3: the parts (one per kSegmentSpan ids) must add up to
// the rows and postings of the file; returns them, two u32 per part.
std::vector<std::uint32_t> read_parts(const Layout& layout, std::size_t part_count,
                                      std::size_t row_count) {
  const auto parts = layout.values<std::uint32_t>(kParts, 2 * part_count);
  std::uint64_t rows_in_parts = 0, postings_in_parts = 0;
  for (std::size_t k = 0; k < part_count; ++k) {
    rows_in_parts += parts[2 * k];
    postings_in_parts += parts[2 * k + 1];
    if ((parts[2 * k] == 0) != (parts[2 * k + 1] == 0) || parts[2 * k] > parts[2 * k + 1])
      layout.fail("part " + std::to_string(k) + " has " + std::to_string(parts[2 * k]) +
                  " rows for " + std::to_string(parts[2 * k + 1]) + " postings");
  }
  if (rows_in_parts != row_count || postings_in_parts != layout.header().postings)
    layout.fail("the parts count " + std::to_string(rows_in_parts) + " rows and " +
                std::to_string(postings_in_parts) + " postings, the sections " +
                std::to_string(row_count) + " and " + std::to_string(layout.header().postings));
  return parts;
}

// Version 3: the parts are the segments, and a part's rows are the bytes a
// segment keeps: a view of source.file, or a copy. Checked here is what
// costs nothing per posting: the parts and rows sections, and each row's
// word, order and length, so that a row is never read outside its part
// (the offsets are built here); check_postings() checks the postings.
template <class Impl>
void lay_out_rows(const Layout& layout, const Source& source, Impl* impl) {
  const std::size_t word_count = impl->word_capacity;
  const EntryId next_id = layout.header().next_entry_id;
  const std::size_t span = detail::kSegmentSpan;
  const std::size_t part_count = (std::size_t{next_id} + span - 1) / span;
  const std::size_t row_count = layout.count_of(kRows, 8);
  const std::vector<std::uint32_t> parts = read_parts(layout, part_count, row_count);
  const std::uint8_t* rows = layout.array(kRows, row_count, 8);
  const detail::Section& postings = layout.section(kPostingBytes);
  impl->word_counts.assign(next_id, 0);  // counted by check_postings
  std::size_t row_at = 0, byte_at = 0;
  for (std::size_t k = 0; k < part_count; ++k) {
    const std::uint32_t part_rows = parts[2 * k];
    if (part_rows == 0) continue;
    const auto first = static_cast<EntryId>(k * span);
    const auto end = static_cast<EntryId>(std::min<std::size_t>(next_id, first + span));
    const std::string where = "part " + std::to_string(k);
    auto segment = std::make_unique<detail::Segment>();
    segment->first_entry = first;
    segment->end_entry = end;
    segment->level = detail::kLoadedLevel;
    segment->posting_count = parts[2 * k + 1];
    segment->offsets.assign(word_count + 1, 0);
    std::uint32_t* offsets = segment->offsets.data();
    std::uint64_t previous_row = 0, part_bytes = 0;
    for (std::uint32_t r = 0; r < part_rows; ++r) {
      const auto word = detail::load_le<std::uint32_t>(rows + 8 * (row_at + r));
      const auto length = detail::load_le<std::uint32_t>(rows + 8 * (row_at + r) + 4);
      if (word >= word_count)
        layout.fail(where + " has a row for word " + std::to_string(word) + ", beyond the " +
                    std::to_string(word_count) + " words");
      const std::uint32_t row = impl->row_order.row(word);
      if (r > 0 && row <= previous_row)
        layout.fail(where + ": rows are not in order (word " + std::to_string(word) + ")");
      if (length < detail::row_bytes(1, 0, true) ||
          length > detail::row_bytes(end - first, 0xFFFF, false) ||
          length > postings.size - byte_at - part_bytes)
        layout.fail(where + ": the row of word " + std::to_string(word) + " has an invalid length");
      offsets[row + 1] = length;
      previous_row = row;
      part_bytes += length;
    }
    if (part_bytes > std::numeric_limits<std::uint32_t>::max())
      layout.fail(where + " holds more than 4 GiB of postings");
    for (std::size_t r = 0; r < word_count; ++r) offsets[r + 1] += offsets[r];
    if (source.file) {
      segment->bytes.view(postings.data + byte_at, part_bytes, source.file);
    } else {
      segment->bytes.resize(part_bytes);
      std::memcpy(segment->bytes.data(), postings.data + byte_at, part_bytes);
    }
    impl->segments.push_back(std::move(segment));
    row_at += part_rows;
    byte_at += part_bytes;
  }
  if (byte_at != postings.size) layout.fail("the postings section has trailing data");
}

// Version 3: every posting, as lay_out_rows() left them: each names a live
// entry of its part, in increasing order, with a finite weight, in a row
// whose gap width is the narrowest its gaps allow (so that a row has one
// form). A count row's word has a weight, and each of its counts is at
// least 1 and of an entry with a divisor (read_divisors() checked them);
// its weights are computed as a query computes them. Counts each entry's
// postings and the weights' range: what load() would compute reading them
// itself. `word_weights` are the vocabulary's (null over word ids: no count
// rows).
detail::BackgroundCheck::Found check_postings(const Layout& layout, const float* word_weights,
                                              const std::atomic<bool>& stop) {
  layout.verify(kPostingBytes);
  const EntryId next_id = layout.header().next_entry_id;
  const std::size_t span = detail::kSegmentSpan;
  const std::size_t part_count = (std::size_t{next_id} + span - 1) / span;
  const std::uint8_t* parts = layout.section(kParts).data;
  const std::uint8_t* rows = layout.section(kRows).data;
  const std::uint8_t* postings = layout.section(kPostingBytes).data;
  const std::uint8_t* alive = layout.section(kEntryStates).data;
  const std::uint8_t* divisors = layout.section(kDivisors).data;
  detail::BackgroundCheck::Found found;
  found.word_counts.assign(next_id, 0);
  std::size_t row_at = 0, byte_at = 0;
  for (std::size_t k = 0; k < part_count && !stop.load(std::memory_order_relaxed); ++k) {
    const auto part_rows = detail::load_le<std::uint32_t>(parts + 8 * k);
    const auto part_postings = detail::load_le<std::uint32_t>(parts + 8 * k + 4);
    const auto first = static_cast<EntryId>(k * span);
    const auto part_span =
        static_cast<std::uint32_t>(std::min<std::size_t>(next_id, first + span) - first);
    const std::string where = "part " + std::to_string(k);
    std::uint64_t part_read = 0;
    for (std::uint32_t r = 0; r < part_rows; ++r) {
      const auto word = detail::load_le<std::uint32_t>(rows + 8 * (row_at + r));
      const auto length = detail::load_le<std::uint32_t>(rows + 8 * (row_at + r) + 4);
      const auto row_fail = [&](const std::string& problem) {
        layout.fail(where + ": the row of word " + std::to_string(word) + " " + problem);
      };
      const std::uint8_t* at = postings + byte_at;
      const std::uint8_t* const row_end = at + length;
      const std::uint8_t row_header = at[0];
      const std::size_t width = detail::header_width(row_header);
      const bool counts = detail::header_counts(row_header);
      const std::size_t stride = detail::header_stride(row_header);
      if ((width != 1 && width != 2) || (row_header & ~(3u | detail::kCountRow)) != 0 ||
          (length - detail::kRowHeaderBytes) % stride != 0)
        row_fail("has a malformed posting");
      const double word_weight =
          counts && word_weights != nullptr ? static_cast<double>(word_weights[word]) : 0.0;
      if (counts && !(word_weight > 0)) row_fail("holds counts, but the word has no weight");
      std::uint32_t gaps = 0, last = detail::kRowStart;
      for (at += detail::kRowHeaderBytes; at != row_end; at += stride) {
        const std::uint32_t gap = detail::read_gap(at, width);
        gaps |= gap;
        last += gap + 1;
        if (last >= part_span || alive[first + last] == 0)
          row_fail("names a missing entry or is not in increasing order");
        float weight;
        if (counts) {
          const std::uint32_t count = at[width];
          const auto divisor = detail::load_le<double>(divisors + 8 * (std::size_t{first} + last));
          if (count == 0 || divisor == 0)
            row_fail("has a count of " + std::to_string(count) + " for entry " +
                     std::to_string(first + last) + (count == 0 ? "" : ", which has no divisor"));
          weight = detail::count_weight(word_weight, count, divisor);
        } else {
          weight = detail::read_weight(at + width);
        }
        if (!std::isfinite(weight)) row_fail("has a non-finite weight");
        found.values.include(weight);
        ++found.word_counts[first + last];
        ++part_read;
      }
      if (detail::gap_width(gaps) != width) row_fail("has gaps wider than needed");
      byte_at += length;
    }
    if (part_read != part_postings)
      layout.fail(where + ": its rows hold " + std::to_string(part_read) + " postings, not " +
                  std::to_string(part_postings));
    row_at += part_rows;
  }
  return found;
}

// Version 2: the parts are the segments, row by row; rows hold 16-bit ids
// and the weights apart, encoded here.
template <class Impl>
void read_postings_v2(const Layout& layout, const Release& release, Impl* impl) {
  const Header& header = layout.header();
  const std::size_t word_count = impl->word_capacity;
  const EntryId next_id = header.next_entry_id;
  const std::size_t span = detail::kSegmentSpan;
  const std::size_t part_count = (std::size_t{next_id} + span - 1) / span;
  const std::size_t row_count = layout.count_of(kRows, 8);
  const std::vector<std::uint32_t> parts = read_parts(layout, part_count, row_count);
  const std::size_t posting_count = layout.count_of(kPostingEntries, 2);
  if (posting_count != header.postings)
    layout.fail("the header counts " + std::to_string(header.postings) + " postings, the index " +
                std::to_string(posting_count));
  const std::uint8_t* rows = layout.array(kRows, row_count, 8);
  const std::uint8_t* postings = layout.array(kPostingEntries, posting_count, 2);
  const std::uint8_t* weights = layout.array(kPostingWeights, posting_count, 4);
  impl->word_counts.assign(next_id, 0);
  std::size_t row_at = 0, posting_at = 0;
  for (std::size_t k = 0; k < part_count; ++k) {
    const std::uint32_t part_rows = parts[2 * k];
    const std::uint32_t part_postings = parts[2 * k + 1];
    if (part_postings == 0) continue;
    const auto first = static_cast<EntryId>(k * span);
    const auto end = static_cast<EntryId>(std::min<std::size_t>(next_id, first + span));
    const std::uint32_t part_span = end - first;
    const std::string where = "part " + std::to_string(k);
    auto segment = std::make_unique<detail::Segment>();
    segment->first_entry = first;
    segment->end_entry = end;
    segment->level = detail::kLoadedLevel;
    segment->posting_count = part_postings;
    segment->offsets.assign(word_count + 1, 0);
    std::uint32_t* offsets = segment->offsets.data();
    // Each row is checked where the file has it (posting_at + its start):
    // every posting names a live entry of the part, in increasing order,
    // with a finite weight; its size in memory goes to offsets.
    std::uint64_t previous_row = 0, part_read = 0, part_bytes = 0;
    for (std::uint32_t r = 0; r < part_rows; ++r) {
      const auto word = detail::load_le<std::uint32_t>(rows + 8 * (row_at + r));
      const auto length = detail::load_le<std::uint32_t>(rows + 8 * (row_at + r) + 4);
      if (word >= word_count)
        layout.fail(where + " has a row for word " + std::to_string(word) + ", beyond the " +
                    std::to_string(word_count) + " words");
      const std::uint32_t row = impl->row_order.row(word);
      if (r > 0 && row <= previous_row)
        layout.fail(where + ": rows are not in order (word " + std::to_string(word) + ")");
      if (length == 0 || length > std::min<std::uint64_t>(part_span, part_postings - part_read))
        layout.fail(where + ": the row of word " + std::to_string(word) + " has an invalid length");
      std::uint32_t last = detail::kRowStart, gaps = 0;
      for (std::uint32_t i = 0; i < length; ++i) {
        const std::size_t at = posting_at + part_read + i;
        const auto relative = detail::load_le<std::uint16_t>(postings + 2 * at);
        if ((i > 0 && relative <= last) || relative >= part_span ||
            impl->alive[first + relative] == 0)
          layout.fail(where + ": the row of word " + std::to_string(word) +
                      " names a missing entry or is not in increasing order");
        const float weight = detail::load_le<float>(weights + 4 * at);
        if (!std::isfinite(weight))
          layout.fail(where + ": the row of word " + std::to_string(word) +
                      " has a non-finite weight");
        impl->values.include(weight);
        ++impl->word_counts[first + relative];
        gaps |= relative - last - 1;
        last = relative;
      }
      const std::uint64_t bytes = detail::row_bytes(length, gaps, false);
      offsets[row + 1] = static_cast<std::uint32_t>(bytes);
      previous_row = row;
      part_read += length;
      part_bytes += bytes;
    }
    if (part_read != part_postings)
      layout.fail(where + ": its rows hold " + std::to_string(part_read) + " postings, not " +
                  std::to_string(part_postings));
    if (part_bytes > std::numeric_limits<std::uint32_t>::max())
      layout.fail(where + " holds more than 4 GiB of postings");
    for (std::size_t r = 0; r < word_count; ++r) offsets[r + 1] += offsets[r];
    segment->bytes.resize(offsets[word_count]);
    // The rows in row order, as in the file.
    std::uint8_t* to = segment->bytes.data();
    std::size_t at = posting_at;
    for (std::uint32_t r = 0; r < part_rows; ++r) {
      const auto length = detail::load_le<std::uint32_t>(rows + 8 * (row_at + r) + 4);
      std::uint32_t gaps = 0, last = detail::kRowStart;
      for (std::uint32_t i = 0; i < length; ++i) {
        const auto relative = detail::load_le<std::uint16_t>(postings + 2 * (at + i));
        gaps |= relative - last - 1;
        last = relative;
      }
      const std::size_t width = detail::gap_width(gaps);
      *to++ = static_cast<std::uint8_t>(width);
      last = detail::kRowStart;
      for (std::uint32_t i = 0; i < length; ++i, ++at) {
        const auto relative = detail::load_le<std::uint16_t>(postings + 2 * at);
        to = detail::put_posting(to, width, relative - last - 1,
                                 detail::load_le<float>(weights + 4 * at));
        last = relative;
      }
    }
    release(postings + 2 * posting_at, part_read * 2);
    release(weights + 4 * posting_at, part_read * 4);
    impl->segments.push_back(std::move(segment));
    row_at += part_rows;
    posting_at += part_read;
  }
}

// Version 1: per entry, its node ids, node end offsets and feature indices.
template <class Impl>
void read_direct_index_v1(const Layout& layout, const Release& release, Impl* impl,
                          std::uint64_t node_count) {
  const EntryId next_id = layout.header().next_entry_id;
  const auto sizes = layout.values<std::uint32_t>(kDirectSizes, std::size_t{next_id} * 2);
  layout.verify(kDirectData);
  const detail::Section& direct_data = layout.section(kDirectData);
  const std::size_t available = layout.count_of(kDirectData, 4);
  impl->direct.resize(next_id);
  std::size_t cursor = 0, released = 0;  // in values of 4 bytes
  for (EntryId entry = 0; entry < next_id; ++entry) {
    const std::uint64_t nodes = sizes[2 * std::size_t{entry}];
    const std::uint64_t features = sizes[2 * std::size_t{entry} + 1];
    if (impl->alive[entry] == 0) {
      if (nodes != 0 || features != 0)
        layout.fail("removed entry " + std::to_string(entry) + " has a direct index");
      continue;
    }
    if (2 * nodes + features > available - cursor)
      layout.fail("direct index of entry " + std::to_string(entry) + " runs past its section");
    const auto read = [&](std::size_t count) {
      std::vector<std::uint32_t> values(count);
      if (count > 0) std::memcpy(values.data(), direct_data.data + cursor * 4, count * 4);
      cursor += count;
      return values;
    };
    std::vector<NodeId> node_ids = read(nodes);
    std::vector<std::uint32_t> offsets = read(nodes);
    offsets.insert(offsets.begin(), 0);
    std::vector<std::uint32_t> indices = read(features);
    if (!node_ids.empty() && node_ids.back() >= node_count)
      layout.fail("direct index of entry " + std::to_string(entry) +
                  " names a node outside the vocabulary");
    try {
      impl->direct[entry] = detail::PackedFeatureVector(
          FeatureVector::from_arrays(std::move(node_ids), std::move(offsets), std::move(indices)));
    } catch (const InvalidArgument& e) {
      layout.fail("direct index of entry " + std::to_string(entry) +
                  " is inconsistent: " + e.what());
    }
    if ((cursor - released) * 4 >= kReleaseBytes) {
      release(direct_data.data + released * 4, (cursor - released) * 4);
      released = cursor;
    }
  }
  if (cursor != available) layout.fail("direct index section has trailing data");
  release(direct_data.data + released * 4, (cursor - released) * 4);
}

// Version 2: per entry, its PackedFeatureVector's encoding.
template <class Impl>
void read_direct_index(const Layout& layout, const Release& release, Impl* impl,
                       std::uint64_t node_count) {
  const EntryId next_id = layout.header().next_entry_id;
  const auto sizes = layout.values<std::uint32_t>(kDirectSizes, std::size_t{next_id} * 3);
  layout.verify(kDirectData);
  const detail::Section& data = layout.section(kDirectData);
  impl->direct.resize(next_id);
  std::size_t cursor = 0, released = 0;
  for (EntryId entry = 0; entry < next_id; ++entry) {
    const std::uint32_t* size = sizes.data() + 3 * std::size_t{entry};
    if (impl->alive[entry] == 0) {
      if (size[0] != 0 || size[1] != 0 || size[2] != 0)
        layout.fail("removed entry " + std::to_string(entry) + " has a direct index");
      continue;
    }
    if (size[2] > data.size - cursor)
      layout.fail("direct index of entry " + std::to_string(entry) + " runs past its section");
    try {
      impl->direct[entry] = detail::PackedFeatureVector::decode(data.data + cursor, size[2],
                                                                size[0], size[1], node_count);
    } catch (const InvalidArgument& e) {
      layout.fail("direct index of entry " + std::to_string(entry) +
                  " is inconsistent: " + e.what());
    }
    // Node positions saved in 8 bits take 7 since version 3.
    if (layout.header().version < 3 && size[0] <= 0x80)
      impl->direct[entry] = detail::PackedFeatureVector(impl->direct[entry].unpack());
    cursor += size[2];
    if (cursor - released >= kReleaseBytes) {
      release(data.data + released, cursor - released);
      released = cursor;
    }
  }
  if (cursor != data.size) layout.fail("direct index section has trailing data");
  release(data.data + released, cursor - released);
}

// Version 3 in source.file: each entry's encoding stays in the file, found
// through the sizes (checked here); check_direct_index() decodes them.
template <class Impl>
void index_direct_index(const Layout& layout, const Source& source, Impl* impl,
                        std::uint64_t node_count) {
  const EntryId next_id = layout.header().next_entry_id;
  const std::uint8_t* sizes = layout.array(kDirectSizes, std::size_t{next_id} * 3, 4);
  const detail::Section& data = layout.section(kDirectData);
  detail::LoadedDirectIndex& loaded = impl->loaded_direct;
  loaded.offsets.resize(std::size_t{next_id} + 1);
  std::uint64_t cursor = 0;
  for (EntryId entry = 0; entry < next_id; ++entry) {
    const std::uint8_t* size = sizes + 12 * std::size_t{entry};
    const auto bytes = detail::load_le<std::uint32_t>(size + 8);
    if (impl->alive[entry] == 0 && (detail::load_le<std::uint32_t>(size) != 0 ||
                                    detail::load_le<std::uint32_t>(size + 4) != 0 || bytes != 0))
      layout.fail("removed entry " + std::to_string(entry) + " has a direct index");
    if (bytes > data.size - cursor)
      layout.fail("direct index of entry " + std::to_string(entry) + " runs past its section");
    loaded.offsets[entry] = cursor;
    cursor += bytes;
  }
  if (cursor != data.size) layout.fail("direct index section has trailing data");
  loaded.offsets[next_id] = cursor;
  loaded.keeper = source.file;
  loaded.name = layout.name();
  loaded.sizes = sizes;
  loaded.data = data.data;
  loaded.node_limit = node_count;
  impl->direct.resize(next_id);
}

// Version 3 in a file: every live entry's encoding decodes (as
// read_direct_index() checks), as index_direct_index() found them.
void check_direct_index(const Layout& layout, std::uint64_t node_count,
                        const std::atomic<bool>& stop) {
  layout.verify(kDirectData);
  const EntryId next_id = layout.header().next_entry_id;
  const std::uint8_t* sizes = layout.section(kDirectSizes).data;
  const std::uint8_t* alive = layout.section(kEntryStates).data;
  const std::uint8_t* data = layout.section(kDirectData).data;
  std::size_t cursor = 0;
  for (EntryId entry = 0; entry < next_id; ++entry) {
    if (entry % 4096 == 0 && stop.load(std::memory_order_relaxed)) return;
    const std::uint8_t* size = sizes + 12 * std::size_t{entry};
    const auto bytes = detail::load_le<std::uint32_t>(size + 8);
    if (alive[entry] == 0) continue;
    try {
      detail::PackedFeatureVector::decode(data + cursor, bytes,
                                          detail::load_le<std::uint32_t>(size),
                                          detail::load_le<std::uint32_t>(size + 4), node_count);
    } catch (const InvalidArgument& e) {
      layout.fail("direct index of entry " + std::to_string(entry) +
                  " is inconsistent: " + e.what());
    }
    cursor += bytes;
  }
}

// What a file's check adds to the FileError it finds after load() returned.
constexpr char kDamagedAfterLoad[] =
    " (found by the check that follows load(): every call on the database loaded from it now "
    "throws this error; restore the file from a backup, or build the database again)";

// Version 3: checks what lay_out_rows() and index_direct_index() left
// unchecked, in the background when the source allows, else now (throwing
// FileError if the file is damaged).
template <class Impl>
void check_file(const Layout& layout, const Source& source, Impl* impl, std::uint64_t node_count,
                bool direct_in_file) {
  const bool background = source.file && source.background;
  // The task keeps the file mapped, the vocabulary (whose word weights it
  // reads) and its own copy of the layout.
  auto task = [layout, file = source.file, vocabulary = impl->vocabulary,
               over_word_ids = impl->over_word_ids, node_count, direct_in_file,
               background](const std::atomic<bool>& stop) {
    try {
      detail::BackgroundCheck::Found found =
          check_postings(layout, over_word_ids ? nullptr : detail::word_weights(vocabulary), stop);
      if (direct_in_file) check_direct_index(layout, node_count, stop);
      return found;
    } catch (const FileError& e) {
      if (!background) throw;
      throw FileError(e.path(), e.problem() + kDamagedAfterLoad);
    }
  };
  impl->file_check = std::make_unique<detail::BackgroundCheck>(layout.name(), task, background);
  impl->file_check_merged = false;
  if (background) return;
  impl->merge_file_check();
  impl->file_check.reset();
}

// `impl` is empty, laid out for the file's words.
template <class Impl>
void read_index(const Layout& layout, const Source& source, Impl* impl) {
  const Release& release = source.release;
  const Header& header = layout.header();
  const std::uint64_t node_count =
      impl->over_word_ids ? kMaxWordCapacity : impl->vocabulary.node_count();
  const EntryId next_id = header.next_entry_id;

  impl->alive = layout.values<std::uint8_t>(kEntryStates, next_id);
  std::size_t live = 0;
  for (std::uint8_t state : impl->alive) {
    if (state > 1) layout.fail("invalid entry state " + std::to_string(state));
    live += state;
  }
  if (live != header.live_entries)
    layout.fail("the header counts " + std::to_string(header.live_entries) +
                " entries, the entry states " + std::to_string(live));
  impl->live_entries = live;

  if (header.version == 1) {
    read_postings_v1(layout, release, impl);
  } else if (header.version == 2) {
    read_postings_v2(layout, release, impl);
    impl->divisors.assign(next_id, 0.0);
  } else {
    read_divisors(layout, impl);
    lay_out_rows(layout, source, impl);
  }
  impl->tail_first_entry = next_id;

  const bool direct_in_file = impl->options.direct_index && header.version >= 3 && source.file;
  if (direct_in_file) {
    index_direct_index(layout, source, impl, node_count);
  } else if (impl->options.direct_index) {
    if (header.version == 1)
      read_direct_index_v1(layout, release, impl, node_count);
    else
      read_direct_index(layout, release, impl, node_count);
  } else if (layout.section(kDirectSizes).size != 0 || layout.section(kDirectData).size != 0) {
    layout.fail("direct index present in a database saved without one");
  } else {
    layout.verify(kDirectSizes);
    layout.verify(kDirectData);
  }

  if (layout.section(kLabelLengths).size != 0) {
    const auto label_lengths = layout.values<std::uint32_t>(kLabelLengths, next_id);
    layout.verify(kLabelBytes);
    const detail::Section& bytes = layout.section(kLabelBytes);
    impl->labels.resize(next_id);
    std::size_t cursor = 0;
    for (EntryId entry = 0; entry < next_id; ++entry) {
      if (label_lengths[entry] > bytes.size - cursor)
        layout.fail("label of entry " + std::to_string(entry) + " runs past its section");
      impl->labels[entry].assign(reinterpret_cast<const char*>(bytes.data) + cursor,
                                 label_lengths[entry]);
      cursor += label_lengths[entry];
    }
    if (cursor != bytes.size) layout.fail("labels section has trailing data");
  } else if (layout.section(kLabelBytes).size != 0) {
    layout.fail("label bytes without label lengths");
  } else {
    layout.verify(kLabelLengths);
    layout.verify(kLabelBytes);
  }
  if (header.version >= 3) check_file(layout, source, impl, node_count, direct_in_file);
}

DatabaseOptions options_of(const Header& header) {
  DatabaseOptions options;
  options.direct_index = (header.flags & kFlagDirectIndex) != 0;
  options.direct_index_levels_up = header.levels_up;
  return options;
}

// A database over a fixed vocabulary, which must be the one it was built with.
template <class Impl>
std::unique_ptr<Impl> read_vocabulary_database(const Layout& layout, Vocabulary vocabulary,
                                               const Source& source) {
  const Header& header = layout.header();
  if (header.over_word_ids())
    layout.fail(
        "the database is over word ids (an online vocabulary's) and has no vocabulary; load it "
        "without one");
  if (vocabulary.empty()) layout.fail("the vocabulary given to load the database is empty");
  if (vocabulary.checksum() != header.vocabulary_checksum)
    layout.fail("the database was built with a different vocabulary (checksum " +
                hex(header.vocabulary_checksum) + ", the given vocabulary has " +
                hex(vocabulary.checksum()) + ")");
  // What this reader does not read is still checked: the file is intact or refused.
  layout.verify(kVocabularyBytes);
  layout.verify(kDescription);
  auto impl = std::make_unique<Impl>(std::move(vocabulary), options_of(header));
  read_index(layout, source, impl.get());
  return impl;
}

// 1 + the largest word with postings (0 without postings).
std::uint64_t largest_word_end(const Layout& layout) {
  if (layout.header().version == 1) {
    layout.verify(kWords);
    const detail::Section& words = layout.section(kWords);
    return words.size >= 4
               ? std::uint64_t{detail::load_le<std::uint32_t>(words.data + words.size - 4)} + 1
               : 0;
  }
  const std::size_t rows = layout.count_of(kRows, 8);
  const std::uint8_t* data = layout.array(kRows, rows, 8);
  std::uint64_t end = 0;
  for (std::size_t r = 0; r < rows; ++r)
    end = std::max<std::uint64_t>(end,
                                  std::uint64_t{detail::load_le<std::uint32_t>(data + 8 * r)} + 1);
  return end;
}

// A database over word ids: its capacity is checked against its words before
// the index is laid out for it.
template <class Impl>
std::unique_ptr<Impl> read_word_id_database(const Layout& layout, const Source& source) {
  const Header& header = layout.header();
  layout.verify(kVocabularyBytes);
  layout.verify(kDescription);
  const std::uint64_t word_end = largest_word_end(layout);
  // Rows cost 4 bytes per word id in memory: ids far sparser than the
  // postings that name them (16 bytes each in the file) are refused, so
  // that a small file cannot claim billions of rows.
  if (word_end > detail::kInitialWordCapacity + 4 * std::uint64_t{layout.file_size()})
    layout.fail("word ids up to " + std::to_string(word_end - 1) +
                " are too sparse for a file of " + std::to_string(layout.file_size()) + " bytes");
  if (header.word_capacity < std::max<std::uint64_t>(word_end, detail::kInitialWordCapacity) ||
      header.word_capacity > largest_capacity(word_end))
    layout.fail("word-id capacity " + std::to_string(header.word_capacity) +
                " does not fit its words (the largest ends at " + std::to_string(word_end) + ")");
  auto impl = std::make_unique<Impl>(header.scoring, options_of(header));
  impl->lay_out(static_cast<std::size_t>(header.word_capacity));
  read_index(layout, source, impl.get());
  return impl;
}

// A database whose file says what it is over: its own vocabulary or word ids.
template <class Impl>
std::unique_ptr<Impl> read_self_contained_database(const Layout& layout, const std::string& name,
                                                   const Source& source) {
  if (layout.header().over_word_ids()) return read_word_id_database<Impl>(layout, source);
  if ((layout.header().flags & kFlagVocabulary) == 0)
    layout.fail("the database does not include its vocabulary (checksum " +
                hex(layout.header().vocabulary_checksum) +
                "); load it together with the vocabulary it was built with");
  layout.verify(kVocabularyBytes);
  const detail::Section& bytes = layout.section(kVocabularyBytes);
  return read_vocabulary_database<Impl>(
      layout, Vocabulary::deserialize(bytes.data, bytes.size, name + " (vocabulary)"), source);
}

// What deserialize() reads: a caller's buffer, copied, with nothing to drop.
Source buffer_source() {
  return {[](const std::uint8_t*, std::size_t) {}, nullptr, false};
}

// What load() reads: the mapped file, kept as the index's storage (version
// 3), or dropped from memory a section at a time once read (versions 1, 2).
Source file_source(const std::shared_ptr<const detail::MappedFile>& file,
                   const DatabaseLoadOptions& options) {
  return {[file](const std::uint8_t* data, std::size_t size) { file->release(data, size); }, file,
          options.verification == Verification::kBackground};
}

}  // namespace

Database Database::deserialize(const std::uint8_t* data, std::size_t size, const std::string& name,
                               Vocabulary vocabulary) {
  const Layout layout(data, size, name, false);
  return Database(read_vocabulary_database<Impl>(layout, std::move(vocabulary), buffer_source()));
}

Database Database::deserialize(const std::uint8_t* data, std::size_t size,
                               const std::string& name) {
  const Layout layout(data, size, name, false);
  return Database(read_self_contained_database<Impl>(layout, name, buffer_source()));
}

// load() maps the file, then replays the journal beside it. A save that
// replaces the file meanwhile may have removed or replaced the journal that
// extends the mapped base: the load starts again on the new file, so that it
// gives a committed state, never a base with another's journal.
struct DatabaseLoading {
  template <class Read>
  static Database load(const std::string& path, const Read& read);
};

namespace {

// What names the journal beside `path`: a save that removes or replaces it
// changes this.
struct JournalIdentity {
  bool exists = false;
  dev_t device = 0;
  ino_t inode = 0;
  off_t size = 0;
  bool operator==(const JournalIdentity& other) const {
    return exists == other.exists && device == other.device && inode == other.inode &&
           size == other.size;
  }
};

JournalIdentity journal_identity(const std::string& path) {
  struct stat st {};
  JournalIdentity identity;
  const std::string journal = detail::journal_path_of(detail::resolve_database_path(path));
  if (::stat(journal.c_str(), &st) == 0) identity = {true, st.st_dev, st.st_ino, st.st_size};
  return identity;
}

}  // namespace

template <class Read>
Database DatabaseLoading::load(const std::string& path, const Read& read) {
  constexpr int kAttempts = 8;
  for (int attempt = 1;; ++attempt) {
    const auto file = std::make_shared<const detail::MappedFile>(path);
    Database database = read(file);
    const JournalIdentity journal = journal_identity(path);
    try {
      database.replay_journal(path, file->data(), file->size());
    } catch (const FileError&) {
      const bool saved_meanwhile = !file->still_at(path) || !(journal_identity(path) == journal);
      if (attempt < kAttempts && saved_meanwhile) continue;
      throw;
    }
    if (attempt == kAttempts || file->still_at(path)) return database;
  }
}

Database Database::load(const std::string& path, const DatabaseLoadOptions& options) {
  return DatabaseLoading::load(path, [&](const std::shared_ptr<const detail::MappedFile>& file) {
    const Layout layout(file->data(), file->size(), path, false);
    return Database(read_self_contained_database<Impl>(layout, path, file_source(file, options)));
  });
}

Database Database::load(const std::string& path, Vocabulary vocabulary,
                        const DatabaseLoadOptions& options) {
  return DatabaseLoading::load(path, [&](const std::shared_ptr<const detail::MappedFile>& file) {
    const Layout layout(file->data(), file->size(), path, false);
    return Database(read_vocabulary_database<Impl>(layout, vocabulary, file_source(file, options)));
  });
}

void Database::wait_until_verified() const {
  impl_->wait_for_file();
}

DatabaseFileInfo Database::inspect(const std::string& path, bool verify) {
  const detail::MappedFile file(path);
  const Layout layout(file.data(), file.size(), path, verify);
  if (verify && ((layout.header().flags & kFlagVocabulary) != 0 || layout.header().over_word_ids()))
    deserialize(file.data(), file.size(), path);
  layout.verify(kDescription);
  const Header& header = layout.header();
  DatabaseFileInfo info;
  info.version = header.version;
  info.entries = header.live_entries;
  info.next_entry_id = header.next_entry_id;
  info.direct_index = (header.flags & kFlagDirectIndex) != 0;
  info.direct_index_levels_up = header.levels_up;
  info.vocabulary_included = (header.flags & kFlagVocabulary) != 0;
  info.vocabulary_checksum = header.vocabulary_checksum;
  const detail::Section& description = layout.section(kDescription);
  info.vocabulary_description.assign(reinterpret_cast<const char*>(description.data),
                                     description.size);
  return info;
}

}  // namespace binbow
