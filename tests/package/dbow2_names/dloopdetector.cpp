// Code written as DLoopDetector calls DBoW2, its include lines unchanged:
// the demo's <DBoW2/DBoW2.h>, the library's bare "DBoW2.h", "FORB.h",
// "TemplatedVocabulary.h", "TemplatedDatabase.h", "QueryResults.h" and
// "BowVector.h" (PlaceDetector.h, TemplatedPlaceDetector.h), a templated
// detector over TemplatedDatabase and TemplatedVocabulary. Checks the
// detector's vectors, direct index and queries against the numbers DBoW2
// itself produced (dbow2_golden.h). Built as C++11.
#include <DBoW2/DBoW2.h>

#include <cstdio>
#include <string>
#include <vector>

#include "PlaceDetector.h"
#include "dbow2_golden.h"

static_assert(__cplusplus == 201103L, "this consumer must build as C++11");

// Upstream DBoW2's headers bring no `using namespace std;` (ORB-SLAM's copy
// does, through its own include names only): with one, this global name
// would be ambiguous with std::vector below.
typedef int vector;

namespace {

using dbow2_golden::check;

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: dloopdetector VOCABULARY GOLDEN\n");
    return 2;
  }
  const vector not_std_vector = 0;
  (void)not_std_vector;
  // DLoopDetector's demo: the vocabulary by its file name, then a detector.
  OrbVocabulary voc(argv[1]);
  const dbow2_golden::Golden golden = dbow2_golden::read(argv[2]);
  check(voc.size() == golden.words && voc.getDepthLevels() == golden.L, "vocabulary");

  // The golden queries ran on DBoW2's OrbDatabase(voc, true, 1) holding
  // every image, entry i being image i.
  const int di_levels = 1;
  OrbPlaceDetector detector(voc, di_levels);
  int compared = 0;
  for (size_t i = 0; i < golden.images.size(); ++i) {
    const DBoW2::EntryId id = detector.add(golden.images[i]);
    check(id == i, "entry id of image " + std::to_string(i));
    std::map<std::pair<int, int>, DBoW2::FeatureVector>::const_iterator fv =
        golden.feature_vectors.find(std::make_pair(di_levels, static_cast<int>(i)));
    if (fv == golden.feature_vectors.end()) continue;  // DBoW2 leaves a node undefined
    check(fv->second == detector.directIndex(id), "direct index of image " + std::to_string(i));
    ++compared;
  }
  check(compared > 0, "direct indexes compared");
  check(detector.getDatabase()->size() == golden.images.size(), "database size");
  for (size_t q = 0; q < golden.queries.size(); ++q) {
    const dbow2_golden::Query& query = golden.queries[q];
    if (query.scoring != "L1_NORM") continue;
    DBoW2::QueryResults ret;
    detector.query(golden.images[query.image], ret, query.max_results, query.max_id);
    check(ret.size() == query.results.size(), "query result count");
    for (size_t r = 0; r < ret.size() && r < query.results.size(); ++r, ++compared)
      check(ret[r].Id == query.results[r].first &&
                dbow2_golden::close(ret[r].Score, query.results[r].second, 1e-6),
            "query result");
  }
  std::printf("numbers equal to DBoW2's: %d, mismatches: %d\n", compared,
              dbow2_golden::mismatches());
  return dbow2_golden::mismatches() == 0 ? 0 : 1;
}
