// The loop detector's state file (.bbld). Layout, all little-endian, in
// binbow's sectioned container (core/sectioned_file.h): header (64 bytes,
// CRC32C in its last 4), section table (24 bytes per section, then its
// CRC32C), then the sections back to back, every byte under a CRC.
//   header 16 flags (1: online vocabulary)   20 code size (bytes)
//          24 frames (images processed)      28 frames with features
//          32, 36, 40 the fixed vocabulary's checksum, word count and levels
//          (0 when online)   44 frames forgotten (version 2; reserved, 0,
//          in version 1)   48 section count   52 keypoints kept (u64)
//   sections 0 parameters (LoopDetectorParams::to_json text)
//            1 temporal state (i32 consistent queries, u32 last island's
//              first and last entry, u32 last query), then the descriptor
//              name recorded by the vocabulary
//            2 previous BoW vector (u32 word, f32 value per entry)
//            3 database (.bbdb bytes without vocabulary; over word ids when online)
//            4 online vocabulary (.bbov bytes; empty with a fixed vocabulary)
//            5 feature counts (u32 per frame)   6 keypoints (x, y, size,
//              angle, response f32, octave i32: 24 bytes each)   7 descriptors
//            (5 to 7 empty with GeometricCheck::kNone, which keeps no features)
//            8 the latest loop (version 3: u32 query, u32 match; empty
//              before the first loop)
// The forgotten frames are the database's removed entries, and have no
// features. Version 1 (before LoopDetector::forget) has none and still loads;
// versions 1 and 2 have 8 sections and load with no latest loop.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "binbow/loop/loop_detector.h"
#include "core/crc32c.h"
#include "core/file_io.h"
#include "core/little_endian.h"
#include "core/sectioned_file.h"
#include "loop/detector/loop_detector_impl.h"

