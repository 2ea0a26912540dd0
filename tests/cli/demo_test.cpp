// The newcomer's path: `binbow demo` on the bundled sample and vocabulary.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "support/test_support.h"

namespace binbow {
namespace {

TEST(Demo, FindsLoopsWithPerfectPrecisionAndWritesAReportThatRenders) {
  test::TempDir dir;
  std::string out;
  // Run from elsewhere: the demo must find its data beside the executable.
  ASSERT_EQ(test::run_command("cd " + dir.path() + " && '" + test::cli_path() + "' demo --out " +
                                  dir.file("demo"),
                              &out),
            0)
      << out;
  const std::string summary = out.substr(out.find("== summary"));
  EXPECT_EQ(test::printed_number(summary, "frames"), 84) << summary;
  EXPECT_EQ(test::printed_number(summary, "precision"), 1.0) << summary;
  EXPECT_GE(test::printed_number(summary, "recall"), 0.90) << summary;  // docs/loop-detection.md
  EXPECT_GT(test::printed_number(summary, "time per frame"), 0) << summary;
  const std::string page = dir.file("demo/index.html");
  EXPECT_NE(summary.find("report: " + page), std::string::npos) << summary;
  ASSERT_TRUE(std::filesystem::exists(page));
  ASSERT_TRUE(test::render_in_chromium(page, dir.file("demo.png"), dir.path()));
  EXPECT_GT(std::filesystem::file_size(dir.file("demo.png")), 20000u) << "blank page?";
}

}  // namespace
}  // namespace binbow
