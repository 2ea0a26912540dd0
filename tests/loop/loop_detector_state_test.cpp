// The loop detector's saved state (.bbld): a run stopped, saved, loaded and
// resumed gives the same results as a run never stopped; the wrong
// vocabulary, damaged files and failed saves are refused cleanly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "binbow/error.h"
#include "binbow/loop/loop_detector.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "core/crc32c.h"
#include "core/little_endian.h"
#include "core/sectioned_file.h"
#include "loop/same_result.h"
#include "support/random_tree.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

using vision::Features;

// rtabmap-samples' 84 frames, extracted once per descriptor.
const std::vector<Features>& sample_features(const std::string& descriptor) {
  static std::map<std::string, std::vector<Features>> cache;
  std::vector<Features>& features = cache[descriptor];
  if (features.empty()) {
    const auto extractor = vision::make_extractor(descriptor);
    vision::ImageSource source({test::samples_folder()});
    vision::Frame frame;
    while (source.next(frame)) features.push_back(extractor->extract(frame.image));
  }
  return features;
}

using test::expect_same_result;

// Runs every frame without stopping, then again stopping after each of
// `stops` frames (save, load, resume), and compares every result.
template <class Make, class Load>
void expect_resume_equals_uninterrupted(const std::vector<Features>& frames, Make make, Load load,
                                        const std::vector<std::size_t>& stops) {
  ASSERT_EQ(frames.size(), 84u);
  LoopDetector uninterrupted = make();
  std::vector<LoopResult> expected;
  std::size_t loops = 0;
  for (const Features& f : frames) {
    expected.push_back(uninterrupted.process(f));
    loops += expected.back().detection() ? 1 : 0;
  }
  ASSERT_GT(loops, 10u) << "the sequence must close loops for the comparison to mean anything";

  test::TempDir dir;
  LoopDetector detector = make();
  std::size_t next = 0;
  for (std::size_t stop : stops) {
    for (; next < stop; ++next) expect_same_result(detector.process(frames[next]), expected[next]);
    const std::string path = dir.file("state_" + std::to_string(stop) + ".bbld");
    detector.save(path);
    const std::vector<std::uint8_t> saved = test::read_file(path);
    detector = load(path);
    ASSERT_EQ(detector.size(), stop);
    EXPECT_EQ(detector.serialize(), saved) << "a loaded state saves the same bytes";
  }
  for (; next < frames.size(); ++next)
    expect_same_result(detector.process(frames[next]), expected[next]);
}

std::string vocabulary_path(const std::string& name) {
  const std::string path = test::source_path("data/vocab/" + name);
  if (!std::filesystem::exists(path)) {
    ADD_FAILURE() << "the bundled vocabulary " << path << " is missing";
    throw std::runtime_error("missing " + path);
  }
  return path;
}

TEST(LoopDetectorState, FixedOrbVocabularyResumesExactly) {
  const Vocabulary vocabulary = Vocabulary::load(vocabulary_path("orb_default.bbw"));
  expect_resume_equals_uninterrupted(
      sample_features("orb"), [&] { return LoopDetector(vocabulary); },
      [&](const std::string& path) { return LoopDetector::load(path, vocabulary); },
      {1, 30, 55, 70});
}

// The acceptance test of saved online states: with the default options
// (approximate search) a resumed online detector continues exactly as the
// uninterrupted one, because the .bbov keeps the vocabulary's search trees.
OnlineVocabularyOptions default_options(const std::string& descriptor) {
  OnlineVocabularyOptions options;
  options.descriptor = descriptor;
  return options;
}

TEST(LoopDetectorState, OnlineOrbResumesExactly) {
  expect_resume_equals_uninterrupted(
      sample_features("orb"), [] { return LoopDetector::online(32, default_options("orb")); },
      [](const std::string& path) { return LoopDetector::load(path); }, {1, 25, 41, 50, 66, 80});
}

TEST(LoopDetectorState, OnlineBriefResumesExactly) {
  expect_resume_equals_uninterrupted(
      sample_features("brief"), [] { return LoopDetector::online(32, default_options("brief")); },
      [](const std::string& path) { return LoopDetector::load(path); }, {0, 17, 40, 60, 75});
}