namespace binbow::loop {

namespace {

constexpr char kMagic[8] = {'B', 'I', 'N', 'B', 'O', 'W', 'L', 'D'};
constexpr std::uint32_t kVersion = 3;
constexpr std::size_t kHeaderSize = binbow::detail::kSectionedHeaderSize;
constexpr std::uint32_t kFlagOnline = 1;
constexpr std::size_t kTemporalStateSize = 16;
constexpr std::size_t kMaxDescriptorName = 64;
constexpr std::size_t kKeypointSize = 24;
// The largest descriptor an OnlineVocabulary takes (8192 bits); a fixed
// vocabulary's must also equal the given vocabulary's.
constexpr std::uint32_t kMaxCodeSize = 1024;

enum Section : std::uint32_t {
  kParams = 0,
  kTemporalState,
  kPreviousBow,
  kDatabase,
  kOnlineVocabulary,
  kFeatureCounts,
  kKeypoints,
  kDescriptors,
  kPreviousLoop,
  kSectionCount,
};
// Sections of a version 1 or 2 file: all but the latest loop.
constexpr std::uint32_t kVersion2SectionCount = kPreviousLoop;
constexpr const char* kSectionNames[kSectionCount] = {
    "parameters",     "temporal state", "previous BoW vector", "database",   "online vocabulary",
    "feature counts", "keypoints",      "descriptors",         "latest loop"};

struct Header {
  std::uint32_t version = 0;
  bool online = false;
  std::uint32_t code_size = 0;
  std::uint32_t frames = 0;
  std::uint32_t featured_frames = 0;
  std::uint32_t forgotten_frames = 0;
  std::uint32_t vocabulary_checksum = 0;
  std::uint32_t vocabulary_words = 0;
  std::uint32_t vocabulary_levels = 0;
  std::uint64_t keypoints = 0;
};

std::string hex(std::uint32_t value) {
  char text[16];
  std::snprintf(text, sizeof text, "%08x", value);
  return text;
}

std::string describe_vocabulary(std::uint32_t checksum, std::uint64_t words, std::uint32_t levels,
                                std::uint64_t code_size) {
  return "checksum " + hex(checksum) + ", " + std::to_string(words) + " words, " +
         std::to_string(levels) + " levels, " + std::to_string(code_size * 8) + "-bit descriptors";
}

// The header, the section table and the small sections of a .bbld image,
// checked; the CRC of every section is checked before it is read.
class Layout {
 public:
  Layout(const std::uint8_t* data, std::size_t size, const std::string& name) : name_(name) {
    if (size < kHeaderSize)
      fail("truncated: " + std::to_string(size) + " bytes, shorter than the " +
           std::to_string(kHeaderSize) + "-byte header of a loop detector state (.bbld)");
    if (std::memcmp(data, kMagic, 8) != 0)
      fail("not a binbow loop detector state (.bbld): wrong magic bytes");
    header_.version = binbow::detail::load_le<std::uint32_t>(data + 8);
    if (header_.version < 1 || header_.version > kVersion)
      fail("unsupported .bbld format version " + std::to_string(header_.version) +
           " (this binbow reads versions 1 to " + std::to_string(kVersion) + ")");
    if (binbow::detail::load_le<std::uint32_t>(data + 60) != binbow::detail::crc32c(data, 60))
      fail("header checksum mismatch: the file is corrupted");
    if (binbow::detail::load_le<std::uint32_t>(data + 12) != kHeaderSize)
      fail("unexpected header size");
    const auto flags = binbow::detail::load_le<std::uint32_t>(data + 16);
    if (flags > kFlagOnline) fail("unknown flags " + std::to_string(flags));
    header_.online = flags == kFlagOnline;
    header_.code_size = binbow::detail::load_le<std::uint32_t>(data + 20);
    header_.frames = binbow::detail::load_le<std::uint32_t>(data + 24);
    header_.featured_frames = binbow::detail::load_le<std::uint32_t>(data + 28);
    header_.vocabulary_checksum = binbow::detail::load_le<std::uint32_t>(data + 32);
    header_.vocabulary_words = binbow::detail::load_le<std::uint32_t>(data + 36);
    header_.vocabulary_levels = binbow::detail::load_le<std::uint32_t>(data + 40);
    header_.forgotten_frames = binbow::detail::load_le<std::uint32_t>(data + 44);
    header_.keypoints = binbow::detail::load_le<std::uint64_t>(data + 52);
    const auto section_count = binbow::detail::load_le<std::uint32_t>(data + 48);
    if (header_.version == 1 && header_.forgotten_frames != 0)
      fail("reserved header bytes are not zero");
    if (header_.code_size == 0 || header_.code_size > kMaxCodeSize)
      fail("descriptor size " + std::to_string(header_.code_size) + " is out of range");
    if (header_.featured_frames > header_.frames || header_.forgotten_frames > header_.frames ||
        header_.frames == kAllEntries)
      fail("inconsistent frame counts in the header");
    if (header_.online && (header_.vocabulary_checksum != 0 || header_.vocabulary_words != 0 ||
                           header_.vocabulary_levels != 0))
      fail("an online state names a fixed vocabulary");
    const std::uint32_t expected_sections =
        header_.version < 3 ? kVersion2SectionCount : kSectionCount;
    if (section_count != expected_sections)
      fail("expected " + std::to_string(expected_sections) + " sections, the header says " +
           std::to_string(section_count));
    const std::vector<binbow::detail::Section> table = binbow::detail::read_section_table(
        data, size, expected_sections, kSectionNames, [this](const std::string& p) { fail(p); });
    for (std::uint32_t i = 0; i < expected_sections; ++i) {
      if (!binbow::detail::section_intact(table[i]))
        fail(std::string("checksum mismatch in section '") + kSectionNames[i] +
             "': the file is corrupted");
      sections_[i] = table[i];
    }

    const binbow::detail::Section& params = sections_[kParams];
    params_ = LoopDetectorParams::from_json(
        std::string(reinterpret_cast<const char*>(params.data), params.size),
        name_ + " (parameters)");
    const binbow::detail::Section& state = sections_[kTemporalState];
    if (state.size < kTemporalStateSize || state.size > kTemporalStateSize + kMaxDescriptorName)
      fail("section 'temporal state' has " + std::to_string(state.size) + " bytes");
    window_.consistent = binbow::detail::load_le<std::int32_t>(state.data);
    window_.last_first = binbow::detail::load_le<std::uint32_t>(state.data + 4);
    window_.last_last = binbow::detail::load_le<std::uint32_t>(state.data + 8);
    window_.last_query = binbow::detail::load_le<std::uint32_t>(state.data + 12);
    if (window_.consistent < 0 || static_cast<std::uint32_t>(window_.consistent) > header_.frames ||
        window_.last_first > window_.last_last ||
        (window_.consistent > 0 && window_.last_last >= header_.frames) ||
        window_.last_query > header_.frames)
      fail("the temporal state names frames that do not exist");
    descriptor_.assign(reinterpret_cast<const char*>(state.data) + kTemporalStateSize,
                       state.size - kTemporalStateSize);
    for (char c : descriptor_)
      if (c < '!' || c > '~') fail("the descriptor name is not printable");
  }

