// Keyframe culling (LoopDetector::forget) on the real corridor sequence: a
// forgotten frame is never proposed again, the detector keeps finding the
// other loops, the state file keeps it forgotten, and its memory goes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "binbow/error.h"
#include "binbow/loop/evaluation.h"
#include "binbow/loop/loop_detector.h"
#include "binbow/loop/similarity.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "loop/same_result.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

using vision::Features;

constexpr std::size_t kFrames = 84;

std::string repository_file(const std::string& relative) {
  const std::string path = test::source_path(relative);
  if (!std::filesystem::exists(path)) {
    ADD_FAILURE() << path << " is missing";
    throw std::runtime_error("missing " + path);
  }
  return path;
}

// data/samples/rtabmap's 84 frames, ORB features extracted once.
const std::vector<Features>& corridor() {
  static const std::vector<Features> frames = [] {
    const auto extractor = vision::make_extractor("orb");
    vision::ImageSource source({repository_file("data/samples/rtabmap/samples")});
    std::vector<Features> out;
    vision::Frame frame;
    while (source.next(frame)) out.push_back(extractor->extract(frame.image));
    return out;
  }();
  EXPECT_EQ(frames.size(), kFrames);
  return frames;
}

const GroundTruth& ground_truth() {
  static const GroundTruth truth =
      GroundTruth::load(repository_file("data/samples/rtabmap/samples_GT_pairs.txt"));
  return truth;
}

const Vocabulary& orb_vocabulary() {
  static const Vocabulary vocabulary =
      Vocabulary::load(repository_file("data/vocab/orb_default.bbw"));
  return vocabulary;
}

OnlineVocabularyOptions online_orb() {
  OnlineVocabularyOptions options;
  options.descriptor = "orb";
  return options;
}

using test::expect_same_result;

std::vector<LoopResult> run_all(LoopDetector detector) {
  std::vector<LoopResult> results;
  for (const Features& f : corridor()) results.push_back(detector.process(f));
  return results;
}

// The frames matched by the detections of queries in [first, last).
std::set<EntryId> matched_frames(const std::vector<LoopResult>& results, std::size_t first,
                                 std::size_t last) {
  std::set<EntryId> matched;
  for (std::size_t t = first; t < last; ++t)
    if (results[t].detection()) matched.insert(results[t].match);
  return matched;
}

// A result names a frame as a candidate through its match (islands are id
// ranges whose members are candidates: the match is their best one).
void expect_never_proposed(const LoopResult& r, const std::set<EntryId>& forgotten) {
  if (r.has_candidate) {
    EXPECT_EQ(forgotten.count(r.match), 0u) << "frame " << r.query << " proposed " << r.match;
  }
}

std::size_t true_detections(const std::vector<LoopResult>& results, std::size_t first) {
  std::size_t found = 0;
  for (std::size_t t = first; t < results.size(); ++t)
    if (results[t].detection()) {
      EXPECT_TRUE(ground_truth().is_loop(t, results[t].match))
          << "false loop " << t << " -> " << results[t].match;
      ++found;
    }
  return found;
}

// Culling the frames the loops so far matched, mid-run: later frames never
// name them, though the detector that keeps them does, and the other frames
// of those places still close loops (without a false one).
TEST(LoopDetectorForget, ForgottenMatchesAreNeverProposedAgain) {
  const std::vector<LoopResult> reference = run_all(LoopDetector(orb_vocabulary()));
  constexpr std::size_t kCull = 60;
  const std::set<EntryId> culled = matched_frames(reference, 0, kCull);
  ASSERT_GE(culled.size(), 3u);
  std::size_t reference_proposals = 0;
  for (std::size_t t = kCull; t < kFrames; ++t)
    reference_proposals += reference[t].has_candidate && culled.count(reference[t].match);
  ASSERT_GT(reference_proposals, 0u) << "without forget(), later frames propose the culled ones";

  LoopDetector detector(orb_vocabulary());
  std::vector<LoopResult> results;
  for (std::size_t t = 0; t < kCull; ++t) results.push_back(detector.process(corridor()[t]));
  for (EntryId frame : culled) detector.forget(frame);
  EXPECT_EQ(detector.forgotten_count(), culled.size());
  EXPECT_EQ(detector.size(), kCull);
  for (std::size_t t = kCull; t < kFrames; ++t) {
    results.push_back(detector.process(corridor()[t]));
    EXPECT_EQ(results.back().query, t) << "ids are not reused";
    expect_never_proposed(results.back(), culled);
  }
  EXPECT_GT(true_detections(results, kCull), 5u);
}