// Exact search resumes exactly too.
TEST(LoopDetectorState, OnlineExactSearchResumesExactly) {
  OnlineVocabularyOptions options = default_options("orb");
  options.exact = true;
  expect_resume_equals_uninterrupted(
      sample_features("orb"), [&] { return LoopDetector::online(32, options); },
      [](const std::string& path) { return LoopDetector::load(path); }, {30, 62});
}

// A small online run (random images, each seen twice) for the file tests.
LoopDetector small_online_detector(std::size_t frames = 12) {
  std::mt19937_64 rng(4);
  LoopDetectorParams params;
  params.dislocal = 2;
  LoopDetector detector = LoopDetector::online(32, {}, params);
  std::vector<Features> places;
  for (std::size_t i = 0; i < frames; ++i) {
    Features f;
    f.descriptors = test::random_descriptors(i == 3 ? 0 : 20, 32, rng);
    for (std::size_t k = 0; k < f.descriptors.rows(); ++k)
      f.keypoints.push_back({float(k), float(2 * k), 7, 1, 1, 0});
    detector.process(f);
  }
  return detector;
}

TEST(LoopDetectorState, InspectSaysWhatToLoadItWith) {
  test::TempDir dir;
  const Vocabulary vocabulary = Vocabulary::load(vocabulary_path("orb_default.bbw"));
  LoopDetector fixed(vocabulary);
  for (std::size_t i = 0; i < 3; ++i) fixed.process(sample_features("orb")[i]);
  fixed.save(dir.file("fixed.bbld"));
  const LoopDetectorFileInfo info = LoopDetector::inspect(dir.file("fixed.bbld"));
  EXPECT_FALSE(info.online);
  EXPECT_EQ(info.frames, 3u);
  EXPECT_EQ(info.code_size, 32u);
  EXPECT_EQ(info.descriptor, vocabulary.descriptor());
  EXPECT_EQ(info.vocabulary_checksum, vocabulary.checksum());
  EXPECT_EQ(info.vocabulary_words, vocabulary.word_count());
  EXPECT_EQ(info.params.to_json(), fixed.params().to_json());

  small_online_detector().save(dir.file("online.bbld"));
  const LoopDetectorFileInfo online = LoopDetector::inspect(dir.file("online.bbld"));
  EXPECT_TRUE(online.online);
  EXPECT_EQ(online.frames, 12u);
  EXPECT_EQ(online.vocabulary_checksum, 0u);
}

std::string load_problem(const std::function<void()>& load) {
  try {
    load();
  } catch (const FileError& e) {
    return e.problem();
  }
  return "loaded";
}

TEST(LoopDetectorState, WrongVocabularyOrKindIsRefused) {
  test::TempDir dir;
  const Vocabulary orb = Vocabulary::load(vocabulary_path("orb_default.bbw"));
  const Vocabulary brief = Vocabulary::load(vocabulary_path("brief_default.bbw"));
  LoopDetector fixed(orb);
  fixed.process(sample_features("orb")[0]);
  const std::string fixed_path = dir.file("fixed.bbld");
  fixed.save(fixed_path);
  EXPECT_NE(load_problem([&] {
              LoopDetector::load(fixed_path, brief);
            }).find("saved with a different vocabulary"),
            std::string::npos);
  // Same tree, other scoring: another vocabulary for the scores.
  EXPECT_NE(load_problem([&] {
              LoopDetector::load(fixed_path, orb.with_scoring(Scoring::kL2));
            }).find("different vocabulary"),
            std::string::npos);
  EXPECT_NE(
      load_problem([&] { LoopDetector::load(fixed_path); }).find("load it with that vocabulary"),
      std::string::npos);
  EXPECT_EQ(load_problem([&] { LoopDetector::load(fixed_path, orb); }), "loaded");

  const std::string online_path = dir.file("online.bbld");
  small_online_detector().save(online_path);
  EXPECT_NE(load_problem([&] {
              LoopDetector::load(online_path, orb);
            }).find("load it without a vocabulary"),
            std::string::npos);
}

