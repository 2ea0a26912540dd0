// Files handed to OpenCV's FileStorage (BRIEF patterns here; loop detector
// parameters in tests/loop) are bounded in size and nesting before OpenCV
// parses them: its parsers recurse once per level.
#include "vision/storage_text.h"

#include <sys/stat.h>

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "binbow/error.h"
#include "formats/gzip.h"
#include "support/test_support.h"
#include "vision/brief_pattern.h"

namespace binbow::vision {
namespace {

void expect_pattern_error_mentioning(const std::string& path, const std::string& needle) {
  try {
    load_brief_pattern(path);
    ADD_FAILURE() << "loaded " << path;
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), path);
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

void write_text(const std::string& path, const std::string& text) {
  test::write_file(path, std::vector<std::uint8_t>(text.begin(), text.end()));
}

// The bound is never below the depth a parser sees.
TEST(StorageNesting, BoundsTheDepthOfEveryFormat) {
  EXPECT_GE(nesting_depth_bound("%YAML:1.0\nx1: [1, 2]\n"), 2u);
  EXPECT_GE(nesting_depth_bound("%YAML:1.0\na:\n  b:\n    c: 1\n"), 3u);
  EXPECT_GE(nesting_depth_bound("%YAML:1.0\na:\n  - - - x\n"), 5u);
  EXPECT_GE(nesting_depth_bound("{\"a\": {\"b\": [1]}}"), 3u);
  EXPECT_GE(nesting_depth_bound("<?xml version=\"1.0\"?>\n<a><b><c>1</c><d/></b></a>"), 3u);
  // Brackets inside quoted scalars and comments inside XML do not nest.
  EXPECT_EQ(nesting_depth_bound("%YAML:1.0\na: \"[[[[{{\"\nb: '[[['\n"), 1u);
  EXPECT_EQ(nesting_depth_bound("<a><!-- <b><c><d> --></a>"), 1u);
  // A quote inside a plain scalar does not start a string that would hide brackets.
  EXPECT_GE(nesting_depth_bound("%YAML:1.0\na: it's [[[[\n"), 5u);
  EXPECT_GE(nesting_depth_bound(std::string(50'000, '[')), 50'000u);
  std::string dashes = "%YAML:1.0\nx:\n";
  for (int i = 0; i < 50'000; ++i) dashes += "- ";
  EXPECT_GE(nesting_depth_bound(dashes + "1\n"), 50'000u);
  std::string xml;
  for (int i = 0; i < 1000; ++i) xml += "<a>";
  EXPECT_GE(nesting_depth_bound(xml), 1000u);
}

// 50,000 levels crashed OpenCV (SIGSEGV, stack overflow); now refused from
// the text, in every format FileStorage reads, gzip-compressed or not.
TEST(BriefPattern, DeeplyNestedFilesAreRefusedBeforeOpenCvParsesThem) {
  test::TempDir dir;
  std::string yaml = "%YAML:1.0\nx1:\n";
  for (int i = 0; i < 50'000; ++i) yaml += "- ";
  yaml += "1\n";
  write_text(dir.file("deep.yml"), yaml);
  expect_pattern_error_mentioning(dir.file("deep.yml"), "nested");
  write_text(dir.file("deep.json"), "{\"x1\": " + std::string(50'000, '[') + "\n");
  expect_pattern_error_mentioning(dir.file("deep.json"), "nested");
  std::string xml = "<?xml version=\"1.0\"?>\n<opencv_storage>";
  for (int i = 0; i < 50'000; ++i) xml += "<x1>";
  write_text(dir.file("deep.xml"), xml);
  expect_pattern_error_mentioning(dir.file("deep.xml"), "nested");
  test::write_file(dir.file("deep.yml.gz"),
                   detail::gzip(std::vector<std::uint8_t>(yaml.begin(), yaml.end())));
  expect_pattern_error_mentioning(dir.file("deep.yml.gz"), "nested");
}

// OpenCV's XML reader crashed on NUL bytes in the <?xml declaration (found
// by fuzzing); a text file has no NUL, so none reaches OpenCV.
TEST(BriefPattern, NulBytesAreRefusedBeforeOpenCvParses) {
  test::TempDir dir;
  std::string xml = "<?xml version=";
  xml += std::string(21, '\0');
  xml += "\"1.0\"?>\n<opencv_storage>\n<x1>-45 11</x1>\n</opencv_storage>\n";
  write_text(dir.file("nul.xml"), xml);
  expect_pattern_error_mentioning(dir.file("nul.xml"), "NUL byte at byte 14");
}

// Found by fuzzing: a string of invalid UTF-8 in a sequence made the error
// message's JSON dump throw past every handler.
TEST(BriefPattern, NonIntegersAreErrorsWhateverTheirBytes) {
  test::TempDir dir;
  write_text(dir.file("utf8.yml"), "x1: [ -5, -3,\xa0-9 ]\ny1: [1]\nx2: [1]\ny2: [1]\n");
  expect_pattern_error_mentioning(dir.file("utf8.yml"), "not an integer within");
  write_text(dir.file("big.json"),
             R"({"x1": [18446744073709551615], "y1": [1], "x2": [1], "y2": [1]})");
  expect_pattern_error_mentioning(dir.file("big.json"), "not an integer within");
}

TEST(BriefPattern, GzipPatternsLoadAndGzipBombsAreRefused) {
  test::TempDir dir;
  const std::vector<std::uint8_t> text =
      test::read_file(test::shared_data("vins-lite-brief-vocab/brief_pattern.yml"));
  ASSERT_FALSE(text.empty());
  test::write_file(dir.file("pattern.yml.gz"), detail::gzip(text));
  EXPECT_EQ(load_brief_pattern(dir.file("pattern.yml.gz")).tests(), 256u);

  // 5 MiB of spaces compress to a few KiB.
  std::vector<std::uint8_t> bomb(text);
  bomb.resize(5 << 20, ' ');
  test::write_file(dir.file("bomb.yml.gz"), detail::gzip(bomb));
  expect_pattern_error_mentioning(dir.file("bomb.yml.gz"), "4194304 bytes");
  test::write_file(dir.file("big.yml"), bomb);
  expect_pattern_error_mentioning(dir.file("big.yml"), "limit of 4194304 bytes");
}

TEST(BriefPattern, SpecialFilesAreRefusedWithoutBlocking) {
  test::TempDir dir;
  ASSERT_EQ(mkfifo(dir.file("pattern.yml").c_str(), 0600), 0);
  expect_pattern_error_mentioning(dir.file("pattern.yml"), "is a FIFO");
  expect_pattern_error_mentioning(dir.file("missing.yml"), "no such file");
}

}  // namespace
}  // namespace binbow::vision
