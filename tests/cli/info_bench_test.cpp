// The CLI as scripts use it: `binbow info` key lines, errors on stderr with
// exit status 1, `binbow info --system`, and `binbow bench` on real frames.
#include <gtest/gtest.h>

#include <random>
#include <regex>
#include <string>
#include <vector>

#include "binbow/database.h"
#include "binbow/descriptors.h"
#include "binbow/vocabulary.h"
#include "support/test_support.h"

namespace binbow {
namespace {

std::string run(const std::string& arguments, int* status) {
  std::string output;
  *status = test::run_cli(arguments, &output);
  return output;
}

Vocabulary small_vocabulary() {
  std::mt19937_64 rng(1);
  const DescriptorMatrix training = test::clustered_descriptors(3000, 32, 80, 0.1, rng);
  std::vector<DescriptorView> images;
  for (std::size_t i = 0; i < 30; ++i) images.push_back(training.view().slice(i * 100, 100));
  BuildOptions options;
  options.branching = 6;
  options.levels = 3;
  return Vocabulary::build(images, options);
}

TEST(CliInfo, PrintsTheKeysScriptsRelyOn) {
  test::TempDir dir;
  const Vocabulary v = small_vocabulary();
  v.save(dir.file("v.bbw"));
  int status = -1;
  const std::string out = run("info " + dir.file("v.bbw"), &status);
  ASSERT_EQ(status, 0) << out;
  for (const std::string& line : std::vector<std::string>{
           "kind: vocabulary\n", "descriptor: orb\n", "descriptor_bits: 256\n", "branching: 6\n",
           "levels: 3\n", "nodes: " + std::to_string(v.node_count()) + "\n",
           "words: " + std::to_string(v.word_count()) + "\n", "weighting: tf-idf\n",
           "scoring: l1\n"})
    EXPECT_NE(out.find(line), std::string::npos) << "missing '" << line << "' in:\n" << out;
}

TEST(CliInfo, NamesTheTrainingDescriptorAndCommandsRefuseAnotherKind) {
  const std::string orb = test::source_path("data/vocab/orb_default.bbw");
  const std::string brief = test::source_path("data/vocab/brief_default.bbw");
  int status = -1;
  std::string out = run("info " + orb, &status);
  ASSERT_EQ(status, 0) << out;
  EXPECT_NE(out.find("descriptor: orb\n"), std::string::npos) << out;
  out = run("info " + brief, &status);
  EXPECT_NE(out.find("descriptor: brief\n"), std::string::npos) << out;

  // ORB and BRIEF descriptors are both 256-bit: only the recorded name tells
  // that an ORB vocabulary cannot quantise BRIEF descriptors.
  test::TempDir dir;
  const std::string frames = test::source_path("data/samples/rtabmap/samples");
  for (const std::string& command :
       {"bench --vocab " + orb + " --descriptor brief --stride 40 " + frames,
        "db build --vocab " + orb + " --descriptor brief -o " + dir.file("d.bbdb") + " " +
            frames}) {
    out = run(command, &status);
    EXPECT_EQ(status, 1) << command << "\n" << out;
    EXPECT_NE(out.find("trained on orb descriptors, not brief: pass --descriptor orb"),
              std::string::npos)
        << out;
  }
}

TEST(CliInfo, ReadsRealDbow2Vocabulary) {
  int status = -1;
  const std::string out =
      run("info " + test::shared_data("vins-lite-brief-vocab/brief_lite.voc.gz"), &status);
  ASSERT_EQ(status, 0) << out;
  EXPECT_NE(out.find("words: 24830\n"), std::string::npos) << out;
  EXPECT_NE(out.find("branching: 10\n"), std::string::npos) << out;
}

// The gzip trailer's size is never trusted for an allocation: brief_lite.voc.gz
// cut by one byte ends in four bytes of deflate data that claim gigabytes.
// Memory is capped so that such a reservation would fail.
TEST(CliInfo, CutGzipFailsAsTruncatedWithinLittleMemory) {
  test::TempDir dir;
  std::vector<std::uint8_t> bytes =
      test::read_file(test::shared_data("vins-lite-brief-vocab/brief_lite.voc.gz"));
  bytes.pop_back();
  test::write_file(dir.file("cut.voc.gz"), bytes);
#if defined(BINBOW_TEST_ASAN)
  // ASan reserves terabytes of shadow memory, so ulimit -v cannot apply.
  const std::string limited = "ASAN_OPTIONS=\"$ASAN_OPTIONS:max_allocation_size_mb=1000\" ";
#else
  const std::string limited = "ulimit -v 1000000 && ";
#endif
  std::string out;
  EXPECT_EQ(test::run_command(
                limited + "'" + test::cli_path() + "' info '" + dir.file("cut.voc.gz") + "'", &out),
            1);
  EXPECT_NE(out.find("binbow: error: " + dir.file("cut.voc.gz") + ": gzip data is truncated"),
            std::string::npos)
      << out;
}

TEST(CliInfo, BadFilesExitOneWithTheFileNamed) {
  test::TempDir dir;
  test::write_file(dir.file("junk.bbw"), {'B', 'B', 'W', 'V', 'O', 'C', 'A', 'B', 1, 2});
  int status = -1;
  std::string out = run("info " + dir.file("junk.bbw"), &status);
  EXPECT_EQ(status, 1);
  EXPECT_NE(out.find("binbow: error: " + dir.file("junk.bbw")), std::string::npos) << out;
  out = run("info " + dir.file("missing.bbw"), &status);
  EXPECT_EQ(status, 1);
  EXPECT_NE(out.find("missing.bbw"), std::string::npos) << out;
}

TEST(CliInfo, ChecksTheWholeDatabaseUnlessHeaderOnly) {
  test::TempDir dir;
  Database database(small_vocabulary());
  std::mt19937_64 rng(2);
  for (int i = 0; i < 5; ++i) database.add(test::random_descriptors(50, 32, rng).view());
  const std::string path = dir.file("d.bbdb");
  database.save(path);
  int status = -1;
  std::string out = run("info " + path, &status);
  ASSERT_EQ(status, 0) << out;
  std::vector<std::uint8_t> bytes = test::read_file(path);
  bytes[bytes.size() - 100] ^= 0x04;  // in the body, far from the header
  test::write_file(path, bytes);
  out = run("info " + path, &status);
  EXPECT_EQ(status, 1) << out;
  EXPECT_NE(out.find("binbow: error: " + path + ": "), std::string::npos) << out;
  out = run("info --header-only " + path, &status);
  EXPECT_EQ(status, 0) << out;
  EXPECT_NE(out.find("entries: 5\n"), std::string::npos) << out;
}

TEST(CliInfo, SystemNamesTheHammingKernelInUseAndTheCpuFeatures) {
  int status = -1;
  const std::string out = run("info --system", &status);
  ASSERT_EQ(status, 0) << out;
  EXPECT_NE(out.find("hamming_kernel: " + std::string(hamming_kernel_name()) + "\n"),
            std::string::npos)
      << out;
  std::string supported;
  for (const std::string& name : supported_hamming_kernels())
    supported += (supported.empty() ? "" : " ") + name;
  EXPECT_NE(out.find("hamming_kernels_supported: " + supported + "\n"), std::string::npos) << out;
  for (const CpuFeature& feature : cpu_features())
    EXPECT_NE(out.find("cpu_" + std::string(feature.name) + ": " +
                       (feature.present ? "yes" : "no") + "\n"),
              std::string::npos)
        << out;
}

TEST(CliInfo, SystemTakesNoFileAndAFileIsOtherwiseRequired) {
  int status = -1;
  std::string out =
      run("info --system " + test::source_path("data/vocab/orb_default.bbw"), &status);
  EXPECT_EQ(status, 1) << out;
  EXPECT_NE(out.find("binbow: error:"), std::string::npos) << out;
  out = run("info", &status);
  EXPECT_EQ(status, 1) << out;
  EXPECT_NE(out.find("FILE"), std::string::npos) << out;
}

TEST(CliBench, TimesEveryStageOnRealFrames) {
  test::TempDir dir;
  small_vocabulary().save(dir.file("v.bbw"));
  const std::string frames = test::source_path("data/samples/rtabmap/samples");
  int status = -1;
  const std::string out = run(
      "bench --vocab " + dir.file("v.bbw") + " --database-size 200 --stride 4 " + frames, &status);
  ASSERT_EQ(status, 0) << out;
  EXPECT_NE(out.find("21 frames"), std::string::npos) << out;
  for (const char* stage : {"features", "transform", "loop detection", "database add",
                            "database query", "vocabulary load"})
    EXPECT_NE(out.find(stage), std::string::npos) << stage << " missing in:\n" << out;
  // Timings depend on the kernel set, so the report names the one that ran.
  EXPECT_NE(out.find("hamming kernel: " + std::string(hamming_kernel_name()) + "\n"),
            std::string::npos)
      << out;
}

// Ten million entries take gigabytes: refused with the estimate before the
// database is filled, here under a 3 GB address-space limit (`ulimit -v`,
// which the estimate counts with the machine's available memory), instead
// of dying out of memory.
TEST(CliBench, RefusesADatabaseSizeBeyondTheAvailableMemory) {
#if defined(BINBOW_TEST_ASAN)
  // Its shadow memory is a reservation of terabytes, which `ulimit -v` forbids.
  GTEST_SKIP() << "an AddressSanitizer build cannot run under an address-space limit; the "
                  "release build runs this test";
#endif
  const std::string frames = test::source_path("data/samples/rtabmap/samples");
  std::string out;
  const int status =
      test::run_command("ulimit -v 3000000 && '" + test::cli_path() +
                            "' bench --database-size 10000000 --stride 20 '" + frames + "'",
                        &out);
  EXPECT_EQ(status, 1) << out;
  const std::regex refusal(
      "binbow: error: --database-size 10000000 needs about ([0-9.]+) GiB; this machine has "
      "([0-9.]+) GiB available");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, refusal)) << out;
  EXPECT_GT(std::stod(m[1]), 3.0) << out;
  EXPECT_LT(std::stod(m[2]), 3.0) << out;
  EXPECT_EQ(out.find("database add"), std::string::npos) << out;
}

}  // namespace
}  // namespace binbow