// The section table of a .bbld image: (offset, length) of each section.
std::vector<std::pair<std::size_t, std::size_t>> sections_of(const std::vector<std::uint8_t>& b) {
  const auto count = binbow::detail::load_le<std::uint32_t>(b.data() + 48);
  std::vector<std::pair<std::size_t, std::size_t>> sections;
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::uint8_t* entry = b.data() + 64 + 24 * i;
    sections.emplace_back(binbow::detail::load_le<std::uint64_t>(entry + 8),
                          binbow::detail::load_le<std::uint64_t>(entry + 16));
  }
  return sections;
}

// The same state in the layout of an older version (1 or 2): the sections
// before the latest loop, which must be empty.
std::vector<std::uint8_t> as_old_version(const std::vector<std::uint8_t>& bytes,
                                         std::uint32_t version) {
  const auto sections = sections_of(bytes);
  EXPECT_EQ(sections.size(), 9u);
  EXPECT_EQ(sections[8].second, 0u) << "an older version has no latest loop";
  std::vector<std::vector<std::uint8_t>> contents;
  for (std::size_t i = 0; i < 8; ++i)
    contents.emplace_back(
        bytes.begin() + static_cast<std::ptrdiff_t>(sections[i].first),
        bytes.begin() + static_cast<std::ptrdiff_t>(sections[i].first + sections[i].second));
  return binbow::detail::write_sectioned_file(
      "BINBOWLD", version, contents.data(), 8, [&](std::uint8_t* header) {
        std::copy(bytes.begin() + 16, bytes.begin() + 48, header + 16);
        std::copy(bytes.begin() + 52, bytes.begin() + 60, header + 52);
      });
}

TEST(LoopDetectorState, DamagedFilesAreRefused) {
  const Vocabulary orb = Vocabulary::load(vocabulary_path("orb_default.bbw"));
  LoopDetector fixed(orb);
  for (std::size_t i = 0; i < 4; ++i) fixed.process(sample_features("orb")[i]);
  struct Case {
    const char* name;
    std::vector<std::uint8_t> bytes;
    std::function<void(const std::vector<std::uint8_t>&)> load;
  };
  const std::vector<Case> cases = {
      {"online", small_online_detector().serialize(),
       [](const std::vector<std::uint8_t>& b) {
         LoopDetector::deserialize(b.data(), b.size(), "damaged.bbld");
       }},
      {"fixed", fixed.serialize(), [&](const std::vector<std::uint8_t>& b) {
         LoopDetector::deserialize(b.data(), b.size(), "damaged.bbld", orb);
       }}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::vector<std::uint8_t>& bytes = c.bytes;
    ASSERT_NO_THROW(c.load(bytes));
    const auto sections = sections_of(bytes);
    ASSERT_EQ(sections.size(), 9u);
    // A flipped byte at a few places of every section (all non-empty ones,
    // in the header and the table too).
    std::vector<std::size_t> places = {0, 9, 20, 30, 61, 64, 70, 64 + 24 * 9 + 1};
    for (const auto& [offset, length] : sections)
      for (std::size_t k = 0; k < 5 && length > 0; ++k) places.push_back(offset + k * length / 5);
    for (std::size_t at : places) {
      std::vector<std::uint8_t> flipped = bytes;
      flipped[at] ^= 0x5A;
      try {
        c.load(flipped);
        ADD_FAILURE() << "byte " << at << " flipped: loaded";
      } catch (const FileError& e) {
        EXPECT_EQ(e.path(), "damaged.bbld") << e.what();
      }
    }
    for (std::size_t size = 0; size < bytes.size(); size += 1 + size / 9) {
      const std::vector<std::uint8_t> truncated(bytes.begin(), bytes.begin() + size);
      EXPECT_THROW(c.load(truncated), FileError) << "truncated to " << size;
    }
    std::vector<std::uint8_t> longer = bytes;
    longer.push_back(0);
    EXPECT_THROW(c.load(longer), FileError);
  }
  // Other binbow files are not states.
  const std::vector<std::uint8_t> vocabulary_bytes = orb.serialize();
  EXPECT_NE(load_problem([&] {
              LoopDetector::deserialize(vocabulary_bytes.data(), vocabulary_bytes.size(), "v");
            }).find("not a binbow loop detector state"),
            std::string::npos);
}

