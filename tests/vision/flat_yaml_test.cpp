// The YAML subset binbow parses itself (parameters, BRIEF patterns): what
// OpenCV writes reads back; anything else is an error naming the line, in
// one pass, however malformed.
#include "vision/flat_yaml.h"

#include <string>

#include <gtest/gtest.h>

#include "binbow/error.h"

namespace binbow::vision {
namespace {

void expect_error(const std::string& text, const std::string& needle) {
  try {
    parse_flat_yaml(text, "p.yml");
    ADD_FAILURE() << "parsed:\n" << text;
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), "p.yml");
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(FlatYaml, ReadsWhatOpenCvWrites) {
  const auto object = parse_flat_yaml(
      "%YAML:1.0\n---\n# a comment\nalpha: 0.3  # trailing\nk: 3\nname: \"direct-index\"\n"
      "plain: exhaustive\nflag: true\nx1:\n  - 0\n  - -4\n- 24\ny1: [ 1, -2,\n  3 ]\n"
      "empty: []\nbig: 1e300\nquoted: 'a # not a comment'\n",
      "p.yml");
  EXPECT_DOUBLE_EQ(object.at("alpha").get<double>(), 0.3);
  EXPECT_EQ(object.at("k").get<int>(), 3);
  EXPECT_TRUE(object.at("k").is_number_integer());
  EXPECT_EQ(object.at("name"), "direct-index");
  EXPECT_EQ(object.at("plain"), "exhaustive");
  EXPECT_EQ(object.at("flag"), true);
  EXPECT_EQ(object.at("x1"), nlohmann::json({0, -4, 24}));
  EXPECT_EQ(object.at("y1"), nlohmann::json({1, -2, 3}));
  EXPECT_TRUE(object.at("empty").is_array() && object.at("empty").empty());
  EXPECT_DOUBLE_EQ(object.at("big").get<double>(), 1e300);
  EXPECT_EQ(object.at("quoted"), "a # not a comment");
}

TEST(FlatYaml, AnythingElseIsAnErrorNamingTheLine) {
  expect_error("a: 1\n  b: 2\n", "line 2");
  expect_error("a:\n  - - 1\n", "nested");
  expect_error("a: [1, [2]]\n", "nested");
  expect_error("a: [1, 2\nb: 3\n", "never closed");
  expect_error("a: [1, 2] x\n", "after a sequence");
  expect_error("a: [1, ]\n", "before the ']'");
  expect_error("a: 1\na: 2\n", "second time");
  expect_error("a:\nb: 1\n", "no value");
  expect_error("a: \"open\n", "quoted");
  expect_error("- 1\n", "where a key was expected");
  expect_error("just text\n", "not \"key: value\"");
  expect_error("a: {b: 1}\n", "not a scalar");
  expect_error("a: &anchor 1\n", "not a scalar");
  expect_error("alpha: .inf\n", "\"alpha\" is a non-finite number");
  expect_error("alpha: [1, .nan]\n", "\"alpha\" is a non-finite number");
  expect_error("alpha: 1e999\n", "non-finite");
}

// Found by fuzzing: OpenCV's YAML parser looped forever on this pattern (a
// ']' closing nothing after a block sequence).
TEST(FlatYaml, TheInputThatHungOpenCvIsAnError) {
  expect_error(
      "%YAML:1.0-8, -10, -10, -06, 0, 5, -3, 12, -11,- 1\n   - 2\n   - 0\nx2:\n   - 2\n"
      "   -, -9, -4, -6, - -11 44 -11 -3,$7, -3, 1, 4 ]\n",
      "line 2");
}

}  // namespace
}  // namespace binbow::vision
