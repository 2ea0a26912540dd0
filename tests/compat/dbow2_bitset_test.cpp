// FBrief's descriptor is std::bitset<256>, as DBoW2's (DLib's
// BRIEF256::bitset); the BRIEF vocabulary and database take bitsets and
// cv::Mat rows of the same bits alike.
#include <gtest/gtest.h>

#include <bitset>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "binbow/compat/DBoW2.h"
#include "compat/bitset_golden.h"
#include "support/test_support.h"

namespace {

static_assert(std::is_same<DBoW2::FBrief::TDescriptor, std::bitset<256> >::value,
              "FBrief::TDescriptor is DBoW2's std::bitset<256>");

TEST(Dbow2Bitsets, StdBitsetsGiveDbow2sGoldenNumbersAndTheRowsResults) {
  BriefDatabase database;
  bitset_golden::expect_golden_numbers(std::bitset<256>(), database);
}

// DLoopDetector's BRIEF demo: demoDetector<BriefVocabulary, BriefLoopDetector,
// FBrief::TDescriptor> runs a FeatureExtractor<FBrief::TDescriptor> that DLib's
// BRIEF256 fills, and hands its descriptors to the vocabulary and database
// through TemplatedLoopDetector<FBrief::TDescriptor, FBrief>.
template <class TDescriptor>
class FeatureExtractor {
 public:
  virtual ~FeatureExtractor() {}
  virtual void operator()(std::size_t image, std::vector<TDescriptor>& descriptors) const = 0;
};

class GoldenBrief256Extractor : public FeatureExtractor<std::bitset<256> > {
 public:
  void operator()(std::size_t image, std::vector<std::bitset<256> >& descriptors) const override {
    descriptors = bitset_golden::images_as(std::bitset<256>())[image];
  }
};

template <class TVocabulary, class TDescriptor>
std::vector<DBoW2::EntryId> detect_like_dloopdetector(const TVocabulary& voc,
                                                      const FeatureExtractor<TDescriptor>& extract,
                                                      std::size_t images) {
  DBoW2::TemplatedDatabase<TDescriptor, DBoW2::FBrief> db(voc, true, 2);
  std::vector<DBoW2::EntryId> best;
  for (std::size_t i = 0; i < images; ++i) {
    std::vector<TDescriptor> descriptors;
    extract(i, descriptors);
    DBoW2::BowVector bow;
    DBoW2::FeatureVector fv;
    voc.transform(descriptors, bow, fv, 2);
    DBoW2::QueryResults ret;
    db.query(bow, ret, 1, -1);
    best.push_back(ret.empty() ? 1000u : ret[0].Id);
    db.add(bow, fv);
  }
  return best;
}

TEST(Dbow2Bitsets, DloopdetectorsBriefDemoTypesInstantiate) {
  const GoldenBrief256Extractor extractor;
  const std::vector<DBoW2::EntryId> best =
      detect_like_dloopdetector<BriefVocabulary, DBoW2::FBrief::TDescriptor>(
          bitset_golden::vocabulary(), extractor, bitset_golden::golden().images.size());
  // The same walk over cv::Mat rows of an OrbVocabulary of the same file.
  const OrbVocabulary orb(binbow::test::source_path("data/vocab/orb_default.bbw"));
  OrbDatabase db(orb, true, 2);
  for (std::size_t i = 0; i < best.size(); ++i) {
    DBoW2::QueryResults ret;
    db.query(bitset_golden::golden().images[i], ret, 1, -1);
    EXPECT_EQ(ret.empty() ? 1000u : ret[0].Id, best[i]) << "image " << i;
    db.add(bitset_golden::golden().images[i]);
  }
}

TEST(Dbow2Bitsets, CreateAndGetWordInBitsetsOrRows) {
  std::mt19937_64 rng(3);
  std::vector<std::vector<std::bitset<256> > > bitsets(4);
  std::vector<std::vector<cv::Mat> > rows(4);
  for (std::size_t i = 0; i < bitsets.size(); ++i)
    for (int f = 0; f < 60; ++f) {
      std::bitset<256> bits;
      for (std::size_t b = 0; b < 256; ++b) bits[b] = (rng() & 1) != 0;
      bitsets[i].push_back(bits);
      rows[i].push_back(cv::Mat::zeros(1, 32, CV_8U));
      for (int b = 0; b < 256; ++b)
        if (bits[static_cast<std::size_t>(b)])
          rows[i].back().at<unsigned char>(0, b / 8) |= static_cast<unsigned char>(1 << (b % 8));
    }
  BriefVocabulary from_bitsets(4, 3), from_rows(4, 3);
  from_bitsets.create(bitsets);
  from_rows.create(rows);
  ASSERT_GT(from_bitsets.size(), 4u);
  ASSERT_EQ(from_rows.size(), from_bitsets.size());
  for (DBoW2::WordId w = 0; w < from_rows.size(); ++w) {
    EXPECT_EQ(from_rows.getWord(w), from_bitsets.getWord(w)) << w;
    EXPECT_EQ(from_rows.getWordWeight(w), from_bitsets.getWordWeight(w)) << w;
  }
  for (std::size_t f = 0; f < bitsets[0].size(); ++f)
    EXPECT_EQ(from_bitsets.transform(bitsets[0][f]), from_bitsets.transform(rows[0][f]));
  // A bitset of another length is refused, as a row of another length is.
  EXPECT_THROW(from_bitsets.transform(std::bitset<128>()), std::invalid_argument);
  EXPECT_THROW(from_bitsets.transform(cv::Mat::zeros(1, 16, CV_8U)), std::invalid_argument);
}

}  // namespace
