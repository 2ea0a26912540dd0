// `binbow build-vocab` on real images: a usable vocabulary, the same bytes
// for any --threads, the summary lines, and clear errors.
#include <gtest/gtest.h>

#include <string>

#include "binbow/formats.h"
#include "binbow/vocabulary.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::read_file;
using test::run_cli;
using test::shared_data;
using test::TempDir;

TEST(CliBuildVocab, BuildsTheSameFileForAnyThreadCount) {
  TempDir dir;
  const std::string images = shared_data("dbow2-demo-images/image0.png");
  const std::string folder = images.substr(0, images.rfind('/'));
  std::string output;
  for (const char* threads : {"1", "2"}) {
    ASSERT_EQ(run_cli("build-vocab --descriptor orb --branching 6 --levels 3 --seed 7 "
                      "--features-per-image 500 --threads " +
                          std::string(threads) + " -o '" + dir.file(std::string(threads) + ".bbw") +
                          "' '" + folder + "'",
                      &output),
              0)
        << output;
  }
  EXPECT_NE(output.find("from 4 images"), std::string::npos) << output;
  EXPECT_NE(output.find("mean quantisation error:"), std::string::npos) << output;
  EXPECT_NE(output.find("words: "), std::string::npos) << output;
  const auto one = read_file(dir.file("1.bbw"));
  ASSERT_FALSE(one.empty());
  EXPECT_EQ(one, read_file(dir.file("2.bbw")));

  const Vocabulary vocabulary = load_vocabulary(dir.file("1.bbw"));
  EXPECT_EQ(vocabulary.branching(), 6u);
  EXPECT_EQ(vocabulary.levels(), 3u);
  EXPECT_EQ(vocabulary.code_size(), 32u);
  EXPECT_EQ(vocabulary.descriptor(), "orb");
  EXPECT_GT(vocabulary.word_count(), 100u);
  EXPECT_LE(vocabulary.word_count(), 216u);
}

TEST(CliBuildVocab, SubsamplesWithWeightingScoringAndOtherFormats) {
  TempDir dir;
  const std::string images = shared_data("dbow2-demo-images/image0.png");
  const std::string folder = images.substr(0, images.rfind('/'));
  std::string output;
  ASSERT_EQ(run_cli("build-vocab --descriptor brief --branching 4 --levels 2 --max-descriptors "
                    "300 --weighting binary --scoring l2 -o '" +
                        dir.file("v.yml.gz") + "' '" + folder + "'",
                    &output),
            0)
      << output;
  EXPECT_NE(output.find("trained on 300 descriptors"), std::string::npos) << output;
  const Vocabulary vocabulary = load_vocabulary(dir.file("v.yml.gz"));
  EXPECT_EQ(vocabulary.weighting(), Weighting::kBinary);
  EXPECT_EQ(vocabulary.scoring(), Scoring::kL2);
}

TEST(CliBuildVocab, RejectsBadArgumentsClearly) {
  TempDir dir;
  const std::string images = shared_data("dbow2-demo-images/image0.png");
  std::string output;
  EXPECT_EQ(
      run_cli("build-vocab --branching 1 -o '" + dir.file("v.bbw") + "' '" + images + "'", &output),
      1);
  EXPECT_NE(output.find("binbow: error: --branching: Value 1 not in range 2 to 255"),
            std::string::npos)
      << output;
  EXPECT_EQ(
      run_cli("build-vocab --levels 17 -o '" + dir.file("v.bbw") + "' '" + images + "'", &output),
      1);
  EXPECT_NE(output.find("--levels: Value 17 not in range 1 to 16"), std::string::npos) << output;
  EXPECT_EQ(
      run_cli("build-vocab -o '" + dir.file("v.bbw") + "' '" + dir.file("missing") + "'", &output),
      1);
  EXPECT_NE(output.find("binbow: error:"), std::string::npos) << output;
  EXPECT_NE(run_cli("build-vocab --descriptor sift -o '" + dir.file("v.bbw") + "' '" + images + "'",
                    &output),
            0);
  EXPECT_TRUE(read_file(dir.file("v.bbw")).empty());
}

// One image gives every word IDF 0, so every BoW vector would be empty: an
// error that says why, and no file.
TEST(CliBuildVocab, RefusesATrainingSetOfOneImage) {
  TempDir dir;
  const std::string image = shared_data("dbow2-demo-images/image0.png");
  std::string output;
  EXPECT_EQ(
      run_cli("build-vocab --branching 4 --levels 2 -o '" + dir.file("v.bbw") + "' '" + image + "'",
              &output),
      1);
  EXPECT_NE(output.find("binbow: error: Vocabulary::build: tf-idf weighting needs at least two "
                        "training images that differ"),
            std::string::npos)
      << output;
  EXPECT_TRUE(read_file(dir.file("v.bbw")).empty());
  // The same image twice: every word is in every image.
  EXPECT_EQ(run_cli("build-vocab --branching 4 --levels 2 -o '" + dir.file("v.bbw") + "' '" +
                        image + "' '" + image + "'",
                    &output),
            1);
  EXPECT_NE(output.find("every word appears in all 2 training images"), std::string::npos)
      << output;
  EXPECT_TRUE(read_file(dir.file("v.bbw")).empty());
}

}  // namespace
}  // namespace binbow
