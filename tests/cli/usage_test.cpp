// The command-line contract: every usage error prints "binbow: error: ..."
// and where to read the usage, and exits 1; outputs are made ready (folders
// created, blocked paths refused) before any work; every command offers the
// same extractors with the same default.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/vocabulary.h"
#include "support/test_support.h"

namespace binbow {
namespace {

namespace fs = std::filesystem;
using test::run_cli;
using test::samples_folder;
using test::shared_data;
using test::TempDir;

std::string quoted(const std::string& path) {
  return "'" + path + "'";
}

// A text list of the first `count` corridor frames: a short real sequence.
std::string short_sequence(const TempDir& dir, int count) {
  std::string list;
  for (int i = 1; i <= count; ++i) list += samples_folder() + "/" + std::to_string(i) + ".jpg\n";
  test::write_file(dir.file("frames.txt"), {list.begin(), list.end()});
  return dir.file("frames.txt");
}

// Runs `arguments`, which must fail as a usage error of `command` (e.g.
// "binbow db query") with a message containing `what`.
void expect_usage_error(const std::string& arguments, const std::string& command,
                        const std::string& what) {
  SCOPED_TRACE("binbow " + arguments);
  std::string output;
  EXPECT_EQ(run_cli(arguments, &output), 1) << output;
  EXPECT_EQ(output.rfind("binbow: error: ", 0), 0u) << output;
  EXPECT_NE(output.find(what), std::string::npos) << output;
  EXPECT_NE(output.find("\nRun '" + command + " --help' for usage.\n"), std::string::npos)
      << output;
}

// A vocabulary whose words all weigh 0 is read (legal), but nothing can be
// recognised with it: every command that uses it says so.
TEST(CliUsage, AVocabularyOfZeroWeightsIsWarnedAbout) {
  TempDir dir;
  VocabularyTree tree = Vocabulary::load(test::source_path("data/vocab/orb_default.bbw")).to_tree();
  std::fill(tree.weights.begin(), tree.weights.end(), 0.0f);
  Vocabulary::from_tree(tree).save(dir.file("zero.bbw"));
  std::string output;
  ASSERT_EQ(run_cli("detect-loops --vocab " + quoted(dir.file("zero.bbw")) + " -o " +
                        quoted(dir.file("loops.csv")) + " " + quoted(short_sequence(dir, 3)),
                    &output),
            0)
      << output;
  EXPECT_NE(output.find("binbow: warning: " + dir.file("zero.bbw") + ": every word weighs 0"),
            std::string::npos)
      << output;
  ASSERT_EQ(run_cli("detect-loops -o " + quoted(dir.file("loops.csv")) + " " +
                        quoted(short_sequence(dir, 3)),
                    &output),
            0)
      << output;
  EXPECT_EQ(output.find("every word weighs 0"), std::string::npos) << output;
}

TEST(CliUsage, AMistypedCommandIsNamedWithTheNearestOne) {
  expect_usage_error("detect-loop x", "binbow",
                     "unknown command 'detect-loop'; did you mean 'detect-loops'?");
  expect_usage_error("db quer x.bbdb", "binbow db",
                     "unknown command 'quer' for 'binbow db'; did you mean 'query'?");
  expect_usage_error("evaluat", "binbow", "did you mean 'evaluate'?");
  // Nothing near: the commands are listed instead of a guess.
  expect_usage_error("frobnicate", "binbow", "unknown command 'frobnicate'; the commands are: ");
}

TEST(CliUsage, EveryUsageErrorExitsOneAndSaysWhereTheUsageIs) {
  TempDir dir;
  const std::string image = quoted(shared_data("rtabmap-samples/samples/1.jpg"));
  const std::string folder = quoted(samples_folder());
  const std::string out = quoted(dir.file("out.csv"));
  test::write_file(dir.file("afile"), {'x'});

  expect_usage_error("", "binbow", "A subcommand is required");
  expect_usage_error("info", "binbow info", "FILE is required");
  expect_usage_error("info --no-such-flag " + image, "binbow info", "--no-such-flag");
  expect_usage_error("info " + image + " extra", "binbow info", "extra");
  expect_usage_error("db", "binbow db", "A subcommand is required");
  expect_usage_error("db query --top 0 x.bbdb " + image, "binbow db query", "--top");
  // The fast-mode tuning needs --fast, and takes what Database::query takes.
  for (const std::string option :
       {"--fast-candidates 10", "--fast-candidate-share 0.5", "--fast-min-postings 0"})
    expect_usage_error("db query " + option + " x.bbdb " + image, "binbow db query",
                       option.substr(0, option.find(' ')) + " requires --fast");
  expect_usage_error("db query --fast --fast-candidates 0 x.bbdb " + image, "binbow db query",
                     "--fast-candidates: must be at least 1, not 0");
  expect_usage_error("db query --fast --fast-candidates -1 x.bbdb " + image, "binbow db query",
                     "--fast-candidates: must be at least 1, not -1");
  expect_usage_error("db query --fast --fast-candidate-share 1.5 x.bbdb " + image,
                     "binbow db query", "--fast-candidate-share: must be in [0, 1], not 1.5");
  expect_usage_error("db query --fast --fast-candidate-share nan x.bbdb " + image,
                     "binbow db query", "--fast-candidate-share: must be in [0, 1], not nan");
  expect_usage_error("db query --fast --fast-min-postings -1 x.bbdb " + image, "binbow db query",
                     "--fast-min-postings: must be at least 0, not -1");
  // A database file holds at most 255: more used to write a file no one could load.
  expect_usage_error("db build --direct-index-levels-up 300 --vocab " +
                         quoted(test::source_path("data/vocab/orb_default.bbw")) + " -o " +
                         quoted(dir.file("x.bbdb")) + " " + folder,
                     "binbow db build",
                     "--direct-index-levels-up: Value 300 not in range 0 to 255");
  expect_usage_error("detect-loops --features abc -o " + out + " " + folder, "binbow detect-loops",
                     "--features");
  expect_usage_error("detect-loops --features -5 -o " + out + " " + folder, "binbow detect-loops",
                     "--features");
  expect_usage_error("detect-loops --descriptor sift -o " + out + " " + folder,
                     "binbow detect-loops", "--descriptor");
  expect_usage_error("features --features -5 " + image, "binbow features", "--features");
  expect_usage_error("features --fast-threshold 300 " + image, "binbow features",
                     "--fast-threshold");
  expect_usage_error("features --descriptor orb --pattern p.yml " + image, "binbow features",
                     "--pattern");
  expect_usage_error("features --draw " + quoted(dir.file("x.unknown")) + " " + image,
                     "binbow features", "--draw");
  expect_usage_error("build-vocab --threads -1 -o " + quoted(dir.file("v.bbw")) + " " + folder,
                     "binbow build-vocab", "--threads");
  expect_usage_error("build-vocab --weighting often -o " + quoted(dir.file("v.bbw")) + " " + folder,
                     "binbow build-vocab", "unknown weighting 'often'");
  expect_usage_error("convert a.bbw b.bbw --from morse", "binbow convert",
                     "unknown vocabulary format 'morse'");
  expect_usage_error("convert a.bbw b.yml --descriptors hex", "binbow convert", "--descriptors");
  expect_usage_error("evaluate --gt-base 2 --gt gt.txt loops.csv", "binbow evaluate", "--gt-base");
  expect_usage_error("demo --out " + quoted(dir.file("afile")), "binbow demo",
                     dir.file("afile") + ": exists and is not a folder");
  EXPECT_FALSE(fs::exists(dir.file("out.csv")));
  EXPECT_FALSE(fs::exists(dir.file("v.bbw")));
  EXPECT_FALSE(fs::exists(dir.file("x.bbdb")));
}

// Every option of an unsigned type takes decimal digits within its type, and
// says so naming the option and the range: CLI11 alone read "-1" and numbers
// past 2^64 - 1 as 2^64 - 1, and "010" as octal.
TEST(CliUsage, UnsignedOptionsRefuseNegativesOverflowAndNonIntegers) {
  TempDir dir;
  const std::string image = quoted(shared_data("rtabmap-samples/samples/1.jpg"));
  const std::string route = "make-route -o " + quoted(dir.file("route")) + " " + image + " ";
  const std::string largest = "18446744073709551615";
  for (const std::string value : {"-1", "18446744073709551616", "1e23", "0x10", "+3", "1.5"})
    expect_usage_error(route + "--seed " + value, "binbow make-route",
                       "--seed: must be a whole number from 0 to " + largest + ", not " + value);
  expect_usage_error("db query --fast --fast-candidates 18446744073709551616 x.bbdb " + image,
                     "binbow db query",
                     "--fast-candidates: must be a whole number from 0 to " + largest +
                         ", not 18446744073709551616");
  expect_usage_error(
      "build-vocab --max-descriptors -1 -o " + quoted(dir.file("v.bbw")) + " " + image,
      "binbow build-vocab",
      "--max-descriptors: must be a whole number from 0 to " + largest + ", not -1");
  // 32-bit options: the range is their type's.
  expect_usage_error("detect-loops --online-vocabulary --trees 4294967296 -o " +
                         quoted(dir.file("loops.csv")) + " " + image,
                     "binbow detect-loops",
                     "--trees: must be a whole number from 0 to 4294967295, not 4294967296");
  expect_usage_error("db remove x.bbdb 3 -2", "binbow db remove",
                     "ENTRY: must be a whole number from 0 to 4294967295, not -2");
  // Leading zeros are decimal: 017 is seventeen (octal 15 would pass).
  expect_usage_error("build-vocab --levels 017 -o " + quoted(dir.file("v.bbw")) + " " + image,
                     "binbow build-vocab", "--levels: Value 17 not in range 1 to 16");
  // The largest value is taken: the command goes on to its photographs.
  std::string output;
  EXPECT_EQ(run_cli("make-route --seed " + largest + " --frames 0010 -o " +
                        quoted(dir.file("route")) + " " + quoted(dir.file("missing.jpg")),
                    &output),
            1);
  EXPECT_EQ(output.find("must be a whole number"), std::string::npos) << output;
  EXPECT_NE(output.find("missing.jpg"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(dir.file("v.bbw")));
  EXPECT_FALSE(fs::exists(dir.file("loops.csv")));
}

TEST(CliUsage, HelpAndVersionStillExitZero) {
  for (const std::string arguments : {"--help", "db query --help", "detect-loops --help"}) {
    std::string output;
    EXPECT_EQ(run_cli(arguments, &output), 0) << output;
    EXPECT_NE(output.find("Usage:"), std::string::npos) << output;
    // Not "error" alone: --max-reprojection-error is a parameter flag.
    EXPECT_EQ(output.find("binbow: error"), std::string::npos) << output;
  }
  std::string output;
  EXPECT_EQ(run_cli("--version", &output), 0) << output;
  EXPECT_EQ(output.rfind("binbow ", 0), 0u) << output;
}

// The fast-mode options' help shows QueryOptions' defaults, whatever they
// become; the share's default (unset) grows with the entries, as it says.
TEST(CliUsage, FastQueryOptionsShowTheLibraryDefaults) {
  const QueryOptions defaults;
  ASSERT_FALSE(defaults.fast_candidate_share.has_value());
  std::string output;
  ASSERT_EQ(run_cli("db query --help", &output), 0) << output;
  for (const std::string& shown :
       {"--fast-candidates UINT=" + std::to_string(defaults.fast_candidates),
        std::string("--fast-candidate-share FLOAT"),
        "--fast-min-postings UINT=" + std::to_string(defaults.fast_min_postings)})
    EXPECT_NE(output.find(shown + " Needs: --fast"), std::string::npos) << shown << "\n" << output;
  EXPECT_NE(output.find("(default: a share that grows with the N entries searched"),
            std::string::npos)
      << output;
}

TEST(CliOutputs, MissingFoldersOfEveryOutputAreCreated) {
  TempDir dir;
  const std::string frames = quoted(short_sequence(dir, 6));
  std::string output;
  ASSERT_EQ(run_cli("detect-loops -o " + quoted(dir.file("r1/loops.csv")) + " --report " +
                        quoted(dir.file("reports/r1")) + " " + frames,
                    &output),
            0)
      << output;
  EXPECT_TRUE(fs::exists(dir.file("r1/loops.csv")));
  EXPECT_TRUE(fs::exists(dir.file("r1/loops.csv.run.json")));
  EXPECT_TRUE(fs::exists(dir.file("reports/r1/index.html")));

  ASSERT_EQ(run_cli("evaluate --gt " + quoted(shared_data("rtabmap-samples/samples_GT.bmp")) +
                        " --report " + quoted(dir.file("reports/eval")) + " " +
                        quoted(dir.file("r1/loops.csv")),
                    &output),
            0)
      << output;
  EXPECT_TRUE(fs::exists(dir.file("reports/eval/index.html")));

  // tf weighting: 16 words all appear in all 6 frames, so tf-idf would weigh them 0.
  ASSERT_EQ(run_cli("build-vocab --branching 4 --levels 2 --weighting tf -o " +
                        quoted(dir.file("nodir/x.bbw")) + " " + frames,
                    &output),
            0)
      << output;
  EXPECT_TRUE(fs::exists(dir.file("nodir/x.bbw")));

  ASSERT_EQ(run_cli("convert " + quoted(dir.file("nodir/x.bbw")) + " " +
                        quoted(dir.file("converted/x.txt")),
                    &output),
            0)
      << output;
  EXPECT_TRUE(fs::exists(dir.file("converted/x.txt")));

  ASSERT_EQ(run_cli("db build --vocab " + quoted(dir.file("nodir/x.bbw")) + " -o " +
                        quoted(dir.file("dbs/a/x.bbdb")) + " " + frames,
                    &output),
            0)
      << output;
  EXPECT_TRUE(fs::exists(dir.file("dbs/a/x.bbdb")));

  ASSERT_EQ(run_cli("features --repeat 1 --draw " + quoted(dir.file("drawn/1.png")) + " " +
                        quoted(shared_data("rtabmap-samples/samples/1.jpg")),
                    &output),
            0)
      << output;
  EXPECT_TRUE(fs::exists(dir.file("drawn/1.png")));
}

// An output under a regular file cannot be written: the command must say so
// before reading anything else. Each command is given an input it would
// reject first if it read it, so only the output check can produce the error.
TEST(CliOutputs, ABlockedOutputFailsBeforeAnyWork) {
  TempDir dir;
  test::write_file(dir.file("afile"), {'x'});
  const std::string blocked = dir.file("afile/out");
  const std::string folder = quoted(samples_folder());
  const std::string missing = quoted(dir.file("missing"));
  struct Case {
    std::string arguments, command, option;
  };
  const std::vector<Case> cases = {
      {"detect-loops --vocab " + missing + " -o " + quoted(blocked) + " " + folder,
       "binbow detect-loops", "-o"},
      {"detect-loops --vocab " + missing + " -o " + quoted(dir.file("ok.csv")) + " --report " +
           quoted(blocked) + " " + folder,
       "binbow detect-loops", "--report"},
      {"build-vocab -o " + quoted(blocked + ".bbw") + " " + missing, "binbow build-vocab", "-o"},
      {"db build --vocab " + missing + " -o " + quoted(blocked) + " " + folder, "binbow db build",
       "-o"},
      {"convert " + missing + " " + quoted(blocked + ".bbw"), "binbow convert", "OUT"},
      {"evaluate --gt " + missing + " --report " + quoted(blocked) + " " + missing,
       "binbow evaluate", "--report"},
      {"features --draw " + quoted(blocked + ".png") + " " + missing, "binbow features", "--draw"},
  };
  for (const Case& c : cases) {
    expect_usage_error(c.arguments, c.command, c.option + " " + dir.file("afile") + "/out");
  }
  std::string output;
  EXPECT_EQ(run_cli("detect-loops -o " + quoted(dir.path()) + " " + folder, &output), 1);
  EXPECT_NE(output.find("is a folder, not a file"), std::string::npos) << output;
}

TEST(CliDescriptors, OrbByDefaultAndEveryExtractorEverywhere) {
  std::string output;
  ASSERT_EQ(run_cli("features --repeat 1 " + quoted(shared_data("rtabmap-samples/samples/1.jpg")),
                    &output),
            0)
      << output;
  EXPECT_NE(output.find("descriptor: orb (32 bytes)\n"), std::string::npos) << output;

  for (const std::string command : {"features", "build-vocab"}) {
    SCOPED_TRACE(command);
    ASSERT_EQ(run_cli(command + " --help", &output), 0) << output;
    EXPECT_NE(output.find("--descriptor TEXT:{orb,brief,akaze,brisk}=orb"), std::string::npos)
        << output;
  }
  // Commands with a vocabulary default to the extractor it records.
  for (const std::string command : {"detect-loops", "db build", "db query", "bench"}) {
    SCOPED_TRACE(command);
    ASSERT_EQ(run_cli(command + " --help", &output), 0) << output;
    EXPECT_NE(output.find("--descriptor TEXT:{orb,brief,akaze,brisk}"), std::string::npos)
        << output;
    EXPECT_NE(output.find("Default: the extractor the vocabulary records, else orb"),
              std::string::npos)
        << output;
  }

  // No bundled vocabulary for AKAZE or BRISK: the error says to pass one.
  TempDir dir;
  for (const std::string& command :
       std::vector<std::string>{"detect-loops -o " + quoted(dir.file("l.csv")), "bench"}) {
    expect_usage_error(command + " --descriptor brisk " + quoted(samples_folder()),
                       "binbow " + command.substr(0, command.find(' ')),
                       "pass a vocabulary of brisk descriptors with --vocab FILE");
  }
}

}  // namespace
}  // namespace binbow
