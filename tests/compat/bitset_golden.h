// DBoW2's golden numbers (dbow2_golden.txt) reached through BRIEF bitsets:
// the golden images' descriptors as bitsets of the same bits (bit i of the
// bitset is bit i % 8 of byte i / 8 of the row, FBrief.h), given to a
// BriefVocabulary and a BriefDatabase over the golden vocabulary, must give
// DBoW2's words, BoW vectors, feature vectors and queries, and exactly what
// the cv::Mat rows give. Shared by the std::bitset test (tests/compat) and
// the boost::dynamic_bitset one (tests/compat_vins).
#ifndef BINBOW_TESTS_COMPAT_BITSET_GOLDEN_H
#define BINBOW_TESTS_COMPAT_BITSET_GOLDEN_H

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "binbow/compat/DBoW2.h"
#include "compat/dbow2_golden.h"
#include "support/test_support.h"

namespace bitset_golden {

inline const dbow2_golden::Golden& golden() {
  static const dbow2_golden::Golden g =
      dbow2_golden::read(binbow::test::source_path("tests/compat/dbow2_golden.txt"));
  return g;
}

// The golden vocabulary, read as a BRIEF vocabulary: binbow compares the
// bytes, whatever the descriptor class.
inline const BriefVocabulary& vocabulary() {
  static const BriefVocabulary voc(binbow::test::source_path("data/vocab/orb_default.bbw"));
  return voc;
}

// `bits` sized to 256 by the caller (std::bitset is; dynamic_bitset is resized).
template <class Bits>
Bits bits_of(const cv::Mat& row, Bits bits) {
  for (int i = 0; i < 256; ++i)
    if ((row.at<unsigned char>(0, i / 8) >> (i % 8)) & 1) bits.set(static_cast<std::size_t>(i));
  return bits;
}

template <class Bits>
std::vector<std::vector<Bits> > images_as(const Bits& empty) {
  std::vector<std::vector<Bits> > images;
  for (const std::vector<cv::Mat>& image : golden().images) {
    images.push_back(std::vector<Bits>());
    for (const cv::Mat& row : image) images.back().push_back(bits_of(row, empty));
  }
  return images;
}

inline bool same_results(const DBoW2::QueryResults& a, const DBoW2::QueryResults& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t r = 0; r < a.size(); ++r)
    if (a[r].Id != b[r].Id || a[r].Score != b[r].Score || a[r].nWords != b[r].nWords) return false;
  return true;
}

// `empty`: an all-zero bitset of 256 bits. `database` gets DBoW2's rule.
template <class Bits>
void expect_golden_numbers(const Bits& empty, BriefDatabase& database) {
  const dbow2_golden::Golden& g = golden();
  const std::vector<std::vector<Bits> > images = images_as(empty);
  const BriefVocabulary& voc = vocabulary();
  ASSERT_EQ(g.words, voc.size());
  std::size_t words = 0, bows = 0, feature_vectors = 0, queries = 0;
  for (std::size_t i = 0; i < images.size(); ++i) {
    for (std::size_t f = 0; f < images[i].size(); ++f, ++words)
      ASSERT_EQ(g.feature_words[i][f], voc.transform(images[i][f]))
          << "image " << i << " feature " << f;
    DBoW2::BowVector v, from_rows;
    voc.transform(images[i], v);
    voc.transform(g.images[i], from_rows);
    EXPECT_TRUE(v == from_rows) << "image " << i;
    const auto expected = g.bows.find(std::make_pair(std::make_pair("TF_IDF", "L1_NORM"), int(i)));
    if (expected != g.bows.end()) {
      ++bows;
      ASSERT_EQ(expected->second.size(), v.size()) << "image " << i;
      for (DBoW2::BowVector::const_iterator e = expected->second.begin(), a = v.begin();
           a != v.end(); ++e, ++a) {
        EXPECT_EQ(e->first, a->first) << "image " << i;
        EXPECT_TRUE(dbow2_golden::close(e->second, a->second, 1e-9)) << "image " << i;
      }
    }
    for (int up = 0; up <= g.L; ++up) {
      DBoW2::BowVector v2, v3;
      DBoW2::FeatureVector fv, fv_rows;
      voc.transform(images[i], v2, fv, up);
      voc.transform(g.images[i], v3, fv_rows, up);
      EXPECT_TRUE(fv == fv_rows && v2 == v) << "levelsup " << up << " image " << i;
      const auto golden_fv = g.feature_vectors.find(std::make_pair(up, static_cast<int>(i)));
      if (golden_fv != g.feature_vectors.end()) {
        ++feature_vectors;
        EXPECT_TRUE(golden_fv->second == fv) << "levelsup " << up << " image " << i;
      }
    }
  }
  // Queries: entries added as bitsets, queried as bitsets; the same
  // entries added as rows answer the same.
  database.setVocabulary(voc, true, 1);
  database.setVinsQueryRule(false);
  BriefDatabase rows(voc, true, 1);
  rows.setVinsQueryRule(false);
  for (std::size_t i = 0; i < images.size(); ++i) {
    DBoW2::BowVector bow;
    DBoW2::FeatureVector fv;
    EXPECT_EQ(i, database.add(images[i], &bow, &fv));
    EXPECT_EQ(i, rows.add(g.images[i]));
    EXPECT_TRUE(fv == database.retrieveFeatures(static_cast<DBoW2::EntryId>(i)));
  }
  for (const dbow2_golden::Query& q : g.queries) {
    if (q.scoring != "L1_NORM") continue;
    ++queries;
    const std::string what = "query " + std::to_string(q.image) + " max_results " +
                             std::to_string(q.max_results) + " max_id " + std::to_string(q.max_id);
    DBoW2::QueryResults ret, from_rows;
    database.query(images[q.image], ret, q.max_results, q.max_id);
    rows.query(g.images[q.image], from_rows, q.max_results, q.max_id);
    EXPECT_TRUE(same_results(ret, from_rows)) << what;
    ASSERT_EQ(q.results.size(), ret.size()) << what;
    for (std::size_t r = 0; r < ret.size(); ++r)
      EXPECT_TRUE(dbow2_golden::close(q.results[r].second, ret[r].Score, 1e-6))
          << what << " result " << r << ": " << q.results[r].second << " vs " << ret[r].Score;
  }
  EXPECT_GT(words, 500u);
  EXPECT_EQ(images.size(), bows);
  EXPECT_GE(feature_vectors, 30u);
  EXPECT_GT(queries, 5u);
}

}  // namespace bitset_golden

#endif