// Every second frame the loops of the whole run matched, culled as soon as
// it is processed (a keyframe judged redundant at once): none is ever
// proposed, and loops are still closed through the others, all true.
TEST(LoopDetectorForget, FramesForgottenAtOnceAreNeverProposed) {
  for (const bool online : {false, true}) {
    SCOPED_TRACE(online ? "online" : "fixed");
    const auto make = [&] {
      return online ? LoopDetector::online(32, online_orb()) : LoopDetector(orb_vocabulary());
    };
    const std::vector<LoopResult> reference = run_all(make());
    std::set<EntryId> culled;
    bool cull = true;
    for (EntryId frame : matched_frames(reference, 0, kFrames)) {
      if (cull) culled.insert(frame);
      cull = !cull;
    }
    ASSERT_GE(culled.size(), 5u);
    LoopDetector detector = make();
    std::vector<LoopResult> results;
    for (std::size_t t = 0; t < kFrames; ++t) {
      results.push_back(detector.process(corridor()[t]));
      expect_never_proposed(results.back(), culled);
      if (culled.count(static_cast<EntryId>(t))) detector.forget(static_cast<EntryId>(t));
    }
    EXPECT_GT(true_detections(results, 0), 5u);
  }
}

// Until a frame is old enough to be a candidate (query t > frame +
// dislocal), when it is forgotten makes no difference: the results are
// those of a detector that never had it as a candidate.
TEST(LoopDetectorForget, ForgettingBeforeItCanMatchEqualsForgettingAtOnce) {
  const std::vector<LoopResult> reference = run_all(LoopDetector(orb_vocabulary()));
  const std::set<EntryId> culled = matched_frames(reference, 0, kFrames);
  LoopDetector at_once(orb_vocabulary());
  LoopDetector late(orb_vocabulary());
  const auto dislocal = static_cast<std::size_t>(late.params().dislocal);
  std::size_t differences_from_reference = 0;
  for (std::size_t t = 0; t < kFrames; ++t) {
    // The last moment: before the first query that could propose the frame.
    if (t > dislocal && culled.count(static_cast<EntryId>(t - dislocal - 1)))
      late.forget(static_cast<EntryId>(t - dislocal - 1));
    const LoopResult a = at_once.process(corridor()[t]);
    const LoopResult b = late.process(corridor()[t]);
    expect_same_result(a, b);
    differences_from_reference += a.match != reference[t].match || a.status != reference[t].status;
    if (culled.count(static_cast<EntryId>(t))) at_once.forget(static_cast<EntryId>(t));
  }
  EXPECT_GT(differences_from_reference, 0u) << "forgetting changed nothing: the test is vacuous";
}