// Content that passes every CRC (recomputed) but disagrees with itself: the
// direct index would make the geometric check read past a frame's features.
TEST(LoopDetectorState, InconsistentContentIsRefusedEvenWithValidChecksums) {
  const Vocabulary orb = Vocabulary::load(vocabulary_path("orb_default.bbw"));
  LoopDetector fixed(orb);
  for (std::size_t i = 0; i < 3; ++i) fixed.process(sample_features("orb")[i]);
  const std::vector<std::uint8_t> bytes = fixed.serialize();
  const auto sections = sections_of(bytes);
  const auto rewritten = [&](std::size_t section, const std::function<void(std::uint8_t*)>& edit) {
    std::vector<std::uint8_t> out = bytes;
    const auto [offset, length] = sections[section];
    edit(out.data() + offset);
    std::uint8_t* entry = out.data() + 64 + 24 * section;
    binbow::detail::store_le<std::uint32_t>(entry + 4,
                                            binbow::detail::crc32c(out.data() + offset, length));
    binbow::detail::store_le<std::uint32_t>(
        out.data() + 64 + 24 * sections.size(),
        binbow::detail::crc32c(out.data() + 64, 24 * sections.size()));
    return out;
  };
  const auto problem = [&](const std::vector<std::uint8_t>& data) {
    return load_problem(
        [&] { LoopDetector::deserialize(data.data(), data.size(), "crafted.bbld", orb); });
  };
  ASSERT_EQ(problem(rewritten(5, [](std::uint8_t*) {})), "loaded");
  // Ten features moved from frame 0 to frame 1: the same total.
  const auto moved = rewritten(5, [](std::uint8_t* counts) {
    binbow::detail::store_le<std::uint32_t>(counts,
                                            binbow::detail::load_le<std::uint32_t>(counts) - 10);
    binbow::detail::store_le<std::uint32_t>(
        counts + 4, binbow::detail::load_le<std::uint32_t>(counts + 4) + 10);
  });
  EXPECT_NE(problem(moved).find("direct index of frame 0"), std::string::npos) << problem(moved);
  // A keypoint at NaN.
  const auto nan = rewritten(6, [](std::uint8_t* keypoints) {
    binbow::detail::store_le<float>(keypoints, std::numeric_limits<float>::quiet_NaN());
  });
  EXPECT_NE(problem(nan).find("non-finite"), std::string::npos) << problem(nan);
  // The previous BoW vector out of order.
  const auto unsorted = rewritten(
      2, [](std::uint8_t* bow) { binbow::detail::store_le<std::uint32_t>(bow, 0xFFFFFFF0u); });
  EXPECT_NE(problem(unsorted).find("previous BoW vector"), std::string::npos) << problem(unsorted);
  // Parameters out of range go through LoopDetectorParams' own validation.
  const auto params = rewritten(0, [](std::uint8_t* json) {
    const std::string text(reinterpret_cast<char*>(json), 20);
    const std::size_t at = text.find('{');
    json[at] = '[';
  });
  EXPECT_NE(problem(params), "loaded");
}