  [[noreturn]] void fail(const std::string& problem) const { throw FileError(name_, problem); }
  const std::string& name() const { return name_; }
  const Header& header() const { return header_; }
  const binbow::detail::Section& section(Section s) const { return sections_[s]; }
  const LoopDetectorParams& params() const { return params_; }
  const detail::TemporalWindow::State& window() const { return window_; }
  const std::string& descriptor() const { return descriptor_; }
  void expect_size(Section s, std::uint64_t expected) const {
    if (sections_[s].size != expected)
      fail(std::string("section '") + kSectionNames[s] + "' has " +
           std::to_string(sections_[s].size) + " bytes, expected " + std::to_string(expected));
  }

 private:
  std::string name_;
  Header header_;
  binbow::detail::Section sections_[kSectionCount];
  LoopDetectorParams params_;
  detail::TemporalWindow::State window_;
  std::string descriptor_;
};

// The latest loop: none (an empty section, or a version 1 or 2 file), or a
// query and an older match among the frames.
template <typename DetectorImpl>
void read_previous_loop(const Layout& layout, DetectorImpl& impl) {
  const binbow::detail::Section& section = layout.section(kPreviousLoop);
  if (section.size == 0) return;
  layout.expect_size(kPreviousLoop, 8);
  const auto query = binbow::detail::load_le<std::uint32_t>(section.data);
  const auto match = binbow::detail::load_le<std::uint32_t>(section.data + 4);
  if (query >= layout.header().frames || match >= query)
    layout.fail("the latest loop names frames that do not exist");
  impl.has_previous_loop = true;
  impl.previous_loop_query = query;
  impl.previous_loop_match = match;
}

// The previous BoW vector, whose words must be below `word_limit`: the
// vocabulary's words, or the online vocabulary's ids ever created. A word
// beyond them scores nothing, so a resumed run would quietly lose the
// normalisation of its next frame.
BowVector read_previous_bow(const Layout& layout, std::uint64_t word_limit) {
  const binbow::detail::Section& section = layout.section(kPreviousBow);
  if (section.size % 8 != 0) layout.fail("section 'previous BoW vector' has a partial entry");
  std::vector<BowEntry> entries(section.size / 8);
  for (std::size_t i = 0; i < entries.size(); ++i) {
    entries[i].word = binbow::detail::load_le<std::uint32_t>(section.data + 8 * i);
    entries[i].value = binbow::detail::load_le<float>(section.data + 8 * i + 4);
    if (!std::isfinite(entries[i].value))
      layout.fail("the previous BoW vector has a non-finite value");
    if (entries[i].word >= word_limit)
      layout.fail("the previous BoW vector names word " + std::to_string(entries[i].word) +
                  ", outside the vocabulary's " + std::to_string(word_limit) + " words");
  }
  try {
    return BowVector(std::move(entries));
  } catch (const InvalidArgument& e) {
    layout.fail(std::string("the previous BoW vector is invalid: ") + e.what());
  }
}

// Counts, keypoints and descriptors of the frames, checked against each other,
// the header and the database's forgotten frames before anything is allocated.
template <class DetectorImpl>
void read_features(const Layout& layout, bool keeps_features, DetectorImpl& impl) {
  const Header& header = layout.header();
  impl.frames.resize(header.frames);
  if (!keeps_features) {
    if (header.keypoints != 0 || layout.section(kFeatureCounts).size != 0 ||
        layout.section(kKeypoints).size != 0 || layout.section(kDescriptors).size != 0)
      layout.fail("features stored by a detector without geometric check");
    return;
  }
  layout.expect_size(kFeatureCounts, std::uint64_t{header.frames} * 4);
  if (header.keypoints > layout.section(kKeypoints).size)
    layout.fail("the header counts more keypoints than the file holds");
  layout.expect_size(kKeypoints, header.keypoints * kKeypointSize);
  layout.expect_size(kDescriptors, header.keypoints * header.code_size);
  const std::uint8_t* counts = layout.section(kFeatureCounts).data;
  std::uint64_t total = 0;
  std::uint32_t featured = 0;
  for (std::size_t frame = 0; frame < header.frames; ++frame) {
    const auto count = binbow::detail::load_le<std::uint32_t>(counts + 4 * frame);
    total += count;
    if (total > header.keypoints)
      layout.fail("feature counts exceed the keypoints (frame " + std::to_string(frame) + ")");
    if (count > 0 && !impl.database.contains(static_cast<EntryId>(frame)))
      layout.fail("forgotten frame " + std::to_string(frame) + " has features");
    featured += count > 0 ? 1 : 0;
  }
  if (total != header.keypoints) layout.fail("feature counts do not cover every keypoint");
  // A forgotten frame's features are gone, whether it had any or not.
  if (featured > header.featured_frames ||
      header.featured_frames - featured > header.forgotten_frames)
    layout.fail("the header counts " + std::to_string(header.featured_frames) +
                " frames with features, the feature counts " + std::to_string(featured) + " and " +
                std::to_string(header.forgotten_frames) + " frames are forgotten");
  const std::uint8_t* keypoint_bytes = layout.section(kKeypoints).data;
  const std::uint8_t* descriptor_bytes = layout.section(kDescriptors).data;
  std::size_t next = 0;
  for (std::size_t frame = 0; frame < header.frames; ++frame) {
    const auto count = binbow::detail::load_le<std::uint32_t>(counts + 4 * frame);
    std::vector<vision::Keypoint>& keypoints = impl.frames[frame].keypoints;
    keypoints.resize(count);
    for (vision::Keypoint& k : keypoints) {
      const std::uint8_t* at = keypoint_bytes + next * kKeypointSize;
      k.x = binbow::detail::load_le<float>(at);
      k.y = binbow::detail::load_le<float>(at + 4);
      k.size = binbow::detail::load_le<float>(at + 8);
      k.angle = binbow::detail::load_le<float>(at + 12);
      k.response = binbow::detail::load_le<float>(at + 16);
      k.octave = binbow::detail::load_le<std::int32_t>(at + 20);
      if (!std::isfinite(k.x) || !std::isfinite(k.y) || !std::isfinite(k.size) ||
          !std::isfinite(k.angle) || !std::isfinite(k.response))
        layout.fail("keypoint " + std::to_string(next) + " has a non-finite coordinate");
      ++next;
    }
    const std::uint8_t* first = descriptor_bytes + (next - count) * header.code_size;
    impl.frames[frame].descriptors.assign(first, first + std::size_t{count} * header.code_size);
  }
}

// The direct index pairs an entry's feature indices with its stored
// descriptors: every index must name one of them.
template <class DetectorImpl>
void check_direct_index(const Layout& layout, const DetectorImpl& impl) {
  if (impl.params.geometric_check != GeometricCheck::kDirectIndex) return;
  for (EntryId entry = 0; entry < layout.header().frames; ++entry) {
    if (!impl.database.contains(entry)) continue;
    const std::size_t features = impl.frames[entry].keypoints.size();
    const FeatureVector vector = impl.database.feature_vector(entry);
    if (vector.feature_count() > features)
      layout.fail("the direct index of frame " + std::to_string(entry) + " has more features (" +
                  std::to_string(vector.feature_count()) + ") than the frame (" +
                  std::to_string(features) + ")");
    for (std::uint32_t index : vector.feature_indices())
      if (index >= features)
        layout.fail("the direct index of frame " + std::to_string(entry) + " names feature " +
                    std::to_string(index) + " of " + std::to_string(features));
  }
}

}  // namespace

std::vector<std::uint8_t> LoopDetector::serialize() const {
  const Impl& d = *impl_;
  std::vector<std::uint8_t> sections[kSectionCount];
  const std::string params = d.params.to_json();
  sections[kParams].assign(params.begin(), params.end());
  const detail::TemporalWindow::State window = d.window.state();
  std::vector<std::uint8_t>& state = sections[kTemporalState];
  binbow::detail::put_le<std::int32_t>(state, window.consistent);
  binbow::detail::put_le<std::uint32_t>(state, window.last_first);
  binbow::detail::put_le<std::uint32_t>(state, window.last_last);
  binbow::detail::put_le<std::uint32_t>(state, window.last_query);
  const std::string& descriptor =
      d.online ? d.online->options().descriptor : d.database.vocabulary().descriptor();
  state.insert(state.end(), descriptor.begin(), descriptor.end());
  if (d.has_previous_loop) {
    binbow::detail::put_le<std::uint32_t>(sections[kPreviousLoop],
                                          static_cast<std::uint32_t>(d.previous_loop_query));
    binbow::detail::put_le<std::uint32_t>(sections[kPreviousLoop],
                                          static_cast<std::uint32_t>(d.previous_loop_match));
  }
  for (const BowEntry& e : d.previous_bow) {
    binbow::detail::put_le<std::uint32_t>(sections[kPreviousBow], e.word);
    binbow::detail::put_le<float>(sections[kPreviousBow], e.value);
  }
  sections[kDatabase] = d.database.serialize(false);
  if (d.online) sections[kOnlineVocabulary] = d.online->serialize();
  std::uint64_t keypoint_count = 0;
  for (const Impl::FrameFeatures& f : d.frames) keypoint_count += f.keypoints.size();
  if (d.keeps_features()) {
    std::vector<std::uint8_t>& keypoints = sections[kKeypoints];
    keypoints.reserve(keypoint_count * kKeypointSize);
    sections[kDescriptors].reserve(keypoint_count * d.code_size);
    for (const Impl::FrameFeatures& f : d.frames) {
      binbow::detail::put_le<std::uint32_t>(sections[kFeatureCounts],
                                            static_cast<std::uint32_t>(f.keypoints.size()));
      for (const vision::Keypoint& k : f.keypoints) {
        binbow::detail::put_le<float>(keypoints, k.x);
        binbow::detail::put_le<float>(keypoints, k.y);
        binbow::detail::put_le<float>(keypoints, k.size);
        binbow::detail::put_le<float>(keypoints, k.angle);
        binbow::detail::put_le<float>(keypoints, k.response);
        binbow::detail::put_le<std::int32_t>(keypoints, k.octave);
      }
      sections[kDescriptors].insert(sections[kDescriptors].end(), f.descriptors.begin(),
                                    f.descriptors.end());
    }
  }
  const Vocabulary& vocabulary = d.database.vocabulary();
  return binbow::detail::write_sectioned_file(
      kMagic, kVersion, sections, kSectionCount, [&](std::uint8_t* h) {
        binbow::detail::store_le<std::uint32_t>(h + 16, d.online ? kFlagOnline : 0);
        binbow::detail::store_le<std::uint32_t>(h + 20, static_cast<std::uint32_t>(d.code_size));
        binbow::detail::store_le<std::uint32_t>(h + 24, static_cast<std::uint32_t>(size()));
        binbow::detail::store_le<std::uint32_t>(h + 28, d.featured_frames);
        binbow::detail::store_le<std::uint32_t>(h + 44,
                                                static_cast<std::uint32_t>(forgotten_count()));
        if (!d.online) {
          binbow::detail::store_le<std::uint32_t>(h + 32, vocabulary.checksum());
          binbow::detail::store_le<std::uint32_t>(
              h + 36, static_cast<std::uint32_t>(vocabulary.word_count()));
          binbow::detail::store_le<std::uint32_t>(h + 40, vocabulary.levels());
        }
        binbow::detail::store_le<std::uint64_t>(h + 52, keypoint_count);
      });
}

void LoopDetector::save(const std::string& path) const {
  const std::vector<std::uint8_t> bytes = serialize();
  binbow::detail::write_file_atomically(path, bytes.data(), bytes.size());
}

namespace {

// What both kinds share once the database (and online vocabulary) is in place.
// (Templates only so that they can name the private LoopDetector::Impl.)
template <class DetectorImpl>
std::unique_ptr<DetectorImpl> restore(const Layout& layout, std::unique_ptr<DetectorImpl> impl,
                                      std::uint64_t word_limit) {
  const Header& header = layout.header();
  const DatabaseOptions expected = detail::database_options(impl->params);
  const DatabaseOptions& options = impl->database.options();
  if (options.direct_index != expected.direct_index ||
      (expected.direct_index && options.direct_index_levels_up != expected.direct_index_levels_up))
    layout.fail("the database's direct index disagrees with the parameters");
  if (impl->database.next_entry_id() != header.frames ||
      impl->database.size() != header.frames - header.forgotten_frames)
    layout.fail("the database holds " + std::to_string(impl->database.size()) + " of " +
                std::to_string(impl->database.next_entry_id()) + " images, the state " +
                std::to_string(header.frames) + " of which " +
                std::to_string(header.forgotten_frames) + " forgotten");
  impl->previous_bow = read_previous_bow(layout, word_limit);
  impl->featured_frames = header.featured_frames;
  impl->window.restore(layout.window());
  read_previous_loop(layout, *impl);
  read_features(layout, impl->keeps_features(), *impl);
  check_direct_index(layout, *impl);
  return impl;
}

LoopDetectorFileInfo info_of(const Layout& layout) {
  const Header& header = layout.header();
  LoopDetectorFileInfo info;
  info.version = header.version;
  info.online = header.online;
  info.code_size = header.code_size;
  info.descriptor = layout.descriptor();
  info.frames = header.frames;
  info.forgotten_frames = header.forgotten_frames;
  info.vocabulary_checksum = header.vocabulary_checksum;
  info.vocabulary_words = header.vocabulary_words;
  info.vocabulary_levels = header.vocabulary_levels;
  info.params = layout.params();
  return info;
}

}  // namespace

LoopDetector LoopDetector::deserialize(const std::uint8_t* data, std::size_t size,
                                       const std::string& name, Vocabulary vocabulary) {
  const Layout layout(data, size, name);
  const Header& header = layout.header();
  if (header.online)
    layout.fail(
        "the state has an online vocabulary (its words grew from the sequence); load it without "
        "a vocabulary");
  if (vocabulary.empty()) layout.fail("the vocabulary given to load the state is empty");
  if (vocabulary.checksum() != header.vocabulary_checksum ||
      vocabulary.code_size() != header.code_size)
    layout.fail("the state was saved with a different vocabulary (" +
                describe_vocabulary(header.vocabulary_checksum, header.vocabulary_words,
                                    header.vocabulary_levels, header.code_size) +
                "); the given vocabulary has " +
                describe_vocabulary(vocabulary.checksum(), vocabulary.word_count(),
                                    vocabulary.levels(), vocabulary.code_size()));
  if (vocabulary.word_count() != header.vocabulary_words ||
      vocabulary.levels() != header.vocabulary_levels)
    layout.fail("the header describes a vocabulary of " + std::to_string(header.vocabulary_words) +
                " words and " + std::to_string(header.vocabulary_levels) +
                " levels; the one with its checksum has " +
                std::to_string(vocabulary.word_count()) + " words and " +
                std::to_string(vocabulary.levels()) + " levels");
  layout.expect_size(kOnlineVocabulary, 0);
  const binbow::detail::Section& database = layout.section(kDatabase);
  auto impl =
      std::make_unique<Impl>(Database::deserialize(database.data, database.size,
                                                   name + " (database)", std::move(vocabulary)),
                             layout.params(), header.code_size);
  return LoopDetector(restore(layout, std::move(impl), header.vocabulary_words));
}

LoopDetector LoopDetector::deserialize(const std::uint8_t* data, std::size_t size,
                                       const std::string& name) {
  const Layout layout(data, size, name);
  const Header& header = layout.header();
  if (!header.online)
    layout.fail("the state was saved with a fixed vocabulary (" +
                describe_vocabulary(header.vocabulary_checksum, header.vocabulary_words,
                                    header.vocabulary_levels, header.code_size) +
                "); load it with that vocabulary");
  const binbow::detail::Section& database = layout.section(kDatabase);
  auto impl = std::make_unique<Impl>(
      Database::deserialize(database.data, database.size, name + " (database)"), layout.params(),
      header.code_size);
  if (!impl->database.vocabulary().empty())
    layout.fail("the database of an online state has a vocabulary");
  const binbow::detail::Section& words = layout.section(kOnlineVocabulary);
  impl->online.emplace(
      OnlineVocabulary::deserialize(words.data, words.size, name + " (online vocabulary)"));
  if (impl->online->code_size() != header.code_size)
    layout.fail("the online vocabulary's descriptors have " +
                std::to_string(impl->online->code_size()) + " bytes, the state's " +
                std::to_string(header.code_size));
  if (impl->online->options().scoring != impl->database.scoring())
    layout.fail("the online vocabulary and the database score differently");
  if (impl->online->image_count() != header.featured_frames)
    layout.fail("the online vocabulary has seen " + std::to_string(impl->online->image_count()) +
                " images, the state " + std::to_string(header.featured_frames) +
                " frames with features");
  if (impl->online->options().descriptor != layout.descriptor())
    layout.fail("the online vocabulary's descriptor name disagrees with the state's");
  const std::uint64_t word_limit = impl->online->next_word_id();
  return LoopDetector(restore(layout, std::move(impl), word_limit));
}

LoopDetector LoopDetector::load(const std::string& path, Vocabulary vocabulary) {
  const binbow::detail::MappedFile file(path);
  return deserialize(file.data(), file.size(), path, std::move(vocabulary));
}

LoopDetector LoopDetector::load(const std::string& path) {
  const binbow::detail::MappedFile file(path);
  return deserialize(file.data(), file.size(), path);
}

LoopDetectorFileInfo LoopDetector::inspect(const std::string& path) {
  const binbow::detail::MappedFile file(path);
  const Layout layout(file.data(), file.size(), path);
  // A fixed vocabulary's word count is in the header; an online one's needs its section.
  if (!layout.header().online) read_previous_bow(layout, layout.header().vocabulary_words);
  return info_of(layout);
}

}  // namespace binbow::loop
