#include <sys/stat.h>

#include <gtest/gtest.h>

#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "binbow/error.h"
#include "binbow/loop/loop_detector.h"
#include "support/test_support.h"

namespace binbow::loop {
namespace {

void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

TEST(LoopDetectorParams, DefaultsAreThePapers) {
  const LoopDetectorParams p;
  EXPECT_DOUBLE_EQ(p.alpha, 0.3);
  EXPECT_EQ(p.k, 3);
  EXPECT_DOUBLE_EQ(p.min_normalisation_score, 0.005);
  EXPECT_EQ(p.dislocal, 20);
  EXPECT_EQ(p.max_db_results, 50);
  EXPECT_EQ(p.max_intra_island_gap, 3);
  EXPECT_EQ(p.geometric_check, GeometricCheck::kDirectIndex);
  EXPECT_EQ(p.direct_index_levels, 2);
  EXPECT_EQ(p.min_inliers, 12);
  EXPECT_DOUBLE_EQ(p.max_neighbor_ratio, 0.6);
  EXPECT_DOUBLE_EQ(p.max_reprojection_error, 2.0);
  // binbow's departures, each switchable (docs/loop-detection.md).
  EXPECT_TRUE(p.skip_featureless_frames);
  EXPECT_EQ(p.fundamental_estimator, vision::FundamentalEstimator::kUsacMagsac);
  EXPECT_FALSE(p.mutual_matching);
  EXPECT_FALSE(p.fast_queries);
  EXPECT_DOUBLE_EQ(p.min_inlier_ratio, 0);
  EXPECT_DOUBLE_EQ(p.min_inlier_spread, 0);
  EXPECT_EQ(p.min_uncorroborated_inliers, 16);
  EXPECT_DOUBLE_EQ(p.min_uncorroborated_view_agreement, kViewExplained);
  EXPECT_DOUBLE_EQ(kViewExplained, 0.5);
  EXPECT_TRUE(p.reject_degenerate_fits);
  EXPECT_TRUE(p.strong_fits_skip_temporal_check);
  EXPECT_EQ(p.corroboration_distance, 4);
  EXPECT_EQ(p.corroboration_horizon, 10);
  EXPECT_DOUBLE_EQ(p.corroboration_pace_tolerance, 0.25);
  EXPECT_TRUE(p.localise_in_island);
  EXPECT_EQ(p.max_localisation_checks, 8);
  const LoopDetectorParams f2 = LoopDetectorParams::for_frequency(2);
  EXPECT_EQ(f2.dislocal, 40);
  EXPECT_EQ(f2.max_db_results, 100);
  EXPECT_EQ(f2.max_intra_island_gap, 6);
  EXPECT_EQ(f2.max_distance_between_queries, 4);
  EXPECT_EQ(f2.corroboration_distance, 8);
  EXPECT_EQ(f2.corroboration_horizon, 20);
  EXPECT_DOUBLE_EQ(f2.alpha, 0.3);
}

TEST(LoopDetectorParams, JsonRoundTrip) {
  LoopDetectorParams p = LoopDetectorParams::for_frequency(3);
  p.alpha = 0.25;
  p.geometric_check = GeometricCheck::kExhaustive;
  p.exhaustive_fallback = false;
  p.skip_featureless_frames = false;
  p.fundamental_estimator = vision::FundamentalEstimator::kRansac;
  p.mutual_matching = true;
  p.fast_queries = true;
  p.min_inlier_ratio = 0.5;
  p.min_inlier_spread = 0.25;
  p.min_uncorroborated_inliers = 0;
  p.min_uncorroborated_view_agreement = 0.25;
  p.reject_degenerate_fits = false;
  p.strong_fits_skip_temporal_check = false;
  p.corroboration_distance = 7;
  p.corroboration_horizon = 9;
  p.corroboration_pace_tolerance = 0.5;
  p.localise_in_island = false;
  p.max_localisation_checks = 3;
  const LoopDetectorParams q = LoopDetectorParams::from_json(p.to_json());
  EXPECT_EQ(q.to_json(), p.to_json());
  EXPECT_EQ(q.dislocal, 60);
  EXPECT_EQ(q.geometric_check, GeometricCheck::kExhaustive);
  EXPECT_TRUE(q.fast_queries);
  EXPECT_EQ(q.fundamental_estimator, vision::FundamentalEstimator::kRansac);
  EXPECT_NE(p.to_json().find("\"fundamental_estimator\": \"ransac\""), std::string::npos);
  EXPECT_EQ(LoopDetectorParams::from_json(R"({"fundamental_estimator": "USAC_ACCURATE"})")
                .fundamental_estimator,
            vision::FundamentalEstimator::kUsacAccurate);
}

TEST(LoopDetectorParams, FrequencyDerivesThenKeysOverride) {
  const LoopDetectorParams p =
      LoopDetectorParams::from_json(R"({"max_db_results": 7, "frequency": 2})");
  EXPECT_EQ(p.dislocal, 40);
  EXPECT_EQ(p.max_db_results, 7);
}

// The CLI derives the defaults from a video's frame rate; a file's keys win.
TEST(LoopDetectorParams, KeysAbsentFromTheFileKeepTheGivenDefaults) {
  LoopDetectorParams defaults = LoopDetectorParams::for_frequency(2);
  defaults.alpha = 0.5;
  const LoopDetectorParams kept = LoopDetectorParams::from_json(R"({"k": 4})", "p", defaults);
  EXPECT_EQ(kept.k, 4);
  EXPECT_EQ(kept.dislocal, 40);
  EXPECT_EQ(kept.max_db_results, 100);
  EXPECT_DOUBLE_EQ(kept.frequency, 2);
  EXPECT_DOUBLE_EQ(kept.alpha, 0.5);
  const LoopDetectorParams set =
      LoopDetectorParams::from_json(R"({"dislocal": 5, "frequency": 3})", "p", defaults);
  EXPECT_EQ(set.dislocal, 5);
  EXPECT_EQ(set.max_db_results, 150);
  EXPECT_DOUBLE_EQ(set.frequency, 3);
  EXPECT_DOUBLE_EQ(set.alpha, 0.5);  // a frequency scales frame counts only
  test::TempDir dir;
  write_text(dir.file("p.yml"), "%YAML:1.0\nk: 2\n");
  EXPECT_EQ(LoopDetectorParams::load(dir.file("p.yml"), defaults).dislocal, 40);
}

TEST(LoopDetectorParams, LoadsYamlAndJsonFiles) {
  test::TempDir dir;
  write_text(dir.file("p.yml"),
             "%YAML:1.0\nalpha: 0.4\nk: 2\ngeometric_check: none\nuse_normalised_score: 0\n");
  const LoopDetectorParams y = LoopDetectorParams::load(dir.file("p.yml"));
  EXPECT_DOUBLE_EQ(y.alpha, 0.4);
  EXPECT_EQ(y.k, 2);
  EXPECT_EQ(y.geometric_check, GeometricCheck::kNone);
  EXPECT_FALSE(y.use_normalised_score);
  write_text(dir.file("p.json"), R"({"alpha": 0.35, "exhaustive_fallback": false})");
  const LoopDetectorParams j = LoopDetectorParams::load(dir.file("p.json"));
  EXPECT_DOUBLE_EQ(j.alpha, 0.35);
  EXPECT_FALSE(j.exhaustive_fallback);
}

void expect_error_mentions(const std::string& path, const std::string& text,
                           const std::string& needle) {
  write_text(path, text);
  try {
    LoopDetectorParams::load(path);
    ADD_FAILURE() << "no error for " << text;
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    EXPECT_EQ(e.path(), path);
  }
}

TEST(LoopDetectorParams, UnknownKeysAndBadValuesAreNamed) {
  test::TempDir dir;
  expect_error_mentions(dir.file("a.json"), R"({"alfa": 0.3})", "alfa");
  expect_error_mentions(dir.file("b.yml"), "%YAML:1.0\nbeta: 1\n", "beta");
  expect_error_mentions(dir.file("c.json"), R"({"k": "three"})", "\"k\"");
  expect_error_mentions(dir.file("d.json"), R"({"k": 2.5})", "\"k\"");
  expect_error_mentions(dir.file("e.json"), R"({"min_inliers": 3})", "min_inliers");
  expect_error_mentions(dir.file("f.json"), R"({"geometric_check": "flann"})", "flann");
  expect_error_mentions(dir.file("i.json"), R"({"fundamental_estimator": "lmeds"})", "usac-magsac");
  expect_error_mentions(dir.file("g.json"), R"({"alpha": )", "JSON");
  expect_error_mentions(dir.file("h.json"), R"([1, 2])", "object");
  EXPECT_THROW(LoopDetectorParams::load(dir.file("missing.json")), FileError);
}

// 50,000 levels in 100 KB crashed OpenCV's YAML parser (stack overflow);
// both formats are refused before any parser sees them.
TEST(LoopDetectorParams, DeeplyNestedFilesAreRefusedBeforeParsing) {
  test::TempDir dir;
  std::string sequences = "%YAML:1.0\nalpha:\n";
  for (int i = 0; i < 50'000; ++i) sequences += "- ";
  expect_error_mentions(dir.file("deep.yml"), sequences + "1\n", "nested");
  expect_error_mentions(dir.file("flow.yml"), "%YAML:1.0\nalpha: " + std::string(50'000, '['),
                        "nested");
  expect_error_mentions(dir.file("deep.json"), "{\"alpha\": " + std::string(50'000, '['), "nested");
  std::string indented = "%YAML:1.0\n";
  for (int i = 0; i < 100; ++i) indented += std::string(static_cast<std::size_t>(i), ' ') + "a:\n";
  expect_error_mentions(dir.file("indented.yml"), indented, "nested");
}

// JSON cannot spell infinity (1e999 is a parse error); YAML's .inf and .nan
// go through the same check.
TEST(LoopDetectorParams, NonFiniteNumbersAreRefusedInYamlAsInJson) {
  test::TempDir dir;
  expect_error_mentions(dir.file("inf.yml"), "%YAML:1.0\nalpha: .inf\n", "\"alpha\"");
  expect_error_mentions(dir.file("nan.yml"), "%YAML:1.0\nmax_reprojection_error: .nan\n",
                        "max_reprojection_error");
  expect_error_mentions(dir.file("inf.json"), R"({"alpha": 1e999})", "JSON");
  LoopDetectorParams p;
  p.alpha = std::numeric_limits<double>::infinity();
  EXPECT_THROW(p.validate(), InvalidArgument);
}

// Every parameter has a documented range; the upper bounds keep a parameter
// file from asking for unbounded work (1,000,000 RANSAC iterations at
// 1e-9 px ran past 120 s on 84 frames).
TEST(LoopDetectorParams, EveryFieldIsBoundedBothWays) {
  test::TempDir dir;
  expect_error_mentions(dir.file("a.json"),
                        R"({"max_ransac_iterations": 1000000, "max_reprojection_error": 1e-9})",
                        "max_reprojection_error must be in [0.1, 100], got 1e-09");
  expect_error_mentions(dir.file("b.json"), R"({"max_ransac_iterations": 1000000})",
                        "max_ransac_iterations must be in [1, 5000], got 1000000");
  expect_error_mentions(dir.file("c.yml"), "%YAML:1.0\nmax_ransac_iterations: 1000000\n",
                        "max_ransac_iterations");
  expect_error_mentions(dir.file("d.json"), R"({"frequency": 1e6})", "frequency");

  struct Bound {
    const char* key;
    double inside, outside;
  };
  for (const Bound& b :
       {Bound{"frequency", kMaxFrequency, kMaxFrequency * 2},
        Bound{"alpha", kMaxScoreThreshold, kMaxScoreThreshold * 2},
        Bound{"min_normalisation_score", 0, -1},
        Bound{"dislocal", kMaxFrameDistance, kMaxFrameDistance + 1.0},
        Bound{"max_db_results", kMaxFrameDistance, kMaxFrameDistance + 1.0},
        Bound{"max_intra_island_gap", 1, 0},
        Bound{"min_matches_per_island", kMaxFrameDistance, kMaxFrameDistance + 1.0},
        Bound{"k", kMaxConsistentQueries, kMaxConsistentQueries + 1.0},
        Bound{"max_distance_between_islands", 0, -1},
        Bound{"max_distance_between_queries", 1, 0},
        Bound{"direct_index_levels", kMaxDirectIndexLevels, kMaxDirectIndexLevels + 1.0},
        Bound{"max_verified_entries", kMaxVerifiedEntries, kMaxVerifiedEntries + 1.0},
        Bound{"max_localisation_checks", kMaxLocalisationChecks, kMaxLocalisationChecks + 1.0},
        Bound{"max_localisation_checks", 1, 0},
        Bound{"max_neighbor_ratio", 1, 0},
        Bound{"max_match_distance", 1, 1.5},
        Bound{"min_inliers", kMaxMinInliers, kMaxMinInliers + 1.0},
        Bound{"max_reprojection_error", kMinReprojectionError, 0.05},
        Bound{"max_reprojection_error", kMaxReprojectionError, 101},
        Bound{"ransac_confidence", 0.5, 1},
        Bound{"max_ransac_iterations", kMaxRansacIterations, kMaxRansacIterations + 1.0},
        Bound{"min_inlier_ratio", 1, 1.5},
        Bound{"min_inlier_ratio", 0, -0.1},
        Bound{"min_inlier_spread", 1, 1.5},
        Bound{"min_inlier_spread", 0, -0.1},
        Bound{"min_uncorroborated_inliers", 0, -1},
        Bound{"min_uncorroborated_view_agreement", 1, 1.5},
        Bound{"min_uncorroborated_view_agreement", 0, -0.1},
        Bound{"corroboration_distance", 1, 0},
        Bound{"corroboration_horizon", 1, 0},
        Bound{"corroboration_pace_tolerance", 1, 1.5},
        Bound{"corroboration_pace_tolerance", 0, -0.1}}) {
    SCOPED_TRACE(b.key);
    const auto json = [&](double value) {
      std::ostringstream text;
      text.precision(17);
      text << "{\"" << b.key << "\": " << value << "}";
      return text.str();
    };
    EXPECT_NO_THROW(LoopDetectorParams::from_json(json(b.inside)));
    try {
      LoopDetectorParams::from_json(json(b.outside));
      ADD_FAILURE() << "accepted " << json(b.outside);
    } catch (const FileError& e) {
      EXPECT_NE(std::string(e.what()).find(b.key), std::string::npos) << e.what();
    }
  }
}

TEST(LoopDetectorParams, SpecialFilesAreRefusedWithoutBlocking) {
  test::TempDir dir;
  ASSERT_EQ(mkfifo(dir.file("params.json").c_str(), 0600), 0);
  try {
    LoopDetectorParams::load(dir.file("params.json"));
    ADD_FAILURE() << "read a FIFO";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("is a FIFO"), std::string::npos) << e.what();
  }
  expect_error_mentions(dir.file("big.json"), "{\"alpha\": 0.3" + std::string(2 << 20, ' ') + "}",
                        "limit of 1048576 bytes");
}

TEST(LoopStatus, Names) {
  EXPECT_STREQ(to_string(LoopStatus::kLoopDetected), "loop-detected");
  EXPECT_STREQ(to_string(LoopStatus::kNoGeometricConsistency), "no-geometric-consistency");
  EXPECT_EQ(parse_geometric_check("direct_index"), GeometricCheck::kDirectIndex);
  EXPECT_THROW(parse_geometric_check("flann"), InvalidArgument);
}

// A --params file that sets nothing is a wrong file (an empty YAML, a
// template never filled), not a wish for the defaults.
TEST(LoopDetectorParams, FilesThatSetNothingAreRefused) {
  test::TempDir dir;
  const std::vector<std::pair<std::string, std::string>> files = {
      {"empty.yml", ""},
      {"empty.yaml", "\n\n"},
      {"params", ""},
      {"comments.yml", "%YAML:1.0\n---\n# alpha: 0.3\n"},
      {"empty.json", "{}"}};
  for (const auto& [name, text] : files) {
    SCOPED_TRACE(name);
    write_text(dir.file(name), text);
    try {
      LoopDetectorParams::load(dir.file(name));
      ADD_FAILURE() << "loaded";
    } catch (const FileError& e) {
      EXPECT_EQ(e.path(), dir.file(name));
      EXPECT_NE(std::string(e.what()).find("sets no parameter"), std::string::npos) << e.what();
    }
  }
  write_text(dir.file("one.yml"), "alpha: 0.4\n");
  EXPECT_DOUBLE_EQ(LoopDetectorParams::load(dir.file("one.yml")).alpha, 0.4);
}

}  // namespace
}  // namespace binbow::loop