// Forget, save, load, continue = forget, continue: the file keeps the
// forgotten frames forgotten and the rest of the state exact. Culled here:
// the matches so far, the latest frame (what the next η divides by) and the
// frames of the last island (the temporal chain's), for fixed, online and
// no-geometric-check detectors.
TEST(LoopDetectorForget, SavedStateKeepsFramesForgotten) {
  LoopDetectorParams no_check;
  no_check.geometric_check = GeometricCheck::kNone;
  struct Case {
    const char* name;
    std::function<LoopDetector()> make;
    std::function<LoopDetector(const std::string&)> load;
  };
  const std::vector<Case> cases = {
      {"fixed", [] { return LoopDetector(orb_vocabulary()); },
       [](const std::string& path) { return LoopDetector::load(path, orb_vocabulary()); }},
      {"online", [] { return LoopDetector::online(32, online_orb()); },
       [](const std::string& path) { return LoopDetector::load(path); }},
      {"no geometric check", [&] { return LoopDetector(orb_vocabulary(), no_check); },
       [](const std::string& path) { return LoopDetector::load(path, orb_vocabulary()); }},
  };
  test::TempDir dir;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::vector<LoopResult> reference = run_all(c.make());
    // A stop inside a temporal chain, with an island to cull from.
    std::size_t stop = 50;
    while (stop < kFrames - 10 && reference[stop - 1].consistent_queries < 2) ++stop;
    ASSERT_GE(reference[stop - 1].consistent_queries, 2);
    std::set<EntryId> culled = matched_frames(reference, 0, stop);
    for (EntryId e = reference[stop - 1].island_first; e <= reference[stop - 1].island_last; ++e)
      culled.insert(e);
    culled.insert(static_cast<EntryId>(stop - 1));

    LoopDetector continued = c.make();
    for (std::size_t t = 0; t < stop; ++t) continued.process(corridor()[t]);
    const std::vector<std::uint8_t> before = continued.serialize();
    for (EntryId frame : culled) continued.forget(frame);
    const std::string path = dir.file(std::string(c.name) + ".bbld");
    continued.save(path);
    const LoopDetectorFileInfo info = LoopDetector::inspect(path);
    EXPECT_EQ(info.version, 3u);
    EXPECT_EQ(info.frames, stop);
    EXPECT_EQ(info.forgotten_frames, culled.size());

    LoopDetector resumed = c.load(path);
    EXPECT_EQ(resumed.serialize(), test::read_file(path)) << "a loaded state saves the same bytes";
    EXPECT_LT(resumed.serialize().size(), before.size());
    EXPECT_EQ(resumed.size(), stop);
    EXPECT_EQ(resumed.forgotten_count(), culled.size());
    for (EntryId frame = 0; frame < stop; ++frame)
      EXPECT_EQ(resumed.is_forgotten(frame), culled.count(frame) == 1) << frame;
    std::size_t proposals = 0;
    for (std::size_t t = stop; t < kFrames; ++t) {
      const LoopResult a = continued.process(corridor()[t]);
      const LoopResult b = resumed.process(corridor()[t]);
      expect_same_result(a, b);
      expect_never_proposed(a, culled);
      proposals += reference[t].has_candidate && culled.count(reference[t].match);
    }
    EXPECT_GT(proposals, 0u) << "the culled frames would have been proposed";
  }
}

