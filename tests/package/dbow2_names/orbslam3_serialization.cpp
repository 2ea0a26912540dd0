// Code written as ORB-SLAM3 archives its keyframes (KeyFrame::serialize,
// System's atlas save and load): a class whose serialize() member archives
// its mBowVec and mFeatVec with Boost.Serialization, the vectors' headers by
// their Thirdparty/ paths (which bring Boost's map and vector support, as the
// copy's headers do). Computes the vectors of DBoW2's golden images as
// ORB-SLAM3 does (ORBvoc.txt, transform(..., 4)), checks them against
// DBoW2's, round-trips them through text and binary archives, and checks
// that the text archive is the one ORB-SLAM3's copy writes (its vectors'
// serialize() members archive the std::map base). Built as C++11.
#include <boost/archive/binary_iarchive.hpp>
#include <boost/archive/binary_oarchive.hpp>
#include <boost/archive/text_iarchive.hpp>
#include <boost/archive/text_oarchive.hpp>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "ORBVocabulary.h"
#include "Thirdparty/DBoW2/DBoW2/BowVector.h"
#include "Thirdparty/DBoW2/DBoW2/FeatureVector.h"
#include "dbow2_golden.h"

static_assert(__cplusplus == 201103L, "this consumer must build as C++11");

namespace {

using dbow2_golden::check;

struct KeyFrame {
  DBoW2::BowVector mBowVec;
  DBoW2::FeatureVector mFeatVec;

  template <class Archive>
  void serialize(Archive& ar, const unsigned int /*version*/) {
    ar& mBowVec;
    ar& mFeatVec;
  }
};

// What ORB-SLAM3's copy declares: the vectors with serialize() members of
// their own, archiving the std::map base.
struct CopyBowVector : std::map<DBoW2::WordId, DBoW2::WordValue> {
  template <class Archive>
  void serialize(Archive& ar, const unsigned int /*version*/) {
    ar& boost::serialization::base_object<std::map<DBoW2::WordId, DBoW2::WordValue> >(*this);
  }
};
struct CopyFeatureVector : std::map<DBoW2::NodeId, std::vector<unsigned int> > {
  template <class Archive>
  void serialize(Archive& ar, const unsigned int /*version*/) {
    ar& boost::serialization::base_object<std::map<DBoW2::NodeId, std::vector<unsigned int> > >(
        *this);
  }
};
struct CopyKeyFrame {
  CopyBowVector mBowVec;
  CopyFeatureVector mFeatVec;

  template <class Archive>
  void serialize(Archive& ar, const unsigned int /*version*/) {
    ar& mBowVec;
    ar& mFeatVec;
  }
};

template <class OArchive, class IArchive>
KeyFrame round_trip(const KeyFrame& kf, std::string& bytes) {
  std::ostringstream out;
  {
    OArchive oa(out);
    oa << kf;
  }
  bytes = out.str();
  KeyFrame loaded;
  std::istringstream in(bytes);
  IArchive ia(in);
  ia >> loaded;
  return loaded;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: orbslam3_serialization ORBVOC_TXT GOLDEN\n");
    return 2;
  }
  ORBVocabulary voc;
  if (!voc.loadFromTextFile(argv[1])) {
    std::fprintf(stderr, "Wrong path to vocabulary: %s\n", argv[1]);
    return 1;
  }
  const dbow2_golden::Golden golden = dbow2_golden::read(argv[2]);
  int compared = 0;
  for (size_t i = 0; i < golden.images.size(); ++i) {
    KeyFrame kf;
    voc.transform(golden.images[i], kf.mBowVec, kf.mFeatVec, 4);
    const DBoW2::BowVector& expected = golden.bows.at(std::make_pair(
        std::make_pair(std::string("TF_IDF"), std::string("L1_NORM")), static_cast<int>(i)));
    check(!kf.mBowVec.empty() && kf.mBowVec.size() == expected.size(),
          "BoW vector of image " + std::to_string(i));
    for (DBoW2::BowVector::const_iterator e = expected.begin(), a = kf.mBowVec.begin();
         e != expected.end() && a != kf.mBowVec.end(); ++e, ++a)
      check(e->first == a->first && dbow2_golden::close(e->second, a->second, 1e-9),
            "BoW value of image " + std::to_string(i));
    std::map<std::pair<int, int>, DBoW2::FeatureVector>::const_iterator fv =
        golden.feature_vectors.find(std::make_pair(4, static_cast<int>(i)));
    check(fv != golden.feature_vectors.end() && fv->second == kf.mFeatVec,
          "feature vector of image " + std::to_string(i));

    std::string text, binary;
    const KeyFrame from_text =
        round_trip<boost::archive::text_oarchive, boost::archive::text_iarchive>(kf, text);
    const KeyFrame from_binary =
        round_trip<boost::archive::binary_oarchive, boost::archive::binary_iarchive>(kf, binary);
    check(from_text.mBowVec == kf.mBowVec && from_text.mFeatVec == kf.mFeatVec,
          "text archive round trip of image " + std::to_string(i));
    check(from_binary.mBowVec == kf.mBowVec && from_binary.mFeatVec == kf.mFeatVec,
          "binary archive round trip of image " + std::to_string(i));
    compared += static_cast<int>(kf.mBowVec.size() + kf.mFeatVec.size());

    CopyKeyFrame copy;
    copy.mBowVec.insert(kf.mBowVec.begin(), kf.mBowVec.end());
    copy.mFeatVec.insert(kf.mFeatVec.begin(), kf.mFeatVec.end());
    std::ostringstream out;
    {
      boost::archive::text_oarchive oa(out);
      oa << copy;
    }
    check(out.str() == text,
          "text archive as ORB-SLAM3's copy writes it, image " + std::to_string(i));
  }
  std::printf("numbers equal to DBoW2's: %d, mismatches: %d\n", compared,
              dbow2_golden::mismatches());
  return dbow2_golden::mismatches() == 0 ? 0 : 1;
}
