// The include name "Thirdparty/DBoW2/DBoW2/BowVector.h" of ORB-SLAM's copy of
// DBoW2: binbow's DBoW2-compatible BowVector, with what the copy's header
// brought along: <iostream>, <map> and <vector>, and (ORB-SLAM3's copy)
// Boost.Serialization of the vector, given here by
// binbow/compat/boost_serialization.h wherever Boost's headers are found.
// Found through the opt-in target binbow::dbow2_names (pkg-config
// binbow-dbow2-names).
#ifndef BINBOW_COMPAT_NAMES_ORBSLAM_BOW_VECTOR_H
#define BINBOW_COMPAT_NAMES_ORBSLAM_BOW_VECTOR_H

#include <iostream>
#include <map>
#include <vector>

#include "binbow/compat/BowVector.h"

#if defined(__has_include)
#if __has_include(<boost/serialization/map.hpp>)
#include "binbow/compat/boost_serialization.h"
#endif
#endif

#endif