// Forgotten frames (version 2): the header's count must be the database's
// removed entries, which hold no features; version 1 has none (and loads).
TEST(LoopDetectorState, ForgottenFramesAreChecked) {
  const Vocabulary orb = Vocabulary::load(vocabulary_path("orb_default.bbw"));
  LoopDetector fixed(orb);
  for (std::size_t i = 0; i < 4; ++i) fixed.process(sample_features("orb")[i]);
  const std::vector<std::uint8_t> whole = fixed.serialize();
  fixed.forget(1);
  const std::vector<std::uint8_t> bytes = fixed.serialize();
  const auto problem = [&](const std::vector<std::uint8_t>& data) {
    return load_problem(
        [&] { LoopDetector::deserialize(data.data(), data.size(), "crafted.bbld", orb); });
  };
  ASSERT_EQ(problem(bytes), "loaded");
  EXPECT_EQ(binbow::detail::load_le<std::uint32_t>(bytes.data() + 8), 3u);
  EXPECT_EQ(binbow::detail::load_le<std::uint32_t>(bytes.data() + 44), 1u);
  const auto header = [](std::vector<std::uint8_t> b, std::size_t at, std::uint32_t value) {
    binbow::detail::store_le<std::uint32_t>(b.data() + at, value);
    binbow::detail::store_le<std::uint32_t>(b.data() + 60, binbow::detail::crc32c(b.data(), 60));
    return b;
  };
  EXPECT_NE(problem(header(bytes, 44, 0)).find("of which 0 forgotten"), std::string::npos)
      << problem(header(bytes, 44, 0));
  EXPECT_NE(problem(header(bytes, 44, 2)).find("of which 2 forgotten"), std::string::npos);
  EXPECT_NE(problem(header(bytes, 44, 5)).find("inconsistent frame counts"), std::string::npos);
  EXPECT_NE(problem(header(bytes, 8, 1)).find("reserved header bytes"), std::string::npos);
  EXPECT_NE(problem(header(bytes, 8, 4)).find("unsupported .bbld format version 4"),
            std::string::npos);
  EXPECT_NE(problem(header(bytes, 8, 2)).find("expected 8 sections"), std::string::npos);
  // Versions 1 (no forgotten frames) and 2 (no latest loop) load, and are
  // saved again as version 3.
  const std::vector<std::uint8_t> version2 = as_old_version(bytes, 2);
  ASSERT_EQ(problem(version2), "loaded");
  EXPECT_EQ(LoopDetector::deserialize(version2.data(), version2.size(), "v2", orb).serialize(),
            bytes);
  const std::vector<std::uint8_t> version1 = as_old_version(whole, 1);
  ASSERT_EQ(problem(version1), "loaded");
  EXPECT_EQ(LoopDetector::deserialize(version1.data(), version1.size(), "v1", orb).serialize(),
            whole);
  // The forgotten frame given ten features of frame 0 (CRCs recomputed).
  const auto sections = sections_of(bytes);
  std::vector<std::uint8_t> moved = bytes;
  std::uint8_t* counts = moved.data() + sections[5].first;
  binbow::detail::store_le<std::uint32_t>(counts,
                                          binbow::detail::load_le<std::uint32_t>(counts) - 10);
  binbow::detail::store_le<std::uint32_t>(counts + 4, 10);
  std::uint8_t* entry = moved.data() + 64 + 24 * 5;
  binbow::detail::store_le<std::uint32_t>(entry + 4, binbow::detail::crc32c(counts, 16));
  binbow::detail::store_le<std::uint32_t>(
      moved.data() + 64 + 24 * sections.size(),
      binbow::detail::crc32c(moved.data() + 64, 24 * sections.size()));
  EXPECT_NE(problem(moved).find("forgotten frame 1 has features"), std::string::npos)
      << problem(moved);
}

// The latest loop (version 3) decides whether the next weak loops are
// corroborated: it is saved, and a file naming frames that do not exist is
// refused.
TEST(LoopDetectorState, LatestLoopIsSavedAndChecked) {
  const Vocabulary orb = Vocabulary::load(vocabulary_path("orb_default.bbw"));
  LoopDetector fixed(orb);
  LoopResult last_loop;
  for (std::size_t i = 0; i < 50; ++i) {
    LoopResult r = fixed.process(sample_features("orb")[i]);
    if (r.detection()) last_loop = r;
  }
  ASSERT_TRUE(last_loop.detection());
  const std::vector<std::uint8_t> bytes = fixed.serialize();
  const auto sections = sections_of(bytes);
  ASSERT_EQ(sections.size(), 9u);
  ASSERT_EQ(sections[8].second, 8u);
  EXPECT_EQ(binbow::detail::load_le<std::uint32_t>(bytes.data() + sections[8].first),
            last_loop.query);
  EXPECT_EQ(binbow::detail::load_le<std::uint32_t>(bytes.data() + sections[8].first + 4),
            last_loop.match);
  const auto with_loop = [&](std::uint32_t query, std::uint32_t match) {
    std::vector<std::uint8_t> out = bytes;
    std::uint8_t* at = out.data() + sections[8].first;
    binbow::detail::store_le<std::uint32_t>(at, query);
    binbow::detail::store_le<std::uint32_t>(at + 4, match);
    binbow::detail::store_le<std::uint32_t>(out.data() + 64 + 24 * 8 + 4,
                                            binbow::detail::crc32c(at, 8));
    binbow::detail::store_le<std::uint32_t>(out.data() + 64 + 24 * 9,
                                            binbow::detail::crc32c(out.data() + 64, 24 * 9));
    return load_problem([&] { LoopDetector::deserialize(out.data(), out.size(), "crafted", orb); });
  };
  EXPECT_EQ(with_loop(last_loop.query, last_loop.match), "loaded");
  EXPECT_NE(with_loop(50, 3).find("latest loop names frames"), std::string::npos);
  EXPECT_NE(with_loop(40, 40).find("latest loop names frames"), std::string::npos);
}

