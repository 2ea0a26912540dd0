// Uses the installed binbow::dbow2 the way ORB-SLAM2 uses DBoW2 (a text
// vocabulary, keyframes' BoW and feature vectors, SearchByBoW's walk over two
// feature vectors, a keyframe database's walk over BoW vectors) and checks
// the results against the numbers DBoW2 itself produced (dbow2_golden.h).
// Built as C++11: the DBoW2 API must not need more.
#include <binbow/compat/DBoW2.h>

#include <cstdio>
#include <list>
#include <string>
#include <vector>

#include "dbow2_golden.h"

static_assert(__cplusplus == 201103L, "this consumer must build as C++11");

typedef DBoW2::TemplatedVocabulary<DBoW2::FORB::TDescriptor, DBoW2::FORB> ORBVocabulary;

namespace {

using dbow2_golden::check;

struct KeyFrame {
  std::vector<cv::Mat> descriptors;
  DBoW2::BowVector bow;
  DBoW2::FeatureVector features;
};

// ORB-SLAM's SearchByBoW: features of two keyframes under the same
// vocabulary node are match candidates; the best under 50 bits wins.
int search_by_bow(const KeyFrame& a, const KeyFrame& b) {
  int matches = 0;
  DBoW2::FeatureVector::const_iterator ait = a.features.begin();
  DBoW2::FeatureVector::const_iterator bit = b.features.begin();
  const DBoW2::FeatureVector::const_iterator aend = a.features.end();
  const DBoW2::FeatureVector::const_iterator bend = b.features.end();
  while (ait != aend && bit != bend) {
    if (ait->first == bit->first) {
      for (size_t i = 0; i < ait->second.size(); ++i) {
        double best = 256;
        for (size_t j = 0; j < bit->second.size(); ++j) {
          const double d =
              DBoW2::FORB::distance(a.descriptors[ait->second[i]], b.descriptors[bit->second[j]]);
          if (d < best) best = d;
        }
        if (best <= 50) ++matches;
      }
      ++ait;
      ++bit;
    } else if (ait->first < bit->first) {
      ait = a.features.lower_bound(bit->first);
    } else {
      bit = b.features.lower_bound(ait->first);
    }
  }
  return matches;
}

// A keyframe database's candidates for `query`: keyframes sharing a word,
// through an inverted file filled by walking BoW vectors, ranked by score.
int best_candidate(const ORBVocabulary& voc, const std::vector<KeyFrame>& keyframes, size_t query) {
  std::vector<std::list<size_t> > inverted(voc.size());
  for (size_t k = 0; k < keyframes.size(); ++k)
    for (DBoW2::BowVector::const_iterator vit = keyframes[k].bow.begin();
         vit != keyframes[k].bow.end(); ++vit)
      inverted[vit->first].push_back(k);
  std::vector<bool> shares(keyframes.size(), false);
  for (DBoW2::BowVector::const_iterator vit = keyframes[query].bow.begin();
       vit != keyframes[query].bow.end(); ++vit)
    for (std::list<size_t>::const_iterator k = inverted[vit->first].begin();
         k != inverted[vit->first].end(); ++k)
      shares[*k] = true;
  int best = -1;
  double best_score = -1;
  for (size_t k = 0; k < keyframes.size(); ++k) {
    if (k == query || !shares[k]) continue;
    const double score = voc.score(keyframes[query].bow, keyframes[k].bow);
    if (score > best_score) {
      best_score = score;
      best = static_cast<int>(k);
    }
  }
  return best;
}

// Code written for DBoW2 often says `using namespace DBoW2;` and then uses
// the typedefs DBoW2 declares at global scope: both must name one type.
void uses_namespace_and_global_typedefs() {
  using namespace DBoW2;
  OrbDatabase* database = NULL;
  BowVector bow;
  (void)database;
  (void)bow;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: consumer ORBVOC_TXT GOLDEN\n");
    return 2;
  }
  uses_namespace_and_global_typedefs();
  ORBVocabulary* voc = new ORBVocabulary();
  if (!voc->loadFromTextFile(argv[1])) {
    std::fprintf(stderr, "Wrong path to vocabulary: %s\n", argv[1]);
    return 1;
  }
  const dbow2_golden::Golden golden = dbow2_golden::read(argv[2]);
  check(voc->size() == golden.words && voc->getDepthLevels() == golden.L, "vocabulary");

  // Keyframes as ORB-SLAM computes them: direct index 4 levels up.
  const int levelsup = 4;
  std::vector<KeyFrame> keyframes(golden.images.size());
  int compared = 0;
  for (size_t i = 0; i < keyframes.size(); ++i) {
    keyframes[i].descriptors = golden.images[i];
    voc->transform(keyframes[i].descriptors, keyframes[i].bow, keyframes[i].features, levelsup);
    const DBoW2::BowVector& expected = golden.bows.at(std::make_pair(
        std::make_pair(std::string("TF_IDF"), std::string("L1_NORM")), static_cast<int>(i)));
    check(expected.size() == keyframes[i].bow.size(), "BoW size of image " + std::to_string(i));
    DBoW2::BowVector::const_iterator e = expected.begin(), a = keyframes[i].bow.begin();
    for (; e != expected.end() && a != keyframes[i].bow.end(); ++e, ++a, ++compared)
      check(e->first == a->first && dbow2_golden::close(e->second, a->second, 1e-9),
            "BoW value of image " + std::to_string(i));
    std::map<std::pair<int, int>, DBoW2::FeatureVector>::const_iterator fv =
        golden.feature_vectors.find(std::make_pair(levelsup, static_cast<int>(i)));
    check(fv != golden.feature_vectors.end() && fv->second == keyframes[i].features,
          "feature vector of image " + std::to_string(i));
  }
  const std::vector<double>& scores =
      golden.scores.at(std::make_pair(std::string("TF_IDF"), std::string("L1_NORM")));
  const size_t n = keyframes.size();
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < n; ++j, ++compared)
      check(dbow2_golden::close(scores[i * n + j], voc->score(keyframes[i].bow, keyframes[j].bow),
                                1e-9),
            "score " + std::to_string(i) + " " + std::to_string(j));

  // DBoW2's own database, as DLoopDetector uses it.
  OrbDatabase db(*voc, true, 1);
  for (size_t i = 0; i < n; ++i) db.add(keyframes[i].descriptors);
  for (size_t q = 0; q < golden.queries.size(); ++q) {
    const dbow2_golden::Query& query = golden.queries[q];
    if (query.scoring != "L1_NORM") continue;
    DBoW2::QueryResults ret;
    db.query(keyframes[query.image].bow, ret, query.max_results, query.max_id);
    check(ret.size() == query.results.size(), "query result count");
    for (size_t r = 0; r < ret.size() && r < query.results.size(); ++r, ++compared)
      check(ret[r].Id == query.results[r].first &&
                dbow2_golden::close(ret[r].Score, query.results[r].second, 1e-6),
            "query result");
  }

  // Images 1 and 3 show the same staircase.
  const int matches = search_by_bow(keyframes[1], keyframes[3]);
  const int candidate = best_candidate(*voc, keyframes, 1);
  check(candidate == 3, "keyframe database candidate of image 1");
  delete voc;
  std::printf("numbers equal to DBoW2's: %d, mismatches: %d, SearchByBoW matches: %d\n", compared,
              dbow2_golden::mismatches(), matches);
  return dbow2_golden::mismatches() == 0 && matches > 0 ? 0 : 1;
}
