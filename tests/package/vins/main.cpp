// Uses binbow's DBoW2 API the way VINS-Mono/Fusion's loop closure uses its
// copy of DBoW2 (its include names, DVision::BRIEF's bitsets, a VINS binary
// vocabulary loaded with `new BriefVocabulary(path)`, a BriefDatabase without
// direct index, queried with max_results 4 and a max_id behind the current
// frame before each keyframe is added), and checks the results against
// DBoW2's own numbers as VINS's copy of it returns them (vins_expected.h).
// Built as C++14, as VINS is.
//
//   consumer VINS_VOCABULARY GOLDEN_FILE
#include <cstdio>
#include <string>
#include <vector>

#include "ThirdParty/DBoW/DBoW2.h"
#include "ThirdParty/DBoW/TemplatedDatabase.h"
#include "ThirdParty/DBoW/TemplatedVocabulary.h"
#include "ThirdParty/DVision/DVision.h"
#include "vins_expected.h"

static_assert(__cplusplus == 201402L, "this consumer must build as C++14");

using namespace std;
using namespace DVision;
using namespace DBoW2;

namespace {

int failures = 0;
int compared = 0;

void check(bool ok, const string& what) {
  ++compared;
  if (!ok) {
    fprintf(stderr, "mismatch: %s\n", what.c_str());
    ++failures;
  }
}

// A keyframe's descriptors as VINS keeps them.
vector<BRIEF::bitset> descriptors_of(const vector<cv::Mat>& rows) {
  vector<BRIEF::bitset> descriptors;
  for (const cv::Mat& row : rows) {
    BRIEF::bitset bits(256);
    for (size_t i = 0; i < bits.size(); ++i)
      bits[i] = ((row.at<unsigned char>(0, static_cast<int>(i / 8)) >> (i % 8)) & 1) != 0;
    descriptors.push_back(bits);
  }
  return descriptors;
}

// keyframe.cpp's HammingDis.
int HammingDis(const BRIEF::bitset& a, const BRIEF::bitset& b) {
  BRIEF::bitset xor_of_bitset = a ^ b;
  return static_cast<int>(xor_of_bitset.count());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    fprintf(stderr, "usage: consumer VINS_VOCABULARY GOLDEN_FILE\n");
    return 2;
  }
  try {
    const dbow2_golden::Golden golden = dbow2_golden::read(argv[2]);
    BriefVocabulary* voc = new BriefVocabulary(string(argv[1]));
    BriefDatabase db;
    db.setVocabulary(*voc, false, 0);
    int newest = 0;
    for (size_t frame_index = 0; frame_index < golden.images.size(); ++frame_index) {
      const vector<BRIEF::bitset> brief_descriptors = descriptors_of(golden.images[frame_index]);
      QueryResults ret;
      db.query(brief_descriptors, ret, vins_expected::kMaxResults,
               static_cast<int>(frame_index) - vins_expected::kGap);
      db.add(brief_descriptors);
      const vector<pair<EntryId, double> > expected = vins_expected::results(golden, frame_index);
      const string what = "frame " + to_string(frame_index);
      check(ret.size() == expected.size(), what + ": " + to_string(ret.size()) + " results");
      for (size_t r = 0; r < ret.size() && r < expected.size(); ++r) {
        check(ret[r].Id == expected[r].first, what + " result " + to_string(r) + " id");
        check(dbow2_golden::close(ret[r].Score, expected[r].second, 1e-6),
              what + " result " + to_string(r) + " score");
        if (frame_index > 0 && ret[r].Id == frame_index - 1) ++newest;
      }
      // Words of single descriptors, as the vocabulary gives them to VINS.
      for (size_t f = 0; f < brief_descriptors.size(); f += 17)
        check(voc->transform(brief_descriptors[f]) == golden.feature_words[frame_index][f],
              what + " feature " + to_string(f) + " word");
    }
    const vector<BRIEF::bitset> first = descriptors_of(golden.images[0]);
    check(HammingDis(first[0], first[1]) == BRIEF::distance(first[0], first[1]), "HammingDis");
    delete voc;
    printf("numbers equal to DBoW2's: %d, mismatches: %d, newest entry returned: %d\n",
           compared - failures, failures, newest);
    return failures == 0 ? 0 : 1;
  } catch (const exception& e) {
    fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