// A state saved before corroboration_horizon and corroboration_pace_tolerance
// existed has neither key among its parameters: it resumes with their
// defaults, the horizon scaled to the state's frequency as the others are.
TEST(LoopDetectorState, ParametersSavedBeforeThePaceRuleResumeWithItsDefaults) {
  LoopDetectorParams params = LoopDetectorParams::for_frequency(2);
  params.dislocal = 2;
  params.corroboration_horizon = 3;
  params.corroboration_pace_tolerance = 0.5;
  LoopDetector detector = LoopDetector::online(32, {}, params);
  std::mt19937_64 rng(5);
  for (int i = 0; i < 6; ++i) {
    Features f;
    f.descriptors = test::random_descriptors(20, 32, rng);
    for (std::size_t k = 0; k < f.descriptors.rows(); ++k)
      f.keypoints.push_back({float(k), float(3 * k), 7, 1, 1, 0});
    detector.process(f);
  }
  const std::vector<std::uint8_t> bytes = detector.serialize();
  const auto sections = sections_of(bytes);
  std::vector<std::vector<std::uint8_t>> contents;
  for (const auto& [offset, length] : sections)
    contents.emplace_back(bytes.begin() + static_cast<std::ptrdiff_t>(offset),
                          bytes.begin() + static_cast<std::ptrdiff_t>(offset + length));
  std::string text(contents[0].begin(), contents[0].end());
  for (const std::string key : {"corroboration_horizon", "corroboration_pace_tolerance"}) {
    const std::size_t at = text.find("\"" + key + "\"");
    ASSERT_NE(at, std::string::npos) << text;
    const std::size_t line = text.rfind('\n', at);
    text.erase(line, text.find('\n', at) - line);
  }
  const std::size_t dangling = text.rfind(",\n}");
  if (dangling != std::string::npos) text.erase(dangling, 1);
  contents[0].assign(text.begin(), text.end());
  const std::vector<std::uint8_t> old = binbow::detail::write_sectioned_file(
      "BINBOWLD", 3, contents.data(), contents.size(), [&](std::uint8_t* header) {
        std::copy(bytes.begin() + 16, bytes.begin() + 48, header + 16);
        std::copy(bytes.begin() + 52, bytes.begin() + 60, header + 52);
      });
  const LoopDetector resumed = LoopDetector::deserialize(old.data(), old.size(), "old");
  EXPECT_EQ(resumed.params().corroboration_horizon, 20);
  EXPECT_DOUBLE_EQ(resumed.params().corroboration_pace_tolerance, 0.25);
  EXPECT_EQ(resumed.params().dislocal, 2);
  EXPECT_EQ(resumed.size(), 6u);
}

TEST(LoopDetectorState, FeaturelessAndNoGeometricCheckStatesRoundTrip) {
  // kNone keeps no features: the file has none and the detector still resumes.
  LoopDetectorParams params;
  params.geometric_check = GeometricCheck::kNone;
  params.dislocal = 2;
  std::mt19937_64 rng(8);
  std::vector<Features> frames;
  for (int i = 0; i < 16; ++i) {
    Features f;
    f.descriptors = test::random_descriptors(i % 5 == 2 ? 0 : 30, 32, rng);
    f.keypoints.resize(f.descriptors.rows());
    frames.push_back(i >= 8 ? frames[i - 8] : f);
  }
  LoopDetector uninterrupted = LoopDetector::online(32, {}, params);
  std::vector<LoopResult> expected;
  for (const Features& f : frames) expected.push_back(uninterrupted.process(f));
  LoopDetector first = LoopDetector::online(32, {}, params);
  for (int i = 0; i < 9; ++i) first.process(frames[i]);
  const std::vector<std::uint8_t> bytes = first.serialize();
  LoopDetector resumed = LoopDetector::deserialize(bytes.data(), bytes.size(), "memory");
  EXPECT_EQ(resumed.keypoints(3).size(), 0u);
  for (std::size_t i = 9; i < frames.size(); ++i)
    expect_same_result(resumed.process(frames[i]), expected[i]);
}

