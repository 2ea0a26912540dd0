// Code written as ORB-SLAM2/3 call DBoW2, their include lines unchanged:
// ORBVocabulary.h's Thirdparty/DBoW2/DBoW2 headers and typedef,
// loadFromTextFile, a frame's transform(..., 4), the FeatureVector walk of
// the matcher's SearchByBoW, the keyframe database's walk over BoW vectors,
// the RANSAC loops' DUtils::Random; and, as their files do, unqualified
// vector, string, list, ifstream and cout, which come from the copy's
// TemplatedVocabulary.h (its `using namespace std;` and <fstream>) and
// BowVector.h (<iostream>). Checks the numbers against the ones DBoW2 itself
// produced (dbow2_golden.h). Built as C++11.
#include <cstdio>
#include <cstdlib>
#include <list>
#include <opencv2/core.hpp>

#include "ORBVocabulary.h"
#include "Thirdparty/DBoW2/DBoW2/BowVector.h"
#include "Thirdparty/DBoW2/DBoW2/FeatureVector.h"
#include "Thirdparty/DBoW2/DUtils/Random.h"
#include "dbow2_golden.h"

static_assert(__cplusplus == 201103L, "this consumer must build as C++11");

namespace {

int failures = 0;

void check(bool ok, const string& what) {
  if (!ok) {
    cerr << "mismatch: " << what << endl;
    ++failures;
  }
}

// A frame as ORB-SLAM's Frame::ComputeBoW fills it.
struct Frame {
  vector<cv::Mat> mDescriptors;
  DBoW2::BowVector mBowVec;
  DBoW2::FeatureVector mFeatVec;

  void ComputeBoW(ORBVocabulary* voc) {
    if (mBowVec.empty()) voc->transform(mDescriptors, mBowVec, mFeatVec, 4);
  }
};

// ORBmatcher::SearchByBoW's walk: features under the same vocabulary node
// are candidates; the best under 50 bits is a match.
int SearchByBoW(const Frame& a, const Frame& b) {
  int nmatches = 0;
  DBoW2::FeatureVector::const_iterator f1it = a.mFeatVec.begin();
  DBoW2::FeatureVector::const_iterator f2it = b.mFeatVec.begin();
  DBoW2::FeatureVector::const_iterator f1end = a.mFeatVec.end();
  DBoW2::FeatureVector::const_iterator f2end = b.mFeatVec.end();
  while (f1it != f1end && f2it != f2end) {
    if (f1it->first == f2it->first) {
      for (size_t i1 = 0; i1 < f1it->second.size(); i1++) {
        int bestDist = 256;
        for (size_t i2 = 0; i2 < f2it->second.size(); i2++) {
          const int dist = static_cast<int>(DBoW2::FORB::distance(
              a.mDescriptors[f1it->second[i1]], b.mDescriptors[f2it->second[i2]]));
          if (dist < bestDist) bestDist = dist;
        }
        if (bestDist <= 50) nmatches++;
      }
      f1it++;
      f2it++;
    } else if (f1it->first < f2it->first) {
      f1it = a.mFeatVec.lower_bound(f2it->first);
    } else {
      f2it = b.mFeatVec.lower_bound(f1it->first);
    }
  }
  return nmatches;
}

// KeyFrameDatabase::DetectLoopCandidates' walk: frames sharing a word through
// an inverted file, the best scoring one.
int DetectCandidate(ORBVocabulary* voc, const vector<Frame>& frames, size_t query) {
  vector<list<size_t> > mvInvertedFile(voc->size());
  for (size_t k = 0; k < frames.size(); k++)
    for (DBoW2::BowVector::const_iterator vit = frames[k].mBowVec.begin(),
                                          vend = frames[k].mBowVec.end();
         vit != vend; vit++)
      mvInvertedFile[vit->first].push_back(k);
  vector<bool> shares(frames.size(), false);
  for (DBoW2::BowVector::const_iterator vit = frames[query].mBowVec.begin(),
                                        vend = frames[query].mBowVec.end();
       vit != vend; vit++)
    for (list<size_t>::const_iterator k = mvInvertedFile[vit->first].begin();
         k != mvInvertedFile[vit->first].end(); k++)
      shares[*k] = true;
  int best = -1;
  double bestScore = -1;
  for (size_t k = 0; k < frames.size(); k++) {
    if (k == query || !shares[k]) continue;
    const double si = voc->score(frames[query].mBowVec, frames[k].mBowVec);
    if (si > bestScore) {
      bestScore = si;
      best = static_cast<int>(k);
    }
  }
  return best;
}

// The RANSAC loops' sampling: SeedRandOnce(0), then RandomInt over the
// indices left. The copy's numbers are the C library's rand() after
// srand(0), mapped onto [min, max] as rand() / (RAND_MAX + 1.0) * (max - min + 1).
void CheckRandom() {
  DUtils::Random::SeedRandOnce(0);
  vector<int> drawn;
  for (int i = 0; i < 20; i++) drawn.push_back(DUtils::Random::RandomInt(0, 99 - i));
  DUtils::Random::SeedRandOnce(0);  // seeds once only: the sequence goes on
  const int next = DUtils::Random::RandomInt(0, 1000000);
  std::srand(0);
  for (int i = 0; i < 20; i++) {
    const int expected = int((double)std::rand() / ((double)RAND_MAX + 1.0) * (100 - i));
    check(drawn[i] == expected, "DUtils::Random::RandomInt after SeedRandOnce(0)");
  }
  check(next == int((double)std::rand() / ((double)RAND_MAX + 1.0) * 1000001),
        "DUtils::Random::SeedRandOnce seeds once");
  DUtils::Random::SeedRand(7);
  const double v = DUtils::Random::RandomValue<double>(2.0, 3.0);
  std::srand(7);
  check(v == (double)std::rand() / (double)RAND_MAX * 1.0 + 2.0, "DUtils::Random::RandomValue");
  const float g = DUtils::Random::RandomGaussianValue<float>(0.f, 1.f);
  check(g == g, "DUtils::Random::RandomGaussianValue");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    cerr << "usage: orbslam ORBVOC_TXT GOLDEN" << endl;
    return 2;
  }
  const string strVocFile = argv[1];
  ifstream vocabularyFile(strVocFile.c_str());
  if (!vocabularyFile.is_open()) {
    cerr << "Failed to open at: " << strVocFile << endl;
    return 1;
  }
  ORBVocabulary* mpVocabulary = new ORBVocabulary();
  if (!mpVocabulary->loadFromTextFile(strVocFile)) {
    cerr << "Wrong path to vocabulary. " << endl;
    return 1;
  }
  const dbow2_golden::Golden golden = dbow2_golden::read(argv[2]);
  check(mpVocabulary->size() == golden.words && mpVocabulary->getDepthLevels() == golden.L,
        "vocabulary");

