// The include name "Thirdparty/DBoW2/DBoW2/FeatureVector.h" of ORB-SLAM's
// copy of DBoW2: binbow's DBoW2-compatible FeatureVector, with what the
// copy's header brought along: its BowVector.h (and so Boost.Serialization of
// both vectors wherever Boost's headers are found), <iostream>, <map> and
// <vector>. Found through the opt-in target binbow::dbow2_names (pkg-config
// binbow-dbow2-names).
#ifndef BINBOW_COMPAT_NAMES_ORBSLAM_FEATURE_VECTOR_H
#define BINBOW_COMPAT_NAMES_ORBSLAM_FEATURE_VECTOR_H

#include <iostream>
#include <map>
#include <vector>

#include "BowVector.h"
#include "binbow/compat/FeatureVector.h"

#endif
