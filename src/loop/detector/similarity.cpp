#include "binbow/loop/similarity.h"

#include <algorithm>

#include "binbow/database.h"
#include "binbow/error.h"
#include "binbow/online_vocabulary.h"

namespace binbow::loop {

namespace {

// `transform` turns descriptors into a BoW vector of `database`'s words.
template <typename Transform>
SimilarityMatrix similarity_matrix(Database database, const Transform& transform,
                                   const std::vector<DescriptorView>& descriptors) {
  SimilarityMatrix m;
  m.frames = descriptors.size();
  if (m.frames == 0) return m;
  m.bin = (m.frames + kMaxSimilarityCells - 1) / kMaxSimilarityCells;
  m.cells = (m.frames + m.bin - 1) / m.bin;
  m.scores.assign(m.cells * m.cells, 0.0f);
  const std::size_t stride = (m.frames + kMaxSimilarityQueries - 1) / kMaxSimilarityQueries;
  m.every_query = stride == 1;

  // One pass, as the detector runs: each image is scored against the images
  // before it (all of them, through the inverted index), then added.
  BowVector bow;
  for (std::size_t i = 0; i < m.frames; ++i) {
    transform(descriptors[i], bow);
    if (i % stride == 0 && i > 0) {
      float* row = &m.scores[m.cell(i) * m.cells];
      for (const QueryResult& r : database.query(bow, i)) {
        float& cell = row[m.cell(r.entry)];
        cell = std::max(cell, static_cast<float>(r.score));
      }
    }
    database.add(bow);
  }
  return m;
}

DatabaseOptions without_direct_index() {
  DatabaseOptions options;
  options.direct_index = false;
  return options;
}

}  // namespace

SimilarityMatrix similarity_matrix(const Vocabulary& vocabulary,
                                   const std::vector<DescriptorView>& descriptors) {
  return similarity_matrix(
      Database(vocabulary, without_direct_index()),
      [&](const DescriptorView& d, BowVector& bow) { vocabulary.transform(d, bow); }, descriptors);
}

SimilarityMatrix similarity_matrix(const Vocabulary& vocabulary,
                                   const std::vector<vision::Features>& features) {
  std::vector<DescriptorView> views;
  views.reserve(features.size());
  for (const vision::Features& f : features) views.push_back(f.descriptors);
  return similarity_matrix(vocabulary, views);
}

namespace {

SimilarityMatrix similarity_matrix(const OnlineVocabulary& online,
                                   const std::vector<DescriptorView>& views) {
  return similarity_matrix(
      Database::over_word_ids(online.options().scoring, without_direct_index()),
      [&](const DescriptorView& d, BowVector& bow) {
        if (d.empty())
          bow.clear();
        else
          online.transform(d, bow);
      },
      views);
}

}  // namespace

SimilarityMatrix online_similarity_matrix(std::size_t code_size,
                                          const std::vector<vision::Features>& features,
                                          const OnlineVocabularyOptions& options) {
  OnlineVocabulary online(code_size, options);
  std::vector<DescriptorView> views;
  views.reserve(features.size());
  for (const vision::Features& f : features) {
    views.push_back(f.descriptors);
    if (!f.descriptors.empty()) online.add_image(f.descriptors);
  }
  return similarity_matrix(online, views);
}

SimilarityMatrix similarity_matrix(const LoopDetector& detector) {
  if (detector.params().geometric_check == GeometricCheck::kNone)
    throw InvalidArgument(
        "the similarity matrix needs the images' features, which a loop detector without a "
        "geometric check does not keep");
  std::vector<DescriptorView> views;
  views.reserve(detector.size());
  for (std::size_t entry = 0; entry < detector.size(); ++entry)
    views.push_back(detector.is_forgotten(static_cast<EntryId>(entry))
                        ? DescriptorView{}
                        : detector.descriptors(static_cast<EntryId>(entry)));
  // With the words and IDF grown over the whole sequence.
  if (const OnlineVocabulary* online = detector.online_vocabulary())
    return similarity_matrix(*online, views);
  return similarity_matrix(detector.database().vocabulary(), views);
}

}  // namespace binbow::loop