TEST(LoopDetectorState, SaveIsAtomic) {
  test::TempDir dir;
  const LoopDetector detector = small_online_detector();
  // Over a folder: refused, nothing created.
  std::filesystem::create_directories(dir.file("state.bbld/inside"));
  EXPECT_THROW(detector.save(dir.file("state.bbld")), FileError);
  std::size_t entries = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    EXPECT_EQ(entry.path().filename(), "state.bbld");
    ++entries;
  }
  EXPECT_EQ(entries, 1u);
  // A good save replaces an old state whole.
  detector.save(dir.file("good.bbld"));
  small_online_detector(5).save(dir.file("good.bbld"));
  EXPECT_EQ(LoopDetector::load(dir.file("good.bbld")).size(), 5u);
  // Into missing folders: they are made.
  detector.save(dir.file("new/folder/state.bbld"));
  EXPECT_EQ(LoopDetector::load(dir.file("new/folder/state.bbld")).size(), detector.size());
}

// The bytes of a .bbld image with section `section` edited and every CRC
// recomputed: content that passes the checksums but not the checks.
std::vector<std::uint8_t> with_section_edited(
    const std::vector<std::uint8_t>& bytes, std::size_t section,
    const std::function<void(std::uint8_t*, std::size_t)>& edit) {
  std::vector<std::uint8_t> out = bytes;
  const auto sections = sections_of(bytes);
  const auto [offset, length] = sections[section];
  edit(out.data() + offset, length);
  std::uint8_t* entry = out.data() + 64 + 24 * section;
  binbow::detail::store_le<std::uint32_t>(entry + 4,
                                          binbow::detail::crc32c(out.data() + offset, length));
  binbow::detail::store_le<std::uint32_t>(
      out.data() + 64 + 24 * sections.size(),
      binbow::detail::crc32c(out.data() + 64, 24 * sections.size()));
  return out;
}

// The last word of the previous BoW vector moved to 4294967280, still in
// order: that word scores nothing, so a resumed run would lose the
// normalisation score of its next frame.
std::vector<std::uint8_t> with_previous_bow_word_outside(const std::vector<std::uint8_t>& bytes) {
  return with_section_edited(bytes, 2, [](std::uint8_t* bow, std::size_t length) {
    EXPECT_GE(length, 8u) << "no previous BoW vector to damage";
    if (length >= 8) binbow::detail::store_le<std::uint32_t>(bow + length - 8, 4294967280u);
  });
}

TEST(LoopDetectorState, PreviousBowWordsOutsideTheVocabularyAreRefused) {
  test::TempDir dir;
  const Vocabulary orb = Vocabulary::load(vocabulary_path("orb_default.bbw"));
  LoopDetector fixed(orb);
  for (std::size_t i = 0; i < 3; ++i) fixed.process(sample_features("orb")[i]);
  const std::vector<std::uint8_t> fixed_bytes = with_previous_bow_word_outside(fixed.serialize());
  EXPECT_NE(load_problem([&] {
              LoopDetector::deserialize(fixed_bytes.data(), fixed_bytes.size(), "f.bbld", orb);
            }).find("previous BoW vector names word 4294967280"),
            std::string::npos);
  // inspect() knows the fixed vocabulary's word count from the header.
  test::write_file(dir.file("fixed.bbld"), fixed_bytes);
  EXPECT_NE(
      load_problem([&] { LoopDetector::inspect(dir.file("fixed.bbld")); }).find("word 4294967280"),
      std::string::npos);

  const std::vector<std::uint8_t> online_bytes =
      with_previous_bow_word_outside(small_online_detector().serialize());
  EXPECT_NE(load_problem([&] {
              LoopDetector::deserialize(online_bytes.data(), online_bytes.size(), "o.bbld");
            }).find("previous BoW vector names word 4294967280"),
            std::string::npos);
}

