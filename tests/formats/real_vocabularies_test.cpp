// The real DBoW2 files of ../shared/data: counts, descriptor decoding, and
// that our DBoW2 writer lists the same nodes and descriptor strings in the
// same order as DBoW2 itself did.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "binbow/formats.h"
#include "formats/gzip.h"
#include "formats/loader.h"
#include "support/test_support.h"

namespace binbow {
namespace {

using test::read_file;
using test::shared_data;
using test::TempDir;

std::string gunzipped(const std::string& path) {
  const std::vector<std::uint8_t> bytes = read_file(path);
  const std::vector<std::uint8_t> text =
      detail::gunzip(bytes.data(), bytes.size(), path, detail::gunzip_limit(bytes.size()));
  return std::string(text.begin(), text.end());
}

// "nodeId:N, parentId:P|descriptor" for every node entry, in file order
// (weights are left out: DBoW2 prints doubles, we print floats).
std::vector<std::string> node_entries(const std::string& yaml) {
  std::vector<std::string> entries;
  for (std::size_t at = yaml.find("{ nodeId:"); at != std::string::npos;
       at = yaml.find("{ nodeId:", at + 1)) {
    const std::size_t ids_end = yaml.find(", weight:", at);
    const std::size_t quote = yaml.find('"', at);
    const std::size_t quote_end = yaml.find('"', quote + 1);
    if (ids_end == std::string::npos || quote_end == std::string::npos) break;
    entries.push_back(yaml.substr(at + 2, ids_end - at - 2) + "|" +
                      yaml.substr(quote + 1, quote_end - quote - 1));
  }
  return entries;
}

TEST(RealVocabularies, BriefLiteDbow2Yaml) {
  const std::string path = shared_data("vins-lite-brief-vocab/brief_lite.voc.gz");
  const detail::LoadedVocabulary loaded =
      detail::load_vocabulary_with_details(path, VocabularyFormat::kAuto);
  const Vocabulary& vocabulary = loaded.vocabulary;
  EXPECT_EQ(loaded.format, VocabularyFormat::kDbow2Yaml);
  EXPECT_TRUE(loaded.compressed);
  EXPECT_EQ(loaded.descriptor_text, detail::DescriptorText::kBits);
  EXPECT_TRUE(loaded.word_ids_match);
  EXPECT_EQ(vocabulary.branching(), 10u);
  EXPECT_EQ(vocabulary.levels(), 6u);
  EXPECT_EQ(vocabulary.code_size(), 32u);
  EXPECT_EQ(vocabulary.weighting(), Weighting::kTfIdf);
  EXPECT_EQ(vocabulary.scoring(), Scoring::kL1);
  EXPECT_EQ(vocabulary.word_count(), 24830u);
  // The file lists 31,232 nodes besides the root (the data README's 56,062 is
  // not what the file holds).
  EXPECT_EQ(vocabulary.node_count(), 31233u);
  // Node 1's string starts "00100000" "11000000": character k is bit 255 - k
  // (bit i of byte i / 8, LSB first), so byte 31 is 0b00100000 (character 2 =
  // bit 253) and byte 30 is 0b11000000 (characters 8, 9 = bits 247, 246).
  const std::uint8_t* node1 = vocabulary.node_descriptor(1);
  EXPECT_EQ(node1[31], 0x20);
  EXPECT_EQ(node1[30], 0xC0);
  // The file's words list: word 0 is node 41, word 24829 node 31232.
  EXPECT_EQ(vocabulary.word_nodes()[0], 41u);
  EXPECT_EQ(vocabulary.word_nodes()[24829], 31232u);
  EXPECT_FLOAT_EQ(vocabulary.word_weight(0), 5.9610053396232736f);

  // Written back with bit strings, node entries match DBoW2's own file.
  TempDir dir;
  save_vocabulary(vocabulary, dir.file("brief.voc.gz"), VocabularyFormat::kAuto, true);
  const std::vector<std::string> original = node_entries(gunzipped(path));
  const std::vector<std::string> ours = node_entries(gunzipped(dir.file("brief.voc.gz")));
  ASSERT_EQ(original.size(), 31232u);
  EXPECT_EQ(original, ours);
  EXPECT_EQ(load_vocabulary(dir.file("brief.voc.gz")).checksum(), vocabulary.checksum());
}

TEST(RealVocabularies, KimeraOrbDbow2Yaml) {
  const std::string path = shared_data("kimera-small-voc/small_voc.yml.gz");
  const detail::LoadedVocabulary loaded =
      detail::load_vocabulary_with_details(path, VocabularyFormat::kAuto);
  const Vocabulary& vocabulary = loaded.vocabulary;
  EXPECT_EQ(loaded.descriptor_text, detail::DescriptorText::kBytes);
  EXPECT_TRUE(loaded.word_ids_match);
  EXPECT_EQ(vocabulary.branching(), 9u);
  EXPECT_EQ(vocabulary.levels(), 3u);
  EXPECT_EQ(vocabulary.code_size(), 32u);
  EXPECT_EQ(vocabulary.node_count(), 782u);
  EXPECT_EQ(vocabulary.word_count(), 692u);
  // "212 176 157 246 ..." is node 1.
  EXPECT_EQ(vocabulary.node_descriptor(1)[0], 212);
  EXPECT_EQ(vocabulary.node_descriptor(1)[3], 246);

  TempDir dir;
  save_vocabulary(vocabulary, dir.file("orb.yml.gz"));
  EXPECT_EQ(node_entries(gunzipped(path)), node_entries(gunzipped(dir.file("orb.yml.gz"))));
  // And through ORB-SLAM text, the other way users go.
  save_vocabulary(vocabulary, dir.file("ORBvoc.txt"));
  EXPECT_EQ(load_vocabulary(dir.file("ORBvoc.txt")).checksum(), vocabulary.checksum());
}

}  // namespace
}  // namespace binbow
