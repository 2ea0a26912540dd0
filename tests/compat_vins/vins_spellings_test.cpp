// Code written as VINS-Mono/Fusion calls its copy of DBoW2: its include
// names, DVision::BRIEF's boost::dynamic_bitset descriptors, a VINS binary
// vocabulary, and its query rule, on by default once these headers are in.
#include <gtest/gtest.h>

#include <boost/dynamic_bitset.hpp>
#include <string>
#include <vector>

#include "ThirdParty/DBoW/DBoW2.h"
#include "ThirdParty/DBoW/TemplatedDatabase.h"
#include "ThirdParty/DBoW/TemplatedVocabulary.h"
#include "ThirdParty/DVision/DVision.h"
#include "binbow/formats.h"
#include "binbow/vocabulary.h"
#include "compat/bitset_golden.h"
#include "compat_vins/vins_expected.h"
#include "support/test_support.h"

namespace {

using namespace DVision;
using namespace DBoW2;

std::vector<std::vector<BRIEF::bitset> > golden_images() {
  return bitset_golden::images_as(BRIEF::bitset(256));
}

TEST(VinsSpellings, DynamicBitsetsGiveDbow2sGoldenNumbersAndTheRowsResults) {
  BriefDatabase database;
  bitset_golden::expect_golden_numbers(BRIEF::bitset(256), database);
}

TEST(VinsSpellings, DatabasesFollowVinsQueryRuleUnlessTheyChoose) {
  BriefDatabase db;
  EXPECT_TRUE(db.usingVinsQueryRule());
  db.setVinsQueryRule(false);
  EXPECT_FALSE(db.usingVinsQueryRule());
}

// pose_graph.cpp's calls, with a VINS binary vocabulary of the golden words.
TEST(VinsSpellings, PoseGraphCallsGiveVinsResults) {
  binbow::test::TempDir dir;
  const std::string path = dir.file("brief_k10L6.bin");
  binbow::save_vocabulary(
      binbow::load_vocabulary(binbow::test::source_path("data/vocab/orb_default.bbw")), path,
      binbow::VocabularyFormat::kVinsBinary);
  BriefVocabulary* voc = new BriefVocabulary(path);
  BriefDatabase db;
  db.setVocabulary(*voc, false, 0);
  const dbow2_golden::Golden& g = bitset_golden::golden();
  const std::vector<std::vector<BRIEF::bitset> > images = golden_images();
  std::size_t newest_returned = 0;
  for (std::size_t i = 0; i < images.size(); ++i) {
    QueryResults ret;
    db.query(images[i], ret, vins_expected::kMaxResults, static_cast<int>(i) - vins_expected::kGap);
    db.add(images[i]);
    const std::vector<std::pair<EntryId, double> > expected = vins_expected::results(g, i);
    ASSERT_EQ(expected.size(), ret.size()) << "image " << i;
    for (std::size_t r = 0; r < ret.size(); ++r) {
      EXPECT_EQ(expected[r].first, ret[r].Id) << "image " << i << " result " << r;
      EXPECT_TRUE(dbow2_golden::close(expected[r].second, ret[r].Score, 1e-6))
          << "image " << i << " result " << r;
      newest_returned += i > 0 && ret[r].Id == i - 1;
    }
  }
  EXPECT_GE(newest_returned, 3u);
  delete voc;
}

}  // namespace
