// Progress in a log: when stderr is a file (a log, CI) the CLI prints no
// carriage-return redraws, a plain progress line at most every ten seconds of
// a stage, and each stage's closing line.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <string>

#include "support/test_support.h"

namespace binbow {
namespace {

TEST(Progress, StderrToAFileGetsPlainLinesOnly) {
  test::TempDir dir;
  const std::string log = dir.file("stderr.log");
  std::string out;
  const auto start = std::chrono::steady_clock::now();
  ASSERT_EQ(test::run_command("{ '" + test::cli_path() + "' demo --out '" + dir.file("demo") +
                                  "' 2>'" + log + "'; }",
                              &out),
            0)
      << out;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::ifstream in(log, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  const std::string printed = text.str();
  ASSERT_NE(printed.find("detecting loops: 84 done in "), std::string::npos) << printed;
  EXPECT_EQ(printed.find('\r'), std::string::npos) << printed;
  EXPECT_EQ(printed.find('\033'), std::string::npos) << printed;
  // "label: done/total (p%) t": at most one a stage per ten seconds it ran.
  std::istringstream lines(printed);
  std::size_t progress_lines = 0;
  for (std::string line; std::getline(lines, line);)
    if (line.find("%) ") != std::string::npos) ++progress_lines;
  EXPECT_LE(progress_lines, static_cast<std::size_t>(seconds / 10)) << printed;
}

}  // namespace
}  // namespace binbow