// The CLI resumes such a state (--resume-state) as the library does, never
// naming a forgotten frame, and `binbow info` counts them.
TEST(LoopDetectorForget, CliResumesAStateWithForgottenFrames) {
  const std::vector<LoopResult> reference = run_all(LoopDetector(orb_vocabulary()));
  constexpr std::size_t kStop = 50;
  const std::set<EntryId> culled = matched_frames(reference, 0, kStop);
  LoopDetector detector(orb_vocabulary());
  for (std::size_t t = 0; t < kStop; ++t) detector.process(corridor()[t]);
  for (EntryId frame : culled) detector.forget(frame);
  test::TempDir dir;
  const std::string state = dir.file("culled.bbld");
  detector.save(state);
  std::vector<std::pair<std::size_t, std::size_t>> expected;
  for (std::size_t t = kStop; t < kFrames; ++t) {
    const LoopResult r = detector.process(corridor()[t]);
    if (r.detection()) expected.emplace_back(r.query, r.match);
  }
  ASSERT_GT(expected.size(), 5u);

  const std::string list = dir.file("rest.txt");
  {
    std::ofstream out(list);
    for (std::size_t t = kStop; t < kFrames; ++t)
      out << repository_file("data/samples/rtabmap/samples/" + std::to_string(t + 1) + ".jpg")
          << "\n";
  }
  const std::string cli = test::cli_path();
  std::string output;
  ASSERT_EQ(test::run_command(cli + " info '" + state + "'", &output), 0) << output;
  EXPECT_NE(output.find("version: 3\n"), std::string::npos) << output;
  EXPECT_NE(output.find("forgotten_frames: " + std::to_string(culled.size()) + "\n"),
            std::string::npos)
      << output;
  ASSERT_EQ(
      test::run_command(cli + " detect-loops --vocab '" +
                            repository_file("data/vocab/orb_default.bbw") + "' --resume-state '" +
                            state + "' -o '" + dir.file("loops.csv") + "' '" + list + "'",
                        &output),
      0)
      << output;
  std::ifstream csv(dir.file("loops.csv"));
  std::string line;
  std::getline(csv, line);  // header
  std::vector<std::pair<std::size_t, std::size_t>> found;
  while (std::getline(csv, line)) {
    const std::size_t comma = line.find(',');
    found.emplace_back(std::stoul(line.substr(0, comma)), std::stoul(line.substr(comma + 1)));
    EXPECT_EQ(culled.count(static_cast<EntryId>(found.back().second)), 0u) << line;
  }
  EXPECT_EQ(found, expected);
}

// What the image was to the sequence stays: forgetting changes neither the
// temporal chain, nor the BoW vector the next η divides by, nor the count of
// frames with features (the time axis); it removes the frame's features.
TEST(LoopDetectorForget, TemporalStateIsKept) {
  LoopDetector detector(orb_vocabulary());
  const std::vector<LoopResult> reference = run_all(LoopDetector(orb_vocabulary()));
  std::size_t stop = 50;
  while (reference[stop - 1].consistent_queries < 2) ++stop;
  for (std::size_t t = 0; t < stop; ++t) detector.process(corridor()[t]);
  const std::vector<std::uint8_t> before = detector.serialize();
  for (EntryId e = reference[stop - 1].island_first; e <= reference[stop - 1].island_last; ++e)
    detector.forget(e);
  detector.forget(static_cast<EntryId>(stop - 1));
  const std::vector<std::uint8_t> after = detector.serialize();
  // Header bytes 24..31 (frames, frames with features) and sections 1 and 2
  // (temporal state, previous BoW vector), found through the section table.
  EXPECT_TRUE(std::equal(before.begin() + 24, before.begin() + 32, after.begin() + 24));
  const auto section = [](const std::vector<std::uint8_t>& b, std::size_t i) {
    const std::uint8_t* entry = b.data() + 64 + 24 * i;
    std::uint64_t offset = 0, length = 0;
    std::memcpy(&offset, entry + 8, 8);
    std::memcpy(&length, entry + 16, 8);
    return std::vector<std::uint8_t>(b.begin() + static_cast<std::ptrdiff_t>(offset),
                                     b.begin() + static_cast<std::ptrdiff_t>(offset + length));
  };
  EXPECT_EQ(section(before, 1), section(after, 1));
  EXPECT_EQ(section(before, 2), section(after, 2));
  EXPECT_LT(section(after, 6).size(), section(before, 6).size());
  // The next frame is normalised by the forgotten latest one, as before.
  const LoopResult next = detector.process(corridor()[stop]);
  ASSERT_TRUE(next.has_candidate);
  EXPECT_EQ(next.normalisation_score, reference[stop].normalisation_score);
}