  vector<Frame> frames(golden.images.size());
  int compared = 0;
  for (size_t i = 0; i < frames.size(); i++) {
    frames[i].mDescriptors = golden.images[i];
    frames[i].ComputeBoW(mpVocabulary);
    const DBoW2::BowVector& expected = golden.bows.at(
        make_pair(make_pair(string("TF_IDF"), string("L1_NORM")), static_cast<int>(i)));
    check(expected.size() == frames[i].mBowVec.size(), "BoW size of image " + to_string(i));
    DBoW2::BowVector::const_iterator e = expected.begin(), a = frames[i].mBowVec.begin();
    for (; e != expected.end() && a != frames[i].mBowVec.end(); ++e, ++a, ++compared)
      check(e->first == a->first && dbow2_golden::close(e->second, a->second, 1e-9),
            "BoW value of image " + to_string(i));
    map<pair<int, int>, DBoW2::FeatureVector>::const_iterator fv =
        golden.feature_vectors.find(make_pair(4, static_cast<int>(i)));
    check(fv != golden.feature_vectors.end() && fv->second == frames[i].mFeatVec,
          "feature vector of image " + to_string(i));
  }
  const vector<double>& scores = golden.scores.at(make_pair(string("TF_IDF"), string("L1_NORM")));
  const size_t n = frames.size();
  for (size_t i = 0; i < n; i++)
    for (size_t j = 0; j < n; j++, compared++)
      check(dbow2_golden::close(scores[i * n + j],
                                mpVocabulary->score(frames[i].mBowVec, frames[j].mBowVec), 1e-9),
            "score " + to_string(i) + " " + to_string(j));

  // Images 1 and 3 show the same staircase.
  const int nmatches = SearchByBoW(frames[1], frames[3]);
  check(nmatches > 0, "SearchByBoW matches between images 1 and 3");
  check(DetectCandidate(mpVocabulary, frames, 1) == 3, "loop candidate of image 1");
  CheckRandom();
  delete mpVocabulary;
  cout << "numbers equal to DBoW2's: " << compared << ", mismatches: " << failures
       << ", SearchByBoW matches: " << nmatches << endl;
  return failures == 0 ? 0 : 1;
}
