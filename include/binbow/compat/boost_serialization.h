// Boost.Serialization of DBoW2::BowVector and DBoW2::FeatureVector, for code
// written against ORB-SLAM3's copy of DBoW2, whose two classes carry a
// serialize() member (ORB-SLAM3 archives its keyframes' mBowVec and mFeatVec
// when it saves and loads an atlas). binbow's classes stay free of Boost, so
// the same is given here as Boost's non-intrusive free functions, writing
// what the copy's members write: the std::map base, through base_object.
// Archives written by either side read on the other.
//
// Header-only over Boost's headers; archives need the consumer to link
// Boost.Serialization (-lboost_serialization), as ORB-SLAM3 already does.
// The ORB-SLAM include names (binbow::dbow2_names) include it wherever
// <boost/serialization/map.hpp> is found.
#ifndef BINBOW_COMPAT_DBOW2_BOOST_SERIALIZATION_H
#define BINBOW_COMPAT_DBOW2_BOOST_SERIALIZATION_H

#include <boost/serialization/base_object.hpp>
#include <boost/serialization/map.hpp>
#include <boost/serialization/serialization.hpp>
#include <boost/serialization/vector.hpp>
#include <map>
#include <vector>

#include "binbow/compat/BowVector.h"
#include "binbow/compat/FeatureVector.h"

namespace boost {
namespace serialization {

template <class Archive>
void serialize(Archive& ar, DBoW2::BowVector& bow, const unsigned int /*version*/) {
  ar& boost::serialization::base_object<std::map<DBoW2::WordId, DBoW2::WordValue> >(bow);
}

template <class Archive>
void serialize(Archive& ar, DBoW2::FeatureVector& features, const unsigned int /*version*/) {
  ar& boost::serialization::base_object<std::map<DBoW2::NodeId, std::vector<unsigned int> > >(
      features);
}

}  // namespace serialization
}  // namespace boost

#endif
