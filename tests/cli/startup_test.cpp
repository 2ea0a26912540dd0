// Start-up: the image/video stack (OpenCV's imgcodecs and videoio, with GDAL,
// GStreamer, FFmpeg, HDF5 and GUI toolkits behind them) is the binbow_media
// module, loaded when a command first reads an image other than a JPEG, a
// video or a .mat file. Commands that read none start without it, and those
// that need no OpenCV at all (--version, info, convert, evaluate, db remove)
// load no OpenCV library: the commands that do are the binbow_cli_vision module.
#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <utility>

#include "binbow/database.h"
#include "binbow/formats.h"
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
    const std::size_t end = line.find_first_of(" [;", at);
    const std::string object = line.substr(at + 5, end - at - 5);
    // A sanitizer build's runtimes are the build's, not binbow's.
    if (object.empty() || object.find("libasan") != std::string::npos ||
        object.find("libubsan") != std::string::npos || object.find("libtsan") != std::string::npos)
      continue;
    run.objects.insert(object);
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

// No OpenCV library at all, nor the module of the commands that need one.
void expect_without_opencv(const std::string& arguments) {
  SCOPED_TRACE("binbow " + arguments);
  const TracedRun run = run_traced(arguments);
  ASSERT_EQ(run.status, 0) << run.output;
  ASSERT_FALSE(run.objects.empty()) << "LD_DEBUG=files printed no object:\n" << run.output;
  for (const std::string& object : run.objects) {
    EXPECT_EQ(object.find("libopencv_"), std::string::npos) << object << " loaded";
    EXPECT_EQ(object.find("binbow_cli_vision"), std::string::npos) << object << " loaded";
  }
}

// A database of the bundled ORB vocabulary with three entries.
std::string small_database(const TempDir& dir) {
  Database database(load_vocabulary(test::source_path("data/vocab/orb_default.bbw")));
  std::mt19937_64 rng(7);
  for (int i = 0; i < 3; ++i)
    database.add(test::random_descriptors(50, 32, rng).view(), "frame" + std::to_string(i));
  const std::string path = dir.file("small.bbdb");
  database.save(path);
  return path;
}

TEST(CliStartup, CommandsReadingNoImageLoadNoImageOrVideoLibrary) {
  TempDir dir;
  const std::string vocabulary = test::source_path("data/vocab/orb_default.bbw");
  expect_light("--version");
  expect_light("info '" + vocabulary + "'");
  expect_light("convert '" + vocabulary + "' '" + dir.file("voc.yml.gz") + "'");
}

TEST(CliStartup, CommandsNeedingNoOpenCvLoadNone) {
  TempDir dir;
  const std::string vocabulary = test::source_path("data/vocab/orb_default.bbw");
  const std::string database = small_database(dir);
  expect_without_opencv("--version");
  expect_without_opencv("info '" + vocabulary + "'");
  expect_without_opencv("info --system");
  expect_without_opencv("info '" + database + "'");
  expect_without_opencv("convert '" + vocabulary + "' '" + dir.file("voc.yml.gz") + "'");
  expect_without_opencv("db remove '" + database + "' 1");
  expect_without_opencv("info --help");
  std::ofstream(dir.file("truth.txt")) << "# 0-based\n2 0\n";
  std::ofstream(dir.file("loops.csv")) << "query,match,score\n2,0,0.5\n";
  expect_without_opencv("evaluate --gt '" + dir.file("truth.txt") + "' '" + dir.file("loops.csv") +
                        "'");
}

// The commands that need OpenCV are a module; without it the others still
// run, and the rest fail saying which file is missing and what to do.
TEST(CliStartup, AMissingCommandsModuleIsAClearError) {
  const std::string missing = "BINBOW_CLI_VISION_MODULE=/nonexistent/binbow_cli_vision.so ";
  std::string output;
  EXPECT_EQ(run_command(missing + "'" + test::cli_path() + "' --version", &output), 0) << output;
  EXPECT_EQ(run_command(missing + "'" + test::cli_path() + "' info '" +
                            test::source_path("data/vocab/orb_default.bbw") + "'",
                        &output),
            0)
      << output;
  for (const std::string arguments : {"features x.jpg", "--help", "db query a.bbdb x.jpg", ""}) {
    SCOPED_TRACE(arguments);
    EXPECT_EQ(run_command(missing + "'" + test::cli_path() + "' " + arguments, &output), 1);
    EXPECT_EQ(output.rfind("binbow: error: cannot load binbow's image and video commands, "
                           "/nonexistent/binbow_cli_vision.so: cannot open shared object file",
                           0),
              0)
        << output;
    EXPECT_NE(output.find("set BINBOW_CLI_VISION_MODULE"), std::string::npos) << output;
  }
}

// What the CLI says when $BINBOW_CLI_VISION_MODULE names `module` and a
// command needs it; it must fail as any error does.
std::string module_error(const std::string& module, const std::string& directory = "") {
  std::string output;
  const std::string command = (directory.empty() ? "" : "cd '" + directory + "' && ") +
                              "BINBOW_CLI_VISION_MODULE='" + module + "' '" + test::cli_path() +
                              "' make-route --help";
  EXPECT_EQ(run_command(command, &output), 1) << module << ": " << output;
  return output;
}

// Files that are not the module (another library, another build's module, a
// file that is no library) are errors naming the file and what is wrong,
// never a crash, whatever the file holds.
TEST(CliStartup, AMalformedCommandsModuleIsAClearError) {
  TempDir dir;
  const std::string prefix = "binbow: error: cannot load binbow's image and video commands, ";
  const std::string modules = BINBOW_MALFORMED_MODULES_DIR;
  const std::pair<std::string, std::string> cases[] = {
      {"data_symbol.so", "binbow_cli_vision_commands is not a function"},
      {"table_address.so", "its entry point returned an address outside the module"},
      {"version_pointer.so", "its table names no binbow version"},
      {"other_interface.so", "built by another build of binbow "},
      {"other_release.so", "built for binbow 0.0.0-other, not for this binbow "},
  };
  for (const auto& [file, reason] : cases) {
    const std::string path = modules + "/" + file;
    const std::string output = module_error(path);
    EXPECT_EQ(output.rfind(prefix + path + ": " + reason, 0), 0u) << output;
  }
  // The version is the same: what differs is the interface, and the message says so.
  const std::string other = module_error(modules + "/other_interface.so");
  EXPECT_NE(other.find("(module interface 1000, this binbow's is "), std::string::npos) << other;
  EXPECT_EQ(other.find("not for this binbow"), std::string::npos) << other;

  test::write_file(dir.file("text.so"), {'n', 'o', 't', '\n'});
  const std::string text = module_error(dir.file("text.so"));
  EXPECT_EQ(text.rfind(prefix + dir.file("text.so") + ": ", 0), 0u) << text;
}

// A module named without a slash is a file in the working directory, as any
// path a user gives: never a library of that name on the library path.
TEST(CliStartup, AModuleNameWithoutASlashIsInTheWorkingDirectory) {
  TempDir dir;
  const std::string libc = module_error("libc.so.6", dir.path());
  EXPECT_EQ(libc.rfind("binbow: error: cannot load binbow's image and video commands, "
                       "./libc.so.6: cannot open shared object file",
                       0),
            0u)
      << libc;
  test::write_file(dir.file("vision.so"), test::read_file(test::cli_vision_module_path()));
  std::string output;
  EXPECT_EQ(run_command("cd '" + dir.path() + "' && BINBOW_CLI_VISION_MODULE=vision.so '" +
                            test::cli_path() + "' make-route --help",
                        &output),
            0)
      << output;
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
