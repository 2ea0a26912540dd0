// The online vocabulary's approximate search against brute force on real
// ORB and BRIEF descriptors of rtabmap-samples' corridor.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "binbow/online_vocabulary.h"
#include "binbow/vision/features.h"
#include "binbow/vision/image_source.h"
#include "support/test_support.h"

namespace binbow {
namespace {

struct Recall {
  double nearest = 0;   // found a word as near as the nearest
  double decision = 0;  // new word or not, as exact search would decide
};

// Grows a vocabulary with the default options from the first 60 frames, then
// searches the words for the descriptors of the last 24 (the corridor's second
// pass) and compares with an exhaustive search.
Recall measure(const std::string& descriptor) {
  const auto extractor = vision::make_extractor(descriptor);
  std::vector<DescriptorMatrix> frames;
  for (int i = 1; i <= 84; ++i)
    frames.push_back(extractor
                         ->extract(vision::read_grey_image(test::samples_folder() + "/" +
                                                           std::to_string(i) + ".jpg"))
                         .descriptors);
  OnlineVocabularyOptions options;
  options.purge_after_images = 0;  // every word stays: the hardest case for the trees
  OnlineVocabulary vocabulary(extractor->code_size(), options);
  for (int i = 0; i < 60; ++i) vocabulary.add_image(frames[i]);
  const std::vector<WordId> words = vocabulary.words();
  const std::uint32_t new_word_bits = static_cast<std::uint32_t>(
      options.new_word_distance * static_cast<double>(vocabulary.code_size() * 8));

  std::size_t queries = 0, nearest = 0, decision = 0;
  for (int i = 60; i < 84; i += 2) {
    const DescriptorMatrix& frame = frames[i];
    std::vector<WordId> found(frame.rows());
    std::vector<std::uint32_t> distances(frame.rows());
    vocabulary.nearest_words(frame, found.data(), distances.data());
    for (std::size_t r = 0; r < frame.rows(); ++r) {
      std::uint32_t best = OnlineVocabulary::kNoWord;
      for (const WordId word : words)
        best = std::min(best, hamming_distance(frame.row(r), vocabulary.word_descriptor(word),
                                               vocabulary.code_size()));
      ++queries;
      nearest += distances[r] == best;
      decision += (distances[r] <= new_word_bits) == (best <= new_word_bits);
    }
  }
  EXPECT_GT(queries, 2000u);
  EXPECT_GT(words.size(), 1000u);
  std::printf("%s: %zu words, %zu queries, nearest %.4f, same new-word decision %.4f\n",
              descriptor.c_str(), words.size(), queries,
              static_cast<double>(nearest) / static_cast<double>(queries),
              static_cast<double>(decision) / static_cast<double>(queries));
  return {static_cast<double>(nearest) / static_cast<double>(queries),
          static_cast<double>(decision) / static_cast<double>(queries)};
}

// Thresholds a little under what docs/online-vocabulary.md reports (ORB:
// nearest 0.86, decision 0.96), so that the test guards the documented
// figures without depending on the last digit.
TEST(OnlineVocabularyReal, DefaultSearchFindsTheNearestOrbWord) {
  const Recall recall = measure("orb");
  EXPECT_GE(recall.nearest, 0.82);
  EXPECT_GE(recall.decision, 0.94);
}

TEST(OnlineVocabularyReal, DefaultSearchFindsTheNearestBriefWord) {
  const Recall recall = measure("brief");
  EXPECT_GE(recall.nearest, 0.82);
  EXPECT_GE(recall.decision, 0.94);
}

}  // namespace
}  // namespace binbow
