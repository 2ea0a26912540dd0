// VINS's fork's query rule (TemplatedDatabase::setVinsQueryRule): its
// queryL1 also considers the newest entry, whatever max_id. Off by default
// here: this program includes no VINS spelling of the headers.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "binbow/compat/DBoW2.h"
#include "compat/bitset_golden.h"
#include "compat/dbow2_golden.h"

namespace {

using bitset_golden::golden;

// VINS's queryL1 written out: entries sharing a word with the query, with
// id < max_id, or any id for max_id == -1, or the newest entry; best score
// first (ids in increasing order among equal scores), the first max_results.
DBoW2::QueryResults vins_query(const BriefVocabulary& voc,
                               const std::vector<DBoW2::BowVector>& entries,
                               const DBoW2::BowVector& query, int max_results, int max_id,
                               bool newest_too) {
  DBoW2::QueryResults ret;
  for (std::size_t id = 0; id < entries.size(); ++id) {
    const bool allowed =
        max_id == -1 || static_cast<int>(id) < max_id || (newest_too && id + 1 == entries.size());
    bool shares = false;
    for (const auto& word : query) shares |= entries[id].count(word.first) > 0;
    if (allowed && shares)
      ret.push_back(DBoW2::Result(static_cast<DBoW2::EntryId>(id), voc.score(query, entries[id])));
  }
  std::stable_sort(ret.begin(), ret.end(), DBoW2::Result::gt);
  if (max_results > 0 && static_cast<int>(ret.size()) > max_results) ret.resize(max_results);
  return ret;
}

void expect_same(const DBoW2::QueryResults& expected, const DBoW2::QueryResults& actual,
                 const std::string& what) {
  ASSERT_EQ(expected.size(), actual.size()) << what;
  for (std::size_t r = 0; r < expected.size(); ++r) {
    EXPECT_EQ(expected[r].Id, actual[r].Id) << what << " result " << r;
    EXPECT_TRUE(dbow2_golden::close(expected[r].Score, actual[r].Score, 1e-6))
        << what << " result " << r;
  }
}

TEST(Dbow2VinsRule, NewestEntryJoinsL1QueriesOnlyWhenChosen) {
  const BriefVocabulary& voc = bitset_golden::vocabulary();
  ASSERT_EQ(DBoW2::L1_NORM, voc.getScoringType());
  const std::vector<std::vector<std::bitset<256> > > images =
      bitset_golden::images_as(std::bitset<256>());
  BriefDatabase dbow2(voc, false, 0), vins(voc, false, 0);
  EXPECT_FALSE(dbow2.usingVinsQueryRule());  // DBoW2's rule by default
  vins.setVinsQueryRule(true);
  EXPECT_TRUE(vins.usingVinsQueryRule());
  EXPECT_TRUE(BriefDatabase(vins).usingVinsQueryRule());  // copies keep it
  std::vector<DBoW2::BowVector> entries;
  std::size_t differing = 0;
  for (std::size_t i = 0; i < images.size(); ++i) {
    // As VINS does: query first, then add the keyframe.
    DBoW2::BowVector bow;
    voc.transform(images[i], bow);
    for (int max_id : {-1, -40, 0, 1, 3, 5, 6, 10})
      for (int max_results : {0, 1, 4}) {
        const std::string what = "image " + std::to_string(i) + " max_id " +
                                 std::to_string(max_id) + " max_results " +
                                 std::to_string(max_results);
        DBoW2::QueryResults with_rule, without;
        vins.query(images[i], with_rule, max_results, max_id);
        dbow2.query(images[i], without, max_results, max_id);
        expect_same(vins_query(voc, entries, bow, max_results, max_id, true), with_rule, what);
        expect_same(vins_query(voc, entries, bow, max_results, max_id, false), without, what);
        differing += with_rule.size() != without.size() ||
                     !std::equal(with_rule.begin(), with_rule.end(), without.begin(),
                                 [](const DBoW2::Result& a, const DBoW2::Result& b) {
                                   return a.Id == b.Id;
                                 });
      }
    EXPECT_EQ(i, vins.add(images[i]));
    EXPECT_EQ(i, dbow2.add(images[i]));
    entries.push_back(bow);
  }
  EXPECT_GT(differing, 20u);
  // An erased newest entry is gone for the rule too.
  vins.erase(static_cast<DBoW2::EntryId>(images.size() - 1));
  DBoW2::QueryResults ret;
  vins.query(images.back(), ret, 0, 1);
  for (const DBoW2::Result& r : ret) EXPECT_EQ(0u, r.Id);
}

TEST(Dbow2VinsRule, OtherScoringsKeepDbow2sRule) {
  BriefVocabulary voc = bitset_golden::vocabulary();
  voc.setScoringType(DBoW2::L2_NORM);
  const std::vector<std::vector<std::bitset<256> > > images =
      bitset_golden::images_as(std::bitset<256>());
  BriefDatabase vins(voc, false, 0);
  vins.setVinsQueryRule(true);
  // Images 0..5 (image 6 shares no word with the others): the newest entry,
  // 5, shares words with image 4, and L1_NORM would return it.
  for (std::size_t i = 0; i < 6; ++i) vins.add(images[i]);
  DBoW2::QueryResults ret;
  vins.query(images[4], ret, 0, 2);
  ASSERT_EQ(2u, ret.size());
  for (const DBoW2::Result& r : ret) EXPECT_LT(r.Id, 2u);
  voc.setScoringType(DBoW2::L1_NORM);
  BriefDatabase l1(voc, false, 0);
  l1.setVinsQueryRule(true);
  for (std::size_t i = 0; i < 6; ++i) l1.add(images[i]);
  l1.query(images[4], ret, 0, 2);
  ASSERT_EQ(3u, ret.size());
  EXPECT_EQ(5u, ret[0].Id);
}

}  // namespace