TEST(LoopDetectorForget, ForgettingEveryFrameLeavesNothingToMatch) {
  LoopDetector detector(orb_vocabulary());
  for (std::size_t t = 0; t < kFrames; ++t) {
    const LoopResult r = detector.process(corridor()[t]);
    EXPECT_FALSE(r.detection());
    EXPECT_FALSE(r.has_candidate);
    EXPECT_EQ(r.status, LoopStatus::kNoDatabaseResults);
    detector.forget(static_cast<EntryId>(t));
  }
  EXPECT_EQ(detector.size(), kFrames);
  EXPECT_EQ(detector.forgotten_count(), kFrames);
  EXPECT_EQ(detector.database().size(), 0u);

  // Everything so far forgotten at once, mid-run: no later frame names one.
  LoopDetector culled(orb_vocabulary());
  for (std::size_t t = 0; t < 50; ++t) culled.process(corridor()[t]);
  for (EntryId e = 0; e < 50; ++e) culled.forget(e);
  for (std::size_t t = 50; t < kFrames; ++t) {
    const LoopResult r = culled.process(corridor()[t]);
    EXPECT_FALSE(r.has_candidate && r.match < 50) << t << " -> " << r.match;
  }
}

// A frame never processed is a caller bug; a forgotten one may be forgotten
// again (culling passes overlap), and its features and label are gone.
TEST(LoopDetectorForget, UnknownFramesAreRefusedForgottenOnesIgnored) {
  LoopDetector detector(orb_vocabulary());
  for (std::size_t t = 0; t < 5; ++t) detector.process(corridor()[t]);
  detector.set_label(2, "2.jpg");
  EXPECT_THROW(detector.forget(5), InvalidArgument);
  EXPECT_THROW(detector.forget(kAllEntries), InvalidArgument);
  EXPECT_THROW((void)detector.is_forgotten(5), InvalidArgument);
  EXPECT_EQ(detector.forgotten_count(), 0u);
  EXPECT_FALSE(detector.is_forgotten(2));
  detector.forget(2);
  detector.forget(2);
  EXPECT_TRUE(detector.is_forgotten(2));
  EXPECT_EQ(detector.forgotten_count(), 1u);
  EXPECT_EQ(detector.size(), 5u);
  EXPECT_THROW(detector.keypoints(2), InvalidArgument);
  EXPECT_THROW(detector.descriptors(2), InvalidArgument);
  EXPECT_THROW(detector.label(2), InvalidArgument);
  EXPECT_THROW(detector.set_label(2, "again"), InvalidArgument);
  EXPECT_EQ(detector.keypoints(3).size(), corridor()[3].keypoints.size());
  EXPECT_EQ(detector.process(corridor()[5]).query, 5u);
  // The similarity matrix scores a forgotten image as one without features.
  const SimilarityMatrix matrix = similarity_matrix(detector);
  ASSERT_EQ(matrix.frames, 6u);
  EXPECT_EQ(matrix.at(2, 1), 0.f);
  EXPECT_EQ(matrix.at(3, 2), 0.f);
  EXPECT_GT(matrix.at(3, 1), 0.f);
  detector.clear();
  EXPECT_EQ(detector.size(), 0u);
  EXPECT_EQ(detector.forgotten_count(), 0u);
}

// The frame's keypoints and descriptors are freed at once, and its direct
// index with its database entry.
TEST(LoopDetectorForget, MemoryIsReleased) {
  LoopDetector detector(orb_vocabulary());
  for (std::size_t t = 0; t < 40; ++t) detector.process(corridor()[t]);
  const std::size_t before = detector.memory_usage();
  const std::size_t database_before = detector.database().memory_usage();
  std::size_t features = 0;
  for (EntryId e = 0; e < 20; ++e) {
    features += detector.keypoints(e).size() * sizeof(vision::Keypoint) +
                detector.descriptors(e).rows * detector.descriptors(e).code_size;
    detector.forget(e);
  }
  ASSERT_GT(features, 20u * 100 * 32);
  EXPECT_LT(detector.database().memory_usage(), database_before);
  EXPECT_GE(before - detector.memory_usage(), features);
}

}  // namespace
}  // namespace binbow::loop