// `binbow info` on a state checks what --resume-state checks: the whole
// file, loaded (a fixed vocabulary's state with --vocab, or the bundled
// vocabulary of its descriptor when it is the state's).
TEST(LoopDetectorState, InfoRefusesWhatResumeRefuses) {
  test::TempDir dir;
  const Vocabulary orb = Vocabulary::load(vocabulary_path("orb_default.bbw"));
  LoopDetector fixed(orb);
  for (std::size_t i = 0; i < 3; ++i) fixed.process(sample_features("orb")[i]);
  // Ten features moved from frame 0 to frame 1: every CRC valid, the
  // direct index of frame 0 then names features frame 0 no longer has.
  const auto moved = [](const std::vector<std::uint8_t>& bytes) {
    return with_section_edited(bytes, 5, [](std::uint8_t* counts, std::size_t) {
      binbow::detail::store_le<std::uint32_t>(counts,
                                              binbow::detail::load_le<std::uint32_t>(counts) - 10);
      binbow::detail::store_le<std::uint32_t>(
          counts + 4, binbow::detail::load_le<std::uint32_t>(counts + 4) + 10);
    });
  };
  const std::string vocab = " --vocab '" + vocabulary_path("orb_default.bbw") + "'";
  std::string out;
  for (const std::string kind : {"fixed", "online"}) {
    SCOPED_TRACE(kind);
    const std::vector<std::uint8_t> good =
        kind == "fixed" ? fixed.serialize() : small_online_detector().serialize();
    const std::string path = dir.file(kind + ".bbld");
    test::write_file(path, good);
    ASSERT_EQ(test::run_cli("info '" + path + "'", &out), 0) << out;
    EXPECT_EQ(out.find("note:"), std::string::npos) << out;
    test::write_file(path, moved(good));
    ASSERT_NO_THROW(LoopDetector::inspect(path)) << "the header alone is intact";
    EXPECT_EQ(test::run_cli("info '" + path + "'", &out), 1) << out;
    EXPECT_NE(out.find("binbow: error: " + path + ": the direct index of frame 0"),
              std::string::npos)
        << out;
    if (kind == "fixed") {
      EXPECT_EQ(test::run_cli("info '" + path + "'" + vocab, &out), 1) << out;
      EXPECT_NE(out.find("the direct index of frame 0"), std::string::npos) << out;
    }
  }
  // A vocabulary binbow does not bundle: info checks what it can without it
  // and says what it could not; given it, checks everything.
  std::mt19937_64 rng(5);
  const Vocabulary own = Vocabulary::from_tree(test::random_tree(4, 3, 32, rng));
  own.save(dir.file("own.bbw"));
  LoopDetector own_detector(own);
  for (std::size_t i = 0; i < 3; ++i) own_detector.process(sample_features("orb")[i]);
  own_detector.save(dir.file("own.bbld"));
  ASSERT_EQ(test::run_cli("info '" + dir.file("own.bbld") + "'", &out), 0) << out;
  EXPECT_NE(out.find("note: " + dir.file("own.bbld") +
                     ": the header, the parameters and the "
                     "previous BoW vector are checked"),
            std::string::npos)
      << out;
  ASSERT_EQ(test::run_cli(
                "info '" + dir.file("own.bbld") + "' --vocab '" + dir.file("own.bbw") + "'", &out),
            0)
      << out;
  EXPECT_EQ(out.find("note:"), std::string::npos) << out;
  // Given the wrong vocabulary, info refuses as resume does.
  test::write_file(dir.file("fixed.bbld"), fixed.serialize());
  EXPECT_EQ(test::run_cli("info '" + dir.file("fixed.bbld") + "' --vocab '" +
                              vocabulary_path("brief_default.bbw") + "'",
                          &out),
            1)
      << out;
}

}  // namespace
}  // namespace binbow::loop
