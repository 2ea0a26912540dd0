// Start-up: the image/video stack (OpenCV's imgcodecs and videoio, with GDAL,
// GStreamer, FFmpeg, HDF5 and GUI toolkits behind them) is the binbow_media
// module, loaded when a command first reads an image other than a JPEG, a
// video or a .mat file. Commands that read none start without it.
#include <gtest/gtest.h>

#include <set>
#include <sstream>
#include <string>

#include "support/test_support.h"

namespace binbow {
namespace {

using test::run_command;
using test::shared_data;
using test::TempDir;

constexpr std::size_t kMaxStartupObjects = 40;
constexpr const char* kHeavy[] = {
    "libavcodec",          "libgstreamer",      "libgdal",           "libgtk",      "libhdf5",
    "libopencv_imgcodecs", "libopencv_videoio", "libopencv_highgui", "binbow_media"};

struct TracedRun {
  int status = -1;
  std::string output;
  std::set<std::string> objects;  // every shared object loaded, linked or dlopen'ed
};

// Runs the CLI with `arguments` under LD_DEBUG=files, with which the dynamic
// loader names each object it loads ("file=libz.so.1 [0];  needed by ...",
// "... dynamically loaded by ...").
TracedRun run_traced(const std::string& arguments, const std::string& environment = "") {
  TracedRun run;
  run.status = run_command(environment + " LD_DEBUG=files '" + test::cli_path() + "' " + arguments,
                           &run.output);
  std::istringstream lines(run.output);
  for (std::string line; std::getline(lines, line);) {
    const std::size_t at = line.find("file=");
    if (at == std::string::npos || line.find("generating link map") != std::string::npos) continue;
    const std::size_t end = line.find_first_of(" [", at);
    run.objects.insert(line.substr(at + 5, end - at - 5));
  }
  return run;
}

std::string listed(const std::set<std::string>& objects) {
  std::string list;
  for (const std::string& object : objects) list += object + "\n";
  return list;
}

void expect_light(const std::string& arguments) {
  SCOPED_TRACE("binbow " + arguments);
  const TracedRun run = run_traced(arguments);
  ASSERT_EQ(run.status, 0) << run.output;
  ASSERT_FALSE(run.objects.empty()) << "LD_DEBUG=files printed no object:\n" << run.output;
  EXPECT_LE(run.objects.size(), kMaxStartupObjects) << listed(run.objects);
  for (const char* heavy : kHeavy)
    for (const std::string& object : run.objects)
      EXPECT_EQ(object.find(heavy), std::string::npos) << object << " loaded";
}

TEST(CliStartup, CommandsReadingNoImageLoadNoImageOrVideoLibrary) {
  TempDir dir;
  const std::string vocabulary = test::source_path("data/vocab/orb_default.bbw");
  expect_light("--version");
  expect_light("info '" + vocabulary + "'");
  expect_light("convert '" + vocabulary + "' '" + dir.file("voc.yml.gz") + "'");
}

TEST(CliStartup, JpegFramesAreReadWithoutTheModule) {
  const TracedRun run = run_traced("features '" + test::samples_folder() + "/1.jpg'",
                                   "BINBOW_MEDIA_MODULE=/nonexistent/binbow_media.so");
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_LE(run.objects.size(), kMaxStartupObjects) << listed(run.objects);
}

TEST(CliStartup, OtherImagesLoadTheModuleOnFirstUse) {
  const std::string png = "features '" + shared_data("dbow2-demo-images/image1.png") + "'";
  const TracedRun run = run_traced(png);
  ASSERT_EQ(run.status, 0) << run.output;
  bool module = false, imgcodecs = false;
  for (const std::string& object : run.objects) {
    module = module || object.find("/binbow_media.so") != std::string::npos;
    imgcodecs = imgcodecs || object.find("libopencv_imgcodecs") != std::string::npos;
  }
  EXPECT_TRUE(module && imgcodecs) << listed(run.objects);

  std::string output;
  EXPECT_EQ(run_command("BINBOW_MEDIA_MODULE=/nonexistent/binbow_media.so '" + test::cli_path() +
                            "' " + png,
                        &output),
            1);
  EXPECT_NE(output.find("binbow: error: cannot load the image/video module "
                        "/nonexistent/binbow_media.so: cannot open shared object file"),
            std::string::npos)
      << output;
}

}  // namespace
}  // namespace binbow
